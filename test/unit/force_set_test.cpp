// ForceSet::computeForces() lets its first element write the forces (ForceElement::setForces())
// instead of zeroing them first: the result must be the bits of zeroing and adding every element.
// SpringForces adds its springs two at a time: the result must be the bits of one at a time.

#include "particle_sim/core/forces/force_set.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "particle_sim/core/forces/gravity.h"
#include "particle_sim/core/forces/springs.h"
#include "particle_sim/core/worker_pool.h"
#include "test_helpers.h"

namespace core = particle_sim::core;
using particle_sim_test::sameBits;

namespace
{
// 0 + Σ element forces, the elements added in order onto a zeroed array.
Eigen::Matrix3Xd zeroedThenAdded(const std::vector<const core::ForceElement*>& elements,
                                 const core::ForceContext& context, const Eigen::Matrix3Xd& x,
                                 const Eigen::Matrix3Xd& v)
{
  Eigen::Matrix3Xd force = Eigen::Matrix3Xd::Zero(3, x.cols());
  for (const core::ForceElement* element : elements)
    element->addForces(context, x, v, force);
  return force;
}

// A 4097-particle chain (more than one chunk of a shared loop) with random masses and state.
struct Chain
{
  Chain()
  {
    mass = Eigen::VectorXd::Random(particles).array().abs() + 0.01;
    x = Eigen::Matrix3Xd::Random(3, particles);
    v = Eigen::Matrix3Xd::Random(3, particles);
    for (int i = 0; i + 1 < particles; ++i)
      springs.push_back(core::Spring{i, i + 1, 0.01, 100.0 + i % 5, 0.1, core::SpringClass::Stretch});
  }
  static constexpr int particles = 4097;
  Eigen::VectorXd mass;
  std::vector<char> pinned = std::vector<char>(particles, 0);
  Eigen::Matrix3Xd x, v;
  std::vector<core::Spring> springs;
};

// 5000 springs on `chain`, mostly neighbours (shared ends, long runs) and some far pairs; every 5th a
// damper alone (so that the damping term's rounding shows). Every 7th and every 11th spring gets its
// two ends at the same position in `x` (zero length).
std::vector<core::Spring> awkwardSprings(const Chain& chain, Eigen::Matrix3Xd& x)
{
  std::vector<core::Spring> springs;
  for (int k = 0; k < 5000; ++k)
  {
    const int i = (k * 3) % (chain.particles - 40);
    const int j = k % 13 == 0 ? (i * 7 + 11) % chain.particles : i + 1 + k % 3;
    springs.push_back(
        core::Spring{i, j, 0.02, k % 5 == 0 ? 0.0 : 50.0 + k % 7, 0.05 * (1 + k % 3), core::SpringClass::Stretch});
  }
  x = chain.x;
  for (std::size_t k = 0; k < springs.size(); k += 7)
    x.col(springs[k].j) = x.col(springs[k].i);
  for (std::size_t k = 4; k < springs.size(); k += 11)
    x.col(springs[k].j) = x.col(springs[k].i);
  return springs;
}
}  // namespace

TEST(ForceSet, FirstElementWritesTheBitsOfZeroingAndAdding)
{
  const Chain chain;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int threads : {1, 2})
  {
    core::WorkerPool pool(threads);
    // A gravity with a −0 component: 0 + (−0) is +0, which writing m g alone would not give.
    const Eigen::Vector3d gravity(-0.0, 1.5, -9.81);
    const core::ForceContext context{chain.mass, chain.pinned, gravity, {}, 0.0, &pool};

    // Gravity alone: every column written, whatever was in the array.
    core::GravityForce gravity_force;
    Eigen::Matrix3Xd written = Eigen::Matrix3Xd::Constant(3, chain.particles, nan);
    gravity_force.setForces(context, chain.x, chain.v, written);
    const Eigen::Matrix3Xd expected_gravity = zeroedThenAdded({&gravity_force}, context, chain.x, chain.v);
    EXPECT_TRUE(sameBits(expected_gravity, written)) << threads << " threads";
    EXPECT_FALSE(std::signbit(written(0, 0)));  // +0, as 0 + (−0)

    // A set of gravity then springs, and of springs alone (the default setForces()).
    core::ForceSet with_gravity, springs_only;
    with_gravity.add(std::make_unique<core::GravityForce>());
    with_gravity.add(std::make_unique<core::SpringForces>(chain.springs));
    springs_only.add(std::make_unique<core::SpringForces>(chain.springs));
    const core::SpringForces springs(chain.springs);
    for (const auto& [set, elements] :
         {std::make_pair(&with_gravity, std::vector<const core::ForceElement*>{&gravity_force, &springs}),
          std::make_pair(&springs_only, std::vector<const core::ForceElement*>{&springs})})
    {
      Eigen::Matrix3Xd force = Eigen::Matrix3Xd::Constant(3, chain.particles, nan);
      set->computeForces(context, chain.x, chain.v, force);
      EXPECT_TRUE(sameBits(zeroedThenAdded(elements, context, chain.x, chain.v), force)) << threads << " threads";
    }
  }
}

