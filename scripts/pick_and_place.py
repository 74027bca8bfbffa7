#!/usr/bin/env python3
"""The grasp and the release of the pick_and_place demo (launch/pick_and_place.launch).

The launch file starts the simulator paused. This node subscribes to what it needs, connects to
~grasp, ~release and ~unpause_physics, sets its parameter ~ready and, with ~unpause (the default),
unpauses the simulator: nothing is missed however long the processes took to start. Then it watches
the sim time on ~status and, when it passes ~grasp_at, asks ~grasp to catch what lies within ~radius
of ~frame's origin (the towel's corner under the scripted gripper); when it passes ~release_at, asks
~release. Meanwhile it prints the grasp's wrench every second of sim time and, with ~csv set, writes
every wrench (sim time [s], force [N] and torque [N·m] in the gripper frame) to that file. With
~screenshot set it takes a picture of the X display at ~screenshot_at (ImageMagick's import; for
scripts/pick_and_place_figures). It ends when sim time passes ~end_at.

Private parameters (defaults in brackets): sim [/particle_sim], body [towel], frame [gripper],
grasp [corner], radius [0.03 m], grasp_at [1.6 s], release_at [12.5 s], end_at [15 s],
csv [''], screenshot [''], screenshot_at [14.5 s], unpause [true].
"""
import subprocess
import sys
import threading

import rospy
from geometry_msgs.msg import WrenchStamped

from particle_sim.msg import SimStatus
from std_srvs.srv import Trigger

from particle_sim.srv import Grasp, GraspRequest, Release


class Choreography:
    def __init__(self):
        self.sim = rospy.get_param("~sim", "/particle_sim")
        self.body = rospy.get_param("~body", "towel")
        self.frame = rospy.get_param("~frame", "gripper")
        self.name = rospy.get_param("~grasp", "corner")
        self.radius = float(rospy.get_param("~radius", 0.03))
        self.grasp_at = float(rospy.get_param("~grasp_at", 1.6))
        self.release_at = float(rospy.get_param("~release_at", 12.5))
        self.end_at = float(rospy.get_param("~end_at", 15.0))
        self.screenshot = rospy.get_param("~screenshot", "")
        self.screenshot_at = float(rospy.get_param("~screenshot_at", 14.5))
        self.unpause = bool(rospy.get_param("~unpause", True))
        csv_path = rospy.get_param("~csv", "")
        self.csv_lock = threading.Lock()  # the wrench callback writes, run() closes
        self.csv = open(csv_path, "w", buffering=1) if csv_path else None
        if self.csv:
            self.csv.write("time,fx,fy,fz,tx,ty,tz\n")
        self.sim_time = None
        self.stage = "waiting"
        self.last_print = -1.0
        self.status_sub = rospy.Subscriber(self.sim + "/status", SimStatus, self.on_status, queue_size=1)
        self.wrench_sub = rospy.Subscriber(self.sim + "/grasp_wrench/" + self.name, WrenchStamped, self.on_wrench,
                                           queue_size=100)
        # Connected once, before the simulator runs: a call at grasp_at then waits for nothing.
        self.services = {}
        for name, kind in (("grasp", Grasp), ("release", Release), ("unpause_physics", Trigger)):
            rospy.wait_for_service(self.sim + "/" + name, timeout=60.0)
            self.services[name] = rospy.ServiceProxy(self.sim + "/" + name, kind, persistent=True)

    def on_status(self, status):
        self.sim_time = status.sim_time

    def on_wrench(self, msg):
        f, t = msg.wrench.force, msg.wrench.torque
        time = msg.header.stamp.to_sec()
        with self.csv_lock:
            if self.csv:
                self.csv.write("%.4f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n" % (time, f.x, f.y, f.z, t.x, t.y, t.z))
        if time - self.last_print >= 1.0:
            self.last_print = time
            rospy.loginfo("t = %5.2f s  grasp force [%.3f, %.3f, %.3f] N in '%s'", time, f.x, f.y, f.z, self.frame)

    def call(self, service, *request):
        answer = self.services[service](*request)
        (rospy.loginfo if answer.success else rospy.logerr)("%s: %s", service, answer.message)
        return answer.success

    def run(self):
        rate = rospy.Rate(200)
        # Ready: say so (the rostest waits for it), then let the simulator run.
        while not rospy.is_shutdown() and self.sim_time is None:
            rate.sleep()
        rospy.set_param("~ready", True)
        ok = self.call("unpause_physics") if self.unpause else True
        while not rospy.is_shutdown() and self.sim_time < self.end_at:
            if self.stage == "waiting" and self.sim_time >= self.grasp_at:
                request = GraspRequest(name=self.name, body=self.body, frame=self.frame,
                                       region=GraspRequest.REGION_SPHERE, radius=self.radius)
                ok = self.call("grasp", request) and ok
                self.stage = "holding"
            elif self.stage == "holding" and self.sim_time >= self.release_at:
                ok = self.call("release", self.name) and ok
                self.stage = "released"
            if self.screenshot and self.sim_time >= self.screenshot_at:
                subprocess.run(["import", "-window", "root", self.screenshot], check=False)
                rospy.loginfo("screenshot at sim time %.2f s: %s", self.sim_time, self.screenshot)
                self.screenshot = ""
            rate.sleep()
        self.wrench_sub.unregister()
        with self.csv_lock:
            if self.csv:
                self.csv.close()
                self.csv = None
        return ok


def main():
    rospy.init_node("pick_and_place")
    sys.exit(0 if Choreography().run() else 1)


if __name__ == "__main__":
    main()
