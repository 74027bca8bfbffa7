#!/usr/bin/env python3
"""rostest: the real command-line tools against the real node, the way a user types them.

1. `rostopic echo -n 1` on every topic the node publishes (the master's list, which must hold the
   documented ones: markers, meshes, status, diagnostics, clock, tf, dynamic_reconfigure's).
2. `rosservice call` on every service the node offers, with a good request (success: True) and a
   bad one (success: False and a message naming what is wrong); after every bad request the node
   still answers `rosnode ping`, and at the end it still publishes its status.
3. `rosrun particle_sim EXECUTABLE --help` for every executable of the package: exit 0 and a usage.

A missing Python message package (python3-*-msgs) makes rostopic or rosservice fail here; an
executable rosrun cannot find (a devel space inside the package's build/) makes step 3 fail.
"""
import math
import os
import subprocess
import sys
import time
import unittest

import rosgraph
import rostest
import yaml

PKG = "particle_sim"
NS = "/particle_sim"
ENV = dict(os.environ, PATH="/usr/bin:" + os.environ.get("PATH", ""))

# Topic -> text that one message of it must contain (rostopic echo's YAML).
TOPICS = {
    NS + "/markers": 'ns: "fountain"',
    NS + "/meshes": "triangles:",
    NS + "/status": 'name: "sheet"',
    NS + "/points": "name: \"particle\"",
    "/diagnostics": "simulation",
    "/clock": "clock:",
    "/tf": "transforms:",
    NS + "/parameter_descriptions": "groups:",
    NS + "/parameter_updates": "doubles:",
}
SERVICES = ["spawn_emitter", "spawn_rope", "spawn_cloth", "spawn_jelly", "set_wind", "set_spring_constants",
            "pin_particle", "unpin_particle", "remove_body", "step", "pause_physics", "unpause_physics", "reset",
            "set_parameters", "grasp", "release", "spawn_collider", "remove_collider"]
EXECUTABLES = {"particle_sim_node", "particle_sim_run", "particle_sim_bench", "particle_sim_perf", "particle_sim_node_probe"}
# Bullet's peer of the performance bench is built when CMake finds Bullet's headers (libbullet-dev,
# which scripts/common.sh installs), where this looks for them too.
if os.path.isfile("/usr/include/bullet/btBulletDynamicsCommon.h"):
    EXECUTABLES.add("particle_sim_bullet_peer")


def run(args, timeout=60.0):
    """Runs a command; returns (exit code, stdout + stderr)."""
    done = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=ENV, timeout=timeout,
                          universal_newlines=True)
    return done.returncode, done.stdout


