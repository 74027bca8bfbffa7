#!/usr/bin/env bash
# Shell test (issue 16, item 4): two simulators in one master survive each other's crash.
#   - multi.launch (two particle_sim_node processes): kill -9 one, the other keeps stepping and
#     answering, and roslaunch keeps it running (each simulator is its own, not `required`);
#   - one nodelet manager with two SimNodelets: kill -9 the loader of one (the manager unloads it
#     when its bond breaks), the other keeps stepping and answering; then the other way round.
# Exits 0 on pass.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
use_devel_space

# pid of a node, from the node itself (its XML-RPC getPid)
pid_of() {
  /usr/bin/python3 - "$1" <<'PY'
import sys
import xmlrpc.client
import rosgraph
uri = rosgraph.Master('/crash_isolation').lookupNode(sys.argv[1])
print(xmlrpc.client.ServerProxy(uri).getPid('/crash_isolation')[2])
PY
}

# The simulator under namespace $1 answers pause, two ~step calls (sim time goes on) and unpause.
answers() {
  local ns="$1" answer first second
  answer="$(timeout 30 rosservice call "$ns/pause_physics" 2>&1)" || fail "$ns/pause_physics: $answer"
  contains "$answer" 'success: True' || fail "$ns/pause_physics: $answer"
  answer="$(timeout 30 rosservice call "$ns/step" 'steps: 10' 2>&1)" || fail "$ns/step: $answer"
  contains "$answer" 'success: True' || fail "$ns/step: $answer"
  first="$(sed -n 's/^sim_time: //p' <<<"$answer")"
  answer="$(timeout 30 rosservice call "$ns/step" 'steps: 10' 2>&1)" || fail "$ns/step: $answer"
  second="$(sed -n 's/^sim_time: //p' <<<"$answer")"
  /usr/bin/python3 -c 'import sys; sys.exit(0 if float(sys.argv[2]) > float(sys.argv[1]) else 1)' "$first" "$second" ||
    fail "$ns: sim time did not go on ($first, then $second)"
  answer="$(timeout 30 rosservice call "$ns/unpause_physics" 2>&1)" || fail "$ns/unpause_physics: $answer"
  contains "$answer" 'success: True' || fail "$ns/unpause_physics: $answer"
  timeout 15 rostopic echo -n 1 "$ns/status" >/dev/null || fail "$ns: no ~status"
  echo "$ns steps and answers (sim time $first -> $second s)"
}

start_roscore

echo "== multi.launch"
for victim in b a; do
  survivor=$([ "$victim" = b ] && echo a || echo b)
  background roslaunch particle_sim multi.launch status_period:=0 >"$work/multi_$victim.log" 2>&1
  launch_pid=$background_pid
  wait_for_service "/sim_a/particle_sim/step" 60 || fail "sim_a did not start"
  wait_for_service "/sim_b/particle_sim/step" 60 || fail "sim_b did not start"
  victim_pid="$(pid_of "/sim_$victim/particle_sim")"
  kill -KILL "$victim_pid"
  echo "killed /sim_$victim/particle_sim (pid $victim_pid)"
  sleep 2
  kill -0 "$launch_pid" 2>/dev/null || fail "roslaunch ended when sim_$victim died: $(tail -n 5 "$work/multi_$victim.log")"
  answers "/sim_$survivor/particle_sim"
  kill -INT "$launch_pid"
  wait "$launch_pid" || true
done

echo "== two SimNodelets in one manager"
background "${nodelet_manager[@]}" __name:=manager >"$work/manager.log" 2>&1
manager_pid=$background_pid
load() {
  background rosrun nodelet nodelet load particle_sim/SimNodelet manager __name:="sim_$1" \
    _scene:="$PARTICLE_SIM_ROOT/config/scenes/rope.yaml" _frame_id:="sim_$1" _status_period:=0 \
    _publish_clock:="$([ "$1" = a ] && echo true || echo false)" >"$work/loader_$1.log" 2>&1
  eval "loader_$1=\$background_pid"
  wait_for_service "/sim_$1/step" 60 || fail "nodelet sim_$1 did not start"
  # The loader's bond with the manager is up (it publishes on /manager/bond): from now on its death unloads.
  local bond_info
  for _ in $(seq 150); do
    bond_info="$(timeout 5 rostopic info /manager/bond 2>/dev/null)" || true
    contains "$(sed -n '/Publishers:/,/Subscribers:/p' <<<"$bond_info")" "/sim_$1 " && return 0
    sleep 0.2
  done
  fail "the loader of sim_$1 formed no bond with the manager"
}
# True once nodelet sim_$1's services are gone from the master, within $2 seconds.
unloaded() {
  local deadline=$((SECONDS + $2)) services
  while [ "$SECONDS" -lt "$deadline" ]; do
    services="$(timeout 5 rosservice list 2>/dev/null)" || continue
    contains "$services" "^/sim_$1/step\$" || return 0
    sleep 0.2
  done
  return 1
}

load a
load b
for victim in b a; do
  survivor=$([ "$victim" = b ] && echo a || echo b)
  victim_loader="loader_$victim"
  kill -KILL "${!victim_loader}"
  echo "killed the loader of nodelet sim_$victim (pid ${!victim_loader})"
  # The manager unloads it when its bond times out: its services go.
  start=$SECONDS
  if unloaded "$victim" 60; then
    echo "the manager unloaded sim_$victim within $((SECONDS - start)) s"
  else
    # Debian's nodelet manager sometimes keeps a nodelet whose loader was killed: its bond never
    # breaks (3 runs in 12 on a loaded machine, 2026-11-26; gdb then showed every thread of the manager
    # idle and both simulators still stepping, so nothing of ours was stuck). That is the manager's
    # bond (bondcpp), not the simulator: the test unloads it as a user would, through the manager's
    # service, and checks the rest as before.
    echo "NOTE: the manager kept sim_$victim after its loader died (its bond did not break); unloading it by its service"
    timeout 30 rosrun nodelet nodelet unload "/sim_$victim" manager || fail "nodelet unload sim_$victim failed"
    unloaded "$victim" 30 || fail "the manager did not unload sim_$victim, even by its service"
  fi
  kill -0 "$manager_pid" 2>/dev/null || fail "the manager died when sim_$victim was unloaded"
  answers "/sim_$survivor"
  [ "$victim" = b ] && load b  # back, for the other way round
done
echo "crash_isolation: passed"
