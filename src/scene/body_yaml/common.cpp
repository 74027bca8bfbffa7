#include "body_yaml.h"

namespace particle_sim
{
namespace scene
{
namespace body_yaml
{
void check(const MapReader& reader, const std::string& prefix, const Status& status)
{
  if (!status) reader.fail(reader.node(), prefix + status.message);
}

namespace
{
// `key` into `value` when the map has it; left empty otherwise.
template <typename T>
void readSetting(MapReader& reader, const std::string& key, std::optional<T>& value)
{
  if (!reader.has(key)) return;
  T given{};
  reader.read(key, given);
  value = given;
}
}  // namespace

void readIntegrator(MapReader& reader, core::BodyIntegratorDef& integrator)
{
  std::string name;
  reader.read("integrator", name);
  if (reader.has("integrator"))
  {
    core::IntegratorType type;
    if (!core::parseIntegratorType(name, type))
      reader.fail(reader.node()["integrator"], reader.field("integrator") + " = " + core::quoteReceived(name) +
                                                   " is not an integrator; allowed: " + core::integratorTypeNames());
    integrator.type = type;
  }
  readSetting(reader, "verlet_damping", integrator.verlet_damping);
  readSetting(reader, "cg_tolerance", integrator.cg_tolerance);
  readSetting(reader, "cg_velocity_tolerance", integrator.cg_velocity_tolerance);
  readSetting(reader, "cg_max_iterations", integrator.cg_max_iterations);
  readSetting(reader, "max_substeps", integrator.max_substeps);
  if (reader.has("linear_solver"))
  {
    std::string solver;
    reader.read("linear_solver", solver);
    core::LinearSolverType type;
    if (!core::parseLinearSolverType(solver, type))
      reader.fail(reader.node()["linear_solver"],
                  reader.field("linear_solver") + " = " + core::quoteReceived(solver) +
                      " is not a linear solver; allowed: " + core::linearSolverTypeNames());
    integrator.linear_solver = type;
  }
}

void readIntegrator(MapReader& reader, core::IntegratorDef& integrator)
{
  core::BodyIntegratorDef given;
  readIntegrator(reader, given);
  integrator = core::resolve(given, integrator);
}

void writeIntegrator(YAML::Node node, const core::BodyIntegratorDef& i)
{
  if (i.type) node["integrator"] = core::toString(*i.type);
  if (i.verlet_damping) node["verlet_damping"] = *i.verlet_damping;
  if (i.cg_tolerance) node["cg_tolerance"] = *i.cg_tolerance;
  if (i.cg_velocity_tolerance) node["cg_velocity_tolerance"] = *i.cg_velocity_tolerance;
  if (i.cg_max_iterations) node["cg_max_iterations"] = *i.cg_max_iterations;
  if (i.max_substeps) node["max_substeps"] = *i.max_substeps;
  if (i.linear_solver) node["linear_solver"] = core::toString(*i.linear_solver);
}

void writeIntegrator(YAML::Node node, const core::IntegratorDef& i)
{
  writeIntegrator(node, core::settingEveryField(i));
}

void readSpringConstants(MapReader& parent, const std::string& key, double& stiffness, double& damping,
                         const std::string& source)
{
  const YAML::Node node = parent.child(key);
  if (!node) return;
  MapReader reader(node, parent.field(key), source);
  reader.read("stiffness", stiffness);
  reader.read("damping", damping);
  reader.finish();
}

YAML::Node springConstants(double stiffness, double damping)
{
  YAML::Node node;
  node.SetStyle(YAML::EmitterStyle::Flow);
  node["stiffness"] = stiffness;
  node["damping"] = damping;
  return node;
}

namespace
{
// Reads {stiffness, damping} of one class of a cloth: what the file gives is set, the rest stays
// unset (the cloth model's default, core::ClothConstant).
void readClothClass(MapReader& reader, const std::string& key, core::ClothConstants& constants,
                    const std::string& source)
{
  double stiffness = constants.stiffness, damping = constants.damping;
  readSpringConstants(reader, key, stiffness, damping, source);
  const YAML::Node node = reader.child(key);
  if (node && node["stiffness"]) constants.stiffness = stiffness;
  if (node && node["damping"]) constants.damping = damping;
}
}  // namespace

void readClothConstants(MapReader& reader, core::ClothConstants& stretch, core::ClothConstants* shear,
                        core::ClothConstants& bend, const std::string& source)
{
  readClothClass(reader, "stretch", stretch, source);
  if (shear) readClothClass(reader, "shear", *shear, source);
  readClothClass(reader, "bend", bend, source);
}

std::vector<int> readIndexList(MapReader& reader, const std::string& key)
{
  std::vector<int> values;
  const YAML::Node node = reader.child(key);
  if (!node) return values;
  if (!node.IsSequence()) reader.fail(node, reader.field(key) + " must be a list of particle indices");
  for (std::size_t i = 0; i < node.size(); ++i)
  {
    int value = 0;
    if (!node[i].IsScalar() || !YAML::convert<int>::decode(node[i], value))
      reader.fail(node[i], reader.field(key) + "[" + std::to_string(i) + "] must be an integer particle index");
    values.push_back(value);
  }
  return values;
}

YAML::Node indexList(const std::vector<int>& values)
{
  YAML::Node node(YAML::NodeType::Sequence);
  node.SetStyle(YAML::EmitterStyle::Flow);
  for (int v : values)
    node.push_back(v);
  return node;
}

void readPins(MapReader& reader, std::vector<int>& indices, std::vector<std::string>* names)
{
  const YAML::Node node = reader.child("pins");
  if (!node) return;
  if (!node.IsSequence()) reader.fail(node, reader.field("pins") + " must be a list of particle indices");
  for (std::size_t i = 0; i < node.size(); ++i)
  {
    int value = 0;
    if (node[i].IsScalar() && YAML::convert<int>::decode(node[i], value))
      indices.push_back(value);
    else if (names && node[i].IsScalar())
      names->push_back(node[i].Scalar());
    else
      reader.fail(node[i], reader.field("pins") + "[" + std::to_string(i) + "] must be an integer particle index" +
                               (names ? std::string(" or a pin name") : std::string()));
  }
}

void readSelfCollision(MapReader& reader, core::SelfCollisionDef& self_collision, const std::string& source)
{
  const YAML::Node node = reader.child("self_collision");
  if (!node) return;
  MapReader entry(node, reader.field("self_collision"), source);
  entry.read("enabled", self_collision.enabled);
  entry.read("thickness", self_collision.thickness);
  entry.finish();
}

void writeSelfCollision(YAML::Node node, const core::SelfCollisionDef& self_collision)
{
  if (!self_collision.enabled) return;
  YAML::Node entry;
  entry.SetStyle(YAML::EmitterStyle::Flow);
  entry["enabled"] = true;
  entry["thickness"] = self_collision.thickness;
  node["self_collision"] = entry;
}

void readStrainLimit(MapReader& reader, core::StrainLimitDef& limit)
{
  reader.read("max_strain", limit.max_strain);
  reader.read("strain_iterations", limit.iterations);
}

void writeStrainLimit(YAML::Node node, const core::StrainLimitDef& limit)
{
  node["max_strain"] = limit.max_strain;
  node["strain_iterations"] = limit.iterations;
}

YAML::Node vector3(const Eigen::Vector3d& v)
{
  YAML::Node node;
  node.SetStyle(YAML::EmitterStyle::Flow);
  for (int i = 0; i < 3; ++i)
    node.push_back(v[i]);
  return node;
}

}  // namespace body_yaml
}  // namespace scene
}  // namespace particle_sim
