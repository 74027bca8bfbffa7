#!/usr/bin/env python3
"""The node bench of issue 13, goals 3 and 4: particle_sim_node measured through ROS.

    node_bench.py --devel DEVEL --out CSV [--warmup S] [--duration S] [--only TEXT]

For each case it starts a roscore of its own on a free port, the node at ~rate 60 Hz with the
case's scene (written to a temporary folder, printed below), and particle_sim_node_probe, which
subscribes to the case's topics with their real message types (every message received and
deserialised, as rviz would) and reads /clock against the wall clock. The probe waits `warmup`
seconds after the first /clock, then measures for `duration` seconds: the real-time factor the node
reaches (sim time over wall time, and its one-second windows), each topic's rate and points per
message, and the wall time between ticks. One CSV row per case (the columns of particle_sim_perf's
CSV: case "node"), which scripts/performance_report.py turns into goals 3 and 4 and the page's
"Node" section.

Cases:
  - fountain 1e6: one fountain of 10^6 live particles (dt = 1/60), one marker subscriber (goal 4);
  - fountains 10 x 1e5: ten fountains of 10^5 each, one marker subscriber (goal 4, many bodies);
  - the same two with ~publishing_thread false, for what the publishing thread is worth;
  - cloth 128 springs / baraff_witkin: a 128 x 128 cloth of the core's default constants, hanging
    by two corners, integrator auto at dt = 1/60, marker and mesh subscribers (goal 3).
"""
import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import time
import xmlrpc.client

RATE = 60.0
DT = '0.0166666666666666667'


def free_port():
    # A port for our own roscore, from scripts/free_port.py beside this script (helpers.bash runs it too).
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'free_port.py')
    return int(subprocess.check_output([sys.executable, script]))


