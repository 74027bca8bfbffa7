#!/usr/bin/env python3
"""rostest: dragging a particle in rviz (~drag), with the feedback rviz sends.

A rope pinned at both ends hangs in the node. The test waits for the rope's interactive marker on
~drag/update_full (as rviz does), then publishes on ~drag/feedback: MOUSE_DOWN with the click on
particle 10, POSE_UPDATEs moving the marker by d = (0.2, 0, 0.3) m, MOUSE_UP. While the mouse is
down the status counts one more pin and particle 10 sits where it was at the click plus d (1 mm);
after the mouse is up the pin is gone and the particle moves. config/particle_sim.rviz shows the
markers (an InteractiveMarkers display on ~drag/update).
"""
import os
import sys
import threading
import time
import unittest

import rospkg
import rospy
import rostest
from geometry_msgs.msg import Point
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2
from visualization_msgs.msg import InteractiveMarkerFeedback, InteractiveMarkerInit

from particle_sim.msg import SimStatus
from particle_sim.srv import SpawnRope, SpawnRopeRequest

PKG = "particle_sim"
NS = "/particle_sim"


class DragTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.latest = {}
        rospy.Subscriber(NS + "/points", PointCloud2, lambda m: self.keep("points", m), queue_size=2)
        rospy.Subscriber(NS + "/status", SimStatus, lambda m: self.keep("status", m), queue_size=2)
        rospy.Subscriber(NS + "/drag/update_full", InteractiveMarkerInit, lambda m: self.keep("init", m), queue_size=2)
        self.feedback = rospy.Publisher(NS + "/drag/feedback", InteractiveMarkerFeedback, queue_size=10)

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

    def particle(self, index):
        """Particle `index` of the rope (body 0) from a cloud received after this call."""
        with self.lock:
            self.latest.pop("points", None)
        self.assertTrue(self.wait_for(lambda: "points" in self.latest))
        with self.lock:
            cloud = self.latest["points"]
        for x, y, z, body, particle in point_cloud2.read_points(cloud):
            if body == 0 and particle == index:
                return (x, y, z)
        self.fail(f"no particle {index} in ~points")

    def pinned(self):
        with self.lock:
            self.latest.pop("status", None)
        self.assertTrue(self.wait_for(lambda: "status" in self.latest))
        with self.lock:
            return self.latest["status"].bodies[0].pinned_count

    def send(self, event_type, position=(0.0, 0.0, 0.0), mouse=None):
        fb = InteractiveMarkerFeedback()
        fb.header.frame_id = "world"
        fb.client_id = "/drag_test"
        fb.marker_name = "line"
        fb.control_name = ""
        fb.event_type = event_type
        fb.pose.position = Point(*position)
        fb.pose.orientation.w = 1.0
        if mouse is not None:
            fb.mouse_point = Point(*mouse)
            fb.mouse_point_valid = True
        self.feedback.publish(fb)

    def test_drag_a_particle(self):
        rospy.wait_for_service(NS + "/spawn_rope", timeout=60.0)
        rope = SpawnRopeRequest(name="line", particles=21, start=Point(0, 0, 2), end=Point(2, 0, 2), mass=0.2,
                                stretch_stiffness=1000.0, stretch_damping=1.0, pins=[0, -1])
        answer = rospy.ServiceProxy(NS + "/spawn_rope", SpawnRope)(rope)
        self.assertTrue(answer.success, answer.message)

        # rviz's view of the markers: the rope's is there.
        def has_marker():
            init = self.latest.get("init")
            return init is not None and any(m.name == "line" for m in init.markers)

        self.assertTrue(self.wait_for(has_marker), "no interactive marker 'line' on ~drag/update_full")
        end = time.monotonic() + 10.0
        while self.feedback.get_num_connections() == 0 and time.monotonic() < end:
            time.sleep(0.1)
        time.sleep(1.0)  # the rope settles a little
        self.assertEqual(self.pinned(), 2)

        # Mouse down on particle 10: it is held where it was.
        click = self.particle(10)
        self.send(InteractiveMarkerFeedback.MOUSE_DOWN, mouse=click)
        time.sleep(0.5)
        self.assertEqual(self.pinned(), 3)
        held = self.particle(10)
        for a, b in zip(held, click):
            self.assertAlmostEqual(a, b, delta=0.05)

        # Drag by d: the particle follows.
        d = (0.2, 0.0, 0.3)
        for k in range(1, 11):
            self.send(InteractiveMarkerFeedback.POSE_UPDATE, position=tuple(c * k / 10.0 for c in d))
            time.sleep(0.05)
        time.sleep(0.5)
        moved = self.particle(10)
        for a, b, c in zip(moved, held, d):
            self.assertAlmostEqual(a, b + c, delta=1e-3)

        # Mouse up: let go; it falls back under gravity and the rope's pull.
        self.send(InteractiveMarkerFeedback.MOUSE_UP, position=d)
        time.sleep(0.5)
        self.assertEqual(self.pinned(), 2)
        self.assertLess(self.particle(10)[2], moved[2] - 0.01)

    def test_rviz_config_shows_the_drag_markers(self):
        path = os.path.join(rospkg.RosPack().get_path(PKG), "config", "particle_sim.rviz")
        with open(path) as f:
            text = f.read()
        self.assertIn("Class: rviz/InteractiveMarkers", text)
        self.assertIn("Update Topic: /particle_sim/drag/update", text)


if __name__ == "__main__":
    rospy.init_node("drag_test")
    rostest.rosrun(PKG, "drag", DragTest, sys.argv)
