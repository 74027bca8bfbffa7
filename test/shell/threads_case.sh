#!/usr/bin/env bash
# Goal 6's case (README "Threads"): `particle_sim_perf --only threads` steps each method's cloth on one
# thread and on two and says whether both ended in the same bits; before and after the cloths it
# measures what the machine lets two threads gain (rows `ceiling`), among them how evenly the host
# runs the two vCPUs (`vcpu balance`: the slower vCPU's speed alone over the faster's). A quick run
# here: every method's two runs end in the same bits; every ceiling row is there, before and after,
# finite and positive; the balance is a ratio of the slower to the faster, so at most 1 (NaN only on
# a machine with one CPU); then the report, on the committed CSV with these rows in place of its own
# ceiling, says the balance beside goal 6.
# Run by scripts/test (see its header for the environment it gives).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
: "${PARTICLE_SIM_ROOT:?run me through scripts/test}"

run_quick_case particle_sim_perf threads "$work/threads.csv"

/usr/bin/python3 - "$work/threads.csv" "$(nproc)" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
cpus = int(sys.argv[2])
two = [r for r in rows if r['case'] == 'threads' and r['variant'].endswith(' 2 threads')]
assert two, 'no threads rows'
for r in two:
    assert 'bit-identical end state' in r['detail'], (r['variant'], r['detail'])
ceiling = {r['variant']: float(r['ms_min']) for r in rows if r['case'] == 'ceiling'}
for when in ('before', 'after'):
    for kind in ('arithmetic', 'triad', 'round trip', 'vcpu balance'):
        name = '%s %s' % (kind, when)
        assert name in ceiling, 'no ceiling row %r in %s' % (name, sorted(ceiling))
        value = ceiling[name]
        if cpus < 2 and kind in ('round trip', 'vcpu balance'):
            continue  # NaN: nothing to hold a second thread on
        assert math.isfinite(value) and value > 0, (name, value)
    balance = ceiling['vcpu balance %s' % when]
    assert cpus < 2 or balance <= 1.0, ('the slower over the faster', balance)
    print('vcpu balance %s: %.3f' % (when, balance))
PY

# The report on the committed run with these ceiling rows in place of its own.
report_with_rows ceiling "$work/threads.csv"
goal="$(grep '^| 6 | two threads' "$work/report.md")"
if [ "$(nproc)" -ge 2 ]; then
  contains "$goal" "before: arithmetic [0-9.]+×, triad [0-9.]+×, round trip [0-9]+ ns, the slower vCPU alone at [0-9.]+ of the faster's speed" ||
    fail "goal 6 does not give the vCPUs' balance: $goal"
fi
echo "PASS"