class Cli(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        deadline = time.monotonic() + 60.0
        while time.monotonic() < deadline:
            code, out = run(["rosservice", "list"], timeout=20.0)
            if code == 0 and NS + "/set_wind" in out.split():
                return
            time.sleep(0.5)
        raise AssertionError("the node's services did not appear within 60 s")

    def assertAlive(self, after):
        code, out = run(["rosnode", "ping", "-c", "1", NS], timeout=30.0)
        self.assertEqual(code, 0, f"rosnode ping {NS} failed after {after}: {out}")
        self.assertIn("reply from", out, f"no reply from {NS} after {after}")

    def call(self, service, request):
        """rosservice call; returns the answer parsed from its YAML output."""
        code, out = run(["rosservice", "call", NS + "/" + service] + ([request] if request else []))
        self.assertEqual(code, 0, f"rosservice call {service} '{request}' failed: {out}")
        return yaml.safe_load(out)

    def good(self, service, request=""):
        answer = self.call(service, request)
        self.assertIs(answer["success"], True, f"{service} '{request}' was refused: {answer}")
        return answer

    def bad(self, service, request, names):
        answer = self.call(service, request)
        self.assertIs(answer["success"], False, f"{service} '{request}' was accepted: {answer}")
        self.assertIn(names, answer["message"], f"{service} '{request}': the message does not name '{names}'")
        self.assertAlive(f"{service} '{request}'")

    def test_1_echo_every_topic(self):
        publishers = {topic for topic, nodes in rosgraph.Master("/cli_test").getSystemState()[0] if NS in nodes}
        self.assertTrue(set(TOPICS) <= publishers, f"missing publications: {set(TOPICS) - publishers}")
        for topic in sorted(publishers):
            code, out = run(["rostopic", "echo", "-n", "1", topic], timeout=60.0)
            self.assertEqual(code, 0, f"rostopic echo -n 1 {topic} failed: {out}")
            self.assertIn(TOPICS.get(topic, "---"), out, f"rostopic echo -n 1 {topic}: unexpected output {out[:500]}")

    def test_2_call_every_service(self):
        offered = {name for name, nodes in rosgraph.Master("/cli_test").getSystemState()[2] if NS in nodes}
        ours = {name[len(NS) + 1:] for name in offered if not name.endswith(("/get_loggers", "/set_logger_level"))}
        self.assertEqual(ours, set(SERVICES), "services offered by the node differ from those this test calls")

        self.good("spawn_emitter", "{name: jet, type: fountain, rate: 50, max_particles: 100}")
        self.bad("spawn_emitter", "{name: bad_jet, type: fountain, rate: -5}", "rate")
        self.good("spawn_rope", "{name: cli_rope, particles: 5, start: {x: 0, y: 2, z: 2}, end: {x: 1, y: 2, z: 2}, "
                  "mass: 0.1, stretch_stiffness: 300, stretch_damping: 0.1, pins: [0]}")
        self.bad("spawn_rope", "{name: bad_rope, particles: 1, end: {x: 1}}", "particles")
        # A material as a user types it (README "Services", Materials), and one that clashes.
        self.good("spawn_rope", "{name: cli_nylon, start: {x: 0, y: 3, z: 2}, end: {x: 1, y: 3, z: 2}, pins: [0], "
                  "material: {preset: nylon_rope}}")
        self.bad("spawn_rope", "{name: bad_nylon, mass: 0.3, material: {preset: nylon_rope}}",
                 "material.preset = 'nylon_rope' and mass = 0.3 kg are both set")
        self.bad("spawn_cloth", "{name: bad_towel, edge_u: {x: 0.5}, edge_v: {y: 0.5}, material: {preset: towel}}",
                 "material.preset = 'towel' is not a cloth material preset; allowed: ")
        self.good("spawn_cloth", "{name: cli_cloth, origin: {x: 0, y: -2, z: 2}, edge_u: {x: 0.5}, edge_v: {y: 0.5}, "
                  "nu: 4, nv: 4, mass: 0.1, stretch_stiffness: 300, named_pins: [corner_00]}")
        self.bad("spawn_cloth", "{name: bad_cloth, edge_u: {x: 0.5}, edge_v: {y: 0.5}, nu: 1, nv: 4}",
                 "nu = 1 is out of range")
        self.good("spawn_jelly", "{name: cli_jelly, origin: {x: -2, y: -2, z: 0.5}, size: {x: 0.2, y: 0.2, z: 0.2}, "
                  "nx: 2, ny: 2, nz: 2, mass: 0.1, stretch_stiffness: 200}")
        self.bad("spawn_jelly", "{name: bad_jelly, size: {x: 0, y: 0.2, z: 0.2}, nx: 2, ny: 2, nz: 2}", "size")
        self.good("set_wind", "{wind: {x: 1, y: 0, z: 0}}")
        self.bad("set_wind", "{wind: {x: .nan, y: 0, z: 0}}", "wind")
        self.good("set_spring_constants", "{body: line, spring_class: stretch, stiffness: 400, damping: 0.2}")
        self.bad("set_spring_constants", "{body: nobody, spring_class: stretch, stiffness: 400, damping: 0.2}",
                 "nobody")
        pinned = self.good("pin_particle", "{body: line, index: 7, target: 1, point: {x: 0, y: 1, z: 2.5}}")
        self.assertEqual(pinned["index"], 7)
        pinned = self.good("pin_particle", "{body: line, index: 4, target: 2, frame: gripper}")
        self.assertEqual(pinned["index"], 4)
        self.bad("pin_particle", "{body: line, index: 99, target: 0}", "99")
        self.good("unpin_particle", "{body: line, index: 7}")
        self.bad("unpin_particle", "{body: line, index: 99}", "99")
        grasped = self.good("grasp", "{name: hand, body: line, frame: gripper, region: 2, count: 2}")
        self.assertEqual(grasped["captured"], 2)
        self.bad("grasp", "{name: bad_hand, frame: gripper, region: 0, radius: 0}", "radius = 0")
        self.assertEqual(self.good("release", "{name: hand}")["released"], 2)
        self.bad("release", "{name: nobody}", "nobody")
        self.good("spawn_collider", "{name: cli_table, shape: box, pose: {position: {x: 3, y: 3, z: 0.4}}, "
                  "size: {x: 0.6, y: 0.4, z: 0.05}, friction: 0.5}")
        self.bad("spawn_collider", "{name: cli_rod, shape: capsule, length: 0.3, radius: 0}", "radius = 0")
        self.good("remove_collider", "{name: cli_table}")
        self.bad("remove_collider", "{name: cli_table}", "cli_table")
        self.good("remove_body", "{name: jet}")
        self.bad("remove_body", "{name: nobody}", "nobody")

        # step is refused while running, answers the new sim time while paused.
        self.bad("step", "{steps: 10}", "pause_physics")
        self.good("pause_physics")
        before = self.good("step", "{steps: 10}")["sim_time"]
        after = self.good("step", "{steps: 10}")["sim_time"]
        self.assertAlmostEqual(after - before, 10 * 0.002, delta=1e-9)
        self.bad("step", "{steps: 0}", "steps")
        self.good("unpause_physics")
        self.good("reset")
        # Trigger services take no field: rosservice itself refuses one, and the node is untouched.
        for service in ("pause_physics", "unpause_physics", "reset"):
            code, out = run(["rosservice", "call", NS + "/" + service, "{foo: 1}"])
            self.assertNotEqual(code, 0, f"rosservice call {service} '{{foo: 1}}' was accepted: {out}")
            self.assertAlive(f"{service} '{{foo: 1}}'")

        # dynamic_reconfigure: a value in range is applied; one outside is clamped to the range that
        # ~parameter_descriptions publishes.
        answer = self.call("set_parameters", "{config: {doubles: [{name: wind_y, value: 2.0}]}}")
        doubles = {d["name"]: d["value"] for d in answer["config"]["doubles"]}
        self.assertEqual(doubles["wind_y"], 2.0)
        code, out = run(["rostopic", "echo", "-n", "1", NS + "/parameter_descriptions"], timeout=60.0)
        descriptions = yaml.safe_load(out.split("\n---")[0])
        highest = {d["name"]: d["value"] for d in descriptions["max"]["doubles"]}["wind_y"]
        answer = self.call("set_parameters", "{config: {doubles: [{name: wind_y, value: 1000000.0}]}}")
        doubles = {d["name"]: d["value"] for d in answer["config"]["doubles"]}
        self.assertTrue(math.isfinite(doubles["wind_y"]) and doubles["wind_y"] == highest,
                        f"wind_y 1e6 gave {doubles['wind_y']}, expected the range's maximum {highest}")
        self.assertAlive("set_parameters wind_y 1e6")

        # Still simulating: the status lists the scene's bodies and those spawned above.
        code, out = run(["rostopic", "echo", "-n", "1", NS + "/status"], timeout=60.0)
        self.assertEqual(code, 0, out)
        for body in ("fountain", "line", "sheet", "cube", "cli_rope", "cli_cloth", "cli_jelly"):
            self.assertIn(f'name: "{body}"', out)
        self.assertNotIn('name: "jet"', out)

    def test_3_rosrun_every_executable_with_help(self):
        code, out = run(["catkin_find", "--without-underlays", "--libexec", PKG])
        self.assertEqual(code, 0, out)
        found = set()
        for folder in out.split():
            for name in os.listdir(folder):
                path = os.path.join(folder, name)
                if os.path.isfile(path) and os.access(path, os.X_OK) and not name.endswith(("_test", "_tests")):
                    found.add(name)
        self.assertEqual(found, EXECUTABLES, "executables of the package differ from those this test runs")
        for executable in sorted(EXECUTABLES):
            code, out = run(["rosrun", PKG, executable, "--help"], timeout=30.0)
            self.assertEqual(code, 0, f"rosrun {PKG} {executable} --help: exit {code}: {out}")
            self.assertIn("usage", out.lower(), f"rosrun {PKG} {executable} --help printed no usage: {out}")


if __name__ == "__main__":
    rostest.rosrun(PKG, "cli", Cli, sys.argv)