def fountains(count, particles):
    """A scene of `count` fountains of `particles` live particles each (rate x lifetime)."""
    lines = ['world:', '  gravity: [0, 0, -9.81]', '  dt: ' + DT, '  seed: 7',
             '  max_particles_per_body: %d' % particles,
             '  ground: {enabled: true, height: 0.0, restitution: 0.4, friction: 0.3}', 'bodies:']
    for i in range(count):
        lines += ['  - name: fountain%d' % i, '    kind: emitter', '    type: fountain',
                  '    origin: [%d, %d, 0]' % (2 * (i % 5), 2 * (i // 5)),
                  '    rate: %d' % (particles // 2), '    speed: 9', '    spread: 1.0', '    lifetime: 2.0',
                  '    max_particles: %d' % particles]
    return '\n'.join(lines) + '\n'


def cloth(model, n):
    """An n x n cloth of the model's default constants, hanging from two corners, integrator auto."""
    return '\n'.join([
        'world:', '  gravity: [0, 0, -9.81]', '  dt: ' + DT, '  integrator: auto',
        '  ground: {enabled: true, height: 0.0, restitution: 0.1, friction: 0.5}', 'bodies:',
        '  - name: cloth', '    kind: cloth', '    model: ' + model, '    origin: [-0.75, 0, 2.5]',
        '    edge_u: [1.5, 0, 0]', '    edge_v: [0, 1.5, 0]', '    resolution: [%d, %d]' % (n, n),
        '    pins: [corner_00, corner_10]']) + '\n'


# (variant, size, particles, scene, topics, extra node parameters)
CASES = [
    ('fountain 1e6', 1000000, 1000000, fountains(1, 1000000), 'markers', []),
    ('fountains 10 x 1e5', 1000000, 1000000, fountains(10, 100000), 'markers', []),
    ('fountain 1e6 publishing_thread false', 1000000, 1000000, fountains(1, 1000000), 'markers',
     ['_publishing_thread:=false']),
    ('fountains 10 x 1e5 publishing_thread false', 1000000, 1000000, fountains(10, 100000), 'markers',
     ['_publishing_thread:=false']),
    ('cloth 128 springs auto', 128, 128 * 128, cloth('springs', 128), 'markers,meshes', []),
    ('cloth 128 baraff_witkin auto', 128, 128 * 128, cloth('baraff_witkin', 128), 'markers,meshes', []),
]


def wait_for_master(uri, seconds=30.0):
    master = xmlrpc.client.ServerProxy(uri)
    end = time.time() + seconds
    while time.time() < end:
        try:
            master.getPid('/node_bench')
            return True
        except OSError:
            time.sleep(0.1)
    return False


def parse_probe(line):
    """The probe's key=value line; `integrators` takes the rest of the line (it has spaces)."""
    head, _, integrators = line.partition(' integrators=')
    values = dict(item.split('=', 1) for item in head.split())
    values['integrators'] = integrators.strip()
    return values


def run_case(devel, work, variant, scene, topics, params, warmup, duration):
    scene_path = os.path.join(work, variant.replace(' ', '_') + '.yaml')
    with open(scene_path, 'w') as f:
        f.write(scene)
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % port, ROS_HOSTNAME='127.0.0.1',
               ROS_LOG_DIR=os.path.join(work, 'ros_log'))
    env.pop('ROS_IP', None)
    logs = open(os.path.join(work, 'logs.txt'), 'a')
    processes = [subprocess.Popen(['roscore', '-p', str(port)], env=env, stdout=logs, stderr=subprocess.STDOUT,
                                  start_new_session=True)]
    try:
        if not wait_for_master(env['ROS_MASTER_URI']):
            raise RuntimeError('roscore did not start')
        processes.append(subprocess.Popen(
            [os.path.join(devel, 'lib/particle_sim/particle_sim_node'), '__name:=particle_sim',
             '_scene:=' + scene_path, '_rate:=%g' % RATE, '_status_period:=0'] + params,
            env=env, stdout=logs, stderr=subprocess.STDOUT, start_new_session=True))
        probe = subprocess.run(
            [os.path.join(devel, 'lib/particle_sim/particle_sim_node_probe'), '--topics', topics,
             '--warmup', str(warmup), '--duration', str(duration)],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
            timeout=warmup + duration + 120)
        if probe.returncode != 0:
            raise RuntimeError('the probe failed: ' + probe.stderr.strip())
        return parse_probe(probe.stdout.strip().splitlines()[-1])
    finally:
        for p in reversed(processes):
            try:
                os.killpg(p.pid, 2)
                p.wait(timeout=20)
            except (ProcessLookupError, subprocess.TimeoutExpired):
                os.killpg(p.pid, 9)
        logs.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--devel', required=True, help="the catkin devel space (particle_sim's binaries)")
    parser.add_argument('--out', required=True, help='the CSV to write')
    parser.add_argument('--warmup', type=float, default=5.0)
    parser.add_argument('--duration', type=float, default=15.0)
    parser.add_argument('--only', default='', help="run only the cases whose name contains TEXT (e.g. 'cloth')")
    args = parser.parse_args()
    cases = [case for case in CASES if args.only in case[0]]
    if not cases:
        parser.error('no case contains %r: %s' % (args.only, ', '.join(case[0] for case in CASES)))
    work = tempfile.mkdtemp(prefix='particle_sim_node_bench.')
    rows = []
    failed = False
    try:
        for k, (variant, size, particles, scene, topics, params) in enumerate(cases):
            print('node bench %d/%d: %s (%s)' % (k + 1, len(cases), variant, topics), flush=True)
            try:
                v = run_case(args.devel, work, variant, scene, topics, params, args.warmup, args.duration)
            except (RuntimeError, subprocess.TimeoutExpired) as error:
                print('  failed: %s (logs: %s)' % (error, work), file=sys.stderr)
                failed = True
                continue
            detail = ' '.join('%s=%s' % (key, v[key]) for key in sorted(v) if key != 'integrators')
            detail += ' integrators=' + v['integrators']
            print('  ' + detail, flush=True)
            rows.append(['node', variant, size, particles, v['tick_ms_min'], v['tick_ms_median'], v['tick_ms_max'], 0,
                         detail])
    finally:
        if not failed:
            shutil.rmtree(work, ignore_errors=True)
    with open(args.out, 'w', newline='') as f:
        writer = csv.writer(f)
        writer.writerow(['case', 'variant', 'size', 'elements', 'ms_min', 'ms_median', 'ms_max', 'cg_iterations',
                         'detail'])
        writer.writerows(rows)
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
