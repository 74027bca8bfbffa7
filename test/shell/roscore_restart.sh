#!/usr/bin/env bash
# Shell test: when roscore stops, the node keeps simulating and warns every few seconds that the
# master is gone; when roscore is back on the same URI, the node registers its topics, services and
# subscriptions again (roscpp does not), so that the usual tools find it, and the simulation state
# is kept (sim time goes on, the same bodies). Exits 0 on pass.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
use_devel_space

start_roscore 1
background "$node_binary" __name:=particle_sim _scene:="$PARTICLE_SIM_ROOT/config/scenes/test_services.yaml" \
  _status_period:=0 >"$work/node.log" 2>&1
node_pid=$background_pid

# Up: it answers and publishes.
wait_for_service /particle_sim/pause_physics 30 || fail "the node's services did not appear"
answer="$(timeout 30 rosservice call /particle_sim/pause_physics 2>&1)" || fail "pause_physics before: $answer"
contains "$answer" 'success: True' || fail "pause_physics before: $answer"
paused_at="$(sed -n 's/.*paused at sim time \([0-9.]*\) s.*/\1/p' <<<"$answer")"
[ -n "$paused_at" ] || fail "pause_physics before: no sim time in $answer"
bodies_before="$(timeout 15 rostopic echo -n 1 /particle_sim/status/bodies | grep '^  name:')" ||
  fail "no ~status before the restart"

# The master goes: the node goes on and warns, again and again.
stop_roscore
wait_for_log 10 "$work/node.log" 'ROS master at .* does not answer' || fail "no warning that the master is gone"
sleep 6
[ "$(grep -c 'ROS master at .* does not answer' "$work/node.log")" -ge 2 ] || fail "the warning is not repeated"
kill -0 "$node_pid" 2>/dev/null || fail "the node died without its master"

# The master is back: the node registers again, and everything is served as before.
start_roscore 2
wait_for_log 20 "$work/node.log" 'ROS master at .* is back \(pid [0-9]+\): registered again' || fail "no re-registration"
nodes="$(timeout 15 rosnode list)" || fail "rosnode list"
contains "$nodes" '^/particle_sim$' || fail "rosnode list does not show /particle_sim: $nodes"
services="$(timeout 15 rosservice list)" || fail "rosservice list"
contains "$services" '^/particle_sim/step$' || fail "~step is not registered again: $services"
contains "$services" '^/particle_sim/set_parameters$' || fail "dynamic_reconfigure is not registered again"
answer="$(timeout 30 rosservice call /particle_sim/step 'steps: 5' 2>&1)" || fail "~step after the restart: $answer"
contains "$answer" 'success: True' || fail "~step after the restart: $answer"
# The simulation state is kept: sim time goes on from where it was paused, the bodies are the same.
sim_time="$(sed -n 's/^sim_time: //p' <<<"$answer")"
/usr/bin/python3 -c 'import sys; sys.exit(0 if float(sys.argv[2]) > float(sys.argv[1]) else 1)' "$paused_at" "$sim_time" ||
  fail "sim time after the restart ($sim_time s) does not go on from $paused_at s"
bodies_after="$(timeout 15 rostopic echo -n 1 /particle_sim/status/bodies | grep '^  name:')" ||
  fail "no ~status after the restart"
[ "$bodies_after" = "$bodies_before" ] || fail "the bodies changed: $bodies_before, then $bodies_after"
tf_info="$(timeout 15 rostopic info /tf)" || fail "rostopic info /tf"
contains "$(sed -n '/Subscribers:/,$p' <<<"$tf_info")" '/particle_sim' ||
  fail "the node's tf subscription is not registered again: $tf_info"
kill -0 "$node_pid" 2>/dev/null || fail "the node died"
echo "roscore_restart: passed"
