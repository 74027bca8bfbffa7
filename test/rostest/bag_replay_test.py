#!/usr/bin/env python3
"""rostest: the rosbag workflow of the README, against the real node.

1. While the node runs (with /use_sim_time), this test subscribes to its markers, meshes and tf
   and keeps every message it receives, serialized, keyed by topic and stamp.
2. `rosbag record` records the same topics for a few seconds and is stopped with Ctrl-C (SIGINT).
3. The node is shut down; `rosbag play --clock` replays the bag with nothing else publishing.
4. Every replayed message must be byte for byte the one published live with the same key, every
   message of the bag must be replayed, the bag's time must be sim time, and the replayed /clock
   must be monotonic and span the bag.
Every wait is on wall time: ROS time is the node's /clock, then the bag's.
"""
import io
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import rosbag
import rosgraph
import rosnode
import rospy
import rostest
from rosgraph_msgs.msg import Clock
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from particle_sim.msg import ClothMesh

NS = "/particle_sim"
TOPICS = [NS + "/markers", NS + "/meshes", "/tf"]
RECORD_SECONDS = 4.0


def serialize(msg):
    buffer = io.BytesIO()
    msg.serialize(buffer)
    return buffer.getvalue()


def keyed(topic, msg):
    """The (key, serialized message) pairs of a message: one per marker array, mesh or transform."""
    if topic.endswith("/markers"):
        stamps = {m.header.stamp.to_nsec() for m in msg.markers}
        return [((topic, min(stamps) if stamps else 0), serialize(msg))]
    if topic.endswith("/meshes"):
        return [((topic, msg.body, msg.header.stamp.to_nsec()), serialize(msg))]
    return [((topic, t.child_frame_id, t.header.stamp.to_nsec()), serialize(t)) for t in msg.transforms]


def wait_for(predicate, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.05)
    return predicate()


class Collector:
    """Keeps what arrives on TOPICS (and /clock) in `target`, which the test can switch."""

    def __init__(self):
        self.lock = threading.Lock()
        self.live, self.replayed = {}, {}
        self.target = self.live
        self.clocks = []
        self.subscribers = [
            rospy.Subscriber(TOPICS[0], MarkerArray, self.on_message, TOPICS[0], queue_size=1000),
            rospy.Subscriber(TOPICS[1], ClothMesh, self.on_message, TOPICS[1], queue_size=1000),
            rospy.Subscriber(TOPICS[2], TFMessage, self.on_message, TOPICS[2], queue_size=1000),
            rospy.Subscriber("/clock", Clock, self.on_clock, queue_size=1000),
        ]

    def on_message(self, msg, topic):
        with self.lock:
            for key, data in keyed(topic, msg):
                self.target[key] = data

    def on_clock(self, msg):
        with self.lock:
            if self.target is self.replayed:
                self.clocks.append(msg.clock.to_sec())

    def count(self, which, topic):
        with self.lock:
            return sum(1 for key in which if key[0] == topic)


def subscribers_of(topic):
    _, subscribers, _ = rosgraph.Master("/bag_replay_test").getSystemState()
    for name, nodes in subscribers:
        if name == topic:
            return nodes
    return []


def publishers_of(topic):
    publishers, _, _ = rosgraph.Master("/bag_replay_test").getSystemState()
    for name, nodes in publishers:
        if name == topic:
            return nodes
    return []


class BagReplayTest(unittest.TestCase):
    def test_record_then_replay_without_the_simulator(self):
        self.assertTrue(rospy.get_param("/use_sim_time"), "the launch file sets /use_sim_time")
        collector = Collector()
        self.assertTrue(wait_for(lambda: all(collector.count(collector.live, t) > 5 for t in TOPICS), 60),
                        "the node does not publish markers, meshes and tf")

        # Record, as the README says: the node's topics, not /clock.
        directory = tempfile.mkdtemp(prefix="particle_sim_bag_")
        self.addCleanup(shutil.rmtree, directory, ignore_errors=True)  # the bag is about 1.4 MB a run
        bag_path = os.path.join(directory, "sim.bag")
        recorder = subprocess.Popen(["rosbag", "record", "--output-name=" + bag_path, "__name:=bag_recorder"] + TOPICS,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
        try:
            self.assertTrue(wait_for(lambda: all("/bag_recorder" in subscribers_of(t) for t in TOPICS), 30),
                            "rosbag record did not subscribe")
            time.sleep(RECORD_SECONDS)
        finally:
            recorder.send_signal(signal.SIGINT)
            recorder.wait(timeout=30)
        # The rosbag wrapper forwards SIGINT to its recorder and exits at once (KeyboardInterrupt),
        # while the recorder is still closing the bag (sim.bag.active -> sim.bag): wait for it.
        wait_for(lambda: os.path.exists(bag_path), 30)
        self.assertTrue(os.path.exists(bag_path), "no bag written: " + str(os.listdir(directory)))

        # Stop the simulator: the replay must be the only source of these topics and of /clock.
        rosnode.kill_nodes([NS])
        self.assertTrue(wait_for(lambda: not publishers_of(TOPICS[0]) and not publishers_of("/clock"), 30),
                        "the node is still publishing")
        time.sleep(0.5)
        with collector.lock:
            collector.target = collector.replayed

        # What the bag holds: its messages keyed as above, and its time against the stamps.
        in_bag = {}
        bag_times = []
        with rosbag.Bag(bag_path) as bag:
            for topic, msg, t in bag.read_messages(topics=TOPICS):
                for key, data in keyed(topic, msg):
                    in_bag[key] = data
                bag_times.append(t.to_sec())
                if topic == TOPICS[0] and msg.markers:
                    # Recorded with sim time: the bag's time is the sim time of the message.
                    self.assertAlmostEqual(t.to_sec(), msg.markers[0].header.stamp.to_sec(), delta=0.5)
        for topic in TOPICS:
            self.assertGreater(sum(1 for key in in_bag if key[0] == topic), 20, topic + " in the bag")

        # Replay with the bag's clock; the delay lets our subscribers connect first.
        player = subprocess.run(["rosbag", "play", "--clock", "--delay=2", "--quiet", bag_path],
                                stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT, timeout=120)
        self.assertEqual(player.returncode, 0)
        self.assertTrue(wait_for(lambda: len(collector.replayed) >= len(in_bag), 10))

        with collector.lock:
            replayed = dict(collector.replayed)
            clocks = list(collector.clocks)
        self.assertEqual(set(replayed), set(in_bag), "replayed messages differ from the bag's")
        for key, data in replayed.items():
            self.assertIn(key, collector.live, "replayed %s was never published live" % (key,))
            self.assertEqual(data, collector.live[key], "replayed %s differs from what was published" % (key,))

        # The bag's clock: monotonic, spanning the recording.
        self.assertGreater(len(clocks), 10)
        self.assertTrue(all(b >= a for a, b in zip(clocks, clocks[1:])), "replayed /clock went back")
        self.assertLessEqual(clocks[0], min(bag_times) + 0.1)
        self.assertGreaterEqual(clocks[-1], max(bag_times) - 0.1)


if __name__ == "__main__":
    rospy.init_node("bag_replay_test")
    rostest.rosrun("particle_sim", "bag_replay", BagReplayTest, sys.argv)