// SpringForces adds its springs two at a time in paired arithmetic: the result must be the bits of
// springForce() added spring after spring in list order, for lists of every length (the odd spring
// at the end), with zero-length springs (no direction, no force) in either lane of a pair, with
// springs sharing ends, and on the shared loop at two threads.
TEST(SpringForces, AddsTheBitsOfEachSpringForceInListOrder)
{
  const Chain chain;
  Eigen::Matrix3Xd x;
  const std::vector<core::Spring> springs = awkwardSprings(chain, x);

  for (std::size_t count : {std::size_t{0}, std::size_t{1}, std::size_t{2}, std::size_t{3}, std::size_t{8},
                            std::size_t{4999}, std::size_t{5000}})
  {
    const std::vector<core::Spring> list(springs.begin(), springs.begin() + count);
    Eigen::Matrix3Xd expected = Eigen::Matrix3Xd::Random(3, chain.particles);
    const Eigen::Matrix3Xd start = expected;
    int zero_length = 0;
    for (const core::Spring& s : list)
    {
      const Eigen::Vector3d f = core::springForce(x.col(s.i), x.col(s.j), chain.v.col(s.i), chain.v.col(s.j),
                                                  s.rest_length, s.stiffness, s.damping);
      expected.col(s.i) += f;
      expected.col(s.j) -= f;
      zero_length += (x.col(s.i) - x.col(s.j)).norm() == 0.0;
    }
    if (count >= 4999)
    {
      EXPECT_GT(zero_length, 1000);
    }
    for (int threads : {1, 2})
    {
      core::WorkerPool pool(threads);
      const core::ForceContext context{chain.mass, chain.pinned, Eigen::Vector3d::Zero(), {}, 0.0, &pool};
      const core::SpringForces forces(list);
      Eigen::Matrix3Xd force = start;
      forces.addForces(context, x, chain.v, force);
      EXPECT_TRUE(sameBits(expected, force)) << count << " springs, " << threads << " threads";
    }
  }
}

// ForceSet::computeForcesAndEnergy() takes the springs' energy out of their force pass (each spring's
// stretch is the force's): its forces must be the bits of computeForces() and its energy the bits of
// energy(), with zero-length springs, for every list length (the odd spring of a pair), at one and two
// threads (where a spring across two chunks of particles is visited twice, or, for springs numbered
// without locality, each spring once into a list), and with the springs as the set's first element
// (which keeps nothing: their energy is then computed apart).
TEST(ForceSet, ForcesAndEnergyInOnePassAreTheBitsOfEachAlone)
{
  const Chain chain;
  Eigen::Matrix3Xd x;
  const std::vector<core::Spring> springs = awkwardSprings(chain, x);
  std::vector<core::Spring> far = springs;  // every spring across the chain: no locality
  for (core::Spring& s : far)
    s.j = (s.i + chain.particles / 2) % chain.particles;
  std::vector<std::vector<core::Spring>> lists;
  for (std::size_t count : {std::size_t{0}, std::size_t{1}, std::size_t{3}, std::size_t{4999}, std::size_t{5000}})
    lists.emplace_back(springs.begin(), springs.begin() + count);
  lists.push_back(far);
  for (const std::vector<core::Spring>& list : lists)
  {
    const std::size_t count = list.size();
    core::ForceSet with_gravity, springs_first;
    with_gravity.add(std::make_unique<core::GravityForce>());
    with_gravity.add(std::make_unique<core::SpringForces>(list));
    springs_first.add(std::make_unique<core::SpringForces>(list));
    springs_first.add(std::make_unique<core::GravityForce>());
    for (int threads : {1, 2})
    {
      core::WorkerPool pool(threads);
      const core::ForceContext context{chain.mass, chain.pinned, Eigen::Vector3d(0.3, -0.2, -9.81), {}, 0.0, &pool};
      for (const core::ForceSet* set : {&with_gravity, &springs_first})
      {
        Eigen::Matrix3Xd expected(3, chain.particles), force(3, chain.particles);
        set->computeForces(context, x, chain.v, expected);
        const double energy = set->computeForcesAndEnergy(context, x, chain.v, force);
        EXPECT_TRUE(sameBits(expected, force)) << count << " springs, " << threads << " threads";
        const double expected_energy = set->energy(context, x);
        EXPECT_EQ(0, std::memcmp(&expected_energy, &energy, sizeof energy))
            << count << " springs, " << threads << " threads: " << energy << " against " << expected_energy;
        // The energy of another state, after forces of that state: not what the last pass kept.
        const Eigen::Matrix3Xd moved = x * 1.5;
        set->computeForces(context, moved, chain.v, force);
        const double moved_energy = set->computeForcesAndEnergy(context, moved, chain.v, force);
        const double expected_moved = set->energy(context, moved);
        EXPECT_EQ(0, std::memcmp(&expected_moved, &moved_energy, sizeof moved_energy)) << count << " springs";
        if (count > 0)
        {
          EXPECT_NE(expected_moved, expected_energy);
        }
      }
    }
  }
}
