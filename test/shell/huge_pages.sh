#!/usr/bin/env bash
# Huge pages for the heap (README "Huge pages", include/particle_sim/process/huge_pages.h), checked
# on particle_sim_run, which starts the way every program of the package does:
#  - when the kernel gives transparent huge pages only to memory that asks for them ("[madvise]"),
#    the running program (same process id) has glibc.malloc.hugetlb=1 in its GLIBC_TUNABLES and
#    its heap asked for huge pages (mappings with the flag hg in /proc/PID/smaps; how many huge
#    pages the kernel then gave, AnonHugePages, is printed: that is the kernel's to decide);
#  - PARTICLE_SIM_HUGE_PAGES=0, or a GLIBC_TUNABLES that already sets glibc.malloc.hugetlb, leaves the
#    environment as the user gave it, and then no mapping asks and the process has no huge page at
#    all; a user's other tunables are kept beside the one added;
#  - the process keeps its name (not "exe");
#  - the physics does not depend on it: a run writes the same states, bit for bit, either way;
#  - with any other kernel mode the program never starts again (its environment is unchanged).
# In a sanitizer build the allocator is the sanitizer's, which glibc's tunable does not reach: there
# the environment checks run and the heap's request is not checked. The node (under a roscore of its own)
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

# A 128 x 128 cloth (about 150 MB of heap): many 2 MiB stretches for the kernel to back.
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
# Huge pages of process PID [kB] (the kernel's to give: reported, not checked).
huge_kb() { awk '/^AnonHugePages:/ {sum += $2} END {print sum + 0}' "/proc/$1/smaps" 2>/dev/null || echo "?"; }
# Mappings of process PID that asked for huge pages (the flag hg of madvise(MADV_HUGEPAGE)).
advised_mappings() { grep -c '^VmFlags:.* hg' "/proc/$1/smaps" 2>/dev/null || true; }

# Reads process $1's GLIBC_TUNABLES into $tunables, how many of its mappings asked for huge pages into
# $asked and its huge pages [kB] into $huge, then stops it.
read_and_stop() {
  running "$1" || fail "the program ($2) ended early"
  tunables="$(tunables_of "$1")"
  asked="$(advised_mappings "$1")"
  name="$(cat "/proc/$1/comm")"
  huge="$(huge_kb "$1")"
  kill -TERM "$1"  # a background job of a script ignores SIGINT
  wait "$1" 2>/dev/null || true
  echo "  $2: GLIBC_TUNABLES='$tunables', $asked mappings asked for huge pages, AnonHugePages ${huge} kB"
}

# particle_sim_run on the cloth with the environment given (env arguments), sampled after it has
# built the cloth and stepped for a while.
sample() {
  background env "$@" "$run" "$work/cloth.yaml" --duration 1000 > "$work/run.log" 2>&1
  sleep 3
  read_and_stop "$background_pid" "$*"
}

# The last sample ($1 names it) started with the tunable where the kernel mode asks for it, and
# its heap asked for huge pages; under any other mode, it did not start again.
expect_restarted() {
  if [ "$advised" = true ]; then
    [ "$tunables" = glibc.malloc.hugetlb=1 ] || fail "$1: GLIBC_TUNABLES is '$tunables', expected glibc.malloc.hugetlb=1"
    if [ "$sanitized" = false ] && ! [ "${asked:-0}" -gt 0 ]; then fail "$1: no mapping asked for huge pages"; fi
  else
    [ -z "$tunables" ] || fail "$1: the kernel mode is '${mode:-absent}' (glibc $glibc), yet GLIBC_TUNABLES became '$tunables'"
  fi
}

# The last sample ($1 says why it must not ask) kept GLIBC_TUNABLES as $2, no mapping asked for huge
# pages, and under '[madvise]' it has none.
expect_not_asked() {
  [ "$tunables" = "$2" ] || fail "$1, yet GLIBC_TUNABLES became '$tunables'"
  if [ "${asked:-0}" != 0 ]; then fail "$1, yet $asked mappings asked for huge pages"; fi
  if [ "$mode" = madvise ] && [ "$huge" != 0 ]; then fail "$1 under '[madvise]', yet the process has $huge kB of huge pages"; fi
}

echo "default environment:"
sample -u GLIBC_TUNABLES -u PARTICLE_SIM_HUGE_PAGES
[ "$name" = "$(basename "$run" | cut -c1-15)" ] || fail "the process is named '$name' (the kernel names it after the path started)"
expect_restarted particle_sim_run

echo "opted out:"
sample -u GLIBC_TUNABLES PARTICLE_SIM_HUGE_PAGES=0
expect_not_asked "PARTICLE_SIM_HUGE_PAGES=0" ""

echo "the user's own hugetlb setting:"
sample -u PARTICLE_SIM_HUGE_PAGES GLIBC_TUNABLES=glibc.malloc.hugetlb=0
expect_not_asked "GLIBC_TUNABLES glibc.malloc.hugetlb=0" glibc.malloc.hugetlb=0

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
expect_restarted particle_sim_node

echo "huge_pages: passed"
