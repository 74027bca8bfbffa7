#!/usr/bin/env bash
# Goal 2's side-by-side case (README "Performance at robot scale"): `particle_sim_perf --only sizes`
# times each of goal 2's ratios with both sizes in one process, in rounds, one size after the other,
# and writes each size's row and a row of the rounds' ratios (the larger size's time over the
# smaller's); scripts/performance_report.py judges goal 2 on those ratios. A quick run here (cloths of
# 16² and 32², ropes of 100 and 1000 segments): the rows are there for every ratio; the ratios are
# consistent with the sizes' times (a round's ratio lies between the larger size's fastest round over
# the smaller's slowest and its slowest over the smaller's fastest); the multigrid's iterations hardly
# grow where block Jacobi's do; then the report, on the committed CSV with these rows added, takes the
# rope's ratio from the rounds, and the cloth's from its own rows, since a quick run's cloths are not
# the goal's 64² and 128².
# Run by scripts/test (see its header for the environment it gives).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
: "${PARTICLE_SIM_ROOT:?run me through scripts/test}"

run_quick_case particle_sim_perf sizes "$work/sizes.csv"

/usr/bin/python3 - "$work/sizes.csv" <<'PY'
import csv, math, re, sys
rows = {r['variant']: r for r in csv.DictReader(open(sys.argv[1])) if r['case'] == 'size_paired'}
iterations = {}
for name, small, large in (('cloth implicit_euler cg', 16, 32), ('cloth implicit_euler multigrid', 16, 32),
                           ('rope implicit_euler direct', 100, 1000)):
    wanted = ['%s %d' % (name, small), '%s %d' % (name, large), 'ratio %s %d/%d' % (name, large, small)]
    missing = [w for w in wanted if w not in rows]
    assert not missing, 'no %s in %s' % (missing, sorted(rows))
    times = [[float(rows[w][k]) for k in ('ms_min', 'ms_median', 'ms_max')] for w in wanted]
    for w, (low, mid, high) in zip(wanted, times):
        assert all(math.isfinite(v) and v > 0 for v in (low, mid, high)) and low <= mid <= high, (w, low, mid, high)
    (s_low, _, s_high), (l_low, _, l_high), ratio = times
    # The CSV keeps six digits: a round's ratio and the times it came from agree to that.
    assert l_low / s_high * (1 - 1e-5) <= ratio[0] and ratio[2] <= l_high / s_low * (1 + 1e-5), (name, ratio)
    rounds = int(re.search(r'\((\d+) rounds', rows[wanted[2]]['detail']).group(1))
    assert rounds == 3, rows[wanted[2]]['detail']
    iterations[name] = [float(rows[w]['cg_iterations']) for w in wanted[:2]]
    print('%s: ratio %.2f (%.2f-%.2f), iterations %s' % (name, ratio[1], ratio[0], ratio[2], iterations[name]))
cg, mg = iterations['cloth implicit_euler cg'], iterations['cloth implicit_euler multigrid']
assert cg[1] > 1.5 * cg[0] and 0 < mg[1] < 1.5 * mg[0], ('block Jacobi against the multigrid', cg, mg)
PY

# The report on the committed run with these rows in place of its own.
report_with_rows size_paired "$work/sizes.csv"
rope="$(grep '^| 2 | rope of 1000 segments against 100 |' "$work/report.md")"
contains "$rope" "[0-9.]+× \(direct\) side by side \(median of 3 rounds' ratios" ||
  fail "goal 2 does not take the rope's ratio from the rounds: $rope"
cloth="$(grep '^| 2 | implicit cloth 128² against 64²' "$work/report.md")"
contains "$cloth" "multigrid: [0-9.]+× \(iterations" || fail "goal 2's cloth is not from the cloth rows: $cloth"
if contains "$cloth" "side by side"; then fail "goal 2 takes a quick run's 32² against 16² for 128² against 64²: $cloth"; fi
grep -q '^| ratio rope implicit_euler direct 1000/100 |' "$work/report.md" || fail "no side-by-side table of goal 2"
echo "PASS"
