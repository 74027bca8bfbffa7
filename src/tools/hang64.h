#pragma once
// hang64, Bullet's soft-body test cloth rebuilt as a particle_sim spring network: for particle_sim_perf,
// which times it, and for particle_sim_bullet_peer, which times it beside Bullet's own (goal 7 of
// issue 13).

#include <cstddef>

#include "particle_sim/core/spring_network.h"

namespace particle_sim_bench
{
// n x n particles on a 1 m square, horizontal at z = 2, two adjacent corners pinned, 1 kg;
// structural springs and one shear diagonal per quad, alternating like
// btSoftBodyHelpers::CreatePatch; k = 1000 N/m, damping 0.01 N·s/m. hang64 is n = 64.
inline particle_sim::core::SpringNetworkDef hang64(int n)
{
  namespace core = particle_sim::core;
  core::SpringNetworkDef def;
  def.name = "hang64";
  def.shape = core::NetworkShape::Cloth;
  auto index = [n](int a, int b) { return b * n + a; };
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a)
      def.positions.emplace_back(static_cast<double>(a) / (n - 1), static_cast<double>(b) / (n - 1), 2.0);
  def.masses.assign(static_cast<std::size_t>(n) * n, 1.0 / (n * n));
  auto spring = [&](int i, int j, core::SpringClass spring_class) {
    core::Spring s;
    s.i = i;
    s.j = j;
    s.rest_length = (def.positions[i] - def.positions[j]).norm();
    s.stiffness = 1000.0;
    s.damping = 0.01;
    s.spring_class = spring_class;
    def.springs.push_back(s);
  };
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a)
    {
      if (a + 1 < n) spring(index(a, b), index(a + 1, b), core::SpringClass::Stretch);
      if (b + 1 < n) spring(index(a, b), index(a, b + 1), core::SpringClass::Stretch);
      if (a + 1 < n && b + 1 < n)
      {
        if ((a + b) % 2 == 0)
          spring(index(a, b), index(a + 1, b + 1), core::SpringClass::Shear);
        else
          spring(index(a + 1, b), index(a, b + 1), core::SpringClass::Shear);
        def.triangles.emplace_back(index(a, b), index(a + 1, b), index(a + 1, b + 1));
        def.triangles.emplace_back(index(a, b), index(a + 1, b + 1), index(a, b + 1));
      }
    }
  def.pins = {index(0, 0), index(n - 1, 0)};
  return def;
}
}  // namespace particle_sim_bench
