#!/usr/bin/env bash
# Huge pages for the heap (README "Huge pages", include/particle_sim/process/huge_pages.h), checked
# on particle_sim_run, which starts the way every program of the package does:
#  - when the kernel gives transparent huge pages only to memory that asks for them ("[madvise]"),
#    the running program (same process id) has glibc.malloc.hugetlb=1 in its GLIBC_TUNABLES and
#    huge pages in its memory (AnonHugePages of /proc/PID/smaps_rollup > 0);
#  - PARTICLE_SIM_HUGE_PAGES=0, or a GLIBC_TUNABLES that already sets glibc.malloc.hugetlb, leaves the
#    environment as the user gave it, and then the process has no huge page at all; a user's other
#    tunables are kept beside the one added;
#  - the physics does not depend on it: a run writes the same states, bit for bit, either way;
#  - with any other kernel mode the program never starts again (its environment is unchanged).
# In a sanitizer build the allocator is the sanitizer's, which glibc's tunable does not reach: there
# the environment checks run and the page counts are not read. The node (under a roscore of its own)
# starts the same way. Exits 0 when every check passes.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
use_devel_space
run="$PARTICLE_SIM_BUILD/devel/lib/particle_sim/particle_sim_run"
[ -x "$run" ] || fail "particle_sim_run not found at $run (build first, or set PARTICLE_SIM_BUILD)"

mode="$(sed -n 's/.*\[\(.*\)\].*/\1/p' /sys/kernel/mm/transparent_hugepage/enabled 2>/dev/null || true)"
glibc="$(getconf GNU_LIBC_VERSION | awk '{print $2}')"
advised=false
if [ "$mode" = madvise ] && [ "$(printf '%s\n2.35\n' "$glibc" | sort -V | head -n 1)" = 2.35 ]; then
  advised=true
fi
sanitized=false
if contains "$(ldd "$run")" libasan; then sanitized=true; fi
echo "kernel transparent huge pages: ${mode:-absent}; glibc $glibc; sanitizer build: $sanitized"

# A 128 x 128 cloth (about 60 MB of heap): enough 2 MiB stretches for the kernel to back.
cat > "$work/cloth.yaml" <<'EOF'
world:
  gravity: [0, 0, -9.81]
  dt: 0.001
  integrator: symplectic_euler
  ground: {enabled: false}
bodies:
  - name: cloth
    kind: cloth
    origin: [0, 0, 2]
    edge_u: [1, 0, 0]
    edge_v: [0, 1, 0]
    resolution: [128, 128]
    mass: 1.0
    stretch: {stiffness: 1000, damping: 0.01}
    shear: {stiffness: 1000, damping: 0.01}
    bend: {stiffness: 100, damping: 0.01}
    pins: [corner_00, corner_10]
EOF

# GLIBC_TUNABLES in the environment of process PID ("" when unset). glibc's parser cuts the string in
# place at each ':' when the program starts, so /proc/PID/environ shows the tunables after the first as
# entries of their own right after it: they are joined back here.
tunables_of() {
  tr '\0' '\n' < "/proc/$1/environ" | awk '
    /^GLIBC_TUNABLES=/ { value = substr($0, 16); inside = 1; next }
    inside && /^glibc\./ { value = value ":" $0; next }
    { inside = 0 }
    END { print value }'
}
# Huge pages of process PID [kB].
huge_kb() { awk '/^AnonHugePages:/ {print $2}' "/proc/$1/smaps_rollup"; }

# Reads process $1's GLIBC_TUNABLES into $tunables and its huge pages [kB] into $huge, then stops it.
read_and_stop() {
  running "$1" || fail "the program ($2) ended early"
  tunables="$(tunables_of "$1")"
  huge="$(huge_kb "$1")"
  kill -TERM "$1"  # a background job of a script ignores SIGINT
  wait "$1" 2>/dev/null || true
  echo "  $2: GLIBC_TUNABLES='$tunables', AnonHugePages ${huge} kB"
}

# particle_sim_run on the cloth with the environment given (env arguments), sampled after it has
# built the cloth and stepped for a while.
sample() {
  background env "$@" "$run" "$work/cloth.yaml" --duration 1000 > "$work/run.log" 2>&1
  sleep 3
  read_and_stop "$background_pid" "$*"
}

