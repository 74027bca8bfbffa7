#!/usr/bin/env bash
# README "Install space": `cmake --build <ws>/build --target install` fills <ws>/install, and a shell
# that sources only <ws>/install/setup.bash finds everything there (rospack, rosrun, roslaunch, the
# generated Python messages, particle_sim_bench's scenes) and runs the node from it.
# Run by scripts/test (see its header for the environment it gives).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
: "${PARTICLE_SIM_BUILD:?run me through scripts/test}"
install="$PARTICLE_SIM_BUILD/install"

echo "== cmake --build $PARTICLE_SIM_BUILD/build --target install"
cmake --build "$PARTICLE_SIM_BUILD/build" --target install -- -j2 >/dev/null
[ -f "$install/setup.bash" ] || fail "no $install/setup.bash after the install"

# Everything below runs in a clean environment with only the install space sourced, from a folder
# outside the source tree.
cat >"$work/check.bash" <<'CHECK'
set -euo pipefail
source "$(dirname "$0")/test/shell/helpers.bash"
set +u; source "$INSTALL/setup.bash"; set -u
cd "$WORK"
[ "$(rospack find particle_sim)" = "$INSTALL/share/particle_sim" ] || fail "rospack find: $(rospack find particle_sim)"
for executable in particle_sim_node particle_sim_run particle_sim_bench; do
  path="$(rosrun --prefix 'echo' particle_sim "$executable")"
  [ "$path" = "$INSTALL/lib/particle_sim/$executable" ] || fail "rosrun runs $path for $executable"
  rosrun particle_sim "$executable" --help | grep -qi usage || fail "rosrun particle_sim $executable --help"
done
path="$(rosrun --prefix 'echo' particle_sim pick_and_place.py)"  # the demo's node, started by its launch file
[ "$path" = "$INSTALL/lib/particle_sim/pick_and_place.py" ] || fail "rosrun runs $path for pick_and_place.py"
[ "$(roslaunch --files particle_sim particle_sim.launch | head -1)" = "$INSTALL/share/particle_sim/launch/particle_sim.launch" ] ||
  fail "roslaunch does not take the installed launch file"
/usr/bin/python3 -c 'import particle_sim.msg, particle_sim.srv, particle_sim.cfg, sys; sys.exit(0 if particle_sim.msg.__file__.startswith(sys.argv[1]) else 1)' "$INSTALL" ||
  fail "the Python messages do not come from the install space"
out="$(rosrun particle_sim particle_sim_bench --quick --only oscillator --no-stability --out "$WORK/bench" 2>&1)" ||
  { echo "$out"; fail "particle_sim_bench from the install space"; }
grep -q "scenes from $INSTALL/share/particle_sim/config/scenes/bench" <<<"$out" || fail "bench scenes not from the install space: $out"
[ -s "$WORK/bench/work_precision.csv" ] || fail "particle_sim_bench wrote no CSV"

# The installed node with an installed scene answers a service.
start_roscore
background roslaunch particle_sim particle_sim.launch scene:=rope status_period:=0 >"$WORK/launch.log" 2>&1
wait_for_service /particle_sim/pause_physics 30 || fail "the installed node's services did not appear"
rosservice call /particle_sim/pause_physics | grep -q "success: True" || fail "pause_physics on the installed node"
echo "installed node answers"
CHECK
# The helpers (and the port picker they run) in their places relative to each other, outside the
# source tree.
mkdir -p "$work/test/shell" "$work/scripts"
cp "$(dirname "${BASH_SOURCE[0]}")/helpers.bash" "$work/test/shell/"
cp "$(dirname "${BASH_SOURCE[0]}")/../../scripts/free_port.py" "$work/scripts/"
env -i HOME="$HOME" PATH=/usr/bin:/bin INSTALL="$install" WORK="$work" /bin/bash "$work/check.bash" ||
  fail "a check in the shell with only the install space sourced failed"
echo "PASS"
