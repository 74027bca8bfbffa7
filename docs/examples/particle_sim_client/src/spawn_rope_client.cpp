// Spawns a rope in a running particle_sim node through ~spawn_rope, then reads it back from
// ~status and prints its particle count and energies.
//
//   rosrun particle_sim_client spawn_rope_client [_sim:=/particle_sim] [_name:=cpp_rope]
// Exit status 0 when the rope was spawned and seen in the status, 1 otherwise.
#include <particle_sim/SimStatus.h>
#include <particle_sim/SpawnRope.h>
#include <ros/ros.h>

#include <cstdio>
#include <string>

int main(int argc, char** argv)
{
  ros::init(argc, argv, "spawn_rope_client", ros::init_options::AnonymousName);
  ros::NodeHandle private_node("~");
  const std::string sim = private_node.param<std::string>("sim", "/particle_sim");
  const std::string name = private_node.param<std::string>("name", "cpp_rope");
  ros::NodeHandle node;

  // Spawn: 10 particles from (0, 0, 2) to (1, 0, 2), 0.1 kg, particle 0 pinned.
  ros::ServiceClient spawn = node.serviceClient<particle_sim::SpawnRope>(sim + "/spawn_rope");
  if (!spawn.waitForExistence(ros::Duration(10.0)))
  {
    std::fprintf(stderr, "no service %s/spawn_rope: is particle_sim running?\n", sim.c_str());
    return 1;
  }
  particle_sim::SpawnRope rope;
  rope.request.name = name;
  rope.request.particles = 10;
  rope.request.start.z = 2.0;
  rope.request.end.x = 1.0;
  rope.request.end.z = 2.0;
  rope.request.mass = 0.1;
  rope.request.stretch_stiffness = 500.0;
  rope.request.stretch_damping = 0.2;
  rope.request.pins = {0};
  if (!spawn.call(rope) || !rope.response.success)
  {
    std::fprintf(stderr, "spawn_rope refused: %s\n", rope.response.message.c_str());
    return 1;
  }
  std::printf("spawn_rope: %s\n", rope.response.message.c_str());

  // Read it back from one ~status message.
  const auto status = ros::topic::waitForMessage<particle_sim::SimStatus>(sim + "/status", node, ros::Duration(10.0));
  if (!status)
  {
    std::fprintf(stderr, "no message on %s/status within 10 s\n", sim.c_str());
    return 1;
  }
  for (const auto& body : status->bodies)
  {
    if (body.name != name) continue;
    std::printf("status: t = %.3f s, body '%s' (%s): %u particles, %u pinned, kinetic %.4f J, potential %.4f J\n",
                status->sim_time, body.name.c_str(), body.type.c_str(), body.particle_count, body.pinned_count,
                body.kinetic_energy, body.potential_energy);
    return 0;
  }
  std::fprintf(stderr, "body '%s' is not in %s/status\n", name.c_str(), sim.c_str());
  return 1;
}
