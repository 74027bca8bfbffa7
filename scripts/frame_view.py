#!/usr/bin/env python3
"""Writes an rviz configuration whose camera frames a scene's bodies at a given moment.

    frame_view.py --run PARTICLE_SIM_RUN --scene SCENE.yaml --seconds T \
                  --template config/particle_sim.rviz --out view.rviz

Runs the scene offline (particle_sim_run) for T seconds of sim time, takes every live particle of
the final state and every sphere collider of the scene, and points rviz's orbit camera at them:
the focal point is the middle of their robust bounding box (per axis, the points between the
`trim` and 1 - `trim` quantiles, so stray emitter particles scattered over the ground do not
shrink the rest), and the distance is the one at which the
sphere around that box just fits the vertical field of view. Prints "distance x y z steps" on
stdout: the camera [m] and the number of physics steps that make those seconds (for ~step).
"""
import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile

import yaml


def percentile(values, fraction):
    ordered = sorted(values)
    if not ordered:
        return 0.0
    position = fraction * (len(ordered) - 1)
    low = math.floor(position)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (position - low)


def final_positions(run, scene, seconds):
    """Positions [m] of every live particle after `seconds` of sim time, and the steps that took."""
    with tempfile.TemporaryDirectory() as folder:
        states = os.path.join(folder, "states.csv")
        # --every larger than any step count: the initial and the final state only.
        summary = subprocess.run([run, scene, "--duration", str(seconds), "--output", states, "--every",
                                  str(2**62)], check=True, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                 universal_newlines=True).stdout
        steps = int(re.search(r"^steps (\d+)", summary, re.M).group(1))
        with open(states, newline="") as handle:
            rows = list(csv.DictReader(handle))
    if not rows:
        return [], steps
    last_time = max(float(row["time"]) for row in rows)
    return [(float(r["x"]), float(r["y"]), float(r["z"])) for r in rows if float(r["time"]) == last_time], steps


def sphere_points(scene):
    """The six extreme points of every sphere collider of the scene file [m]."""
    with open(scene) as handle:
        data = yaml.safe_load(handle) or {}
    points = []
    for sphere in (data.get("world") or {}).get("spheres") or []:
        center, radius = sphere.get("center", [0, 0, 0]), float(sphere.get("radius", 0))
        for axis in range(3):
            for sign in (-1.0, 1.0):
                point = [float(c) for c in center]
                point[axis] += sign * radius
                points.append(tuple(point))
    return points


def has_emitters(scene):
    with open(scene) as handle:
        data = yaml.safe_load(handle) or {}
    return any((body or {}).get("kind") == "emitter" for body in data.get("bodies") or [])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", required=True, help="the particle_sim_run executable")
    parser.add_argument("--scene", required=True, help="scene file")
    parser.add_argument("--seconds", type=float, required=True, help="sim time of the picture [s]")
    parser.add_argument("--template", required=True, help="rviz configuration to copy")
    parser.add_argument("--out", required=True, help="rviz configuration to write")
    parser.add_argument("--fill", type=float, default=0.9, help="fraction of the view's height the bodies fill")
    parser.add_argument("--trim", type=float, default=None,
                        help="fraction of points left out at each end of each axis (default: 0.15 for scenes "
                             "with emitters, whose spray scatters far over the ground; 0.02 otherwise)")
    args = parser.parse_args()

    if args.trim is None:
        args.trim = 0.15 if has_emitters(args.scene) else 0.02
    particles, steps = final_positions(args.run, args.scene, args.seconds)
    points = particles + sphere_points(args.scene)
    if not points:
        points = [(0.0, 0.0, 0.0)]
    low = [percentile([p[axis] for p in points], args.trim) for axis in range(3)]
    high = [percentile([p[axis] for p in points], 1 - args.trim) for axis in range(3)]
    center = [(a + b) / 2 for a, b in zip(low, high)]
    radius = max(0.25, 0.5 * math.dist(low, high))

    with open(args.template) as handle:
        config = handle.read()
    fov = float(re.search(r"^      Field of View: ([0-9.]+)$", config, re.M).group(1))
    # The sphere of `radius` around the centre spans `fill` of the view's height.
    distance = radius / math.sin(args.fill * fov / 2)

    config = re.sub(r"^      Distance: .*$", f"      Distance: {distance:.3f}", config, flags=re.M)
    focal = "      Focal Point:\n" + "".join(f"        {name}: {value:.3f}\n" for name, value in zip("XYZ", center))
    config = re.sub(r"^      Focal Point:\n        X: .*\n        Y: .*\n        Z: .*\n", focal, config, flags=re.M)
    with open(args.out, "w") as handle:
        handle.write(config)
    print(f"{distance:.3f} {center[0]:.3f} {center[1]:.3f} {center[2]:.3f} {steps}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
