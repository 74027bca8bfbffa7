#!/usr/bin/env bash
# scripts/balance_shards.py, which CI's run under the sanitizers shards by: every listed test lands in
# exactly one shard, tests missing from the earlier run count that run's median, the shards' times
# are as close as the longest-first rule makes them, and an empty shard runs nothing.
# Run by scripts/test (see its header for the environment it gives).
set -euo pipefail
: "${PARTICLE_SIM_ROOT:?run me through scripts/test}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# An earlier run's results: times 8, 5, 4, 3, 2 and 1 s; "New.test" and the parameterised test
# were not in it.
cat > "$work/gtest-binary-0.xml" <<'XML'
<testsuites>
  <testsuite name="A"><testcase classname="A" name="eight" time="8"/><testcase classname="A" name="one" time="1"/></testsuite>
  <testsuite name="B"><testcase classname="B" name="five" time="5"/><testcase classname="B" name="two" time="2"/></testsuite>
</testsuites>
XML
cat > "$work/gtest-binary-1.xml" <<'XML'
<testsuites><testsuite name="C"><testcase classname="C" name="four" time="4"/><testcase classname="C" name="three" time="3"/></testsuite></testsuites>
XML
# What --gtest_list_tests prints (comments after '#' for parameterised tests).
listing='A.
  eight
  one
B.
  five
  two
C.
  four
  three
New.
  test
Values/P.  # TypeParam = int
  case/0  # GetParam() = 1
'
balance() { printf '%s' "$listing" | /usr/bin/python3 "$PARTICLE_SIM_ROOT/scripts/balance_shards.py" "$work" "$1"; }

# Two shards: 8 → 0; 5 → 1; 4 → 1 (9); 3.5 (New, the median of 1..8) → 0 (11.5); 3.5 (P) → 1 (12.5);
# 3 → 0 (14.5); 2 → 1 (14.5); 1 → 0 (15.5).
mapfile -t shards < <(balance 2)
expected=("A.eight:A.one:C.three:New.test" "B.five:B.two:C.four:Values/P.case/0")
for k in 0 1; do
  if [ "${shards[$k]}" != "${expected[$k]}" ]; then
    echo "FAIL: shard $k is '${shards[$k]}', expected '${expected[$k]}'" >&2
    exit 1
  fi
done
# More shards than tests: each test once, the rest run nothing.
mapfile -t shards < <(balance 10)
[ "${#shards[@]}" -eq 10 ] || { echo "FAIL: ${#shards[@]} lines for 10 shards" >&2; exit 1; }
all="$(printf '%s\n' "${shards[@]}" | grep -v '^-\*$' | tr ':' '\n' | sort)"
[ "$(wc -l <<< "$all")" -eq 8 ] && [ "$(sort -u <<< "$all" | wc -l)" -eq 8 ] ||
  { echo "FAIL: 8 tests expected once each, got: $all" >&2; exit 1; }
[ "$(printf '%s\n' "${shards[@]}" | grep -c '^-\*$')" -eq 2 ] || { echo "FAIL: 2 empty shards expected" >&2; exit 1; }
echo "balance_shards: 2 and 10 shards as expected"
