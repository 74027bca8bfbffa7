#!/usr/bin/env bash
# The downstream-package example of the README (docs/examples/particle_sim_client): it builds with
# catkin_make in a temporary catkin workspace on top of particle_sim's devel space, and its C++ and
# Python clients spawn a rope in a live node and read it back from ~status.
# Run by scripts/test (see its header for the environment it gives).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
: "${PARTICLE_SIM_ROOT:?run me through scripts/test}"

mkdir -p "$work/ws/src"
cp -a "$PARTICLE_SIM_ROOT/docs/examples/particle_sim_client" "$work/ws/src/"

# Build it as the README says, in a shell where only particle_sim's devel space is sourced.
echo "== catkin_make in $work/ws"
(cd "$work/ws" && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -j2 >"$work/catkin_make.log" 2>&1) ||
  fail "catkin_make of the client example failed"
set +u
# shellcheck disable=SC1091
source "$work/ws/devel/setup.bash"
set -u
[ "$(rospack find particle_sim_client)" = "$work/ws/src/particle_sim_client" ] ||
  fail "rospack does not find particle_sim_client in the temporary workspace"
rospack find particle_sim >/dev/null || fail "particle_sim is no longer found on top of the client's workspace"

# A live node with an empty world, on a master of our own.
start_roscore
background rosrun particle_sim particle_sim_node _status_period:=0 >"$work/node.log" 2>&1
wait_for_service /particle_sim/spawn_rope 30 || fail "the node's services did not appear"

echo "== C++ client"
out="$(rosrun particle_sim_client spawn_rope_client _name:=cpp_rope 2>&1)" || { echo "$out"; fail "C++ client failed"; }
echo "$out"
grep -q "body 'cpp_rope' (rope): 10 particles, 1 pinned" <<<"$out" || fail "C++ client: rope not read back"

echo "== Python client"
out="$(rosrun particle_sim_client spawn_rope_client.py _name:=py_rope 2>&1)" || { echo "$out"; fail "Python client failed"; }
echo "$out"
grep -q "body 'py_rope' (rope): 10 particles, 1 pinned" <<<"$out" || fail "Python client: rope not read back"

# A second spawn under a taken name is refused, and the client says so with the node's reason.
if out="$(rosrun particle_sim_client spawn_rope_client.py _name:=py_rope 2>&1)"; then
  fail "spawning py_rope twice succeeded: $out"
fi
echo "$out"
grep -q "spawn_rope refused: .*py_rope" <<<"$out" || fail "the refusal does not name the body: $out"
echo "PASS"
