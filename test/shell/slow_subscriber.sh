#!/usr/bin/env bash
# Shell test (issue 16, item 4): subscribers that read slowly (a callback that sleeps 1 s, so that
# the TCP connection backs up) on ~markers, ~meshes, ~status and /tf do not slow the simulation:
# roscpp queues at most 10 messages per subscriber and drops the oldest, never waits (README
# "Published topics": queue sizes and latching). Compares the real-time factor seen on /clock over
# 5 s of wall time before and while they are connected, checks that services still answer and that
# the node's resident memory stays bounded. Exits 0 on pass.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/helpers.bash"
use_devel_space

start_roscore
# The demo scene (large marker arrays, four emitters) at a real-time factor the machine reaches.
background "$node_binary" __name:=particle_sim _scene:="$PARTICLE_SIM_ROOT/config/scenes/demo.yaml" \
  _real_time_factor:=0.25 _status_period:=0 >"$work/node.log" 2>&1
node_pid=$background_pid
wait_for_service /particle_sim/set_wind 30 || fail "the node's services did not appear"

/usr/bin/python3 - "$node_pid" <<'PY' || fail "a slow subscriber slowed the simulation (see above)"
import sys
import time

import rospy
from geometry_msgs.msg import Vector3
from particle_sim.msg import ClothMesh, SimStatus
from particle_sim.srv import SetWind
from rosgraph_msgs.msg import Clock
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

node_pid = int(sys.argv[1])
rospy.init_node('slow_subscriber_test', disable_signals=True)
sim = [None]
rospy.Subscriber('/clock', Clock, lambda m: sim.__setitem__(0, m.clock.to_sec()), queue_size=100)


def rss_kb():
    with open('/proc/%d/status' % node_pid) as status:
        return next(int(line.split()[1]) for line in status if line.startswith('VmRSS:'))


def real_time_factor(seconds=5.0):
    while sim[0] is None:
        time.sleep(0.05)
    wall0, sim0 = time.monotonic(), sim[0]
    time.sleep(seconds)
    return (sim[0] - sim0) / (time.monotonic() - wall0)


time.sleep(3.0)  # emitter pools fill
before = real_time_factor()
rss_before = rss_kb()
received = {}


def slow(topic):
    received[topic] = 0

    def callback(_):
        received[topic] += 1
        time.sleep(1.0)  # reads one message a second: the connection backs up
    return callback


slow_subscribers = [rospy.Subscriber('/particle_sim/markers', MarkerArray, slow('markers'), queue_size=1),
                    rospy.Subscriber('/particle_sim/meshes', ClothMesh, slow('meshes'), queue_size=1),
                    rospy.Subscriber('/particle_sim/status', SimStatus, slow('status'), queue_size=1),
                    rospy.Subscriber('/tf', TFMessage, slow('tf'), queue_size=1)]
deadline = time.monotonic() + 20
while any(s.get_num_connections() == 0 for s in slow_subscribers[:3]) and time.monotonic() < deadline:
    time.sleep(0.1)
time.sleep(2.0)
during = real_time_factor()
wind = rospy.ServiceProxy('/particle_sim/set_wind', SetWind)(wind=Vector3(1, 0, 0))
rss_during = rss_kb()
print('real-time factor %.3f before, %.3f with the slow subscribers (target 0.25); slow subscribers read %s; '
      'VmRSS %d -> %d kB; set_wind: %s' % (before, during, received, rss_before, rss_during, wind.message))
assert before > 0.125, 'the node does not reach half its target even without slow subscribers'
assert received['markers'] <= 12, 'the markers subscriber was not slow: %s' % received
assert during >= 0.9 * before, 'the real-time factor dropped by more than 10 %'
assert wind.success, wind.message
assert rss_during - rss_before < 50 * 1024, 'the node grew by more than 50 MB'
PY
kill -0 "$node_pid" 2>/dev/null || fail "the node died"
echo "slow_subscriber: passed"
