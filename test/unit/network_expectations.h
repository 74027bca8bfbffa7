#pragma once
// Expectations on built spring networks, shared by the tests that compare two ways of building one.

#include <gtest/gtest.h>

#include <string>

#include "particle_sim/core/spring.h"
#include "particle_sim/core/spring_network.h"

namespace particle_sim_test
{
inline void expectConstants(const particle_sim::core::SpringConstants& actual,
                            const particle_sim::core::SpringConstants& expected, const std::string& where)
{
  EXPECT_EQ(actual.stiffness, expected.stiffness) << where;
  EXPECT_EQ(actual.damping, expected.damping) << where;
}

// Two networks are the same cloth: particles, masses, pins, triangles, every spring with its
// constants, and the Baraff–Witkin conditions with theirs.
inline void expectSameNetwork(const particle_sim::core::SpringNetworkDef& a,
                              const particle_sim::core::SpringNetworkDef& b)
{
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.masses, b.masses);
  EXPECT_EQ(a.pins, b.pins);
  EXPECT_EQ(a.triangles, b.triangles);
  ASSERT_EQ(a.springs.size(), b.springs.size());
  for (std::size_t k = 0; k < a.springs.size(); ++k)
  {
    const particle_sim::core::Spring &s = a.springs[k], &t = b.springs[k];
    EXPECT_EQ(s.i, t.i) << "spring " << k;
    EXPECT_EQ(s.j, t.j) << "spring " << k;
    EXPECT_EQ(s.rest_length, t.rest_length) << "spring " << k;
    EXPECT_EQ(s.stiffness, t.stiffness) << "spring " << k;
    EXPECT_EQ(s.damping, t.damping) << "spring " << k;
    EXPECT_EQ(s.spring_class, t.spring_class) << "spring " << k;
  }
  const particle_sim::core::BaraffWitkinDef &p = a.baraff_witkin, &q = b.baraff_witkin;
  ASSERT_EQ(p.triangles.size(), q.triangles.size());
  for (std::size_t k = 0; k < p.triangles.size(); ++k)
  {
    EXPECT_EQ(p.triangles[k].v, q.triangles[k].v) << "triangle " << k;
    EXPECT_EQ(p.triangles[k].area, q.triangles[k].area) << "triangle " << k;
  }
  ASSERT_EQ(p.bends.size(), q.bends.size());
  for (std::size_t k = 0; k < p.bends.size(); ++k)
  {
    EXPECT_EQ(p.bends[k].v, q.bends[k].v) << "bend " << k;
    EXPECT_EQ(p.bends[k].rest_angle, q.bends[k].rest_angle) << "bend " << k;
  }
  EXPECT_EQ(p.bend_weights, q.bend_weights);
  expectConstants(p.stretch, q.stretch, "Baraff–Witkin stretch");
  expectConstants(p.shear, q.shear, "Baraff–Witkin shear");
  expectConstants(p.bend, q.bend, "Baraff–Witkin bend");
  EXPECT_EQ(p.b_u, q.b_u);
  EXPECT_EQ(p.b_v, q.b_v);
}

}  // namespace particle_sim_test
