#!/usr/bin/env python3
"""Writes docs/performance.md and its plots from the CSV of particle_sim_perf (issue 13).

scripts/bench --performance runs the bench and then this script:

    performance_report.py --csv performance.csv --doc docs/performance.md --plots docs/performance \
        --machine "..." --build "..."

Every figure in the document comes from the one CSV: the time per step of each case and size (the
minimum over repeats, with the median and maximum beside it), the exponent of a least-squares fit
of log(time) against log(size), and each goal of issue 13 beside its target. Plots are drawn with
gnuplot when it is installed.
"""

import argparse
import csv
import math
import os
import re
import shutil
import subprocess
import sys
from collections import OrderedDict


def factorization_rate(direct):
    """'about N GFlop/s': the direct hang64 step's factorization flops over its time (the solve, a few per
    cent of the flops, and the assembly counted in the time), or a pointer to the table."""
    match = re.search(r'factorization ([0-9.]+) Mflop', direct['detail']) if direct and direct['detail'] else None
    if not match or direct['ms_min'] <= 0:
        return 'a rate given by the table'
    return 'about %.1f GFlop/s (its flops over the whole step\'s time)' % (float(match.group(1)) / direct['ms_min'])


def direct_megaflops(direct):
    """The direct step's factorization and solve flops [Mflop] from its detail, or None."""
    text = direct['detail'] if direct and direct['detail'] else ''
    factor = re.search(r'factorization ([0-9.]+) Mflop', text)
    solve = re.search(r'solve ([0-9.]+) Mflop', text)
    return float(factor.group(1)) + float(solve.group(1)) if factor and solve else None


def roof_text(rows, direct, subject):
    """What goal 1's 3 ms would ask of the direct step against the build's arithmetic roof, as a clause
    about `subject` (the step as the sentence names it): '' without the roof row or the direct row's
    flops."""
    roof = [r for r in rows if r['case'] == 'roof' and r['variant'] == 'arithmetic']
    megaflops = direct_megaflops(direct)
    if not roof or megaflops is None or direct['ms_min'] <= 0:
        return ''
    peak = roof[0]['ms_min']  # GFlop/s (the bench stores it in the time columns)
    needed, today = megaflops / 3.0, megaflops / direct['ms_min']  # Mflop per ms = GFlop/s
    text = ('%s\'s %.1f Mflop (factorization and solve) in 3 ms would take %.1f GFlop/s, %.0f %% '
            'of this build\'s arithmetic roof of %.1f GFlop/s (it runs at %.1f GFlop/s, %.0f %%)'
            % (subject, megaflops, needed, 100 * needed / peak, peak, today, 100 * today / peak))
    fma = [r for r in rows if r['case'] == 'roof' and r['variant'] == 'arithmetic fma']
    if fma and fma[0]['ms_min'] > 0:
        wide = fma[0]['ms_min']
        text += ('; %.0f %% of the FMA roof of %.1f GFlop/s that its supernodal products run on (it runs at %.0f %%)'
                 % (100 * needed / wide, wide, 100 * today / wide))
    return text


def roof_sentence(rows, direct):
    """Goal 1's 3 ms for the direct step against the build's arithmetic roof, as a sentence."""
    text = roof_text(rows, direct, 'the step')
    if not text:
        return ('the bench measures this build\'s arithmetic roof beside the direct step (independent multiplies '
                'and adds on Eigen\'s packets of two doubles), and this run has no such row, so no share is given '
                'here.')
    return ('%s. The roof is independent multiplies and adds on Eigen\'s packets of two doubles: SSE2, the '
            'x86-64 baseline that every x86-64 machine runs, with no fused multiply-add; the FMA roof is '
            'independent fused multiply-adds on AVX2\'s four lanes, which the direct solver\'s supernodal products '
            'take where the processor has AVX2 and FMA (README, "Or directly").'
            % text)


def read_rows(path):
    with open(path, newline='') as f:
        rows = []
        for r in csv.DictReader(f):
            for key in ('size', 'elements', 'ms_min', 'ms_median', 'ms_max', 'cg_iterations'):
                r[key] = float(r[key])
            # Every detail lands in a Markdown table cell, where a bare '|' (as in |r|/|b|) would end it.
            r['detail'] = r['detail'].replace('|', '\\|')
            rows.append(r)
        return rows


def series(rows, case, variant):
    return sorted((r for r in rows if r['case'] == case and r['variant'] == variant), key=lambda r: r['size'])


