#!/usr/bin/env bash
# particle_sim_run through its command line, as a user runs it:
#  - a dt or duration that gives zero steps, or more steps than fit in 64 bits, is refused (exit 2,
#    message naming --duration, dt and the step count) instead of printing "steps 0" and exiting 0;
#  - --integrator NAME applies to every spring body: rope, spring network, grid cloth, mesh cloth
#    and jelly (it used to reach ropes and networks only);
#  - the solver summary names the implicit method that ran (bdf2 too), and for an `auto` body each
#    method auto ran with its step count (auto bodies used to be left out);
#  - a world's integrator reaches every spring body that sets none.
# Exits 0 when every check passes, 1 with a message per failed check otherwise.
#
# The binary is $PARTICLE_SIM_RUN, else $PARTICLE_SIM_BUILD/devel/lib/particle_sim/particle_sim_run
# (PARTICLE_SIM_BUILD defaults to the workspace scripts/common.sh uses, ../<checkout>_ws).
set -uo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${PARTICLE_SIM_BUILD:-$(dirname "$root")/$(basename "$root")_ws}"
run="${PARTICLE_SIM_RUN:-$build/devel/lib/particle_sim/particle_sim_run}"
if [ ! -x "$run" ]; then
  echo "FAIL: particle_sim_run not found at $run (build first, or set PARTICLE_SIM_BUILD)" >&2
  exit 1
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
failures=0
fail() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

# Runs particle_sim_run with "$@"; sets $status, $out (stdout) and $err (stderr).
invoke() {
  "$run" "$@" >"$work/out" 2>"$work/err"
  status=$?
  out="$(cat "$work/out")"
  err="$(cat "$work/err")"
}

# expect_refusal DESCRIPTION TEXT_IN_STDERR ARGS...: exit status 2, nothing stepped, the message.
expect_refusal() {
  local what="$1" message="$2"
  shift 2
  invoke "$@"
  [ "$status" -eq 2 ] || fail "$what: exit status $status, expected 2 (stdout: $out)"
  case "$out" in *steps*) fail "$what: it stepped anyway: $out" ;; esac
  case "$err" in *"$message"*) ;; *) fail "$what: stderr does not say '$message': $err" ;; esac
}

# expect_every_spring_body WHAT TEXT: stdout says "body 'NAME' TEXT" for each spring body.
expect_every_spring_body() {
  local what="$1" text="$2" body
  for body in rope network grid mesh jelly; do
    case "$out" in
      *"body '$body' $text"*) ;;
      *) fail "$what did not reach body '$body':"$'\n'"$out" ;;
    esac
  done
}

# A scene with one body of each spring kind, each asking for symplectic Euler itself.
cat >"$work/bodies.yaml" <<'EOF'
world:
  dt: 0.001
  integrator: symplectic_euler
bodies:
  - {name: rope, kind: rope, particles: 5, integrator: symplectic_euler}
  - name: network
    kind: spring_network
    particles: [{position: [0, 0, 1]}, {position: [1, 0, 1]}]
    springs: [{particles: [0, 1], stiffness: 50}]
    integrator: symplectic_euler
  - {name: grid, kind: cloth, resolution: [4, 4], integrator: symplectic_euler}
  - name: mesh
    kind: cloth
    vertices: [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
    triangles: [[0, 1, 2], [0, 2, 3]]
    integrator: symplectic_euler
  - {name: jelly, kind: jelly, resolution: [3, 3, 3], integrator: symplectic_euler}
  - {name: spray, kind: emitter, type: fountain, rate: 10}
EOF

# 1. Step counts: zero steps, and more than 2^64 - 1 steps, are refused.
expect_refusal "--dt 1e-300" "more than fit in 64 bits" "$work/bodies.yaml" --duration 1 --dt 1e-300
expect_refusal "--duration 1e300" "more than fit in 64 bits" "$work/bodies.yaml" --duration 1e300
expect_refusal "--duration 1e-300" "gives 0 steps: at least 1 is needed" "$work/bodies.yaml" --duration 1e-300
expect_refusal "--duration 1e300 (figures)" "--duration 1e+300 s with dt = 0.001 s gives 1e+303 steps" \
  "$work/bodies.yaml" --duration 1e300
# A duration of exactly one step runs that step and exits 0.
invoke "$work/bodies.yaml" --duration 0.001
[ "$status" -eq 0 ] || fail "--duration 0.001 (one step): exit status $status: $err"
case "$out" in "steps 1,"*) ;; *) fail "--duration 0.001 should run exactly 1 step: $out" ;; esac

