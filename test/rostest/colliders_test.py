#!/usr/bin/env python3
"""rostest: box and capsule colliders in the node.

1. The box `pusher` follows the tf frame `pusher_frame`, which this test broadcasts: ~markers draws
   it (a CUBE in "_colliders") at the frame's position and turn, each time the frame moves.
2. The frame then moves along +x at 0.2 m/s for 1.5 s of wall time: the box pushes the jelly that
   rests in its way, whose particles (~points) all stay outside it, and the jelly's centre moves
   along +x.
3. The capsule `finger` follows the scripted frame `orbit` (broadcast on tf by the node): its
   CYLINDER marker is where tf says the frame is.
4. ~spawn_collider adds a box (drawn where the request puts it), refuses an unknown shape naming
   it, and ~remove_collider takes the box away again (its marker goes) and refuses it a second time.
"""
import math
import sys
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import TransformStamped, Vector3
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import Marker, MarkerArray

from particle_sim.srv import RemoveCollider, SpawnCollider, SpawnColliderRequest

PKG = "particle_sim"
NS = "/particle_sim"
HALF = (0.1, 0.2, 0.1)  # the box's half size, from colliders.yaml


class CollidersTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.latest = {}
        self.pose = ((-0.3, 0.0, 0.1), 0.0)  # the frame: position, yaw
        self.tf = rospy.Publisher("/tf", TFMessage, queue_size=10)
        rospy.Subscriber(NS + "/markers", MarkerArray, self.on_markers, queue_size=5)
        rospy.Subscriber(NS + "/points", PointCloud2, lambda m: self.keep("points", m), queue_size=2)
        rospy.Subscriber("/tf", TFMessage, self.on_tf, queue_size=50)
        threading.Thread(target=self.broadcast, daemon=True).start()

    def keep(self, key, msg):
        with self.lock:
            self.latest[key] = msg

    def on_markers(self, msg):
        colliders = [m for m in msg.markers if m.ns == "_colliders" and m.action == Marker.ADD]
        with self.lock:
            if colliders:  # every array of the node draws every collider
                self.latest["colliders"] = colliders

    def drawn(self, kind):
        return [m for m in self.latest.get("colliders", []) if m.type == kind]

    def on_tf(self, msg):
        for t in msg.transforms:
            if t.child_frame_id == "orbit":
                self.keep("orbit", t)

    def broadcast(self):
        while not rospy.is_shutdown():
            with self.lock:
                (x, y, z), yaw = self.pose
            t = TransformStamped()
            t.header.stamp = rospy.Time.now()
            t.header.frame_id = "world"
            t.child_frame_id = "pusher_frame"
            t.transform.translation = Vector3(x, y, z)
            t.transform.rotation.z = math.sin(yaw / 2.0)
            t.transform.rotation.w = math.cos(yaw / 2.0)
            try:
                self.tf.publish(TFMessage(transforms=[t]))
            except rospy.ROSException:
                if rospy.is_shutdown():
                    return  # the test ended and rospy closed the topic under this thread
                raise
            time.sleep(0.02)

    def wait_for(self, predicate, seconds=30.0):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            with self.lock:
                if predicate():
                    return True
            time.sleep(0.05)
        return False

    def cube_at(self, position, yaw, tolerance=1e-3):
        for cube in self.drawn(Marker.CUBE):
            p, q = cube.pose.position, cube.pose.orientation
            if (math.dist((p.x, p.y, p.z), position) < tolerance
                    and abs(q.z - math.sin(yaw / 2.0)) < tolerance and abs(q.w - math.cos(yaw / 2.0)) < tolerance):
                return True
        return False

    def jelly(self):
        return [(x, y, z) for x, y, z in point_cloud2.read_points(self.latest["points"], field_names=("x", "y", "z"))]

    def test_box_follows_tf_and_pushes_and_capsule_follows_its_scripted_frame(self):
        # 1. Drawn where the frame is, turned as it is.
        self.assertTrue(self.wait_for(lambda: self.cube_at((-0.3, 0.0, 0.1), 0.0)), "the box is not drawn on its frame")
        with self.lock:
            self.pose = ((-0.3, 0.0, 0.15), 0.4)
        self.assertTrue(self.wait_for(lambda: self.cube_at((-0.3, 0.0, 0.15), 0.4)), "the box did not follow")
        cube = self.drawn(Marker.CUBE)[0]
        self.assertAlmostEqual(cube.scale.x, 0.2, places=9)
        self.assertAlmostEqual(cube.scale.y, 0.4, places=9)
        with self.lock:
            self.pose = ((-0.3, 0.0, 0.1), 0.0)
        self.assertTrue(self.wait_for(lambda: self.cube_at((-0.3, 0.0, 0.1), 0.0)))

        # 2. It pushes the jelly along +x, and nothing of the jelly is inside it.
        self.assertTrue(self.wait_for(lambda: "points" in self.latest))
        before = self.jelly()
        start_x = sum(p[0] for p in before) / len(before)
        start = time.monotonic()
        while time.monotonic() - start < 1.5:
            with self.lock:
                self.pose = ((-0.3 + 0.2 * (time.monotonic() - start), 0.0, 0.1), 0.0)
            time.sleep(0.02)
        with self.lock:
            reached = self.pose[0][0]
        self.assertTrue(self.wait_for(lambda: self.cube_at((reached, 0.0, 0.1), 0.0)))
        time.sleep(0.3)
        with self.lock:
            after = self.jelly()
        end_x = sum(p[0] for p in after) / len(after)
        self.assertGreater(end_x - start_x, 0.1, "the jelly was not pushed: its centre went from %.3f to %.3f m"
                           % (start_x, end_x))
        for x, y, z in after:
            inside = abs(x - reached) < HALF[0] - 1e-3 and abs(y) < HALF[1] - 1e-3 and abs(z - 0.1) < HALF[2] - 1e-3
            self.assertFalse(inside, "a jelly particle is inside the box: (%.3f, %.3f, %.3f)" % (x, y, z))

        # 3. The capsule rides its scripted frame (broadcast by the node on tf).
        def capsule_on_orbit():
            cylinders, orbit = self.drawn(Marker.CYLINDER), self.latest.get("orbit")
            if not cylinders or orbit is None:
                return False
            cylinder = cylinders[0]
            p, t = cylinder.pose.position, orbit.transform.translation
            return math.dist((p.x, p.y, p.z), (t.x, t.y, t.z)) < 0.02  # one tick of the orbit at 0.8 m/s
        self.assertTrue(self.wait_for(capsule_on_orbit), "the capsule is not on its scripted frame")

        # 4. Added and removed at run time.
        rospy.wait_for_service(NS + "/spawn_collider", timeout=30.0)
        spawn = rospy.ServiceProxy(NS + "/spawn_collider", SpawnCollider)
        remove = rospy.ServiceProxy(NS + "/remove_collider", RemoveCollider)
        shelf = SpawnColliderRequest(name="shelf", shape=SpawnColliderRequest.SHAPE_BOX, friction=0.3)
        shelf.pose.position.x, shelf.pose.position.y, shelf.pose.position.z = 0.0, 1.0, 0.5
        shelf.size = Vector3(0.4, 0.4, 0.02)
        answer = spawn(shelf)
        self.assertTrue(answer.success, answer.message)
        self.assertTrue(self.wait_for(lambda: self.cube_at((0.0, 1.0, 0.5), 0.0)), "the shelf is not drawn")
        cone = SpawnColliderRequest(name="cone", shape="cone")
        answer = spawn(cone)
        self.assertFalse(answer.success)
        self.assertIn("shape = 'cone' is not a collider shape; allowed: box, capsule", answer.message)
        answer = spawn(shelf)
        self.assertFalse(answer.success)
        self.assertIn("'shelf' is taken", answer.message)
        answer = remove(name="shelf")
        self.assertTrue(answer.success, answer.message)
        self.assertTrue(self.wait_for(lambda: len(self.drawn(Marker.CUBE)) == 1 and not self.cube_at((0.0, 1.0, 0.5), 0.0)),
                        "the shelf is still drawn")
        answer = remove(name="shelf")
        self.assertFalse(answer.success)
        self.assertIn("no sphere, box or capsule collider has that name", answer.message)


if __name__ == "__main__":
    rospy.init_node("colliders_test")
    rostest.rosrun(PKG, "colliders", CollidersTest, sys.argv)