def fitted_exponent(points):
    """Slope of log(ms) against log(elements), least squares; None with fewer than two sizes."""
    pts = [(math.log(r['elements']), math.log(r['ms_min'])) for r in points if r['elements'] > 0 and r['ms_min'] > 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx > 0 else None


def node_figures(r):
    """The probe's figures of a node row (scripts/node_bench.py): numbers, and `integrators` as text."""
    head, _, integrators = r['detail'].partition(' integrators=')
    figures = {key: float(value) for key, value in (item.split('=', 1) for item in head.split())}
    figures['integrators'] = integrators
    return figures


def ms(value):
    if value >= 100:
        return '%.0f' % value
    if value >= 10:
        return '%.1f' % value
    if value >= 1:
        return '%.2f' % value
    return '%.3g' % value


def spread(r):
    return '%s (%s–%s)' % (ms(r['ms_min']), ms(r['ms_median']), ms(r['ms_max']))


def step_of(variant):
    """The time step [s] a hang64 variant runs at: 'dt 1/N' in its name, else 1/60."""
    m = re.search(r'dt 1/(\d+)', variant)
    return 1.0 / int(m.group(1)) if m else 1.0 / 60.0


def implicit_methods_text(thread_rows):
    """The threads case's implicit rows in words (older runs have CG's alone, runs since 2026-12-03 the
    multigrid's too), for its prose: '' when it has none."""
    cg = any(r['variant'].startswith('implicit_euler cg') for r in thread_rows)
    multigrid = any(r['variant'].startswith('implicit_euler multigrid') for r in thread_rows)
    parts = []
    if cg:
        parts.append('with block Jacobi\'s CG (at 128² only: seconds a step at 256²)')
    if multigrid:
        parts.append('with the multigrid (its passes over each level\'s nodes shared, the setup\'s Galerkin products '
                     'among them; its power iterations\' norms, coarsest solve and CG vector passes not)')
    text = '; implicit Euler at dt = 1/60 to a relative 1e-6 ' + ' and '.join(parts) if parts else ''
    if any(r['variant'].startswith('implicit_euler direct hang64') for r in thread_rows):
        text += ('; and hang64 (64², goal 1\'s case, not goal 6\'s) by the direct solver at dt = 1/60, its '
                 'factorization\'s two shares of subtrees at once (README, "Or directly")')
    return text


def side_by_side_table(lines, rows_by_variant):
    """A table of rows timed side by side: each body's times per step, and the rows of ratios."""
    lines.append('| row | ms per step (or ratio), min (median–max) | CG iterations per step | detail |')
    lines.append('|---|---|---|---|')
    for v, r in rows_by_variant.items():
        lines.append('| %s | %s | %s | %s |' % (
            v, ('%.2f× (%.2f–%.2f)' % (r['ms_min'], r['ms_median'], r['ms_max'])) if v.startswith('ratio')
            else spread(r), '%.0f' % r['cg_iterations'] if r['cg_iterations'] > 0 else '—', r['detail']))
    lines.append('')


def auto_paired_rows(rows):
    """particle_sim_perf's auto_paired case: each body's row (by variant) and the ratio rows."""
    return OrderedDict((r['variant'], r) for r in rows if r['case'] == 'auto_paired')


def auto_paired_members(rows, dt):
    """At one dt of the auto_paired case: auto's row, and the fastest fixed choice's name and row by median."""
    members = [(v, r) for v, r in auto_paired_rows(rows).items() if not v.startswith('ratio') and step_of(v) == dt]
    auto_row = next(r for v, r in members if v.startswith('auto'))
    best_variant, best = min(((v, r) for v, r in members if not v.startswith('auto')), key=lambda m: m[1]['ms_median'])
    return auto_row, best_variant, best


def size_paired_rows(rows):
    """particle_sim_perf's sizes case: each size's row (by variant, the size last) and the ratio rows."""
    return OrderedDict((r['variant'], r) for r in rows if r['case'] == 'size_paired')


def size_paired_ratio(rows, case, variant, small, large):
    """The sizes case's ratio of `case` and `variant` ('cloth', 'implicit_euler cg') at sizes `large`
    over `small`: the ratio row and the two sizes' rows, or None when the run has not all three (a quick
    run times smaller cloths)."""
    paired = size_paired_rows(rows)
    found = [paired.get('ratio %s %s %d/%d' % (case, variant, large, small)),
             paired.get('%s %s %d' % (case, variant, small)), paired.get('%s %s %d' % (case, variant, large))]
    return found if all(found) else None


def auto_method(auto_row):
    """The method `auto` ran, from the last part of its row's detail ('implicit_euler', 'verlet, 5 substeps')."""
    return auto_row['detail'].split('; ')[-1]


def paired_rounds(ratio_row):
    """How many rounds a ratio row's detail says it has."""
    m = re.search(r'\((\d+) rounds', ratio_row['detail'])
    return m.group(1) if m else '?'


# Bullet's own CG stops at r.r < SIMD_EPSILON min(1, b.b): |r| / |b| < sqrt(1.19e-7) for |b| <= 1.
BULLET_DEFAULT_TOLERANCE = 3.45e-4
# The relative tolerance of particle_sim_perf's hang64 CG rows without 'tol' in their name.
PERF_DEFAULT_TOLERANCE = 1e-6


def tolerance_of(variant):
    """The relative residual a hang64 implicit variant is solved to: 'tol T' in its name; else Bullet's
    default for a Bullet row, 0 (exact) for particle_sim's direct solver, and the bench's 1e-6 for its CG."""
    m = re.search(r'tol ([0-9.eE+-]+)', variant)
    if m:
        return float(m.group(1))
    if variant.startswith('bullet'):
        return BULLET_DEFAULT_TOLERANCE
    return 0.0 if 'direct' in variant else PERF_DEFAULT_TOLERANCE


def peak_strain(r):
    """The peak strain the bench's detail reports (hang64 rows), or None."""
    m = re.search(r'peak strain ([0-9.eE+-]+)', r['detail'])
    return float(m.group(1)) if m else None


def per_simulated_second(r):
    """Seconds of CPU per simulated second (min over repeats)."""
    return r['ms_min'] / 1000.0 / step_of(r['variant'])


def find(rows, case, variant, size):
    for r in rows:
        if r['case'] == case and r['variant'] == variant and r['size'] == size:
            return r
    return None


def find_any(rows, case, variant):
    """Whether the run has a row of this case and variant."""
    return any(r['case'] == case and r['variant'] == variant for r in rows)


def iterative(variant):
    """Whether the variant's rows carry CG iterations (block Jacobi's CG or the multigrid's)."""
    return 'cg' in variant or 'multigrid' in variant


def scaling_table(rows, case, variants, size_label, elements_label):
    # Only the variants this run has (a run from before a variant existed has no column for it).
    variants = [v for v in variants if find_any(rows, case, v)]
    same = size_label == elements_label  # one column when the size is what the cost grows with
    header = '| %s |' % size_label + ('' if same else ' %s |' % elements_label)
    lines = [header + ' %s |' % ' | '.join(
        '%s: ms per step, min (median–max)%s' % (v, '; CG iterations' if iterative(v) else '') for v in variants),
        '|---|' + ('' if same else '---|') + '---|' * len(variants)]
    sizes = sorted({r['size'] for r in rows if r['case'] == case and r['variant'] in variants})
    for size in sizes:
        cells = []
        elements = ''
        for v in variants:
            r = find(rows, case, v, size)
            if r is None:
                cells.append('—')
                continue
            elements = '%d' % r['elements']
            text = spread(r)
            if iterative(v) and r['cg_iterations'] > 0:
                text += '; %.0f' % r['cg_iterations']
            if r['detail']:
                text += '; ' + r['detail']
            cells.append(text)
        lines.append('| %d |' % size + ('' if same else ' %s |' % elements) + ' %s |' % ' | '.join(cells))
    exponents = []
    for v in variants:
        e = fitted_exponent(series(rows, case, v))
        exponents.append('%.2f' % e if e is not None else '—')
    lines.append('| fitted exponent (time ∝ %s^p) |' % elements_label + ('' if same else ' |') +
                 ' %s |' % ' | '.join(exponents))
    return '\n'.join(lines)


def ceiling_text(rows):
    """The machine's two-thread ceiling around the threads case (rows of case 'ceiling'), as a phrase."""
    def value(variant):
        r = next((r for r in rows if r['case'] == 'ceiling' and r['variant'] == variant), None)
        return r['ms_min'] if r else None
    parts = []
    balanced = False
    for when in ('before', 'after'):
        arithmetic, triad, trip = (value('%s %s' % (kind, when)) for kind in ('arithmetic', 'triad', 'round trip'))
        if arithmetic is not None and triad is not None and trip is not None:
            part = '%s: arithmetic %.2f×, triad %.2f×, round trip %.0f ns' % (when, arithmetic, triad, trip)
            balance = value('vcpu balance %s' % when)
            if balance is not None and balance == balance:  # not NaN
                part += ', the slower vCPU alone at %.2f of the faster\'s speed' % balance
                balanced = True
            parts.append(part)
    if not parts:
        return ''
    return ('what two threads could get from this machine at the time (two kernels on two threads at once '
            'against one alone, 2 = two whole cores; a cache line\'s round trip between the threads, some '
            '100 ns when the vCPUs share a cache' +
            ('; each vCPU\'s speed alone, a 128² cloth\'s symplectic Euler steps on one thread held on it, '
             '1 when even: a loop cut in equal halves waits for the slower' if balanced else '') +
            '): ' + '; '.join(parts))


def thread_pairs(rows):
    """(method, size, speed-up of 2 threads over 1, end state bit-identical) per method and size."""
    pairs = []
    for r in rows:
        if r['case'] != 'threads' or not r['variant'].endswith(' 2 threads'):
            continue
        method = r['variant'][:-len(' 2 threads')]
        one = find(rows, 'threads', method + ' 1 thread', r['size'])
        if one and r['ms_min'] > 0:
            pairs.append((method, int(r['size']), one['ms_min'] / r['ms_min'], 'bit-identical' in r['detail']))
    return pairs


def plot(path_png, title, xlabel, curves):
    """curves: list of (label, [(x, y), ...]); log-log. No plot when no curve has a point (a partial run)."""
    curves = [(label, points) for label, points in curves if points]
    if not curves:
        return False
    if shutil.which('gnuplot') is None:
        print('performance_report.py: gnuplot not found, no plot %s' % path_png, file=sys.stderr)
        return False
    data = path_png[:-4] + '.dat'
    with open(data, 'w') as f:
        for label, points in curves:
            f.write('# %s\n' % label)
            for x, y in points:
                f.write('%g %g\n' % (x, y))
            f.write('\n\n')
    plots = ', '.join("'%s' index %d with linespoints lw 2 pt 7 title '%s'" % (os.path.basename(data), i, label)
                      for i, (label, _) in enumerate(curves))
    script = ("set terminal pngcairo size 820,520 enhanced font 'DejaVu Sans,11'\n"
              "set output '%s'\nset title '%s'\nset logscale xy\nset grid\nset key top left box opaque\n"
              "set xlabel '%s'\nset ylabel 'ms per step (min over repeats)'\nplot %s\n"
              % (os.path.basename(path_png), title, xlabel, plots))
    subprocess.run(['gnuplot'], input=script.encode(), cwd=os.path.dirname(path_png) or '.', check=True)
    os.remove(data)
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--csv', required=True)
    parser.add_argument('--doc', required=True)
    parser.add_argument('--plots', required=True)
    parser.add_argument('--machine', default='')
    parser.add_argument('--build', default='')
    parser.add_argument('--date', default='')
    args = parser.parse_args()
    rows = read_rows(args.csv)
    os.makedirs(args.plots, exist_ok=True)
    rel = os.path.relpath(args.plots, os.path.dirname(args.doc))

    def curve(case, variant):
        return [(r['elements'], r['ms_min']) for r in series(rows, case, variant)]

    plot(os.path.join(args.plots, 'rope.png'), 'Implicit Euler, dt = 1/60: a rope of N segments',
         'segments', [('direct (sparse L D L^T)', curve('rope', 'implicit_euler direct')),
                      ('conjugate gradient (tolerance 1e-8)', curve('rope', 'implicit_euler cg'))])
    plot(os.path.join(args.plots, 'cloth.png'), 'Implicit Euler, dt = 1/60: an n x n spring cloth',
         'particles', [('conjugate gradient (tolerance 1e-6)', curve('cloth', 'implicit_euler cg')),
                       ('direct', curve('cloth', 'implicit_euler direct')),
                       ('multigrid-preconditioned CG (tolerance 1e-6)', curve('cloth', 'implicit_euler multigrid'))])
    plot(os.path.join(args.plots, 'emitters.png'), 'A fountain of N live particles, dt = 1/60',
         'live particles', [('fountain', curve('emitters', 'fountain'))])

    # Goals of issue 13, each figure beside its target.
    goals = []
    hang = OrderedDict((r['variant'], r) for r in rows if r['case'] == 'hang64')
    ours = OrderedDict((v, r) for v, r in hang.items() if not v.startswith('bullet'))
    bullet = OrderedDict((v, r) for v, r in hang.items() if v.startswith('bullet'))
    implicit60 = {v: r for v, r in ours.items() if v.startswith('implicit_euler') and step_of(v) == 1.0 / 60.0}
    if implicit60:
        best = min(implicit60.values(), key=lambda r: r['ms_min'])
        roof_clause = roof_text(rows, ours.get('implicit_euler direct'), 'the direct step')
        # The direct step at two threads (the threads case: the factorization's two shares of subtrees,
        # README "Or directly"), one and two threads side by side; goal 1 is judged on either.
        direct_one = find(rows, 'threads', 'implicit_euler direct hang64 1 thread', 64)
        direct_two = find(rows, 'threads', 'implicit_euler direct hang64 2 threads', 64)
        two_clause = ''
        fastest = best['ms_min']
        if direct_one and direct_two and direct_two['ms_min'] > 0:
            fastest = min(fastest, direct_two['ms_min'])
            two_clause = ('; at two threads, the default on this machine, %s ms by the direct solver (%.2f× one '
                          'thread\'s %s ms beside it in the threads case%s)'
                          % (ms(direct_two['ms_min']), direct_one['ms_min'] / direct_two['ms_min'],
                             ms(direct_one['ms_min']),
                             ', the same bits' if 'bit-identical' in direct_two['detail'] else ', END STATE DIFFERS'))
        goals.append(('1', 'hang64, implicit Euler at h = 1/60, converged', '≤ 3 ms per step',
                      '%s ms (%s; %s)%s%s' % (ms(best['ms_min']), best['variant'], '; '.join(
                          '%s %s ms' % (v, ms(r['ms_min'])) for v, r in implicit60.items() if r is not best),
                          two_clause, '; ' + roof_clause if roof_clause else ''),
                      'yes' if fastest <= 3 else 'no'))
    # Goal 2 for each iterative solver of the cloth rows (CG with block Jacobi, CG with multigrid),
    # judged on the one that grows least; and the rope of 1000 segments against 100. Side by side when
    # the run has particle_sim_perf's sizes case: the median of the rounds' ratios (the larger size's
    # time over the smaller's in each round). Otherwise from the separate rows, min against min, which
    # also carries how the machine's load moved between the rows.
    cloth_ratios = []
    for solver in ('cg', 'multigrid'):
        cloth_pair = size_paired_ratio(rows, 'cloth', 'implicit_euler ' + solver, 64, 128)
        if cloth_pair:
            r, small_row, large_row = cloth_pair
            cloth_ratios.append((r['ms_median'], '%s: %.1f× side by side (median of %s rounds\' ratios, %.1f–%.1f; '
                                 'iterations %.0f → %.0f)' % (
                                     solver, r['ms_median'], paired_rounds(r), r['ms_min'], r['ms_max'],
                                     small_row['cg_iterations'], large_row['cg_iterations'])))
            continue
        small = find(rows, 'cloth', 'implicit_euler ' + solver, 64)
        large = find(rows, 'cloth', 'implicit_euler ' + solver, 128)
        if small and large:
            cloth_ratios.append((large['ms_min'] / small['ms_min'], '%s: %.1f× (iterations %.0f → %.0f)' % (
                solver, large['ms_min'] / small['ms_min'], small['cg_iterations'], large['cg_iterations'])))
    if cloth_ratios:
        goals.append(('2', 'implicit cloth 128² against 64², fixed relative tolerance', '≤ 5×',
                      '; '.join(text for _, text in cloth_ratios),
                      'yes' if min(ratio for ratio, _ in cloth_ratios) <= 5 else 'no'))
    rope_pair = size_paired_ratio(rows, 'rope', 'implicit_euler direct', 100, 1000)
    r100, r1000 = find(rows, 'rope', 'implicit_euler direct', 100), find(rows, 'rope', 'implicit_euler direct', 1000)
    if rope_pair:
        r = rope_pair[0]
        goals.append(('2', 'rope of 1000 segments against 100', '≤ 15×',
                      '%.1f× (direct) side by side (median of %s rounds\' ratios, %.1f–%.1f)'
                      % (r['ms_median'], paired_rounds(r), r['ms_min'], r['ms_max']),
                      'yes' if r['ms_median'] <= 15 else 'no'))
    elif r100 and r1000:
        ratio = r1000['ms_min'] / r100['ms_min']
        goals.append(('2', 'rope of 1000 segments against 100', '≤ 15×', '%.1f× (direct)' % ratio,
                      'yes' if ratio <= 15 else 'no'))
    r10k = find(rows, 'rope', 'implicit_euler direct', 10000)
    if r10k:
        goals.append(('2', 'rope of 10,000 segments', '≤ 5 ms per step', '%s ms (direct)' % ms(r10k['ms_min']),
                      'yes' if r10k['ms_min'] <= 5 else 'no'))
    e = fitted_exponent(series(rows, 'rope', 'implicit_euler direct'))
    if e is not None:
        goals.append(('2', 'ropes solved exactly in O(N)', 'exponent 1', 'fitted exponent %.2f (direct, exact)' % e,
                      'yes' if e <= 1.15 else 'no'))
    triad = [r for r in rows if r['case'] == 'springs' and r['variant'] == 'triad bandwidth']
    springs = series(rows, 'springs', 'symplectic_euler')
    if triad and springs:
        bandwidth = triad[0]['ms_min']  # GB/s (the bench stores it in the time columns)
        floor_ns = 40.0 / bandwidth  # the 40-byte spring record read once per step
        biggest = springs[-1]
        ns = biggest['ms_min'] * 1e6 / biggest['elements']
        alone = re.search(r'force evaluation alone ([0-9.]+) ns', biggest['detail'] or '')
        alone_text = ('; the force evaluation alone (gravity and springs, no energy) %.1f ns = %.1f× the floor'
                      % (float(alone.group(1)), float(alone.group(1)) / floor_ns)) if alone else ''
        goals.append(('5', 'explicit springs (symplectic Euler, %d² cloth) against the memory floor' % biggest['size'],
                      '≤ 2× the floor', '%.1f ns per spring per step = %.1f× the floor of %.2f ns (40-byte spring '
                      'record at the triad\'s %.1f GB/s)%s' % (ns, ns / floor_ns, floor_ns, bandwidth, alone_text),
                      'yes' if ns <= 2 * floor_ns else 'no'))
    # Goal 7: Bullet beside it. Implicit against implicit at the same dt; and each engine with its
    # cheapest method that holds together (cost per simulated second), compared when particle_sim's
    # stretches no more than Bullet's. Bullet rows marked BROKEN (link strain past 10, or a time taken
    # on such a body) are left out: their times are those of solves that gave up.
    working = OrderedDict((v, r) for v, r in bullet.items() if 'BROKEN' not in r['detail'])
    # The same-dt ratios timed side by side in one process (particle_sim_bullet_peer's paired case:
    # alternating rounds, Bullet's time over particle_sim's round by round, min, median and max in
    # the time columns). When the run has them the goal is judged on their medians: the hang64 rows
    # of the two programs are timed minutes apart, and the machine's load moves each on its own.
    paired = OrderedDict((r['variant'], r) for r in rows if r['case'] == 'paired')
    paired_ratios = [(v, r) for v, r in paired.items() if v.startswith('ratio')]
    def paired_engine_row(engine, ratio_variant):
        """The paired row of one engine ('bullet' or 'implicit_euler') behind a row of ratios."""
        return next((p for pv, p in paired.items() if pv.startswith(engine) and step_of(pv) == step_of(ratio_variant)
                     and tolerance_of(pv) == tolerance_of(ratio_variant)), None)

    if bullet:
        same_dt, ratios = [], []
        for v, r in paired_ratios:
            tolerance = tolerance_of(v)
            theirs, mine = paired_engine_row('bullet', v), paired_engine_row('implicit_euler', v)
            ratios.append(r['ms_median'])
            rounds = re.search(r'(\d+) rounds of (\d+) steps', r['detail'])
            same_dt.append('dt 1/%d, both to a relative residual of %g, side by side (%s, alternating in one '
                           'process): %.1f× (median of the rounds\' ratios; %.1f–%.1f%s)' % (
                               round(1 / step_of(v)), tolerance,
                               '%s rounds of %s steps' % rounds.groups() if rounds else 'rounds',
                               r['ms_median'], r['ms_min'], r['ms_max'],
                               '; medians %s ms against %s ms' % (ms(theirs['ms_median']), ms(mine['ms_median']))
                               if theirs and mine else ''))
        # Without paired rows: each working Bullet implicit row against particle_sim's fastest implicit
        # row at the same dt solved at least as tightly. The goal is judged at equal tolerance; a Bullet
        # row at its own looser default is shown beside it, against particle_sim held to its tighter one.
        separate_rows = OrderedDict() if paired_ratios else working
        for bv, br in separate_rows.items():
            if 'implicit' not in bv:
                continue
            mine = [r for v, r in ours.items() if v.startswith('implicit_euler') and step_of(v) == step_of(bv)
                    and tolerance_of(v) <= tolerance_of(bv)]
            if mine:
                best = min(mine, key=lambda r: r['ms_min'])
                ratio = br['ms_min'] / best['ms_min']
                equal_tolerance = tolerance_of(best['variant']) == tolerance_of(bv)
                if equal_tolerance:
                    ratios.append(ratio)
                same_dt.append('dt 1/%d, %s: %.1f× (%s %s ms; %s %s ms)' % (
                    round(1 / step_of(bv)),
                    'both to a relative residual of %g' % tolerance_of(bv) if equal_tolerance
                    else 'Bullet to its default relative residual of %g, particle_sim to %g' % (
                        tolerance_of(bv), tolerance_of(best['variant'])),
                    ratio, bv, ms(br['ms_min']), best['variant'], ms(best['ms_min'])))
        broken_implicit = sorted({'1/%d' % round(1 / step_of(v)) for v, r in bullet.items()
                                  if 'implicit' in v and 'BROKEN' in r['detail']})
        if broken_implicit:
            same_dt.append('Bullet\'s implicit solver breaks the cloth at dt %s' % ', '.join(broken_implicit))
        # At equal stretch: Bullet's least-stretching method that holds together (the cheapest of them, per
        # simulated second) against particle_sim's cheapest that stretches no more.
        stable_ours = [r for r in ours.values() if peak_strain(r) is not None and 'FROZE' not in r['detail']]
        equal, equal_ratio = 'no Bullet variant holds the cloth together', None
        measured = [r for r in working.values() if peak_strain(r) is not None]
        if measured:
            least = min(peak_strain(r) for r in measured)
            rival = min((r for r in measured if peak_strain(r) <= least), key=per_simulated_second)
            mine = [r for r in stable_ours if peak_strain(r) <= least]
            if mine:
                best = min(mine, key=per_simulated_second)
                equal_ratio = per_simulated_second(rival) / per_simulated_second(best)
                equal = ('%.1f× at Bullet\'s least stretch (%s: peak strain %.3g, %.3g s per simulated s; '
                         'particle_sim\'s cheapest that stretches no more, %s: %.3g, %.3g s/s)' % (
                             equal_ratio, rival['variant'], least, per_simulated_second(rival), best['variant'],
                             peak_strain(best), per_simulated_second(best)))
            else:
                equal = 'no particle_sim method stretches as little as Bullet\'s least (%.3g)' % least
        goals.append(('7', 'Bullet 3.24 beside it on hang64: implicit against implicit at the same dt; and at equal '
                      'stretch, each engine with its cheapest method',
                      '≥ 5× at the same dt; ≥ 10× at equal stretch',
                      '%s; %s' % ('; '.join(same_dt) or 'no working Bullet implicit row', equal),
                      'yes' if ratios and min(ratios) >= 5 and equal_ratio is not None and equal_ratio >= 10
                      else 'no'))
    # Goal 8: `auto` against the cheapest fixed choice at each dt of the bench. Side by side when the run
    # has particle_sim_perf's auto_paired case: the median of the rounds' ratios (auto over the fastest
    # fixed choice of each round). Otherwise from the separate hang64 rows, min against min, which also
    # carries how the machine's load moved between the rows.
    auto_ratios = [(v, r) for v, r in auto_paired_rows(rows).items() if v.startswith('ratio')]
    autos = [r for v, r in ours.items() if v.startswith('auto')]
    parts, worst = [], 0.0
    for v, r in auto_ratios:
        auto_row, best_variant, best = auto_paired_members(rows, step_of(v))
        worst = max(worst, r['ms_median'])
        parts.append('dt 1/%d: %.2f× side by side (median of %s rounds\' ratios, %.2f–%.2f; auto ran %s, %s ms '
                     'a step; the fastest fixed choice by median %s, %s ms)' % (
                         round(1 / step_of(v)), r['ms_median'], paired_rounds(r), r['ms_min'], r['ms_max'],
                         auto_method(auto_row), ms(auto_row['ms_median']), best_variant, ms(best['ms_median'])))
    for a in [] if auto_ratios else autos:  # the separate rows only when the run has no rounds
        fixed = [r for v, r in ours.items() if not v.startswith('auto') and step_of(v) == step_of(a['variant'])]
        if not fixed:
            continue
        best = min(fixed, key=lambda r: r['ms_min'])
        ratio = a['ms_min'] / best['ms_min']
        worst = max(worst, ratio)
        parts.append('dt 1/%d: %.2f× (auto ran %s; best %s)' % (round(1 / step_of(a['variant'])), ratio,
                                                                a['detail'].split(';')[0], best['variant']))
    if auto_ratios or autos:
        goals.append(('8', '`auto` within 1.2× of the best fixed choice on hang64 at every dt', '≤ 1.2×',
                      '; '.join(parts), 'yes' if parts and worst <= 1.2 else 'no'))
    # Goal 6: each method and size at two threads against one (min against min), and the same end state.
    # Goal 6 asks for 128² and larger: hang64's direct step (64², goal 1's case) is in the table, not here.
    pairs = [pair for pair in thread_pairs(rows) if pair[1] >= 128]
    ceiling = ceiling_text(rows)
    if pairs:
        worst = min(ratio for _, _, ratio, _ in pairs)
        identical = all(same for _, _, _, same in pairs)
        goals.append(('6', 'two threads: ≥ 1.6× on 128² and larger, bit-identical', '≥ 1.6×, same bits',
                      '; '.join('%s %d²: %.2f×%s' % (method, size, ratio, '' if same else ' (END STATE DIFFERS)')
                                for method, size, ratio, same in pairs) +
                      ('; every end state bit-identical to one thread' if identical else '') +
                      ('; ' + ceiling if ceiling else ''),
                      'yes' if worst >= 1.6 and identical else 'no'))
    # Goals 3 and 4: the node measured through ROS (scripts/node_bench.py), real-time factor from /clock.
    node = {r['variant']: node_figures(r) for r in rows if r['case'] == 'node'}
    cloth_cases = [(v, f) for v, f in node.items() if v.startswith('cloth 128 ')]
    if cloth_cases:
        goals.append(('3', 'a 128×128 cloth in the node at real-time factor ≥ 1 (60 Hz, `auto`, markers and meshes '
                      'subscribed), spring model and Baraff–Witkin', 'real-time factor ≥ 1',
                      '; '.join('%s: real-time factor %.3g (%s ms per tick), markers %.3g Hz, meshes %.3g Hz'
                                % (v.replace('cloth 128 ', '').replace(' auto', ''), f['rtf'], ms(f['tick_ms_median']),
                                   f['markers_hz'], f.get('meshes_hz', 0.0)) for v, f in cloth_cases),
                      'yes' if all(f['rtf'] >= 1.0 for _, f in cloth_cases) else 'no'))
    else:
        goals.append(('3', 'a 128×128 cloth in the node at real-time factor ≥ 1', 'see issue 13',
                      'not measured: run scripts/bench --performance with ROS installed', 'no'))
    fountain_cases = [(v, f) for v, f in node.items() if v.startswith('fountain') and 'publishing_thread' not in v]
    if fountain_cases:
        goals.append(('4', 'publishing never slows the physics: 10⁶ emitter particles at dt = 1/60, one marker '
                      'subscriber', 'real-time factor ≥ 0.98, markers ≥ 30 Hz',
                      '; '.join('%s: real-time factor %.3f (1-s windows %.3f–%.3f), markers %.1f Hz of %d points'
                                % (v, f['rtf'], f['rtf_window_min'], f['rtf_window_max'], f['markers_hz'],
                                   f['markers_points']) for v, f in fountain_cases),
                      'yes' if all(f['rtf'] >= 0.98 and f['markers_hz'] >= 30.0 for _, f in fountain_cases)
                      else 'no'))
    else:
        goals.append(('4', 'publishing never slows the physics', 'see issue 13',
                      'not measured: run scripts/bench --performance with ROS installed', 'no'))
    stopping = [r for r in rows if r['case'] == 'stopping']
    if stopping:
        def count(r, pattern):
            match = re.search(pattern, r['detail'])
            return int(match.group(1)) if match else 0
        unconverged = sum(count(r, r'(\d+) unconverged;') for r in stopping)
        at_defaults = [count(r, r'at the defaults \([^)]*\): (\d+) steps unconverged') for r in stopping]
        measured_at_defaults = all('at the defaults' in r['detail'] for r in stopping)
        over_cap = [r for r in stopping if count(r, r'(\d+) steps over the default cap') > 0]
        measured = ('CG to the rule with no cap: %d of %d bench scenes met it on every step (%d unconverged steps)'
                    % (len(stopping) - len([r for r in stopping if count(r, r'(\d+) unconverged;') > 0]),
                       len(stopping), unconverged))
        if over_cap:
            measured += ('; the rule needs more than the default cap of 500 iterations in %s (at most %s)'
                         % (', '.join('%s %d' % (r['variant'], r['size']) for r in over_cap),
                            ', '.join(str(count(r, r'max (\d+) iterations')) for r in over_cap)))
        if measured_at_defaults:
            measured += ('; at every default (linear solver `auto`, whose CG goes past the cap of 500 up to a '
                         'direct solve\'s cost and then solves the step again directly): %d unconverged steps in all '
                         '%d scenes'
                         % (sum(at_defaults), len(stopping)))
        met = unconverged == 0 and measured_at_defaults and sum(at_defaults) == 0
        goals.append(('9', 'a stopping rule that fits the physics, converging at its default (velocity error ≤ '
                      '1e-5 m/s) on every bench scene', 'every scene, every step', measured, 'yes' if met else 'no'))
    else:
        goals.append(('9', 'a stopping rule that fits the physics', 'see issue 13', 'not measured by this bench yet',
                      'no'))
    if not bullet:
        goals.append(('7', 'Bullet beside it: ≥ 5× at the same dt, ≥ 10× at equal stretch', 'see issue 13',
                      'not measured: particle_sim_bullet_peer is built only when libbullet-dev is found', 'no'))
    goals.sort(key=lambda g: int(g[0]))

    emitter_rows = series(rows, 'emitters', 'fountain')
    direct64 = hang.get('implicit_euler direct')
    cg_tol = hang.get('implicit_euler cg tol 1e-6')
    lines = []
    lines.append('# Performance')
    lines.append('')
    lines.append('Issue 13 asks for real time at robot scale. This page gives each of its goals beside its target, '
                 'the cost of each kind of body against its size with the fitted exponent, and where the time goes. '
                 'Everything below the line of run facts comes from one run of one command:')
    lines.append('')
    lines.append('```bash')
    lines.append('scripts/bench --performance   # builds particle_sim_perf, runs it, rewrites this page and its plots')
    lines.append('```')
    lines.append('')
    lines.append('`particle_sim_perf` (src/tools/particle_sim_perf.cpp) builds each body in code, takes warm-up steps, '
                 'then times the step alone (steady_clock) over several repeats of many steps: each figure is the '
                 'minimum time per step over the repeats, with the median and the maximum in brackets (the spread '
                 'is the noise of the machine). Its CSV is `docs/performance/performance.csv`.')
    lines.append('')
    lines.append('Run: %s. Machine: %s. Build: %s.' % (args.date or 'unknown date', args.machine or 'unknown machine',
                                                     args.build or 'unknown build'))
    lines.append('')
    pages = [r for r in rows if r['case'] == 'memory']
    if pages:
        lines.append('Pages of the heap (README "Huge pages"; every program of the package and the Bullet peer alike): %s.'
                     % '; '.join('`%s`, %s' % (r['variant'], r['detail']) for r in pages))
        lines.append('')
    lines.append('## Goals of issue 13')
    lines.append('')
    lines.append('| goal | what | target | measured | met |')
    lines.append('|---|---|---|---|---|')
    for g in goals:
        lines.append('| %s | %s | %s | %s | %s |' % g)
    lines.append('')
    lines.append('Goal 10, no allocation in a warmed-up step, is a unit test (`StepAllocations`), at one and at two '
                 'threads: zero allocations in 1000 steps of every shipped scene, but for the steps of `cloth_tear` '
                 'that split a vertex along its tear (the cloth grows; `TearAllocations` counts its other steps: zero).')
    lines.append('')
    lines.append('## Ropes')
    lines.append('')
    lines.append('![ropes](%s/rope.png)' % rel)
    lines.append('')
    lines.append('The hard case of `config/scenes/hard/long_rope.yaml` at every size: 5 m, 1 kg, stretch springs of '
                 '20000 N/m, pinned at one end and released from horizontal, implicit Euler at dt = 1/60. '
                 'The direct solver (`linear_solver: direct`, what `auto` picks for a rope) factors the chain with '
                 'no fill: its cost grows linearly. The conjugate gradient needs more iterations the longer the rope '
                 '(the condition number grows with N²).')
    lines.append('')
    lines.append(scaling_table(rows, 'rope', ['implicit_euler direct', 'implicit_euler cg'], 'segments', 'segments'))
    lines.append('')
    lines.append('## Cloth')
    lines.append('')
    lines.append('![cloth](%s/cloth.png)' % rel)
    lines.append('')
    lines.append('A 1 m square spring cloth of n × n particles (structural, shear and bend springs of 1000, 1000 and '
                 '100 N/m; 1 kg), horizontal, hanging from two adjacent corners; implicit Euler at dt = 1/60, relative '
                 'CG tolerance 1e-6, for block Jacobi\'s CG (`cg`) and for CG preconditioned by a cycle of '
                 'smoothed-aggregation multigrid (`multigrid`, whose iterations hardly grow with n). The direct solver '
                 'is timed up to 64² (its fill grows like n log n, its work like n^1.5).')
    lines.append('')
    lines.append(scaling_table(rows, 'cloth', ['implicit_euler cg', 'implicit_euler direct', 'implicit_euler multigrid'],
                               'n', 'particles'))
    lines.append('')
    lines.append('**hang64**, Bullet\'s soft-body test cloth rebuilt exactly as a spring network (64 × 64 particles on '
                 'a 1 m square, horizontal, two adjacent corners pinned, 1 kg; structural springs and one shear '
                 'diagonal per quad alternating like `btSoftBodyHelpers::CreatePatch`; 1000 N/m, 0.01 N·s/m). '
                 'Each method is timed from rest (warm-up steps, then repeats), and run again for 2 s from rest for '
                 'its stretch: the peak over all steps of the largest spring strain, and the sag at 2 s (the lowest '
                 'particle below the pinned corners). Rows starting with `bullet` are Bullet 3.24 on the same cloth '
                 '(`particle_sim_bullet_peer`, built when Debian\'s libbullet-dev is found; see goal 7).')
    lines.append('')
    lines.append('| method | dt [s] | ms per step, min (median–max) | CPU s per simulated s | CG iterations per step '
                 '| detail |')
    lines.append('|---|---|---|---|---|---|')
    for v, r in ours.items():
        lines.append('| %s | 1/%d | %s | %.3g | %s | %s |' % (
            v, round(1 / step_of(v)), spread(r), per_simulated_second(r),
            '%.0f' % r['cg_iterations'] if r['cg_iterations'] > 0 else '—', r['detail']))
    lines.append('')
    bullet_rows = [r for r in rows if r['variant'].startswith('bullet') and r['case'] != 'paired']
    if bullet_rows:
        lines.append('Bullet 3.24 (Debian\'s libbullet-dev, float build) on the same cloth and on the ropes of the '
                     'next section, from `particle_sim_bullet_peer` in the same run (its source comment says how '
                     'each solver is set up and checked). Its implicit solver is the deformable world\'s '
                     'linearised backward Euler with a conjugate gradient; its classic solver is position-based '
                     '(links of stiffness 1, `piterations` sweeps). Rows marked BROKEN had a link stretched past '
                     '10 times its length: Bullet\'s implicit solve keeps the indefinite stiffness of compressed '
                     'springs, its CG stops on negative curvature, and at large steps the cloth or the long rope '
                     'comes apart.')
        lines.append('')
        lines.append('| case | size | method | ms per step, min (median–max) | CPU s per simulated s | CG iterations '
                     'per step | detail |')
        lines.append('|---|---|---|---|---|---|---|')
        for r in bullet_rows:
            lines.append('| %s | %d | %s | %s | %.3g | %s | %s |' % (
                r['case'], r['size'], r['variant'], spread(r), per_simulated_second(r),
                '%.0f' % r['cg_iterations'] if r['cg_iterations'] > 0 else '—', r['detail']))
        lines.append('')
    if paired:
        lines.append('Side by side: hang64 at dt = 1/1000 in Bullet\'s implicit world and in particle_sim\'s implicit '
                     'Euler (CG) to the same relative residual, built and warmed up in one process '
                     '(`particle_sim_bullet_peer`\'s paired case), then timed in rounds, one engine after the '
                     'other, which goes first alternating: a spell of load on the virtual machine slows both alike. '
                     'Each round gives Bullet\'s time over particle_sim\'s; goal 7\'s same-dt figure is the median '
                     'of those ratios. The hang64 rows above are timed by two programs minutes apart, so their '
                     'ratios also carry how the machine\'s load moved in between.')
        lines.append('')
        side_by_side_table(lines, paired)
    size_paired = size_paired_rows(rows)
    if size_paired:
        lines.append('Goal 2\'s ratios side by side: for each, the body at both sizes (the cloth above at 64² and '
                     '128² with each iterative solver, the rope of the section above at 100 and 1000 segments '
                     'solved directly), built and warmed up from rest together in one process '
                     '(`particle_sim_perf`\'s `sizes` case), then timed in rounds, each size after the other, the '
                     'order swapped each round, so that both cover the same span of simulated time. Each round '
                     'gives the larger size\'s time over the smaller\'s; goal 2\'s figures are the median of '
                     'those ratios. The tables above are timed a minute or more apart, so their ratios also carry '
                     'how the machine\'s load moved in between.')
        lines.append('')
        side_by_side_table(lines, size_paired)
    auto_paired = auto_paired_rows(rows)
    if auto_paired:
        lines.append('`auto` side by side (goal 8): at each dt of the hang64 rows above, `auto` and every fixed '
                     'choice of that dt, built and warmed up in one process (`particle_sim_perf`\'s `auto` case), '
                     'then timed in rounds, each body after the other, the order shifted by one each round; all '
                     'start from rest together, so each round times every body over the same span of simulated '
                     'time. Each round gives auto\'s time over the fastest fixed choice\'s in that round; goal '
                     '8\'s figure is the median of those ratios. The separate rows above are timed seconds to '
                     'minutes apart, so their ratios also carry how the machine\'s load moved in between.')
        lines.append('')
        side_by_side_table(lines, auto_paired)
    lines.append('Where the time goes: the direct step is one factorization of the implicit system a step (%s) '
                 'and a solve; assembly and forces are a few per cent. The factorization runs at %s '
                 'in an approximate-minimum-degree order. What is left to the 3 ms of goal 1 by this '
                 'route is less than it looked: %s Since 2026-12-02 a sheet is factored by supernodes (README, '
                 '"Or directly"): dense panels whose products run on AVX2\'s four lanes where the processor has '
                 'it (since 2026-12-06 as fused multiply-adds, under the FMA roof above); outside the bench that '
                 'day, side by side on hang64\'s pattern, the factorization took 4.7 ms against 7.7 on 3×3 blocks (128²: 44 against 92 ms). Nor does a fill-reducing order help here: counted outside the engine on 2026-11-29 (the '
                 'same flops, hang64\'s pattern), nested dissection with grid lines as separators needs 99.5 Mflop, '
                 'a plain minimum degree order 69.7, and the engine\'s approximate minimum degree 57.9. What remains '
                 'is a preconditioner that does not need a new factorization every step. Keeping '
                 'the factorization of an earlier step as CG\'s preconditioner was tried and fails here: while the '
                 'cloth swings, the implicit system changes so much from one step to the next at h = 1/60 that CG '
                 'needs more than 20 iterations with it (each a solve with the factor), every step (measured again '
                 'in the engine on 2026-12-06, to a relative 1e-6: 38 iterations a step with the factor of the step '
                 'before, 87 with one made every fourth step); and at h = 1/1000, '
                 'tried in the engine on 2026-11-29, refactored every 5, 10, 20 or 40 steps, CG took 5.2, 8.5, 15.1 '
                 'and 25.3 iterations a step and the step 6.3 to 17 ms, against 3.1 ms with block Jacobi: a solve '
                 'with the factor costs about 0.6 ms, as much as a dozen products with the springs\' blocks. The '
                 'conjugate '
                 'gradient%s spends about half its time in its products with the springs\' blocks (one symmetric '
                 '3×3 block a spring, multiplied as C (p_j − p_i): since 2026-11-28, 1.3 to 1.45 times faster a step '
                 'than with the two full blocks a spring in the block matrix; since 2026-11-29 each particle\'s own '
                 'diagonal, its mass and any global damping, is read as one number instead of a 3×3 block, 5 to 14 %% '
                 'of a step side by side); its iterations grow with the '
                 'side n, so the cost of a cloth grows like n³ (the fitted exponent in particles is about 1.7 above), '
                 'which multigrid would bring to about n². A plain aggregation multigrid as CG\'s preconditioner '
                 '(neighbours lumped into aggregates whose blocks are summed, three levels, block Gauss–Seidel or '
                 'damped block Jacobi smoothing, tried on 2026-11-28 and not kept) cut the iterations of the spring '
                 'cloth above tenfold (64²: 27 against 286; 128²: 44 against 611, at 1e-6) but not their '
                 'growth with n, and each iteration cost five to six passes over the matrix, so a step was only '
                 '1.1 to 2.3 times cheaper than with block Jacobi, and dearer than the direct solve at 64²: '
                 'piecewise-constant aggregates carry the cloth\'s translations but not its rotations. Smoothed '
                 'aggregation with the six rigid-body modes per aggregate (three translations, three rotations; '
                 'the tentative prolongator orthonormalised per aggregate of 3 × 3 particles, smoothed by one damped '
                 'Jacobi step, Galerkin coarse levels down to a direct solve; V-cycles with two damped block Jacobi '
                 'sweeps before and after) was tried outside the engine on 2026-11-28, on a hang64-like cloth '
                 'stretched 5 %% and crumpled at random (no bend springs), at h = 1/60 to a relative 1e-6: 12, 13 and '
                 '17 iterations at 32², 64² and 128², against block Jacobi\'s 209, 422 and 843, so the iterations '
                 'hardly grow with n any more; at h = 1/1000 (64²) 10 against 31. An iteration costs about eleven '
                 'products with A there, and the setup (the Galerkin products above all) is dear. The prolongator '
                 'need not follow every step: built on one state and used on the system of another (the 64² cloth '
                 'folded by up to 0.2 m, then 0.5 m, and its x jittered by 3 %%), with only the coarse levels\' Galerkin '
                 'products and smoothers made again, CG took 15 and 16 iterations (13 with a new hierarchy, 69 and '
                 '73 with the old one whole, 501 and 509 with block Jacobi). That is the way on for goals 1 to 3: '
                 'the prolongator kept while the shape is alike, the coarse levels made again each step, in 3 × 3 '
                 'and 6 × 6 blocks. Built on 2026-12-01 as the linear solver `multigrid` (README, "Or by multigrid"; '
                 'its rows are `implicit_euler multigrid` in the tables above in runs from that day on), with the whole '
                 'hierarchy made again every solve: kept '
                 'whole for later solves, the rigid-body modes of hang64 swinging at h = 1/60 turn away within a few '
                 'steps (24 iterations a step with a new hierarchy every solve, 36 with one every second solve, 136 '
                 'every tenth; at h = 1/1000 about 7 in each case). Keeping the prolongator alone, as the prototype '
                 'did, would save its smoothing and orthonormalisation but not the Galerkin products, the larger '
                 'part of the setup; not tried in the engine. In a profile of hang64 at h = 1/60 the setup is about '
                 'a quarter of the step and the V-cycles\' products with the levels\' matrices most of the rest. '
                 'Since 2026-12-02 the prolongator is smoothed by the lumped matrix (A with its weak couplings, a '
                 'cloth\'s bend springs, added to the diagonal instead: Vaněk, Mandel & Brezina\'s filtered matrix), '
                 'so that P reaches an aggregate\'s strong neighbours only: on the bench\'s 128² cloth P went from '
                 '4.06 to 2.74 blocks a row, the setup from 47 to 34 ms and a V-cycle from 3.25 to 2.45 ms (the '
                 'fastest of each, the two builds one after the other) at the same iterations, and the step from '
                 '155 to 113 ms (64²: 21.5 to 16.1 ms); hang64, without bend springs, is hardly touched. What keeps '
                 'goal 2 from 5× is the growth of the iterations from 64² to 128² (an iteration cost 4.7 times as '
                 'much for four times the particles in a run that day). Tried outside the engine that day over the '
                 'same steps of both cloths: two smoothing sweeps on the coarse levels (14.5 to 11.9 iterations at '
                 '64², 20.8 to 17.3 at 128²), a W-cycle below the finest level (12.8 and 17.0), a larger coarsest '
                 'level (25 nodes at 128²: 20.4); each left 128² needing 1.4 to 1.5 times the iterations of 64², '
                 'and none made a step cheaper by more than the noise. The levels\' matrices multiplied from their '
                 'upper triangles (half the bytes, a symmetric product) made a V-cycle slower (3.9 against 2.5 ms at '
                 '128²), and a copy of the levels in float no faster (2.5 against 2.6 ms) with more iterations '
                 '(64²: 20 against 14) and a 128² cloth that froze; not kept. Since 2026-12-05 the products with '
                 'A on the finest level (CG\'s, and the two residuals of each V-cycle there) take the springs\' '
                 'pairs, one symmetric 3 × 3 block a spring as block Jacobi\'s CG does, instead of the hierarchy\'s '
                 '3 × 3 blocks (a third of the bytes, read three times an iteration): whole runs of the 128² cloth '
                 'side by side took 0.85 of the time before at one thread (0.91 at two; 64²: 0.91), at the same '
                 'iterations; in a profile of the 128² cloth the 6 × 6 level\'s products are now the largest part '
                 '(about a fifth of the step). Tried that day and not kept: float copies of the prolongators and '
                 'of the 6 × 6 levels\' matrices for the V-cycle (the same iterations; single whole runs 3 to 12 %% '
                 'slower than the double ones at 64² and 128²), and the 6 × 6 products as AVX2 sums of rows (no '
                 'faster): neither the bytes nor the arithmetic of those products bound them. Tried on '
                 '2026-12-06 and not kept: the coarse levels as Galerkin products of the lumped matrix (README, '
                 '"Or by multigrid": 0.83 and 0.87 of the time on this cloth at 64² and 128², but a coarse level '
                 'that lost its definiteness on the node bench\'s cloth). Where the iterations grow: 12, 13, 19 '
                 'and 19 at 32², 64², 128² and 256² in the run of 2026-12-06 05:54, so between 64² and 128² and '
                 'not beyond; with the coarse levels solved almost exactly (30 more smoothing sweeps a V-cycle on '
                 'each, outside the engine that day) 9.8 and 11.9 at 64² and 128², so even the two-grid method '
                 'needs 1.2 times the iterations at 128²; a weaker threshold for strong couplings evens the two '
                 'sizes only by slowing 64² (θ = 0.04: 15.2 and 19.9 iterations). Since 2026-12-07 the cycle '
                 'smooths twice before the coarse correction and twice after on every level, and is a W-cycle '
                 'below the first coarse level (README, "Or by multigrid"): 9.5 and 12.7 iterations a step at 64² '
                 'and 128² instead of 14.2 and 20.4 (a growth of 1.33 instead of 1.44), and goal 2\'s paired ratio '
                 '4.76 (4.58–4.92) against the V-cycle\'s 5.22 (4.73–5.53) that hour, where each change alone had '
                 'left the growth at 1.4 on 2026-12-02, before the prolongator was smoothed on the lumped matrix. '
                 'Since 10:26 UTC on 2026-12-07 the springs\' Jacobian pass leaves the vector registers\' upper '
                 'halves clear (README, "The vector passes leave the vector registers clean"): on the AMD EPYC host '
                 'the plain SSE code after it had run slowly, the multigrid\'s Galerkin products about three times '
                 'as long. Both sizes got faster (goal 2\'s paired medians 19.5 and 108 ms in the run of 11:05 '
                 'against 43.1 and 205 that morning), 64² more than 128², whose levels outgrow this host\'s cache at '
                 'one thread (the 6 × 6 level\'s matrix alone is 10.6 MB at 128², 2.6 at 64²): the paired ratio '
                 'went from about 5.0 to 5.6. Since 13:30 UTC that day the restriction and the Galerkin product '
                 'read the prolongator from a copy in the order of its columns (README, "Or by multigrid"): 0.955 of '
                 'the time before at 128² and 1.007 at 64², whole runs side by side. In a profile of that hour (one '
                 'thread, 40 steps of each size) the finest level\'s pair product, smoothing and prolongation cost '
                 '9.5 to 12.5 times as much at 128² as at 64², where four times the nodes and 1.33 times the '
                 'iterations would make 5.3: the finest level\'s vectors (0.4 to 0.5 MB each at 128², several of '
                 'them to a pass) no longer fit this host\'s 1 MB second-level cache, as they do at 64². That, with '
                 'the growth of the iterations, is what is left of goal 2 at one thread. Since the evening of '
                 '2026-12-07 the cycle smooths with a Chebyshev polynomial of degree two in place of the two '
                 'damped Jacobi sweeps, at the same cost and with the same reach (README, "Or by multigrid"): 8.60 '
                 'and 11.47 iterations a step at 64² and 128² instead of 9.53 and 12.68, a growth of 1.33 either '
                 'way, so it takes time off both sizes (0.976 and 0.944 of the time, the two smoothers alternating '
                 'step by step in one process) but leaves goal 2\'s ratio about where it was. '
                 'A block symmetric Gauss–Seidel preconditioner (SSOR with ω = 1 on the 3×3 blocks) was tried '
                 'outside the engine on hang64\'s implicit system on 2026-11-28. To 1e-6 it needs 2.0 to 2.8 '
                 'times fewer iterations than block Jacobi (h = 1/60: 138 against 381; h = 1/1000: 11 against 29; '
                 '128² at h = 1/60: 295 against 780), a few more when each of two fixed halves of the rows is '
                 'swept alone, as two threads would sweep them with the same bits (169 and 14 at 64²). Applied '
                 'with Eisenstat\'s trick (its sweeps replace the product; the true residual is checked once the '
                 'estimate is met), an iteration cost 1.8 to 2 of block Jacobi\'s in that prototype, so the solve '
                 'was only 1.0 to 1.5 times faster: in two halves 1.04× at h = 1/1000 and 1.22× at 1/60 (1.21× '
                 'and 1.32× at 128²), swept whole 1.36× and 1.51×. That is not enough for goals 1 and 3, and '
                 'enough for goal 7 only with whole sweeps, which two threads cannot share; so it is not built. '
                 'Nor does a better start help CG: tried in the engine on 2026-11-29 on hang64 (relative 1e-6), '
                 'starting from the combination of the last two steps\' Δv that is best in the norm of A (a '
                 'Galerkin step on the two, one more product a step) instead of the last Δv took 27.6 iterations '
                 'a step against 29.6 at h = 1/1000 and 354 against 357 at 1/60, and the last Δv scaled alone '
                 'the same way 29.7 and 393: not kept then. Since 2026-12-06 the start is moved along the '
                 'quadratic through the last three steps\' starts (the last change plus the change of the '
                 'change), by the step that is best in the norm of A along it, when the start is more than 100 '
                 'times the tolerance away (README, "Ropes, spring networks and integrators"): at h = 1/1000 10.6 iterations a step '
                 'against 15.0 at 3.45e-4 and 24.9 against 29.6 at 1e-6, whole runs 0.90 and 0.91 of the time; '
                 'the line through two starts gave 12.2 and 26.7; at 1/60 nothing (355 and 356). At h = 1/1000, where CG needs a few dozen '
                 'iterations a step, the rest of the step weighs more: since 2026-11-29 (evening) each spring\'s '
                 'blocks are built from its parts (a d dᵀ + b I for ∂f/∂x, a\' d dᵀ for ∂f/∂v; about half '
                 'the arithmetic of the full 3×3 blocks, a change of rounding only), and the step takes the energy it '
                 'starts from out of its force pass (one pass over the springs fewer, the same bits): side by side '
                 'on hang64 at h = 1/1000, the step went from 2.22 to 2.12 ms with CG to 1e-6 and from 1.35 to 1.20 '
                 'ms with CG to Bullet\'s default of 3.45e-4 (the fastest of eight runs of each library, taken in '
                 'turn, on a noisy host). The block symmetric Gauss–Seidel above was tried again on 2026-11-30, '
                 'in the engine this time, as a quick prototype (Eisenstat\'s trick on the kept pairs, swept '
                 'whole, the true residual checked once the estimate was met) on hang64 at h = 1/1000: 6.2 '
                 'iterations a step against block Jacobi\'s 15.5 at a relative 3.45e-4, and 11.8 against 30.1 at '
                 '1e-6, but each iteration cost about three of block Jacobi\'s, so the step was slower (2.07 against '
                 '1.46 ms, 3.78 against 3.16 ms, one run after the other). Tighter code would bring that towards the two of '
                 'the prototype outside the engine, not further: each row of a sweep needs the row before it '
                 '(a chain of dependent 3×3 products, where the product\'s rows are independent), so the solve '
                 'would gain about 1.3×, the step at most about 1.2×, short of goal 7\'s 5× from 4.2×; not kept. '
                 'What did it, later on 2026-11-30: the conjugate gradient\'s passes over the particles with a '
                 'particle\'s three coordinates in one 256-bit register where the processor has AVX2 (asked at run '
                 'time; each lane in the scalar passes\' order and without fused multiply-adds, so the same bits, '
                 'which a golden test checks by forcing the scalar passes), its vectors padded to four doubles a '
                 'particle: hang64 at h = 1/1000 took 0.99–1.05 ms a step against 1.20–1.25 at 3.45e-4 and '
                 '1.62–1.80 against 2.21–2.43 ms at 1e-6 (the two libraries in turn, five pairs, each the fastest '
                 'of 30 runs of 100 steps). The springs\' Jacobians (a fifth of that step) were tried with their '
                 'four divisions (the direction\'s three and L/l) in one four-lane division, the same bits: no '
                 'faster (23.5 against 21.9 %% of the step in a profile), so the divider does not bound them; not '
                 'kept. Nor did wider registers help the pair product, on 2026-12-06: two pairs in one 512-bit '
                 'register where the processor has AVX-512 (each lane\'s products and sums as in the AVX2 pass, the '
                 'same bits, no fused multiply-adds) made hang64\'s step at h = 1/1000 slower, 2.11–2.16 ms against '
                 '1.78–1.91 at 1e-6 (three runs of each in turn), likely because 512-bit operations issue on two ports '
                 'of this Xeon instead of three and the shuffles that set out the two pairs\' blocks take one of them; not kept. '
                 'Two threads for the direct solver\'s factorization, counted on hang64\'s tree of supernodes the '
                 'same day (built afterwards, README "Or directly"; its figure is goal 1\'s row): the approximate '
                 'minimum degree order leaves the tree lopsided. The root '
                 'supernode (100 block columns) holds 14 %% of the flops, the subtrees under it 61, 20 and 6 %%, and '
                 'the largest of those splits into 34 and 17 %% under a supernode of 10 %%. With each supernode on one '
                 'thread, started once its children are done, two threads could at best take 0.64 of the time '
                 '(1.55× faster): a step of about 3.6 ms, still above goal 1\'s 3 ms unless the largest supernodes\' '
                 'own products are shared between the threads as well.'
                 % (direct64['detail'].split(';')[0] if direct64 and direct64['detail'] else 'see the table',
                    factorization_rate(direct64), roof_sentence(rows, direct64),
                    ' (%.0f iterations a step at 1e-6)' % cg_tol['cg_iterations'] if cg_tol else ''))
    lines.append('')
    tick = 1000.0 / 60.0
    mg_one = find(rows, 'threads', 'implicit_euler multigrid 1 thread', 128)
    mg_two = find(rows, 'threads', 'implicit_euler multigrid 2 threads', 128)
    springs_node = node.get('cloth 128 springs auto')
    if mg_one and mg_two:
        mg_text = ('the multigrid\'s step of the bench\'s 128² spring cloth alone (goal 6\'s case, to a relative '
                   '1e-6) took %s ms on one thread and %s on two in this run, %.1f and %.1f ticks'
                   % (ms(mg_one['ms_min']), ms(mg_two['ms_min']), mg_one['ms_min'] / tick, mg_two['ms_min'] / tick))
    else:
        mg_text = 'the multigrid\'s step of the 128² cloth takes several ticks (the Cloth table)'
    node_text = ''
    if springs_node:
        ran = springs_node['integrators'].split(' (')[0]
        node_text = (' In the node (goal 3\'s row) the spring cloth\'s status said `%s`, and a tick took %s ms.'
                     % (ran, ms(springs_node['tick_ms_median'])) if ran else
                     ' In the node (goal 3\'s row) a tick of the spring cloth took %s ms.'
                     % ms(springs_node['tick_ms_median']))
    lines.append('What is left for goal 3, a 128² cloth in real time at 60 Hz, a tick of 16.7 ms: since '
                 '2026-12-03 `auto` hands such a cloth to the multigrid after its first hard step (README, "Or by '
                 'multigrid"), some 13 iterations a step since the cycle of 2026-12-07 (20 with the V-cycle before; '
                 '13.5 on the node bench\'s cloth with the Chebyshev smoother of that evening, 15.3 before) '
                 'where block Jacobi\'s CG needs some 500 (the Cloth table). '
                 'Still, ' + mg_text + '.' + node_text + ' In a profile of that step on one thread (2026-12-05, '
                 'with the V-cycle; on the AMD EPYC host of 2026-12-07 the setup was about half of it until the '
                 'vector registers were kept clean at 10:26 UTC, which halved the step) the '
                 'setup takes about a quarter, the 6 × 6 level\'s products about a fifth, the springs\' pair '
                 'products an eighth and the finest level\'s restriction and prolongation a tenth; with neither the '
                 'bytes nor the arithmetic of the largest part bounding it (above), no factor of four or more is in '
                 'sight from this solver. A method whose matrix does not change from step to step would: projective dynamics '
                 '(Bouaziz et al. 2014), where each step alternates a local projection of every spring onto its '
                 'rest length with a global solve whose matrix, M/h² + Σ k (e_i − e_j)(e_i − e_j)ᵀ, is one '
                 'scalar matrix for x, y and z, factored once. Counted outside the engine on 2026-11-30 (Eigen\'s '
                 'SimplicialLDLT, one thread) for the node bench\'s 128² spring cloth (97 026 structural, shear '
                 'and bend springs): 1.13 million entries in the factor (69 a row), factored in 105 ms; one '
                 'local-global iteration (every projection, then the three solves) 5.5 ms, and 1.3 ms at 64². '
                 'So three iterations fit in a tick at 60 Hz on one thread, about five on two (the three solves '
                 'are independent). But so few leave the step far from the backward Euler it converges to: on the '
                 '64² cloth released from horizontal (pins as attachments of '
                 'weight 1e8, no damping), after 1 s, 3, 5 and 10 iterations a step gave a sag of 0.63, 0.46 and '
                 '0.35 m against 0.37 m with 400, and peak strains of 0.35, 0.31 and 0.26 against 0.32; '
                 'Chebyshev acceleration (Wang 2015, ρ from 0.99 to 0.9999 from the first iteration) blew up at '
                 '3 to 10 iterations. Real time that way would cost accuracy that the page would have to report '
                 'beside it; not built.')
    lines.append('')
    if stopping:
        lines.append('## The stopping rule')
        lines.append('')
        lines.append('Every CG scene of this bench, from rest, implicit Euler with CG and the default stopping rule '
                     '(`cg_velocity_tolerance` 1e-5 m/s or `cg_tolerance` 1e-8, whichever comes first; README '
                     '"Ropes, spring networks and integrators"), with no cap in practice: the iterations the rule needs, the steps '
                     'it would leave unconverged at the default `cg_max_iterations` of 500, and the worst '
                     'velocity error. The rule asks for the same accuracy of the velocities at any size and step, '
                     'so its iterations follow the conditioning of the system: they grow with the side of a '
                     'cloth and the length of a rope at dt = 1/60, and fall to about a dozen at dt = 1/1000, where '
                     'the warm start is nearly the answer. Each scene then runs the same steps again at every '
                     'default: the linear solver `auto` (direct from the start for a rope; for a cloth, CG, past the '
                     'cap of 500 if need be, until a solve costs more iterations than a factorization, and then '
                     'direct, the step that CG gave up solved again directly and its iterations counted). The '
                     'detail counts the steps that ended unconverged there and those solved directly.')
        lines.append('')
        lines.append('| scene | size | particles | ms per step (one run) | CG iterations per step (mean) | detail |')
        lines.append('|---|---|---|---|---|---|')
        for r in stopping:
            lines.append('| %s | %d | %d | %s | %.0f | %s |' % (r['variant'], r['size'], r['elements'],
                                                               ms(r['ms_min']), r['cg_iterations'], r['detail']))
        lines.append('')
    lines.append('## Explicit springs and the memory roof')
    lines.append('')
    if triad:
        lines.append('Triad bandwidth `a[i] = b[i] + s c[i]`: %.1f GB/s (%s).' % (triad[0]['ms_min'], triad[0]['detail']))
        lines.append('')
    lines.append('A symplectic Euler step of an n × n spring cloth at half its stability limit, one force pass a '
                 'step: the blow-up guard\'s energy after the step comes out of the pass that evaluates the end '
                 'state\'s forces, which the next step takes (README, "Stability on hard cases"), so no pass over '
                 'the springs is the guard\'s alone; on one thread that pass also sums the springs\' energies, chunk '
                 'by chunk, and stores none of them. The floor is the 40-byte spring record read once at the triad '
                 'bandwidth; the step also integrates (into the arrays of the state it may roll back to, which are then '
                 'swapped with the state: no pass to save it), applies the pins and sums the kinetic and gravity '
                 'energies (passes over the particles), so it is further from the '
                 'floor than the force pass alone, which the bench times on its own as well (the force evaluation '
                 'of gravity and every spring on the state the steps left, without the energy the step\'s pass '
                 'also sums).')
    lines.append('')
    lines.append('| n | springs | ms per step, min (median–max) | per spring |')
    lines.append('|---|---|---|---|')
    for r in springs:
        lines.append('| %d | %d | %s | %s |' % (r['size'], r['elements'], spread(r), r['detail']))
    lines.append('')
    lines.append('What bounds the force pass (2026-12-06, outside the bench: a driver stepping this cloth with the '
                 'pass replaced by a changed copy, one run of each, in turn). Not the divider: the direction\'s three '
                 'divisions replaced by one reciprocal and three products (a change of rounding) left the step where '
                 'it was (64²: 7.19 and 7.29 against 7.03 and 7.21 ns a spring; 256²: 7.36 and 7.47 against 7.50 and '
                 '7.83). Nor the chain of additions into a particle\'s force (five of a cloth point\'s six springs '
                 'start at it, one after the other): summing a run of springs that share their end i in registers, '
                 'stored once a run (the same bits), made it no faster (64²: 7.19 and 7.22 against 7.03 and 7.27 ns; '
                 '256²: 8.2 and 8.4 against 7.8 and 7.9). At 64², where springs and particles fit in the second-level '
                 'cache, the pass alone takes 5.1 ns a spring, some 13 cycles at 2.6 GHz, with two springs in the '
                 'lanes of 128-bit registers and every coordinate loaded and added alone: what is left is most '
                 'likely the instructions it issues, so the way to 2× the floor is fewer of them a spring (wider '
                 'registers, a particle\'s coordinates loaded at once) and the passes over the particles folded into '
                 'the force pass. Since 2026-12-07 the pass takes four springs at a time in AVX2\'s lanes where the '
                 'processor has it (README, "The explicit force pass": two particles\' first two coordinates in one '
                 'register, the third by broadcasts and blends, end i\'s force in registers, each chunk\'s '
                 'energies summed as it goes; the same bits): side by side with the two-lane pass, 6.6–7.0 against '
                 '8.6–8.9 ns a step and spring at 64², 7.4–7.9 against 9.7–10.7 ns at 256² (one thread). The '
                 'divider still does not bound it (one division and three products instead of three divisions: '
                 'no faster), nor does end i in registers alone. Since the evening of 2026-12-07 each end\'s three '
                 'coordinates come in with one masked load, the four forces go out as (x, y, z, 0) a register and '
                 'are read back from the force array in the two pieces they were stored in, so that the read takes '
                 'its numbers from the stores just before it (read whole, it waited for both stores to reach the '
                 'cache, and the pass with fewer instructions was no faster); the passes over the particles are '
                 'written out on the arrays\' numbers (README, "The explicit force pass"; the same bits): the '
                 'pass alone 0.85–0.89 of the time before at 64² and 0.88–0.90 at 256² (a driver calling the two '
                 'passes in turn), 38 % fewer instructions in the pass and 0.95 of them in the step (callgrind). '
                 'What is left to 2× the floor: the pass issues some 56 instructions a spring.')
    lines.append('')
    collision_rows = [r for r in rows if r['case'] == 'selfcollision']
    if collision_rows:
        lines.append('## Self-collision (issue 15)')
        lines.append('')
        lines.append('What the self-collision pass (`SelfCollisionSolver`, README "Self-collision") costs beside the '
                     'rest of the step. Each scene\'s bodies are stepped as `World::step` steps them, then the pass runs '
                     'over them; both parts are timed on their own over the same steps, so the share is measured on one '
                     'trajectory. A 64 × 64 spring cloth, 1 m, 1 kg, no pins, implicit Euler at dt = 1/60 with the '
                     'default stopping rule, thickness 5 mm: falling freely (no pair within reach; the candidates of '
                     'its first step serve every later one, so the pass is the check that they still cover every path '
                     'and one test of each candidate pair), and dropped on a sphere of radius 0.25 m and draped over it onto '
                     'the ground (timed from 1.2 s on), and folded in half on the ground as the self-collision tests fold '
                     'theirs, its upper half lying on its lower half (timed from 0.2 s on). The pile is `config/scenes/cloth_pile.yaml` rebuilt in code: '
                     'five 17 × 17 cloths landing on each other on the sphere, implicit Euler with CG at dt = 0.005 '
                     '(timed from 0.5 s on). "candidate searches" counts the broad phase\'s searches per step (below 1: '
                     'the candidates of an earlier step served). Issue 15\'s target: at 64², the pass costs at most '
                     'as much as the rest of the step.')
        lines.append('')
        lines.append('| scene | particles | ms per step, min (median–max) | pass [ms per step] | pass share of the '
                     'step | pass / rest (target ≤ 1 at 64²) | per step |')
        lines.append('|---|---|---|---|---|---|---|')
        for r in collision_rows:
            m = re.match(r'pass ([^ ]+) ms per step, ([^ ]+) % of the step, ([^ ]+)x the rest; per step (.*)',
                         r['detail'])
            if m:
                lines.append('| %s | %d | %s | %.3g | %.0f %% | %.2f | %s |' % (
                    r['variant'], r['elements'], spread(r), float(m.group(1)), float(m.group(2)),
                    float(m.group(3)), m.group(4)))
            else:
                lines.append('| %s | %d | %s | | | | %s |' % (r['variant'], r['elements'], spread(r), r['detail']))
        lines.append('')
    thread_rows = [r for r in rows if r['case'] == 'threads']
    if thread_rows:
        lines.append('## Threads (goal 6)')
        lines.append('')
        lines.append('The spring cloth of "Cloth" (structural, shear and bend springs; two corners pinned) at 128² and '
                     '256², stepped from rest by one thread and by two (`WorkerPool`, README "Threads") over the same '
                     'steps; the two runs must end in the same bits. Verlet at dt = 1/60 with the substeps its '
                     'stability needs (191 at 128², more than the default cap of 64, so `auto` runs implicit Euler '
                     'there), and symplectic Euler at half its limit (one force pass a step)%s. The two bodies\' '
                     'repeats '
                     'alternate (one thread, two threads, one, ...), so that load on the other core slows both alike. '
                     'This machine has 2 cores; the ratio is min against min. Each thread takes its home range of '
                     'every loop\'s chunks first (thread t of T: the t-th of T equal runs), so that the particles it '
                     'integrates stay in its core\'s cache; run side by side with the earlier queue of chunks, this '
                     'raised symplectic Euler at 128² from 1.53–1.57× to 1.80–1.88× and Verlet from 1.55–1.74× to '
                     '1.99–2.02× (two runs of each build in turn, 2026-11-28).' % implicit_methods_text(thread_rows))
        lines.append('')
        if ceiling:
            lines.append('Before and after the cloths, the bench measures %s. On this virtual machine the '
                         'round trip has been 100 ns at some hours and 1100 ns at others (2026-11-29), and two '
                         'threads of the cloth step ran from 1.7× as fast as one to slower than one with it: the '
                         'host decides where the two vCPUs run. At some hours one vCPU is slower than the other: on '
                         '2026-12-08 the 128² symplectic step alone took 0.68–0.73 ms on one and 0.49 ms on the other '
                         '(each process held on one with taskset), and the slower one changed within minutes. A '
                         'loop cut in equal halves then waits for the slower, and two threads can be at most '
                         '2 / 1.4 = 1.43× as fast as one on the faster vCPU; a fixed uneven cut (58 %% of the '
                         'particles to the stepping thread) gained 4 %% in one such spell, but which vCPU is the '
                         'slower is not known in advance, so the cut stays even.' % ceiling)
            lines.append('')
        lines.append('| method | n | ms per step at 1 thread, min (median–max) | at 2 threads | speed-up, end state |')
        lines.append('|---|---|---|---|---|')
        for r in thread_rows:
            if not r['variant'].endswith(' 2 threads'):
                continue
            one = find(rows, 'threads', r['variant'].replace(' 2 threads', ' 1 thread'), r['size'])
            lines.append('| %s | %d | %s | %s | %s |' % (r['variant'].replace(' 2 threads', ''), r['size'],
                                                        spread(one) if one else '—', spread(r), r['detail']))
        lines.append('')
    if node:
        lines.append('## The node (goals 3 and 4)')
        lines.append('')
        lines.append('`particle_sim_node` at ~rate 60 Hz under a roscore of its own, measured from outside by '
                     '`particle_sim_node_probe` (scripts/node_bench.py runs both): it subscribes to the topics below '
                     'with their real types, so every message is received and deserialised as rviz would, and reads '
                     '/clock against the wall clock. The real-time factor is the one reached (sim time over wall time '
                     'after a warm-up), with its one-second windows; the wall time between ticks should be 16.7 ms. '
                     'The node, the probe and roscore share the machine\'s cores. The loop makes up a late tick, '
                     'up to ~max_lag (0.5 s; README "Time"), so a factor above 1 is lag from before the window made '
                     'up within it. An emitter\'s marker points are written by the publishing thread from a snapshot '
                     'that the tick\'s last step took of the particles, and that thread sends the messages at a '
                     'lower priority than the physics (README "Publishing"); the rows with `publishing_thread false` '
                     'build and send everything on the physics thread, for comparison.')
        lines.append('')
        lines.append('| case | particles | real-time factor (1-s windows) | wall ms between ticks, min (median–max) | '
                     'topics: rate, points per message | integrator |')
        lines.append('|---|---|---|---|---|---|')
        for r in rows:
            if r['case'] != 'node':
                continue
            f = node_figures(r)
            topics = ', '.join('%s %.3g Hz × %d' % (t, f[t + '_hz'], f[t + '_points'])
                               for t in ('markers', 'meshes', 'points') if t + '_hz' in f)
            lines.append('| %s | %d | %.3f (%.3f–%.3f) | %s | %s | %s |'
                         % (r['variant'], r['elements'], f['rtf'], f['rtf_window_min'], f['rtf_window_max'],
                            spread(r), topics, f['integrators'] if f['integrators'] != '-' else '—'))
        lines.append('')
    lines.append('## Emitters')
    lines.append('')
    lines.append('![emitters](%s/emitters.png)' % rel)
    lines.append('')
    lines.append('A fountain holding N live particles (rate N / lifetime), stepped at dt = 1/60 on one thread (a world of '
                 'more threads shares its motion and collisions between them: README "Threads").')
    lines.append('')
    lines.append('| live particles | ms per step, min (median–max) | throughput |')
    lines.append('|---|---|---|')
    for r in emitter_rows:
        lines.append('| %d | %s | %s |' % (r['elements'], spread(r), r['detail']))
    e = fitted_exponent(emitter_rows)
    if e is not None:
        lines.append('')
        lines.append('Fitted exponent: %.2f.' % e)
    lines.append('')
    with open(args.doc, 'w') as f:
        f.write('\n'.join(lines))
    print('performance_report.py: wrote %s (%d rows)' % (args.doc, len(rows)))


if __name__ == '__main__':
    main()
