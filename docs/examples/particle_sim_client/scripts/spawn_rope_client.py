#!/usr/bin/env python3
"""Spawns a rope in a running particle_sim node through ~spawn_rope, then reads it back from
~status and prints its particle count and energies.

  rosrun particle_sim_client spawn_rope_client.py [_sim:=/particle_sim] [_name:=py_rope]
Exit status 0 when the rope was spawned and seen in the status, 1 otherwise."""
import sys

import rospy
from geometry_msgs.msg import Point
from particle_sim.msg import SimStatus
from particle_sim.srv import SpawnRope, SpawnRopeRequest


def main():
    rospy.init_node("spawn_rope_client_py", anonymous=True)
    sim = rospy.get_param("~sim", "/particle_sim")
    name = rospy.get_param("~name", "py_rope")

    # Spawn: 10 particles from (0, 0, 2) to (1, 0, 2), 0.1 kg, particle 0 pinned.
    try:
        rospy.wait_for_service(sim + "/spawn_rope", timeout=10.0)
    except rospy.ROSException:
        print(f"no service {sim}/spawn_rope: is particle_sim running?", file=sys.stderr)
        return 1
    spawn = rospy.ServiceProxy(sim + "/spawn_rope", SpawnRope)
    answer = spawn(SpawnRopeRequest(name=name, particles=10, start=Point(0, 0, 2), end=Point(1, 0, 2), mass=0.1,
                                    stretch_stiffness=500.0, stretch_damping=0.2, pins=[0]))
    if not answer.success:
        print(f"spawn_rope refused: {answer.message}", file=sys.stderr)
        return 1
    print(f"spawn_rope: {answer.message}")

    # Read it back from one ~status message.
    try:
        status = rospy.wait_for_message(sim + "/status", SimStatus, timeout=10.0)
    except rospy.ROSException:
        print(f"no message on {sim}/status within 10 s", file=sys.stderr)
        return 1
    for body in status.bodies:
        if body.name == name:
            print(f"status: t = {status.sim_time:.3f} s, body '{body.name}' ({body.type}): {body.particle_count} "
                  f"particles, {body.pinned_count} pinned, kinetic {body.kinetic_energy:.4f} J, "
                  f"potential {body.potential_energy:.4f} J")
            return 0
    print(f"body '{name}' is not in {sim}/status", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
