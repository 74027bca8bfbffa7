#include "particle_sim/core/forces/baraff_witkin_model.h"

#include <algorithm>
#include <map>
#include <numeric>
#include <string>

#include "particle_sim/core/builders/mesh_topology.h"

namespace particle_sim
{
namespace core
{
bool buildBaraffWitkin(const std::vector<Eigen::Vector3d>& positions, const std::vector<Eigen::Vector2d>& uvs,
                       const std::vector<Eigen::Vector3i>& triangles, BaraffWitkinDef& def, std::string& error)
{
  def.triangles.clear();
  def.bends.clear();
  def.bend_weights.clear();

  // Triangles: rest map from (u, v).
  for (std::size_t k = 0; k < triangles.size(); ++k)
  {
    const Eigen::Vector3i& t = triangles[k];
    BwTriangle rest;
    if (!makeBwTriangle(t[0], t[1], t[2], uvs[t[0]], uvs[t[1]], uvs[t[2]], rest))
    {
      error = "triangles[" + std::to_string(k) + "] has no area in (u, v): its texture coordinates are degenerate";
      return false;
    }
    def.triangles.push_back(rest);
  }

  // Interior edges: the directed edge a -> b of one triangle and its two opposite vertices.
  for (const auto& [edge, sides] : meshEdges(triangles))
  {
    if (sides.size() != 2) continue;  // a border edge (or a non-manifold one) bends nothing
    BwBend bend;
    bend.v = {sides[0].opposite, sides[0].a, sides[0].b, sides[1].opposite};
    Eigen::Matrix<double, 3, 4> x;
    for (int m = 0; m < 4; ++m)
      x.col(m) = positions[bend.v[m]];
    bend.rest_angle = dihedralAngle(x);
    const double length2 = (uvs[sides[0].b] - uvs[sides[0].a]).squaredNorm();
    def.bends.push_back(bend);
    def.bend_weights.push_back(length2 /
                               (def.triangles[sides[0].triangle].area + def.triangles[sides[1].triangle].area));
  }
  return true;
}

BaraffWitkinModel::BaraffWitkinModel(const BaraffWitkinDef& def)
    : def_(def), built_def_(def), built_{def.stretch, def.shear, def.bend}
{
  // Each bend's two triangles, (x_0, x_1, x_2) and (x_3, x_2, x_1), found by their corners (once,
  // at build), so that a torn triangle takes the bends across its edges with it.
  auto key = [](int a, int b, int c) {
    std::array<int, 3> k{a, b, c};
    std::sort(k.begin(), k.end());
    return k;
  };
  std::map<std::array<int, 3>, int> triangle_of;
  for (std::size_t k = 0; k < def.triangles.size(); ++k)
  {
    const BwTriangle& t = def.triangles[k];
    triangle_of.emplace(key(t.v[0], t.v[1], t.v[2]), static_cast<int>(k));
  }
  for (const BwBend& b : def.bends)
  {
    auto side = [&](int a, int c, int d) {
      const auto found = triangle_of.find(key(a, c, d));
      return found == triangle_of.end() ? -1 : found->second;
    };
    built_bend_sides_.push_back({side(b.v[0], b.v[1], b.v[2]), side(b.v[3], b.v[2], b.v[1])});
  }
  bend_sides_ = built_bend_sides_;
  triangle_origin_.resize(def.triangles.size());
  std::iota(triangle_origin_.begin(), triangle_origin_.end(), 0);
  triangle_torn_.assign(def.triangles.size(), 0);
}

void BaraffWitkinModel::setConstants(SpringClass spring_class, double stiffness, double damping)
{
  SpringConstants& c = spring_class == SpringClass::Stretch ? def_.stretch
                       : spring_class == SpringClass::Shear ? def_.shear
                                                            : def_.bend;
  c = {stiffness, damping};
}

void BaraffWitkinModel::setClassConstants(std::optional<SpringClass> spring_class, double stiffness, double damping)
{
  for (SpringClass c : {SpringClass::Stretch, SpringClass::Shear, SpringClass::Bend})
  {
    if (!spring_class || *spring_class == c) setConstants(c, stiffness, damping);
  }
}

void BaraffWitkinModel::resetConstants()
{
  def_.stretch = built_[0];
  def_.shear = built_[1];
  def_.bend = built_[2];
}

const SpringConstants& BaraffWitkinModel::constants(SpringClass spring_class) const
{
  return spring_class == SpringClass::Stretch ? def_.stretch
         : spring_class == SpringClass::Shear ? def_.shear
                                              : def_.bend;
}

void BaraffWitkinModel::coupledPairs(std::vector<std::pair<int, int>>& pairs) const
{
  for (const BwTriangle& t : def_.triangles)
    for (int m = 0; m < 3; ++m)
      for (int n = m + 1; n < 3; ++n)
        pairs.emplace_back(t.v[m], t.v[n]);
  for (const BwBend& b : def_.bends)
    for (int m = 0; m < 4; ++m)
      for (int n = m + 1; n < 4; ++n)
        pairs.emplace_back(b.v[m], b.v[n]);
}

void BaraffWitkinModel::bindPattern(const ImplicitEulerSolver& solver)
{
  // The blocks of the triangles and bends as they are, and as built (after a vertex split the built
  // ones' may be missing, −1: mend() is followed by a rebuild of the pattern).
  auto bind = [&solver](const BaraffWitkinDef& def, std::vector<std::array<int, 9>>& triangle_blocks,
                        std::vector<std::array<int, 16>>& bend_blocks) {
    triangle_blocks.clear();
    bend_blocks.clear();
    for (const BwTriangle& t : def.triangles)
    {
      std::array<int, 9> blocks;
      for (int m = 0; m < 3; ++m)
        for (int n = 0; n < 3; ++n)
          blocks[3 * m + n] = solver.blockIndex(t.v[m], t.v[n]);
      triangle_blocks.push_back(blocks);
    }
    for (const BwBend& b : def.bends)
    {
      std::array<int, 16> blocks;
      for (int m = 0; m < 4; ++m)
        for (int n = 0; n < 4; ++n)
          blocks[4 * m + n] = solver.blockIndex(b.v[m], b.v[n]);
      bend_blocks.push_back(blocks);
    }
  };
  bind(def_, triangle_blocks_, bend_blocks_);
  bind(built_def_, built_triangle_blocks_, built_bend_blocks_);
}

void BaraffWitkinModel::splitParticle(int original, int copy, const std::vector<int>& /*neighbours*/,
                                      const std::vector<Eigen::Vector3i>& triangles)
{
  // Triangles are matched by their corners, in any order.
  auto sorted = [](int a, int b, int c) {
    std::array<int, 3> corners{a, b, c};
    std::sort(corners.begin(), corners.end());
    return corners;
  };
  auto given = [&](int a, int b, int c) {
    const std::array<int, 3> corners = sorted(a, b, c);
    for (const Eigen::Vector3i& t : triangles)
      if (sorted(t[0], t[1], t[2]) == corners) return true;
    return false;
  };
  for (BwTriangle& t : def_.triangles)
  {
    if (std::find(t.v.begin(), t.v.end(), original) != t.v.end() && given(t.v[0], t.v[1], t.v[2]))
      std::replace(t.v.begin(), t.v.end(), original, copy);
  }
  // A bend's triangles are (x0, x1, x2) and (x3, x2, x1): the one holding `original` decides (both
  // hold it when it is on their shared edge, and then they are in the same group).
  for (BwBend& b : def_.bends)
  {
    const auto at = std::find(b.v.begin(), b.v.end(), original);
    if (at == b.v.end()) continue;
    const bool moves = at == b.v.begin() + 3 ? given(b.v[3], b.v[2], b.v[1]) : given(b.v[0], b.v[1], b.v[2]);
    if (moves) *at = copy;
  }
}

Eigen::Matrix3d BaraffWitkinModel::corners(const Eigen::Matrix3Xd& x, const BwTriangle& t) const
{
  Eigen::Matrix3d c;
  for (int m = 0; m < 3; ++m)
    c.col(m) = x.col(t.v[m]);
  return c;
}

Eigen::Matrix<double, 3, 4> BaraffWitkinModel::corners(const Eigen::Matrix3Xd& x, const BwBend& b) const
{
  Eigen::Matrix<double, 3, 4> c;
  for (int m = 0; m < 4; ++m)
    c.col(m) = x.col(b.v[m]);
  return c;
}

void BaraffWitkinModel::addForces(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& force) const
{
  // Each condition C with gradient g (over its corners) and corner velocities u pushes with
  // f = −k g C − k_d g Ċ, Ċ = g·u.
  for (const BwTriangle& t : def_.triangles)
  {
    const Eigen::Matrix3d xc = corners(x, t);
    Gradient9 u;
    for (int m = 0; m < 3; ++m)
      u.segment<3>(3 * m) = v.col(t.v[m]);
    Eigen::Vector2d c;
    std::array<Gradient9, 2> g;
    stretchCondition(t, xc, def_.b_u, def_.b_v, c, g);
    double shear;
    Gradient9 gs;
    shearCondition(t, xc, shear, gs);
    Gradient9 f = Gradient9::Zero();
    for (int d = 0; d < 2; ++d)
      f -= (def_.stretch.stiffness * c[d] + def_.stretch.damping * g[d].dot(u)) / t.area * g[d];
    f -= (def_.shear.stiffness * shear + def_.shear.damping * gs.dot(u)) / t.area * gs;
    for (int m = 0; m < 3; ++m)
      force.col(t.v[m]) += f.segment<3>(3 * m);
  }
  for (std::size_t k = 0; k < def_.bends.size(); ++k)
  {
    const BwBend& b = def_.bends[k];
    double c;
    Gradient12 g;
    bendCondition(b, corners(x, b), c, g);
    Gradient12 u;
    for (int m = 0; m < 4; ++m)
      u.segment<3>(3 * m) = v.col(b.v[m]);
    const Gradient12 f = -def_.bend_weights[k] * (def_.bend.stiffness * c + def_.bend.damping * g.dot(u)) * g;
    for (int m = 0; m < 4; ++m)
      force.col(b.v[m]) += f.segment<3>(3 * m);
  }
}

void BaraffWitkinModel::addJacobians(const Eigen::Matrix3Xd& x, ImplicitEulerSolver& solver) const
{
  for (std::size_t k = 0; k < def_.triangles.size(); ++k)
  {
    const BwTriangle& t = def_.triangles[k];
    const Eigen::Matrix3d xc = corners(x, t);
    Eigen::Vector2d c;
    std::array<Gradient9, 2> g;
    std::array<Hessian9, 2> h;
    stretchCondition(t, xc, def_.b_u, def_.b_v, c, g, &h);
    double shear;
    Gradient9 gs;
    shearCondition(t, xc, shear, gs);

    // K = −k (g gᵀ + H C) for stretch (H C only when stretched), −k g gᵀ for shear; D = −k_d g gᵀ.
    const double ks = def_.stretch.stiffness / t.area, ds = def_.stretch.damping / t.area;
    const double kh = def_.shear.stiffness / t.area, dh = def_.shear.damping / t.area;
    Hessian9 dfdx = -kh * gs * gs.transpose();
    Hessian9 dfdv = -dh * gs * gs.transpose();
    for (int d = 0; d < 2; ++d)
    {
      const Hessian9 outer = g[d] * g[d].transpose();
      dfdx -= ks * outer;
      if (c[d] > 0.0) dfdx -= ks * c[d] * h[d];
      dfdv -= ds * outer;
    }
    for (int m = 0; m < 3; ++m)
      for (int n = 0; n < 3; ++n)
        solver.addBlock(triangle_blocks_[k][3 * m + n], dfdx.block<3, 3>(3 * m, 3 * n), dfdv.block<3, 3>(3 * m, 3 * n));
  }
  for (std::size_t k = 0; k < def_.bends.size(); ++k)
  {
    const BwBend& b = def_.bends[k];
    double c;
    Gradient12 g;
    bendCondition(b, corners(x, b), c, g);
    const Hessian12 outer = g * g.transpose();
    const double w = def_.bend_weights[k];
    for (int m = 0; m < 4; ++m)
      for (int n = 0; n < 4; ++n)
        solver.addBlock(bend_blocks_[k][4 * m + n], -w * def_.bend.stiffness * outer.block<3, 3>(3 * m, 3 * n),
                        -w * def_.bend.damping * outer.block<3, 3>(3 * m, 3 * n));
  }
}

void BaraffWitkinModel::addStabilityRows(const std::vector<Eigen::Vector3d>& x, std::vector<double>& stiffness_rows,
                                         std::vector<double>& damping_rows) const
{
  // Each condition with corner gradient norms |g_m| and stiffness k adds k |g_m| Σ_n |g_n| to row m.
  auto add = [&](const auto& vertices, const auto& norms, double k, double d) {
    double sum = 0.0;
    for (double g : norms)
      sum += g;
    for (std::size_t m = 0; m < norms.size(); ++m)
    {
      stiffness_rows[vertices[m]] += k * norms[m] * sum;
      damping_rows[vertices[m]] += d * norms[m] * sum;
    }
  };
  for (const BwTriangle& t : def_.triangles)
  {
    // At rest |ŵ| = 1 and |w_u| = |w_v| = 1: |∂C_u/∂x_m| = a |dwu_m|, |∂C_shear/∂x_m| <= a (|dwu_m| + |dwv_m|);
    // with k = stiffness / a per condition.
    std::array<double, 3> u, v, shear;
    for (int m = 0; m < 3; ++m)
    {
      u[m] = t.area * std::abs(t.dwu[m]);
      v[m] = t.area * std::abs(t.dwv[m]);
      shear[m] = u[m] + v[m];
    }
    add(t.v, u, def_.stretch.stiffness / t.area, def_.stretch.damping / t.area);
    add(t.v, v, def_.stretch.stiffness / t.area, def_.stretch.damping / t.area);
    add(t.v, shear, def_.shear.stiffness / t.area, def_.shear.damping / t.area);
  }
  for (std::size_t k = 0; k < def_.bends.size(); ++k)
  {
    const BwBend& b = def_.bends[k];
    Eigen::Matrix<double, 3, 4> corners_at_rest;
    for (int m = 0; m < 4; ++m)
      corners_at_rest.col(m) = x[b.v[m]];
    double c;
    Gradient12 g;
    bendCondition(b, corners_at_rest, c, g);
    std::array<double, 4> norms;
    for (int m = 0; m < 4; ++m)
      norms[m] = g.segment<3>(3 * m).norm();
    add(b.v, norms, def_.bend_weights[k] * def_.bend.stiffness, def_.bend_weights[k] * def_.bend.damping);
  }
}

double BaraffWitkinModel::energy(const Eigen::Matrix3Xd& x) const
{
  double energy = 0.0;
  for (const BwTriangle& t : def_.triangles)
  {
    const Eigen::Matrix3d xc = corners(x, t);
    Eigen::Vector2d c;
    std::array<Gradient9, 2> g;
    stretchCondition(t, xc, def_.b_u, def_.b_v, c, g);
    double shear;
    Gradient9 gs;
    shearCondition(t, xc, shear, gs);
    energy += 0.5 * (def_.stretch.stiffness * c.squaredNorm() + def_.shear.stiffness * shear * shear) / t.area;
  }
  for (std::size_t k = 0; k < def_.bends.size(); ++k)
  {
    double c;
    Gradient12 g;
    bendCondition(def_.bends[k], corners(x, def_.bends[k]), c, g);
    energy += 0.5 * def_.bend_weights[k] * def_.bend.stiffness * c * c;
  }
  return energy;
}

namespace
{
double triangleStrain(const BwTriangle& t, const Eigen::Matrix3d& xc, double b_u, double b_v)
{
  const Eigen::Vector3d wu = t.dwu[0] * xc.col(0) + t.dwu[1] * xc.col(1) + t.dwu[2] * xc.col(2);
  const Eigen::Vector3d wv = t.dwv[0] * xc.col(0) + t.dwv[1] * xc.col(1) + t.dwv[2] * xc.col(2);
  return std::max(wu.norm() / b_u, wv.norm() / b_v) - 1.0;
}
}  // namespace

double BaraffWitkinModel::maxStrain(const Eigen::Matrix3Xd& x) const
{
  double strain = 0.0;
  for (const BwTriangle& t : def_.triangles)
    strain = std::max(strain, triangleStrain(t, corners(x, t), def_.b_u, def_.b_v));
  return strain;
}

void BaraffWitkinModel::vertexStrains(const Eigen::Matrix3Xd& x, std::vector<double>& strains) const
{
  for (const BwTriangle& t : def_.triangles)
  {
    const double strain = triangleStrain(t, corners(x, t), def_.b_u, def_.b_v);
    for (int m = 0; m < 3; ++m)
      strains[t.v[m]] = std::max(strains[t.v[m]], strain);
  }
}

void BaraffWitkinModel::tear(const Eigen::Matrix3Xd& x, double tear_strain, TearRecord& torn)
{
  // Triangles past the tear strain go, in one pass that keeps the others in order (with their
  // blocks); then every bend with a torn triangle on either side of its edge.
  const bool bound = !triangle_blocks_.empty();
  std::size_t kept = 0;
  bool any = false;
  for (std::size_t k = 0; k < def_.triangles.size(); ++k)
  {
    const BwTriangle& t = def_.triangles[k];
    if (triangleStrain(t, corners(x, t), def_.b_u, def_.b_v) > tear_strain)
    {
      torn.triangles.emplace_back(t.v[0], t.v[1], t.v[2]);
      triangle_torn_[triangle_origin_[k]] = 1;
      any = true;
      continue;
    }
    def_.triangles[kept] = t;
    triangle_origin_[kept] = triangle_origin_[k];
    if (bound) triangle_blocks_[kept] = triangle_blocks_[k];
    ++kept;
  }
  if (!any) return;
  def_.triangles.resize(kept);
  triangle_origin_.resize(kept);
  if (bound) triangle_blocks_.resize(kept);

  kept = 0;
  for (std::size_t k = 0; k < def_.bends.size(); ++k)
  {
    const std::array<int, 2>& sides = bend_sides_[k];
    if ((sides[0] >= 0 && triangle_torn_[sides[0]]) || (sides[1] >= 0 && triangle_torn_[sides[1]])) continue;
    def_.bends[kept] = def_.bends[k];
    def_.bend_weights[kept] = def_.bend_weights[k];
    bend_sides_[kept] = sides;
    if (bound) bend_blocks_[kept] = bend_blocks_[k];
    ++kept;
  }
  def_.bends.resize(kept);
  def_.bend_weights.resize(kept);
  bend_sides_.resize(kept);
  if (bound) bend_blocks_.resize(kept);
}

void BaraffWitkinModel::mend()
{
  def_.triangles = built_def_.triangles;
  def_.bends = built_def_.bends;
  def_.bend_weights = built_def_.bend_weights;
  triangle_blocks_ = built_triangle_blocks_;
  bend_blocks_ = built_bend_blocks_;
  bend_sides_ = built_bend_sides_;
  triangle_origin_.resize(built_def_.triangles.size());
  std::iota(triangle_origin_.begin(), triangle_origin_.end(), 0);
  std::fill(triangle_torn_.begin(), triangle_torn_.end(), 0);
}

}  // namespace core
}  // namespace particle_sim