# 2. --integrator reaches every spring body (implicit_euler bodies print their CG figures).
invoke "$work/bodies.yaml" --duration 0.01 --integrator implicit_euler
[ "$status" -eq 0 ] || fail "--integrator implicit_euler: exit status $status: $err"
expect_every_spring_body "--integrator implicit_euler" "implicit_euler: CG iterations"
# And with auto, every spring body says what auto picked.
invoke "$work/bodies.yaml" --duration 0.01 --integrator auto
[ "$status" -eq 0 ] || fail "--integrator auto: exit status $status: $err"
expect_every_spring_body "--integrator auto" "auto: "

# 3. The summary names the method that ran: bdf2 bodies say bdf2.
invoke "$work/bodies.yaml" --duration 0.01 --integrator bdf2
[ "$status" -eq 0 ] || fail "--integrator bdf2: exit status $status: $err"
expect_every_spring_body "--integrator bdf2" "bdf2: CG iterations"
# An auto body reports each method auto ran, with its steps: at dt = 0.02 s the two-particle
# network (omega_max = 31.6 1/s) needs one Verlet substep, the jelly more substeps than its
# implicit step is estimated to cost.
invoke "$work/bodies.yaml" --duration 0.1 --dt 0.02 --integrator auto
[ "$status" -eq 0 ] || fail "--integrator auto --dt 0.02: exit status $status: $err"
case "$out" in
  *"body 'network' auto ran verlet for 5 of 5 steps"*) ;;
  *) fail "auto: the network's verlet steps are not reported:"$'\n'"$out" ;;
esac
case "$out" in
  *"body 'jelly' auto ran implicit_euler for 5 of 5 steps: CG iterations"*) ;;
  *) fail "auto: the jelly's implicit_euler steps and CG figures are not reported:"$'\n'"$out" ;;
esac

# 4. The world's integrator reaches every spring body that sets none.
sed -e 's/integrator: symplectic_euler/integrator: bdf2/' -e 's/, integrator: bdf2}/}/' \
  -e '/^    integrator: bdf2$/d' "$work/bodies.yaml" >"$work/world_default.yaml"
grep -c "integrator" "$work/world_default.yaml" | grep -qx 1 || fail "world_default.yaml should name only the world's integrator"
invoke "$work/world_default.yaml" --duration 0.01
[ "$status" -eq 0 ] || fail "world default bdf2: exit status $status: $err"
expect_every_spring_body "the world's bdf2" "bdf2: CG iterations"

# 5. --pin-forces: the rope hangs from its pinned ends; the pins hold its weight, so the vertical force
# is positive at every row written, and the file has its header.
cat >"$work/hanging.yaml" <<'EOF'
world: {dt: 0.001, ground: {enabled: false}}
bodies:
  - {name: rope, kind: rope, particles: 11, start: [0, 0, 1], end: [1, 0, 1], mass: 0.5, pins: [0, -1]}
  - {name: spray, kind: emitter, type: fountain, rate: 10}
EOF
invoke "$work/hanging.yaml" --duration 0.05 --every 10 --pin-forces "$work/forces.csv"
[ "$status" -eq 0 ] || fail "--pin-forces: exit status $status: $err"
header="$(head -n 1 "$work/forces.csv")"
[ "$header" = "time,body,pinned,fx,fy,fz,tx,ty,tz" ] || fail "--pin-forces: header $header"
rows="$(tail -n +2 "$work/forces.csv")"
[ "$(wc -l <<<"$rows")" -eq 5 ] || fail "--pin-forces: expected 5 rows (steps 10..50), got:"$'\n'"$rows"
awk -F, '$2 != "rope" || $3 != 2 || !($6 > 0) { bad = 1 } END { exit bad }' <<<"$rows" ||
  fail "--pin-forces: every row is the rope's 2 pins holding it up:"$'\n'"$rows"
expect_refusal "--pin-forces without a file" "--pin-forces needs a file name" "$work/hanging.yaml" --duration 0.01 \
  --pin-forces

if [ "$failures" -ne 0 ]; then
  echo "particle_sim_run_cli: $failures check(s) failed" >&2
  exit 1
fi
echo "particle_sim_run_cli: all checks passed"