echo "default environment:"
sample -u GLIBC_TUNABLES -u PARTICLE_SIM_HUGE_PAGES
if [ "$advised" = true ]; then
  [ "$tunables" = glibc.malloc.hugetlb=1 ] || fail "GLIBC_TUNABLES is '$tunables', expected glibc.malloc.hugetlb=1"
  if [ "$sanitized" = false ] && ! [ "${huge:-0}" -gt 0 ]; then fail "no huge page in the process (AnonHugePages $huge kB)"; fi
else
  [ -z "$tunables" ] || fail "the kernel mode is '${mode:-absent}' (glibc $glibc), yet GLIBC_TUNABLES became '$tunables'"
fi

echo "opted out:"
sample -u GLIBC_TUNABLES PARTICLE_SIM_HUGE_PAGES=0
[ -z "$tunables" ] || fail "PARTICLE_SIM_HUGE_PAGES=0, yet GLIBC_TUNABLES became '$tunables'"
if [ "$mode" = madvise ] && [ "$sanitized" = false ] && [ "${huge:-0}" != 0 ]; then
  fail "PARTICLE_SIM_HUGE_PAGES=0 under '[madvise]', yet the process has $huge kB of huge pages"
fi

echo "the user's own hugetlb setting:"
sample -u PARTICLE_SIM_HUGE_PAGES GLIBC_TUNABLES=glibc.malloc.hugetlb=0
[ "$tunables" = glibc.malloc.hugetlb=0 ] || fail "GLIBC_TUNABLES glibc.malloc.hugetlb=0 became '$tunables'"
if [ "$mode" = madvise ] && [ "$sanitized" = false ] && [ "${huge:-0}" != 0 ]; then
  fail "glibc.malloc.hugetlb=0 under '[madvise]', yet the process has $huge kB of huge pages"
fi

echo "the user's other tunables:"
sample -u PARTICLE_SIM_HUGE_PAGES GLIBC_TUNABLES=glibc.malloc.tcache_count=0
expected=glibc.malloc.tcache_count=0
[ "$advised" = true ] && expected="$expected:glibc.malloc.hugetlb=1"
[ "$tunables" = "$expected" ] || fail "GLIBC_TUNABLES glibc.malloc.tcache_count=0 became '$tunables', expected '$expected'"

echo "the same states either way:"
for setting in 1 0; do
  PARTICLE_SIM_HUGE_PAGES=$setting env -u GLIBC_TUNABLES "$run" "$work/cloth.yaml" --duration 0.05 \
    --output "$work/states_$setting.csv" --every 10 > "$work/states_$setting.log" 2>&1 ||
    fail "particle_sim_run with PARTICLE_SIM_HUGE_PAGES=$setting failed"
done
if cmp -s "$work/states_1.csv" "$work/states_0.csv" && [ -s "$work/states_1.csv" ]; then
  echo "  $(wc -l < "$work/states_1.csv") rows, identical"
else
  fail "the states written with and without huge pages differ (or are empty)"
fi

echo "the node:"
start_roscore
background env -u GLIBC_TUNABLES -u PARTICLE_SIM_HUGE_PAGES "$node_binary" \
  _scene:="$PARTICLE_SIM_ROOT/config/scenes/cloth_hanging.yaml" > "$work/node.log" 2>&1
wait_for_service /particle_sim/reset 60 || fail "the node did not offer its services"
read_and_stop "$background_pid" "particle_sim_node"
if [ "$advised" = true ]; then
  [ "$tunables" = glibc.malloc.hugetlb=1 ] || fail "the node's GLIBC_TUNABLES is '$tunables', expected glibc.malloc.hugetlb=1"
  if [ "$sanitized" = false ] && ! [ "${huge:-0}" -gt 0 ]; then fail "no huge page in the node (AnonHugePages $huge kB)"; fi
else
  [ -z "$tunables" ] || fail "the kernel mode is '${mode:-absent}', yet the node's GLIBC_TUNABLES became '$tunables'"
fi

echo "huge_pages: passed"
