#include "particle_sim/core/forces/plate_bending.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "particle_sim/core/builders/mesh_topology.h"

namespace particle_sim
{
namespace core
{
bool buildPlateBending(const std::vector<Eigen::Vector2d>& rest, const std::vector<Eigen::Vector3i>& triangles,
                       double rigidity, double damping, PlateBendingDef& def, std::string& error)
{
  // Cotangent weights of the flat pattern, edge by edge (mesh_topology.h): the corner opposite an
  // edge on each side adds half the cotangent of its angle to the edge's weight; an edge with one
  // side is on the border, and so are its ends. A vertex's area is a third of its triangles'.
  const int n = static_cast<int>(rest.size());
  std::vector<double> area(n, 0.0);
  for (std::size_t t = 0; t < triangles.size(); ++t)
  {
    const Eigen::Vector3i& tri = triangles[t];
    const Eigen::Vector2d e1 = rest[tri[1]] - rest[tri[0]], e2 = rest[tri[2]] - rest[tri[0]];
    const double twice_area = std::abs(e1.x() * e2.y() - e1.y() * e2.x());
    if (!(twice_area > 0.0))
    {
      error = "triangle " + std::to_string(t) + " has no area in the flat pattern (plate bending)";
      return false;
    }
    for (int c = 0; c < 3; ++c)
      area[tri[c]] += twice_area / 6.0;
  }
  std::vector<std::map<int, double>> edge_weight(n);  // ordered: the stencils come out the same every time
  std::vector<char> border(n, 0);
  for (const auto& [edge, sides] : meshEdges(triangles))
  {
    const auto [a, b] = edge;
    if (sides.size() == 1) border[a] = border[b] = 1;
    for (const EdgeSide& side : sides)
    {
      const Eigen::Vector2d u = rest[a] - rest[side.opposite], w = rest[b] - rest[side.opposite];
      const double cot = u.dot(w) / std::abs(u.x() * w.y() - u.y() * w.x());
      edge_weight[a][b] += 0.5 * cot;
      edge_weight[b][a] += 0.5 * cot;
    }
  }

  // One stencil per interior vertex: y_v = Σ_j w_vj (x_v − x_j).
  def = PlateBendingDef();
  def.rigidity = rigidity;
  def.damping = damping;
  def.row_start.push_back(0);
  for (int v = 0; v < n; ++v)
  {
    if (border[v] || edge_weight[v].empty()) continue;
    double diagonal = 0.0;
    for (const auto& [j, w] : edge_weight[v])
      diagonal += w;
    def.particles.push_back(v);
    def.weights.push_back(diagonal);
    for (const auto& [j, w] : edge_weight[v])
    {
      def.particles.push_back(j);
      def.weights.push_back(-w);
    }
    def.row_start.push_back(static_cast<int>(def.particles.size()));
    def.inverse_area.push_back(1.0 / area[v]);
  }
  return true;
}

Eigen::Vector3d PlateBendingForce::curvatureNormal(int s, const Eigen::Matrix3Xd& x) const
{
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  for (int k = def_.row_start[s]; k < def_.row_start[s + 1]; ++k)
    y.noalias() += def_.weights[k] * x.col(def_.particles[k]);
  return y;
}

void PlateBendingForce::addForces(const ForceContext& /*context*/, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                                  Eigen::Matrix3Xd& force) const
{
  // f_k = −w_k (B y + η ẏ) / A_v, stencil by stencil.
  for (int s = 0; s < def_.stencils(); ++s)
  {
    const Eigen::Vector3d push =
        -def_.inverse_area[s] * (def_.rigidity * curvatureNormal(s, x) + def_.damping * curvatureNormal(s, v));
    for (int k = def_.row_start[s]; k < def_.row_start[s + 1]; ++k)
      force.col(def_.particles[k]).noalias() += def_.weights[k] * push;
  }
}

void PlateBendingForce::coupledPairs(std::vector<std::pair<int, int>>& pairs) const
{
  for (int s = 0; s < def_.stencils(); ++s)
    for (int a = def_.row_start[s]; a < def_.row_start[s + 1]; ++a)
      for (int b = a + 1; b < def_.row_start[s + 1]; ++b)
        pairs.emplace_back(def_.particles[a], def_.particles[b]);
}

void PlateBendingForce::bindPattern(const ImplicitEulerSolver& solver)
{
  blocks_.clear();
  blocks_start_.clear();
  for (int s = 0; s < def_.stencils(); ++s)
  {
    blocks_start_.push_back(static_cast<int>(blocks_.size()));
    for (int a = def_.row_start[s]; a < def_.row_start[s + 1]; ++a)
      for (int b = def_.row_start[s]; b < def_.row_start[s + 1]; ++b)
        blocks_.push_back(solver.blockIndex(def_.particles[a], def_.particles[b]));
  }
}

void PlateBendingForce::addJacobians(const ForceContext& /*context*/, const Eigen::Matrix3Xd& /*x*/,
                                     ImplicitEulerSolver& solver) const
{
  // Constant: ∂f_a/∂x_b = −B w_a w_b / A_v I and ∂f_a/∂v_b = −η w_a w_b / A_v I.
  for (int s = 0; s < def_.stencils(); ++s)
  {
    const int start = def_.row_start[s], m = def_.row_start[s + 1] - start;
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b)
      {
        const double w = def_.weights[start + a] * def_.weights[start + b] * def_.inverse_area[s];
        solver.addBlock(blocks_[blocks_start_[s] + a * m + b], -def_.rigidity * w * Eigen::Matrix3d::Identity(),
                        -def_.damping * w * Eigen::Matrix3d::Identity());
      }
  }
}

void PlateBendingForce::addStabilityRows(const std::vector<Eigen::Vector3d>& /*rest*/,
                                         std::vector<double>& stiffness_rows, std::vector<double>& damping_rows) const
{
  for (int s = 0; s < def_.stencils(); ++s)
  {
    double sum = 0.0;
    for (int k = def_.row_start[s]; k < def_.row_start[s + 1]; ++k)
      sum += std::abs(def_.weights[k]);
    for (int k = def_.row_start[s]; k < def_.row_start[s + 1]; ++k)
    {
      const double row = std::abs(def_.weights[k]) * sum * def_.inverse_area[s];
      stiffness_rows[def_.particles[k]] += def_.rigidity * row;
      damping_rows[def_.particles[k]] += def_.damping * row;
    }
  }
}

void PlateBendingForce::setClassConstants(std::optional<SpringClass> spring_class, double stiffness, double damping)
{
  if (spring_class && *spring_class != SpringClass::Bend) return;
  def_.rigidity = stiffness;
  def_.damping = damping;
}

void PlateBendingForce::resetConstants()
{
  def_.rigidity = built_rigidity_;
  def_.damping = built_damping_;
}

void PlateBendingForce::addEnergy(const ForceContext& /*context*/, const Eigen::Matrix3Xd& x, double& energy) const
{
  for (int s = 0; s < def_.stencils(); ++s)
    energy += 0.5 * def_.rigidity * def_.inverse_area[s] * curvatureNormal(s, x).squaredNorm();
}

}  // namespace core
}  // namespace particle_sim
