#pragma once

#include <Eigen/Core>
#include <array>

namespace particle_sim
{
namespace core
{
/// The conjugate gradient's per-particle passes with a particle's three coordinates in one 256-bit
/// register (AVX2), on PaddedVectors, for ImplicitEulerSolver where the processor has AVX2. Each
/// lane does its row's multiplies and adds in the order of the scalar passes in
/// implicit_euler_solver.cpp, so the results are the same bits; the target is AVX2 without FMA,
/// which would fuse a multiply and an add and round once instead of twice. Every padding lane they
/// write is zero (given zero padding in what they read).
namespace cg_avx2
{
/// Whether this processor runs these passes (x86-64 with AVX2).
bool available();

/// out_i += C (p_j − p_i) at end i (if add_i), out_j −= C (p_j − p_i) at end j (if add_j), for the
/// pairs [first, last) in order, C's lower triangle (C00, C10, C20, C11, C21, C22) in `cs`.
void addPairProducts(bool add_i, bool add_j, const std::array<int, 2>* ends, const std::array<double, 6>* cs, int first,
                     int last, const double* p, double* out);
/// out_i = scale_i p_i on the rows [first, last).
void scaleRows(const double* scale, int first, int last, const double* p, double* out);
/// Zeroes the pinned rows of the product q, and returns Σ d_i · q_i over the rows [first, last),
/// summed per coordinate and then x + y + z.
double curvature(const char* pinned, int first, int last, const double* direction, double* product);

/// One chunk's sums of an iteration's update: r·z, |r|² and Σ |r_i|² / m_i.
struct UpdateSums
{
  double preconditioned, squared, weighted;
};
/// Δv += α d, r −= α q, z = D⁻¹ r on the rows [first, last), with the sums of z and r.
UpdateSums updateIterate(int first, int last, double alpha, const double* inverse_mass,
                         const Eigen::Matrix3d* inverse_diagonal, const double* direction, const double* product,
                         double* delta_v, double* residual, double* preconditioned);
/// d = z + β d on the rows [first, last), zero where pinned.
void updateDirection(const char* pinned, int first, int last, double beta, const double* preconditioned,
                     double* direction);
}  // namespace cg_avx2

}  // namespace core
}  // namespace particle_sim
