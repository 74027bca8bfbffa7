#!/usr/bin/env bash
# README "Recording and replaying": record.launch with a duration ends by itself (the recorder is
# required, so the simulator stops with it) and writes a bag of that length; replay.launch on a
# machine without a display starts no rviz and ends when the bag is played.
# Run by scripts/test (see its header for the environment it gives).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"

export ROS_HOME="$work/ros_home"
unset DISPLAY

echo "== record.launch duration:=3 (must end by itself)"
port="$(free_port)"
export ROS_MASTER_URI="http://127.0.0.1:$port"
code=0
timeout 120 roslaunch -p "$port" particle_sim record.launch scene:=rope bag:="$work/rope.bag" duration:=3 \
  >"$work/record.log" 2>&1 || code=$?
[ "$code" -ne 124 ] || fail "record.launch duration:=3 still ran after 120 s"
[ "$code" -eq 0 ] || fail "record.launch exited with $code"
grep -q "REQUIRED process \[record-[0-9]*\] has died" "$work/record.log" ||
  fail "record.launch did not end because the recorder finished"
grep -q "process has finished cleanly" "$work/record.log" || fail "the recorder did not finish cleanly"
info="$(rosbag info --yaml "$work/rope.bag")"
duration="$(sed -n 's/^duration: //p' <<<"$info")"
messages="$(sed -n 's/^messages: //p' <<<"$info")"
echo "bag: duration $duration s, $messages messages"
/usr/bin/python3 -c "import sys; d = float(sys.argv[1]); sys.exit(0 if 2.5 <= d <= 3.5 else 1)" "$duration" ||
  fail "the bag spans $duration s of sim time, expected about 3"
[ "$messages" -gt 10 ] || fail "the bag holds only $messages messages"
grep -q "/particle_sim/markers" <<<"$info" || fail "the bag has no markers"

echo "== replay.launch without a display: no rviz, ends after the bag"
nodes="$(roslaunch --nodes particle_sim replay.launch bag:="$work/rope.bag")"
[ "$nodes" = "/play" ] || fail "replay.launch without DISPLAY would start: $nodes"
nodes="$(DISPLAY=:0 roslaunch --nodes particle_sim replay.launch bag:="$work/rope.bag" | sort | tr '\n' ' ')"
[ "$nodes" = "/play /rviz " ] || fail "replay.launch with a DISPLAY would start: $nodes (expected rviz too)"
nodes="$(DISPLAY=:0 roslaunch --nodes particle_sim replay.launch bag:="$work/rope.bag" rviz:=false)"
[ "$nodes" = "/play" ] || fail "replay.launch rviz:=false would start: $nodes"
port="$(free_port)"
export ROS_MASTER_URI="http://127.0.0.1:$port"
code=0
timeout 60 roslaunch -p "$port" particle_sim replay.launch bag:="$work/rope.bag" >"$work/replay.log" 2>&1 || code=$?
[ "$code" -eq 0 ] || fail "replay.launch exited with $code"
echo "PASS"
