#!/usr/bin/env bash
# Goal 7's side-by-side case (README "Bullet beside it"): `particle_sim_bullet_peer --only paired`
# times hang64 in Bullet and in particle_sim in alternating rounds and writes, per tolerance, each
# engine's row and a row of the rounds' ratios; scripts/performance_report.py judges goal 7's same-dt
# half on those ratios. A quick run here: the rows are there, each engine's solver ran, and the
# ratios are consistent with the two engines' times (every round's ratio lies between the slowest
# Bullet round over the fastest particle_sim round and the other way round); then the report, on
# the committed CSV with these rows added, takes goal 7's same-dt figure from them.
# Run by scripts/test (see its header for the environment it gives); needs Debian's libbullet-dev,
# which scripts/common.sh installs.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
: "${PARTICLE_SIM_ROOT:?run me through scripts/test}"

[ -f /usr/include/bullet/btBulletDynamicsCommon.h ] || fail "libbullet-dev is missing (scripts/common.sh installs it)"
run_quick_case particle_sim_bullet_peer paired "$work/paired.csv"

/usr/bin/python3 - "$work/paired.csv" <<'PY'
import csv, math, sys
rows = {r['variant']: r for r in csv.DictReader(open(sys.argv[1])) if r['case'] == 'paired'}
for tol, bullet in (('3.45e-4', 'bullet implicit dt 1/1000'), ('1e-6', 'bullet implicit dt 1/1000 tol 1e-6')):
    ours, ratio = 'implicit_euler cg dt 1/1000 tol ' + tol, 'ratio dt 1/1000 tol ' + tol
    for name in (bullet, ours, ratio):
        assert name in rows, 'no row %r in %s' % (name, sorted(rows))
    b, o, r = ({k: float(rows[name][k]) for k in ('ms_min', 'ms_median', 'ms_max', 'cg_iterations')}
               for name in (bullet, ours, ratio))
    assert b['cg_iterations'] > 0 and o['cg_iterations'] > 0, 'a solver took no CG iterations: %s %s' % (b, o)
    assert all(math.isfinite(v) and v > 0 for v in list(b.values())[:3] + list(o.values())[:3] + list(r.values())[:3])
    assert r['ms_min'] <= r['ms_median'] <= r['ms_max'], r
    low, high = b['ms_min'] / o['ms_max'], b['ms_max'] / o['ms_min']
    # The CSV keeps six digits: a round's ratio and the times it came from agree to that.
    assert low * (1 - 1e-5) <= r['ms_min'] and r['ms_max'] <= high * (1 + 1e-5), (tol, r, low, high)
    print('tol %s: ratio %.2f (%.2f-%.2f), within %.2f-%.2f' % (tol, r['ms_median'], r['ms_min'], r['ms_max'], low, high))
PY

# The report on the committed run plus these rows: goal 7's same-dt figure comes from the rounds.
report_with_rows "" "$work/paired.csv"
goal7="$(grep '^| 7 |' "$work/report.md")"
contains "$goal7" "dt 1/1000, both to a relative residual of 0.000345, side by side \(2 rounds of 5 steps" ||
  fail "goal 7 does not take the paired rounds at 3.45e-4: $goal7"
contains "$goal7" "dt 1/1000, both to a relative residual of 1e-06, side by side \(2 rounds of 5 steps" ||
  fail "goal 7 does not take the paired rounds at 1e-6: $goal7"
grep -q '^| ratio dt 1/1000 tol 1e-6 |' "$work/report.md" || fail "no Side by side table in the report"
echo "PASS"
