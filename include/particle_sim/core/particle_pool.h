#pragma once

#include <Eigen/Core>

namespace particle_sim
{
namespace core
{
/// The particles of one body, stored as struct-of-arrays: each attribute is one contiguous
/// array, and a 3-vector attribute is a 3 x capacity column-major matrix (x0 y0 z0 x1 ...), so a
/// whole attribute can be viewed as one flat vector of 3n doubles by the implicit solver.
///
/// Only the first `size()` columns are live. The capacity is fixed when the body is built;
/// nothing here allocates after `resize()`. A step may swap an array's storage with another of the
/// body's (the state a step starts from is kept that way): hold the matrices by reference, never a
/// pointer into their data, from one step to the next.
struct ParticlePool
{
  Eigen::Matrix3Xd position;           ///< [m]
  Eigen::Matrix3Xd velocity;           ///< [m/s]
  Eigen::Matrix3Xd previous_position;  ///< [m], position one step ago (Verlet)
  Eigen::VectorXd inverse_mass;        ///< [1/kg]; 0 marks a pinned (kinematic) particle
  Eigen::VectorXd age;                 ///< [s] since the particle was created

  /// Allocates room for `capacity` particles and sets the live count to `live`.
  void resize(int capacity, int live)
  {
    position.setZero(3, capacity);
    velocity.setZero(3, capacity);
    previous_position.setZero(3, capacity);
    inverse_mass.setZero(capacity);
    age.setZero(capacity);
    live_count = live;
  }

  int capacity() const { return static_cast<int>(inverse_mass.size()); }
  int size() const { return live_count; }

  /// Copies particle `from` over particle `to` (used to keep live particles contiguous).
  void copy(int from, int to)
  {
    position.col(to) = position.col(from);
    velocity.col(to) = velocity.col(from);
    previous_position.col(to) = previous_position.col(from);
    inverse_mass[to] = inverse_mass[from];
    age[to] = age[from];
  }

  int live_count = 0;
};

}  // namespace core
}  // namespace particle_sim
