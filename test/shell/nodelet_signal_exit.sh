#!/usr/bin/env bash
# Shell test (issue 16, item 4): SIGINT or SIGTERM to a nodelet manager that holds the simulator
# (launch/nodelet.launch's arrangement: a manager, and a loader process naming the nodelet) while a
# long ~step runs: the manager exits within 1 s (the simulator's loop and ~step threads end with
# ROS; they do not hold the process), and the ~step client is not left waiting. The manager is
# nodelet's own program: on SIGINT roscpp shuts down and it exits with status 0; SIGTERM keeps its
# default action (status 143 at once), since a nodelet must not take over its manager's signals.
# Either way the client's call ends (with the manager's connection closed). Exits 0 on pass.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
use_devel_space

start_roscore
for signal in INT TERM; do
  echo "== SIG$signal"
  background "${nodelet_manager[@]}" __name:=sim_manager >"$work/manager_$signal.log" 2>&1
  manager_pid=$background_pid
  background rosrun nodelet nodelet load particle_sim/SimNodelet sim_manager __name:=particle_sim \
    _scene:="$PARTICLE_SIM_ROOT/config/scenes/demo.yaml" _paused:=true _status_period:=0 \
    >"$work/loader_$signal.log" 2>&1
  loader_pid=$background_pid
  wait_for_service /particle_sim/step 60 || fail "SIG$signal: the nodelet's services did not appear"

  # A ~step of 100 000 demo steps (tens of seconds here); it runs once /clock moves.
  background timeout 120 rosservice call /particle_sim/step 'steps: 100000' >"$work/step_$signal.log" 2>&1
  step_pid=$background_pid
  timeout 30 rostopic echo -n 1 /clock >/dev/null || fail "SIG$signal: the ~step does not run"
  sleep 1
  kill -0 "$step_pid" 2>/dev/null || fail "SIG$signal: the ~step ended before the signal: $(cat "$work/step_$signal.log")"

  # The signal to the manager's process (rosrun execs it); it must be gone within 1 s.
  start_ns="$(date +%s%N)"
  kill -"$signal" "$manager_pid"
  while running "$manager_pid" && [ $(($(date +%s%N) - start_ns)) -lt 5000000000 ]; do
    sleep 0.01
  done
  elapsed_ms=$((($(date +%s%N) - start_ns) / 1000000))
  code=0
  if running "$manager_pid"; then
    kill -KILL "$manager_pid" 2>/dev/null || true
    fail "SIG$signal: the manager still ran 5 s after the signal; its log: $(tail -5 "$work/manager_$signal.log")"
  fi
  wait "$manager_pid" || code=$?
  echo "manager exited with status $code after $elapsed_ms ms"
  [ "$elapsed_ms" -le 1000 ] || fail "SIG$signal: the manager took $elapsed_ms ms to exit (bound 1000 ms)"
  expected_code=0
  [ "$signal" = TERM ] && expected_code=143
  [ "$code" -eq "$expected_code" ] ||
    fail "SIG$signal: the manager exited with status $code, not $expected_code: $(tail -5 "$work/manager_$signal.log")"
  # The ~step client is not left waiting for an answer that cannot come.
  for _ in $(seq 50); do kill -0 "$step_pid" 2>/dev/null || break; sleep 0.1; done
  kill -0 "$step_pid" 2>/dev/null && fail "SIG$signal: the ~step client still waits 5 s after the manager exited"
  wait "$step_pid" || true
  echo "~step client: $(cat "$work/step_$signal.log")"
  kill "$loader_pid" 2>/dev/null || true
  wait "$loader_pid" 2>/dev/null || true
done
echo "nodelet_signal_exit: passed"
