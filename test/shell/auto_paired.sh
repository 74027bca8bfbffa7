#!/usr/bin/env bash
# Goal 8's side-by-side case (README "Performance at robot scale"): `particle_sim_perf --only auto`
# times hang64 under `auto` and under every fixed choice of the same dt in rounds, one body after the
# other, and writes each body's row and a row of the rounds' ratios (auto over the fastest fixed
# choice of the round); scripts/performance_report.py judges goal 8 on those ratios. A quick run
# here: the rows are there at both dts; the ratios are consistent with the bodies' times (a round's
# fastest fixed time lies between the least of the fixed bodies' fastest rounds and the least of
# their slowest, so every ratio lies between auto's fastest round over the latter and auto's slowest
# over the former); each round had one fastest fixed choice; then the report, on the committed CSV
# with these rows added, takes goal 8's figures from them.
# Run by scripts/test (see its header for the environment it gives).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
: "${PARTICLE_SIM_ROOT:?run me through scripts/test}"

run_quick_case particle_sim_perf auto "$work/auto.csv"

/usr/bin/python3 - "$work/auto.csv" <<'PY'
import csv, math, re, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r['case'] == 'auto_paired']
for suffix in ('', ' dt 1/1000'):
    at = [r for r in rows if ('dt 1/1000' in r['variant']) == bool(suffix)]  # that dt's bodies and ratio
    names = [r['variant'] for r in at]
    assert 'auto' + suffix in names and 'ratio' + suffix in names, 'no auto or ratio row%s in %s' % (suffix, names)
    times = {r['variant']: [float(r[k]) for k in ('ms_min', 'ms_median', 'ms_max')] for r in at}
    for name, (low, mid, high) in times.items():
        assert all(math.isfinite(v) and v > 0 for v in (low, mid, high)) and low <= mid <= high, (name, low, mid, high)
    auto, ratio = times.pop('auto' + suffix), times.pop('ratio' + suffix)
    assert len(times) >= 2, 'fewer than two fixed choices beside auto%s: %s' % (suffix, sorted(times))
    fastest_low = min(t[0] for t in times.values())   # no round's fastest fixed time is below this
    fastest_high = min(t[2] for t in times.values())  # nor above this
    low, high = auto[0] / fastest_high, auto[2] / fastest_low
    # The CSV keeps six digits: a round's ratio and the times it came from agree to that.
    assert low * (1 - 1e-5) <= ratio[0] and ratio[2] <= high * (1 + 1e-5), (suffix, ratio, low, high)
    rounds = int(re.search(r'\((\d+) rounds', next(r for r in at if r['variant'] == 'ratio' + suffix)['detail']).group(1))
    wins = [int(re.search(r'fastest fixed choice in (\d+) of', r['detail']).group(1))
            for r in at if r['variant'] not in ('auto' + suffix, 'ratio' + suffix)]
    assert sum(wins) == rounds, 'the fastest fixed choice of %d rounds counted %s times%s' % (rounds, wins, suffix)
    print('auto%s: ratio %.2f (%.2f-%.2f), within %.2f-%.2f' % (suffix, ratio[1], ratio[0], ratio[2], low, high))
PY

# The report on the committed run with these rows in place of its own: goal 8's figures come from the rounds.
report_with_rows auto_paired "$work/auto.csv"
goal8="$(grep '^| 8 |' "$work/report.md")"
contains "$goal8" "dt 1/60: [0-9.]+× side by side \(median of 3 rounds' ratios" ||
  fail "goal 8 does not take the rounds at dt 1/60: $goal8"
contains "$goal8" "dt 1/1000: [0-9.]+× side by side \(median of 3 rounds' ratios" ||
  fail "goal 8 does not take the rounds at dt 1/1000: $goal8"
grep -q '^| ratio dt 1/1000 |' "$work/report.md" || fail "no side-by-side table of auto in the report"
echo "PASS"
