#!/usr/bin/env bash
# Shell test (issue 16, item 4): SIGINT or SIGTERM, sent to the node and to a recording rosbag at
# once (as Ctrl-C or `kill` of a launch would) while a long ~step runs: the node exits within 1 s
# with status 0, the ~step client gets the answer that the node is shutting down, and the bag is
# closed (no .active file) and readable, its /clock strictly increasing. Exits 0 on pass.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
use_devel_space

start_roscore
for signal in INT TERM; do
  echo "== SIG$signal"
  background "$node_binary" __name:=particle_sim _scene:="$PARTICLE_SIM_ROOT/config/scenes/demo.yaml" \
    _paused:=true _status_period:=0 >"$work/node_$signal.log" 2>&1
  node_pid=$background_pid
  wait_for_service /particle_sim/step 30 || fail "SIG$signal: the node's services did not appear"
  bag="$work/sig$signal.bag"
  background rosrun rosbag record -a -O "$bag" >"$work/record_$signal.log" 2>&1
  recorder_pid=$background_pid
  recording=false
  for _ in $(seq 150); do
    clock_info="$(timeout 5 rostopic info /clock 2>/dev/null)" || true
    if contains "$(sed -n '/Subscribers:/,$p' <<<"$clock_info")" '/record_'; then recording=true; break; fi
    sleep 0.2
  done
  [ "$recording" = true ] || fail "SIG$signal: rosbag does not record /clock"

  # A ~step of 100 000 demo steps (tens of seconds here); it runs once /clock moves.
  background timeout 120 rosservice call /particle_sim/step 'steps: 100000' >"$work/step_$signal.log" 2>&1
  step_pid=$background_pid
  timeout 30 rostopic echo -n 1 /clock >/dev/null || fail "SIG$signal: the ~step does not run"
  sleep 1
  kill -0 "$step_pid" 2>/dev/null || fail "SIG$signal: the ~step ended before the signal: $(cat "$work/step_$signal.log")"

  # The signal, to both at once; the node must be gone within 1 s (the bound issue 16 names).
  start_ns="$(date +%s%N)"
  kill -"$signal" "$node_pid" "$recorder_pid"
  while running "$node_pid" && [ $(($(date +%s%N) - start_ns)) -lt 5000000000 ]; do
    sleep 0.01
  done
  elapsed_ms=$((($(date +%s%N) - start_ns) / 1000000))
  code=0
  wait "$node_pid" || code=$?
  echo "node exited with status $code after $elapsed_ms ms"
  [ "$elapsed_ms" -le 1000 ] || fail "SIG$signal: the node took $elapsed_ms ms to exit (bound 1000 ms)"
  [ "$code" -eq 0 ] || fail "SIG$signal: the node exited with status $code, not 0"
  wait "$step_pid" || true
  step_answer="$(cat "$work/step_$signal.log")"
  contains "$step_answer" 'the node is shutting down' ||
    fail "SIG$signal: the ~step client did not get the shutdown answer: $step_answer"

  # The bag: closed and readable, /clock strictly increasing.
  for _ in $(seq 100); do kill -0 "$recorder_pid" 2>/dev/null || break; sleep 0.1; done
  wait "$recorder_pid" || true
  [ ! -e "$bag.active" ] || fail "SIG$signal: the bag was left open ($bag.active)"
  rosbag info "$bag" >"$work/info_$signal.txt" 2>&1 || fail "SIG$signal: rosbag info cannot read the bag"
  /usr/bin/python3 - "$bag" <<'PY' || fail "SIG$signal: the bag does not read back"
import sys
import rosbag
with rosbag.Bag(sys.argv[1]) as bag:
    clocks = [m.clock.to_sec() for _, m, _ in bag.read_messages(topics=['/clock'])]
    total = bag.get_message_count()
print('bag: %d messages, %d /clock from %.3f to %.3f s' % (total, len(clocks), clocks[0], clocks[-1]))
assert len(clocks) > 10, 'too few /clock messages'
assert all(b > a for a, b in zip(clocks, clocks[1:])), '/clock is not strictly increasing'
PY
done
echo "signal_exit: passed"
