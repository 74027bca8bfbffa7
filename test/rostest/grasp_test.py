#!/usr/bin/env python3
"""rostest: ~grasp and ~release, with gripper frames this test broadcasts on tf (parent: the node's
frame, "world").

1. Paused, a 0.5 m cloth (11 x 11) is spawned flat at z = 1 and grasped by a sphere of 0.06 m around
   the gripper at its corner: exactly the three particles within 0.06 m (0.05 m spacing). Refused:
   the same name again, a region with nothing in it, an unknown frame; nothing changes.
2. Running, the gripper moves to (0.1, 0.2, 1.3) and turns 90° about z: the three particles sit at
   pose · offset (offset = where they were in the gripper frame at the grasp) within 1 mm.
3. Paused again: ~grasp_wrench/corner (in the gripper frame) is ~status's grasp force turned by
   the gripper's rotation; the grasp holds the cloth up.
4. ~release lets the three go: the status lists no grasp and the cloth falls.
5. A 2 kg cloth grasped by its nearest particle with a breakaway force of 5 N (below its weight)
   lets go by itself once running: ~status shows it released, with the reason, and ~release says so.
"""
import math
import sys
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Point, TransformStamped, Vector3, WrenchStamped
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2
from std_srvs.srv import Trigger
from tf2_msgs.msg import TFMessage

from particle_sim.msg import SimStatus
from particle_sim.srv import Grasp, GraspRequest, Release, SpawnCloth, SpawnClothRequest

PKG = "particle_sim"
NS = "/particle_sim"


class Gripper:
    """Broadcasts frames under "world" on /tf at 50 Hz, each at a pose the test sets."""

    def __init__(self):
        self.publisher = rospy.Publisher("/tf", TFMessage, queue_size=10)
        self.poses = {}
        self.lock = threading.Lock()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def set(self, frame, position, yaw=0.0):
        with self.lock:
            self.poses[frame] = (position, yaw)

    def run(self):
        while not rospy.is_shutdown():
            with self.lock:
                poses = dict(self.poses)
            transforms = []
            for frame, ((x, y, z), yaw) in poses.items():
                t = TransformStamped()
                t.header.stamp = rospy.Time.now()
                t.header.frame_id = "world"
                t.child_frame_id = frame
                t.transform.translation = Vector3(x, y, z)
                t.transform.rotation.z = math.sin(yaw / 2.0)
                t.transform.rotation.w = math.cos(yaw / 2.0)
                transforms.append(t)
            try:
                self.publisher.publish(TFMessage(transforms=transforms))
            except rospy.ROSException:
                if rospy.is_shutdown():
                    return  # the test ended and rospy closed the topic under this thread
                raise
            time.sleep(0.02)


class GraspTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.latest = {}
        rospy.Subscriber(NS + "/points", PointCloud2, lambda m: self.keep("points", m), queue_size=2)
        rospy.Subscriber(NS + "/status", SimStatus, lambda m: self.keep("status", m), queue_size=2)
        rospy.Subscriber(NS + "/grasp_wrench/corner", WrenchStamped, lambda m: self.keep("wrench", m), queue_size=2)
        for name in ("spawn_cloth", "grasp", "release", "pause_physics", "unpause_physics"):
            rospy.wait_for_service(NS + "/" + name, timeout=60.0)
        self.grasp = rospy.ServiceProxy(NS + "/grasp", Grasp)
        self.release = rospy.ServiceProxy(NS + "/release", Release)
        self.pause = rospy.ServiceProxy(NS + "/pause_physics", Trigger)
        self.unpause = rospy.ServiceProxy(NS + "/unpause_physics", Trigger)

    def keep(self, key, msg):
        with self.lock:
            self.latest[key] = msg

    def wait_for(self, predicate, seconds=30.0):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            with self.lock:
                if predicate():
                    return True
            time.sleep(0.05)
        return False

    def fresh(self, keys, seconds=30.0):
        """Messages of `keys` received after this call, all with one stamp."""
        with self.lock:
            for key in keys:
                self.latest.pop(key, None)

        def same_stamp():
            msgs = [self.latest.get(k) for k in keys]
            return all(msgs) and len({m.header.stamp for m in msgs}) == 1

        self.assertTrue(self.wait_for(same_stamp, seconds), f"no {keys} with one stamp within {seconds} s")
        with self.lock:
            return [self.latest[k] for k in keys]

    def particles(self, cloud, status, body):
        index = [b.name for b in status.bodies].index(body)
        return {p: (x, y, z) for x, y, z, b, p in point_cloud2.read_points(
            cloud, field_names=("x", "y", "z", "body", "particle")) if b == index}

    def grasp_request(self, name, frame, **fields):
        req = GraspRequest(name=name, frame=frame)
        for key, value in fields.items():
            setattr(req, key, value)
        return req

    def test_grasp_follow_release_and_breakaway(self):
        gripper = Gripper()
        gripper.set("gripper", (0.0, 0.0, 1.0))
        gripper.set("gripper2", (3.0, 0.0, 1.0))
        spawn = rospy.ServiceProxy(NS + "/spawn_cloth", SpawnCloth)
        answer = spawn(SpawnClothRequest(name="towel", origin=Point(0, 0, 1), edge_u=Vector3(0.5, 0, 0),
                                         edge_v=Vector3(0, 0.5, 0), nu=11, nv=11, stretch_stiffness=500.0,
                                         stretch_damping=0.5, shear_stiffness=100.0))
        self.assertTrue(answer.success, answer.message)

        # 1. Capture, once tf has the frame; refusals.
        corner = self.grasp_request("corner", "gripper", region=GraspRequest.REGION_SPHERE, radius=0.06)
        end = time.monotonic() + 30.0
        answer = self.grasp(corner)
        while not answer.success and "unknown to tf" in answer.message and time.monotonic() < end:
            time.sleep(0.2)
            answer = self.grasp(corner)
        self.assertTrue(answer.success, answer.message)
        self.assertEqual(answer.captured, 3, answer.message)  # (0,0), (1,0), (0,1): 0, 0.05, 0.05 m; (1,1) is 0.071 m
        for request, words in ((corner, "is held by an active grasp"),
                               (self.grasp_request("air", "gripper", region=GraspRequest.REGION_SPHERE, radius=0.06,
                                                   offset=Vector3(0, 0, 2)), "captured nothing"),
                               (self.grasp_request("ghost", "no_such_frame", region=GraspRequest.REGION_NEAREST,
                                                   count=1), "unknown to tf")):
            refused = self.grasp(request)
            self.assertFalse(refused.success, refused.message)
            self.assertIn(words, refused.message)
        cloud, status = self.fresh(["points", "status"])
        self.assertEqual([g.name for g in status.grasps], ["corner"])
        self.assertEqual(status.grasps[0].particle_count, 3)
        held = self.particles(cloud, status, "towel")
        offsets = {p: (held[p][0], held[p][1], held[p][2] - 1.0) for p in (0, 1, 11)}  # gripper at (0, 0, 1), unturned

        # 2. Move and turn the gripper; the three follow rigidly.
        self.assertTrue(self.unpause().success)
        position, yaw = (0.1, 0.2, 1.3), math.pi / 2.0
        gripper.set("gripper", position, yaw)
        time.sleep(1.5)
        self.assertTrue(self.pause().success)
        cloud, status, wrench = self.fresh(["points", "status", "wrench"])
        held = self.particles(cloud, status, "towel")
        c, s = math.cos(yaw), math.sin(yaw)
        for p, (ox, oy, oz) in offsets.items():
            expected = (position[0] + c * ox - s * oy, position[1] + s * ox + c * oy, position[2] + oz)
            for got, want in zip(held[p], expected):
                self.assertAlmostEqual(got, want, delta=1e-3, msg=f"particle {p}: {held[p]} against {expected}")

        # 3. The wrench in the gripper frame is the status's force turned by -yaw; it holds the cloth up.
        self.assertEqual(wrench.header.frame_id, "gripper")
        f = status.grasps[0].force
        self.assertGreater(f.z, 0.0)
        for got, want in zip((wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z),
                             (c * f.x + s * f.y, -s * f.x + c * f.y, f.z)):
            self.assertAlmostEqual(got, want, delta=1e-4 * max(1.0, abs(f.z)))

        # 4. Release: the status lists no grasp, the towel falls.
        released = self.release(name="corner")
        self.assertTrue(released.success, released.message)
        self.assertEqual(released.released, 3)
        released_at = self.fresh(["status"])[0].sim_time
        self.assertTrue(self.unpause().success)
        # 0.3 s of sim time, however slowly it runs (a sanitizer build runs at a fraction of real
        # time): a free fall of g t² / 2 = 0.44 m, the corner held back by the cloth still drops 0.1 m.
        self.assertTrue(self.wait_for(lambda: self.latest.get("status") is not None and
                                      self.latest["status"].sim_time >= released_at + 0.3, 60.0),
                        "sim time did not advance 0.3 s after the release")
        cloud, status = self.fresh(["points", "status"])
        self.assertEqual(status.grasps, [])
        self.assertLess(self.particles(cloud, status, "towel")[0][2], 1.3 - 0.1, "the released corner falls")

        # 5. Breakaway: 2 kg (19.6 N) on a grasp that lets go above 5 N.
        self.assertTrue(self.pause().success)
        answer = spawn(SpawnClothRequest(name="heavy", origin=Point(3, 0, 1), edge_u=Vector3(0.5, 0, 0),
                                         edge_v=Vector3(0, 0.5, 0), nu=6, nv=6, mass=2.0, stretch_stiffness=2000.0,
                                         stretch_damping=1.0, shear_stiffness=500.0))
        self.assertTrue(answer.success, answer.message)
        weak = self.grasp_request("weak", "gripper2", region=GraspRequest.REGION_NEAREST, count=1, breakaway_force=5.0)
        answer = self.grasp(weak)
        self.assertTrue(answer.success, answer.message)
        self.assertEqual(answer.captured, 1)
        self.assertTrue(self.unpause().success)

        def broke():
            status = self.latest.get("status")
            return status is not None and any(g.name == "weak" and g.released for g in status.grasps)

        self.assertTrue(self.wait_for(broke, 30.0),
                        f"the 5 N grasp never broke away under 19.6 N: {self.latest.get('status').grasps}")
        with self.lock:
            weak_status = [g for g in self.latest["status"].grasps if g.name == "weak"][0]
        self.assertIn("exceeded the breakaway force 5 N", weak_status.release_reason)
        self.assertEqual(weak_status.particle_count, 0)
        self.assertGreater(weak_status.released_at, 0.0)
        answer = self.release(name="weak")
        self.assertTrue(answer.success, answer.message)
        self.assertIn("had broken away at sim time", answer.message)
        self.assertEqual(answer.released, 0)


if __name__ == "__main__":
    rospy.init_node("grasp_test")
    rostest.rosrun(PKG, "grasp", GraspTest, sys.argv)
