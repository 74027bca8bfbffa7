#!/usr/bin/env python3
"""rostest: ~points, every body's particles as one sensor_msgs/PointCloud2, read the way a
perception pipeline reads it (sensor_msgs.point_cloud2.read_points).

The node starts paused with the demo scene (four emitters, a rope); the test spawns a cloth and a
jelly and steps the world, so that every message after the step describes one state. Then:
- the cloud has the fields x, y, z (float32), body and particle (uint32), is dense and finite;
- per body, its points are the status's particle_count, with particle indices 0..count-1 in order,
  and its body index is the body's place in ~status;
- the cloth's and the jelly's points are where ~meshes puts their vertices (float32 rounding);
- ~pin_wrench/sheet, the cloth's one pin: its force is ~status's pin_force, and its torque about the
  frame's origin is x × F with x the pinned particle's position in the cloud.
"""
import math
import sys
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Point, Vector3, WrenchStamped
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2, PointField

from particle_sim.msg import ClothMesh, SimStatus
from particle_sim.srv import SpawnCloth, SpawnClothRequest, SpawnJelly, SpawnJellyRequest, Step

PKG = "particle_sim"
NS = "/particle_sim"


class Points(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.latest = {}
        self.meshes = {}
        rospy.Subscriber(NS + "/points", PointCloud2, lambda m: self.keep("points", m), queue_size=2)
        rospy.Subscriber(NS + "/status", SimStatus, lambda m: self.keep("status", m), queue_size=2)
        rospy.Subscriber(NS + "/meshes", ClothMesh, self.keep_mesh, queue_size=10)
        rospy.Subscriber(NS + "/pin_wrench/sheet", WrenchStamped, lambda m: self.keep("wrench", m), queue_size=2)

    def keep(self, key, msg):
        with self.lock:
            self.latest[key] = msg

    def keep_mesh(self, msg):
        with self.lock:
            self.meshes[msg.body] = msg

    def wait_for(self, predicate, seconds=30.0):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            with self.lock:
                if predicate():
                    return True
            time.sleep(0.05)
        return False

    def test_cloud_matches_status_and_meshes(self):
        for name in ("spawn_cloth", "spawn_jelly", "step"):
            rospy.wait_for_service(NS + "/" + name, timeout=60.0)
        cloth = SpawnClothRequest(name="sheet", origin=Point(0.5, -0.5, 3), edge_u=Vector3(1, 0, 0),
                                  edge_v=Vector3(0, 1, 0), nu=6, nv=5, pins=[0])
        answer = rospy.ServiceProxy(NS + "/spawn_cloth", SpawnCloth)(cloth)
        self.assertTrue(answer.success, answer.message)
        jelly = SpawnJellyRequest(name="block", origin=Point(2, 2, 1), size=Vector3(0.5, 0.5, 0.5), nx=4, ny=4, nz=4)
        answer = rospy.ServiceProxy(NS + "/spawn_jelly", SpawnJelly)(jelly)
        self.assertTrue(answer.success, answer.message)
        stepped = rospy.ServiceProxy(NS + "/step", Step)(steps=300)
        self.assertTrue(stepped.success, stepped.message)

        # Paused after the step: every message stamped with the step's end describes one state.
        stamp = rospy.Time.from_sec(stepped.sim_time)

        def current():
            msgs = [self.latest.get(k) for k in ("points", "status", "wrench")] + [self.meshes.get(b) for b in ("sheet", "block")]
            return all(m is not None and m.header.stamp == stamp for m in msgs)

        self.assertTrue(self.wait_for(current), "no cloud, status, wrench and meshes of the stepped state within 30 s")
        with self.lock:
            cloud, status, wrench = self.latest["points"], self.latest["status"], self.latest["wrench"]
            meshes = dict(self.meshes)

        # Fields, as a perception pipeline checks them.
        fields = [(f.name, f.datatype, f.count) for f in cloud.fields]
        self.assertEqual(fields, [("x", PointField.FLOAT32, 1), ("y", PointField.FLOAT32, 1),
                                  ("z", PointField.FLOAT32, 1), ("body", PointField.UINT32, 1),
                                  ("particle", PointField.UINT32, 1)])
        self.assertEqual(cloud.height, 1)
        self.assertTrue(cloud.is_dense)
        self.assertEqual(cloud.header.frame_id, status.header.frame_id)
        points = list(point_cloud2.read_points(cloud, field_names=("x", "y", "z", "body", "particle")))
        self.assertEqual(len(points), cloud.width)
        self.assertTrue(all(math.isfinite(c) for p in points for c in p[:3]))

        # Per body: the status's count, particle indices in order.
        by_body = {}
        for x, y, z, body, particle in points:
            by_body.setdefault(body, []).append((particle, (x, y, z)))
        names = [b.name for b in status.bodies]
        self.assertEqual(set(by_body), {i for i, b in enumerate(status.bodies) if b.particle_count > 0})
        for index, body in enumerate(status.bodies):
            indices = [particle for particle, _ in by_body.get(index, [])]
            self.assertEqual(indices, list(range(body.particle_count)), f"points of body {index} ({body.name})")
        self.assertGreater(sum(b.particle_count for b in status.bodies if b.type == "emitter"), 0)

        # The cloth's and the jelly's points are their mesh vertices (float64 there, float32 here).
        for name in ("sheet", "block"):
            mine = dict(by_body[names.index(name)])
            mesh = meshes[name]
            self.assertGreater(len(mesh.particles), 0)
            for particle, vertex in zip(mesh.particles, mesh.mesh.vertices):
                for a, b in zip(mine[particle], (vertex.x, vertex.y, vertex.z)):
                    self.assertAlmostEqual(a, b, delta=1e-6 * max(1.0, abs(b)), msg=f"{name} particle {particle}")
        # The cloth hangs from its pin: it has moved, so the cloud is the stepped state, not the spawned one.
        sheet = dict(by_body[names.index("sheet")])
        self.assertLess(min(z for _, _, z in sheet.values()), 3.0 - 0.05)

        # The pin's wrench: the status's pin force, and about the origin x_pin × F (one pin).
        self.assertEqual(wrench.header.frame_id, status.header.frame_id)
        body = status.bodies[names.index("sheet")]
        force = (wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z)
        self.assertEqual(force, (body.pin_force.x, body.pin_force.y, body.pin_force.z))
        self.assertGreater(force[2], 0.0, "the pin holds the cloth up")
        x = sheet[0]
        expected = (x[1] * force[2] - x[2] * force[1], x[2] * force[0] - x[0] * force[2], x[0] * force[1] - x[1] * force[0])
        scale = max(abs(c) for c in force) * max(abs(c) for c in x)
        for got, want in zip((wrench.wrench.torque.x, wrench.wrench.torque.y, wrench.wrench.torque.z), expected):
            self.assertAlmostEqual(got, want, delta=1e-6 * scale)


if __name__ == "__main__":
    rospy.init_node("points_test")
    rostest.rosrun(PKG, "points", Points, sys.argv)
