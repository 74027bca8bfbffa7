#include "body_yaml.h"

namespace particle_sim
{
namespace scene
{
namespace body_yaml
{
core::SpringNetworkDef readSpringNetwork(MapReader& reader, const core::WorldDef& world, const std::string& source)
{
  core::SpringNetworkDef def;
  reader.require("name", def.name);

  const YAML::Node particles = reader.child("particles");
  if (!particles || !particles.IsSequence() || particles.size() == 0)
    reader.fail(particles ? particles : reader.node(),
                reader.field("particles") + " must be a non-empty list of {position, mass, velocity}");
  bool any_velocity = false;
  std::vector<Eigen::Vector3d> velocities;
  for (std::size_t i = 0; i < particles.size(); ++i)
  {
    MapReader p(particles[i], reader.field("particles") + "[" + std::to_string(i) + "]", source);
    Eigen::Vector3d position = Eigen::Vector3d::Zero(), velocity = Eigen::Vector3d::Zero();
    double mass = 0.1;
    p.require("position", position);
    p.read("mass", mass);
    any_velocity = any_velocity || p.has("velocity");
    p.read("velocity", velocity);
    p.finish();
    def.positions.push_back(position);
    def.masses.push_back(mass);
    velocities.push_back(velocity);
  }
  if (any_velocity) def.velocities = velocities;

  if (const YAML::Node springs = reader.child("springs"))
  {
    if (!springs.IsSequence()) reader.fail(springs, reader.field("springs") + " must be a list of springs");
    for (std::size_t k = 0; k < springs.size(); ++k)
    {
      MapReader s(springs[k], reader.field("springs") + "[" + std::to_string(k) + "]", source);
      std::vector<int> ends = readIndexList(s, "particles");
      if (ends.size() != 2) s.fail(springs[k], s.field("particles") + " must be two particle indices [i, j]");
      core::Spring spring;
      spring.i = ends[0];
      spring.j = ends[1];
      // The rest length is a number [m] or "initial": the distance at the start.
      const YAML::Node rest_node = s.child("rest_length");
      const bool initial_rest = !rest_node || (rest_node.IsScalar() && rest_node.Scalar() == "initial");
      if (!initial_rest) s.read("rest_length", spring.rest_length);
      s.read("stiffness", spring.stiffness);
      s.read("damping", spring.damping);
      if (s.has("class"))
      {
        std::string name;
        s.read("class", name);
        if (!core::parseSpringClass(name, spring.spring_class))
          s.fail(springs[k]["class"], s.field("class") + " = " + core::quoteReceived(name) +
                                          " is not a spring class; allowed: stretch, shear, bend");
      }
      s.finish();
      const int n = static_cast<int>(def.positions.size());
      if (initial_rest && spring.i >= 0 && spring.i < n && spring.j >= 0 && spring.j < n)
        spring.rest_length = (def.positions[spring.j] - def.positions[spring.i]).norm();
      def.springs.push_back(spring);
    }
  }
  def.pins = readIndexList(reader, "pins");
  readIntegrator(reader, def.integrator);
  reader.read("contact_thickness", def.contact_thickness);
  reader.read("tear_strain", def.tear_strain);
  readSelfCollision(reader, def.self_collision, source);
  reader.finish();
  check(reader, reader.field(""), core::validate(def, world.max_particles_per_body));
  return def;
}

YAML::Node writeSpringNetwork(const core::SpringNetworkDef& def)
{
  YAML::Node node;
  node["name"] = def.name;
  node["kind"] = "spring_network";
  for (std::size_t i = 0; i < def.positions.size(); ++i)
  {
    YAML::Node particle;
    particle.SetStyle(YAML::EmitterStyle::Flow);
    particle["position"] = vector3(def.positions[i]);
    particle["mass"] = def.masses[i];
    if (!def.velocities.empty()) particle["velocity"] = vector3(def.velocities[i]);
    node["particles"].push_back(particle);
  }
  for (const core::Spring& spring : def.springs)
  {
    YAML::Node s;
    s.SetStyle(YAML::EmitterStyle::Flow);
    s["particles"] = indexList({spring.i, spring.j});
    s["rest_length"] = spring.rest_length;
    s["stiffness"] = spring.stiffness;
    s["damping"] = spring.damping;
    s["class"] = core::toString(spring.spring_class);
    node["springs"].push_back(s);
  }
  node["pins"] = indexList(def.pins);
  node["contact_thickness"] = def.contact_thickness;
  if (def.tear_strain != 0.0) node["tear_strain"] = def.tear_strain;
  writeSelfCollision(node, def.self_collision);
  writeIntegrator(node, def.integrator);
  return node;
}

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
