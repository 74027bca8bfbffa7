#!/usr/bin/env python3
"""rostest: the pick_and_place demo (launch/pick_and_place.launch) as a user runs it, in real time.

The scene's scripted gripper picks the towel's corner off the floor (the demo's own node calls
~grasp), lifts it, lets it hang, shakes it, carries it to the table and lays it over the table, and
the demo's node calls ~release. The test watches from outside, through ~status, ~points and
~grasp_wrench/corner, and checks against the scene file's own numbers. The simulator starts paused;
the test unpauses it once the demo's node is ready (its parameter ready) and the test receives.

1. The grasp holds the corner: the particles within its 3 cm sphere (the corner and its two
   neighbours, 2.5 cm away on a 21 x 21 grid of 0.5 m), and the corner rises with the gripper.
   While it lifts the towel off the floor, the vertical force stays under Newton's bound
   m (g + a_max) + λ v_max² (the lifted mass's largest acceleration, and the momentum of the mass
   being picked up; see RestingContact.AClothPeeledOffTheFloorByItsCornerIsNeverGluedToIt): a grip
   that followed the gripper in jerks shows as spikes above it.
2. Hanging still, the grasp carries the towel: averaged over half a second late in the hang, the
   vertical force in the gripper frame is the towel's weight m g within 2 %, and the towel's
   kinetic energy is below 1 % of m g times its size (it hangs, it does not swing).
3. After ~release (by 13 s) the status lists no grasp; two seconds after it the towel lies over the table at
   rest: no particle inside the table, part of it on the top (within 1 cm of the top's height,
   inside its outline), part of it hanging down over an edge, and none below the ground.
"""
import math
import sys
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import WrenchStamped
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2
from std_srvs.srv import Trigger

from particle_sim.msg import SimStatus

PKG = "particle_sim"
NS = "/particle_sim"

# From config/scenes/pick_and_place.yaml.
TOWEL_MASS = 0.1  # [kg]
GRAVITY = 9.81  # [m/s^2]
TOWEL_SIZE = 0.5  # [m] side
TABLE_CENTER = (0.7, 0.0, 0.2)  # [m]
TABLE_SIZE = (0.5, 0.5, 0.4)  # [m]
LIFT = (2.0, 4.0, 1.295)  # [s], [s], [m]: the gripper's minimum-jerk lift from 0.005 m to 1.3 m
HANG = (5.4, 5.9)  # [s] late in the hang (the gripper holds still at 1.3 m from 4 to 6 s)
RELEASE_AT = 12.5  # [s] launch/pick_and_place.launch's default (scripts/pick_and_place.py)
RELEASED_BY = 13.0  # [s] the gripper holds still until then
SETTLED_AT = RELEASE_AT + 2.0  # [s]


class PickAndPlaceTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.latest = {}
        self.wrenches = []  # (sim time, force z in the gripper frame)
        rospy.Subscriber(NS + "/status", SimStatus, lambda m: self.keep("status", m), queue_size=2)
        rospy.Subscriber(NS + "/points", PointCloud2, lambda m: self.keep("points", m), queue_size=2)
        rospy.Subscriber(NS + "/grasp_wrench/corner", WrenchStamped, self.on_wrench, queue_size=100)

    def keep(self, key, msg):
        with self.lock:
            self.latest[key] = msg

    def on_wrench(self, msg):
        with self.lock:
            self.wrenches.append((msg.header.stamp.to_sec(), msg.wrench.force.z))

    def status_after(self, sim_time, seconds=120.0):
        """The first status at or after `sim_time` [s], with the point cloud of the same stamp."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            with self.lock:
                status, cloud = self.latest.get("status"), self.latest.get("points")
            if status and cloud and status.sim_time >= sim_time and status.header.stamp == cloud.header.stamp:
                return status, cloud
            time.sleep(0.01)
        self.fail(f"no status and points of one stamp after sim time {sim_time} s within {seconds} s")

    @staticmethod
    def towel(status, cloud):
        body = [b.name for b in status.bodies].index("towel")
        return status.bodies[body], [(x, y, z) for x, y, z, b in point_cloud2.read_points(
            cloud, field_names=("x", "y", "z", "body")) if b == body]

    def start(self):
        """Unpauses the simulator once the demo's node is ready and this test receives its status."""
        end = time.monotonic() + 60.0
        while not rospy.get_param("/pick_and_place/ready", False) and time.monotonic() < end:
            time.sleep(0.05)
        self.assertTrue(rospy.get_param("/pick_and_place/ready", False), "the demo's node never became ready")
        status, _ = self.status_after(0.0)
        self.assertTrue(status.paused, "the demo should start paused")
        self.assertEqual(status.sim_time, 0.0)
        rospy.wait_for_service(NS + "/unpause_physics", timeout=60.0)
        self.assertTrue(rospy.ServiceProxy(NS + "/unpause_physics", Trigger)().success)

    def test_pick_lift_hang_shake_and_lay_over_the_table(self):
        self.start()
        # 1. Grasped by 2 s (the demo grasps at 1.6 s), then lifted with the gripper.
        status, cloud = self.status_after(2.0)
        self.assertEqual([g.name for g in status.grasps], ["corner"], "the demo's ~grasp did not take")
        self.assertEqual(status.grasps[0].particle_count, 3)
        self.assertFalse(status.grasps[0].released)
        status, cloud = self.status_after(4.0)
        _, points = self.towel(status, cloud)
        self.assertGreater(max(z for _, _, z in points), 1.25, "the corner rose with the gripper to 1.3 m")
        weight = TOWEL_MASS * GRAVITY
        duration, height = LIFT[1] - LIFT[0], LIFT[2]
        a_max = 10.0 / math.sqrt(3.0) * height / duration ** 2
        v_max = 15.0 / 8.0 * height / duration
        linear_density = TOWEL_MASS / TOWEL_SIZE ** 2 * TOWEL_SIZE * math.sqrt(2.0)  # [kg/m] widest diagonal
        bound = TOWEL_MASS * (GRAVITY + a_max) + linear_density * v_max ** 2
        with self.lock:
            lifting = [f for t, f in self.wrenches if LIFT[0] <= t <= LIFT[1]]
        self.assertGreater(len(lifting), 50, "too few wrenches in the lift")
        self.assertLess(max(lifting), bound, f"the lift's force peaked at {max(lifting):.3f} N over Newton's bound")

        # 2. Hanging still: the grasp carries the weight.
        status, cloud = self.status_after(HANG[1])
        with self.lock:
            forces = [f for t, f in self.wrenches if HANG[0] <= t <= HANG[1]]
        self.assertGreater(len(forces), 10, "too few wrenches in the hang")
        mean = sum(forces) / len(forces)
        self.assertAlmostEqual(mean, weight, delta=0.02 * weight,
                               msg=f"mean grasp force {mean:.4f} N against the weight {weight:.4f} N")
        towel, _ = self.towel(status, cloud)
        self.assertLess(towel.kinetic_energy, 0.01 * weight * TOWEL_SIZE, "the towel still swings")

        # 3. Released and laid over the table.
        status, cloud = self.status_after(RELEASED_BY)
        self.assertEqual(status.grasps, [], "the demo's ~release did not take")
        status, cloud = self.status_after(SETTLED_AT)
        towel, points = self.towel(status, cloud)
        self.assertEqual(len(points), 21 * 21)
        top = TABLE_CENTER[2] + TABLE_SIZE[2] / 2.0
        half = (TABLE_SIZE[0] / 2.0, TABLE_SIZE[1] / 2.0)

        def over_table(x, y):
            return abs(x - TABLE_CENTER[0]) <= half[0] and abs(y - TABLE_CENTER[1]) <= half[1]

        inside = [p for p in points if abs(p[0] - TABLE_CENTER[0]) < half[0] - 1e-3 and
                  abs(p[1] - TABLE_CENTER[1]) < half[1] - 1e-3 and p[2] < top - 1e-3]  # on a face is not in
        self.assertEqual(inside, [], "particles inside the table")
        on_top = [p for p in points if over_table(p[0], p[1]) and p[2] <= top + 0.01]
        hanging = [p for p in points if not over_table(p[0], p[1]) and p[2] < top - 0.05]
        self.assertGreater(len(on_top), len(points) // 4, "too little of the towel lies on the table")
        self.assertGreater(len(hanging), 0, "nothing hangs over an edge")
        self.assertGreaterEqual(min(z for _, _, z in points), -1e-6, "a particle below the ground")
        self.assertLess(towel.kinetic_energy, 0.01 * weight * TOWEL_SIZE, "the towel has not come to rest")


if __name__ == "__main__":
    rospy.init_node("pick_and_place_test")
    rostest.rosrun(PKG, "pick_and_place_demo", PickAndPlaceTest, sys.argv)
