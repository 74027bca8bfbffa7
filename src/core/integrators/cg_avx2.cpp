#include "particle_sim/core/integrators/cg_avx2.h"

#include "particle_sim/core/integrators/padded_vectors.h"
#include "particle_sim/core/vector_registers.h"

#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <cstdlib>

namespace particle_sim
{
namespace core
{
namespace cg_avx2
{
#if defined(__x86_64__)
namespace
{
constexpr int kStride = PaddedVectors::kStride;

// (x + y) + z of a register's first three lanes.
[[gnu::always_inline]] __attribute__((target("avx2"))) inline double sumOfThree(__m256d v)
{
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, v);
  return (lanes[0] + lanes[1]) + lanes[2];
}

// The padding lane set to zero.
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m256d withoutPadding(__m256d v)
{
  return _mm256_blend_pd(v, _mm256_setzero_pd(), 0x8);
}

// The scalar form's run: a run of pairs that share end i keeps out_i in a register, stored when
// end i changes. C's columns (C00, C10, C20), (C10, C11, C21), (C20, C21, C22) come from three
// overlapping loads of its six numbers; lane r then computes (C_r0 d0 + C_r1 d1) + C_r2 d2.
template <bool kAddI, bool kAddJ>
__attribute__((target("avx2"))) void addPairRun(const std::array<int, 2>* ends, const std::array<double, 6>* cs,
                                                int first, int last, const double* p, double* out)
{
  int held = -1;
  __m256d sum_i = _mm256_setzero_pd(), p_i = _mm256_setzero_pd();
  for (int k = first; k < last; ++k)
  {
    const int i = ends[k][0];
    const int j = ends[k][1];
    if (i != held)
    {
      if (kAddI && held >= 0) _mm256_store_pd(out + kStride * held, sum_i);
      held = i;
      p_i = _mm256_load_pd(p + kStride * i);
      if (kAddI) sum_i = _mm256_load_pd(out + kStride * i);
    }
    const double* const c = cs[k].data();
    const __m256d column0 = _mm256_loadu_pd(c);
    const __m256d column1 = _mm256_permute4x64_pd(_mm256_loadu_pd(c + 1), 0xF8);  // lanes 0, 2, 3, 3
    const __m256d column2 = _mm256_permute4x64_pd(_mm256_loadu_pd(c + 2), 0xF8);
    const __m256d d = _mm256_sub_pd(_mm256_load_pd(p + kStride * j), p_i);
    const __m256d w =
        withoutPadding(_mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(column0, _mm256_permute4x64_pd(d, 0x00)),
                                                   _mm256_mul_pd(column1, _mm256_permute4x64_pd(d, 0x55))),
                                     _mm256_mul_pd(column2, _mm256_permute4x64_pd(d, 0xAA))));
    if (kAddI) sum_i = _mm256_add_pd(sum_i, w);
    if (kAddJ)
    {
      if (kAddI && j == i)
        sum_i = _mm256_sub_pd(sum_i, w);
      else
        _mm256_store_pd(out + kStride * j, _mm256_sub_pd(_mm256_load_pd(out + kStride * j), w));
    }
  }
  if (kAddI && held >= 0) _mm256_store_pd(out + kStride * held, sum_i);
}

__attribute__((target("avx2"))) void addPairProductsAvx2(bool add_i, bool add_j, const std::array<int, 2>* ends,
                                                         const std::array<double, 6>* cs, int first, int last,
                                                         const double* p, double* out)
{
  if (add_i && add_j)
    addPairRun<true, true>(ends, cs, first, last, p, out);
  else if (add_i)
    addPairRun<true, false>(ends, cs, first, last, p, out);
  else if (add_j)
    addPairRun<false, true>(ends, cs, first, last, p, out);
}

__attribute__((target("avx2"))) void scaleRowsAvx2(const double* scale, int first, int last, const double* p,
                                                   double* out)
{
  for (int i = first; i < last; ++i)
    _mm256_store_pd(out + kStride * i, _mm256_mul_pd(_mm256_set1_pd(scale[i]), _mm256_load_pd(p + kStride * i)));
}

__attribute__((target("avx2"))) double curvatureAvx2(const char* pinned, int first, int last, const double* direction,
                                                     double* product)
{
  __m256d sum = _mm256_setzero_pd();
  for (int i = first; i < last; ++i)
  {
    if (pinned[i]) _mm256_store_pd(product + kStride * i, _mm256_setzero_pd());
    sum = _mm256_add_pd(sum,
                        _mm256_mul_pd(_mm256_load_pd(direction + kStride * i), _mm256_load_pd(product + kStride * i)));
  }
  return sumOfThree(sum);
}

__attribute__((target("avx2"))) UpdateSums updateIterateAvx2(int first, int last, double alpha,
                                                             const double* inverse_mass,
                                                             const Eigen::Matrix3d* inverse_diagonal,
                                                             const double* direction, const double* product,
                                                             double* delta_v, double* residual, double* preconditioned)
{
  const __m256d step = _mm256_set1_pd(alpha);
  __m256d sum_rz = _mm256_setzero_pd(), sum_r2 = _mm256_setzero_pd(), sum_weighted = _mm256_setzero_pd();
  for (int i = first; i < last; ++i)
  {
    const int at = kStride * i;
    _mm256_store_pd(delta_v + at,
                    _mm256_add_pd(_mm256_load_pd(delta_v + at), _mm256_mul_pd(step, _mm256_load_pd(direction + at))));
    const __m256d r = _mm256_sub_pd(_mm256_load_pd(residual + at), _mm256_mul_pd(step, _mm256_load_pd(product + at)));
    _mm256_store_pd(residual + at, r);
    // z = D⁻¹ r as Eigen evaluates a 3x3 block times a 3-vector: rows 0 and 1 as (a + b) + c, row 2
    // as a + (b + c), of a = D⁻¹_r0 r0, b = D⁻¹_r1 r1, c = D⁻¹_r2 r2. Columns from the block's nine
    // numbers (column-major) without reading past them: the third from the load at 5, moved down.
    const double* const block = inverse_diagonal[i].data();
    const __m256d a = _mm256_mul_pd(_mm256_loadu_pd(block), _mm256_permute4x64_pd(r, 0x00));
    const __m256d b = _mm256_mul_pd(_mm256_loadu_pd(block + 3), _mm256_permute4x64_pd(r, 0x55));
    const __m256d c =
        _mm256_mul_pd(_mm256_permute4x64_pd(_mm256_loadu_pd(block + 5), 0xF9), _mm256_permute4x64_pd(r, 0xAA));
    const __m256d z = withoutPadding(
        _mm256_blend_pd(_mm256_add_pd(_mm256_add_pd(a, b), c), _mm256_add_pd(a, _mm256_add_pd(b, c)), 0x4));
    _mm256_store_pd(preconditioned + at, z);
    sum_rz = _mm256_add_pd(sum_rz, _mm256_mul_pd(r, z));
    const __m256d r2 = _mm256_mul_pd(r, r);
    sum_r2 = _mm256_add_pd(sum_r2, r2);
    sum_weighted = _mm256_add_pd(sum_weighted, _mm256_mul_pd(_mm256_set1_pd(inverse_mass[i]), r2));
  }
  return {sumOfThree(sum_rz), sumOfThree(sum_r2), sumOfThree(sum_weighted)};
}

__attribute__((target("avx2"))) void updateDirectionAvx2(const char* pinned, int first, int last, double beta,
                                                         const double* preconditioned, double* direction)
{
  const __m256d scale = _mm256_set1_pd(beta);
  for (int i = first; i < last; ++i)
  {
    const int at = kStride * i;
    const __m256d d =
        _mm256_add_pd(_mm256_load_pd(preconditioned + at), _mm256_mul_pd(scale, _mm256_load_pd(direction + at)));
    _mm256_store_pd(direction + at, pinned[i] ? _mm256_setzero_pd() : d);
  }
}
}  // namespace

bool available()
{
  static const bool has_avx2 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has_avx2;
}

// The passes, each followed by the clearing of the upper halves (vector_registers.h).
void addPairProducts(bool add_i, bool add_j, const std::array<int, 2>* ends, const std::array<double, 6>* cs, int first,
                     int last, const double* p, double* out)
{
  addPairProductsAvx2(add_i, add_j, ends, cs, first, last, p, out);
  clearUpperHalves();
}

void scaleRows(const double* scale, int first, int last, const double* p, double* out)
{
  scaleRowsAvx2(scale, first, last, p, out);
  clearUpperHalves();
}

double curvature(const char* pinned, int first, int last, const double* direction, double* product)
{
  const double sum = curvatureAvx2(pinned, first, last, direction, product);
  clearUpperHalves();
  return sum;
}

UpdateSums updateIterate(int first, int last, double alpha, const double* inverse_mass,
                         const Eigen::Matrix3d* inverse_diagonal, const double* direction, const double* product,
                         double* delta_v, double* residual, double* preconditioned)
{
  const UpdateSums sums = updateIterateAvx2(first, last, alpha, inverse_mass, inverse_diagonal, direction, product,
                                            delta_v, residual, preconditioned);
  clearUpperHalves();
  return sums;
}

void updateDirection(const char* pinned, int first, int last, double beta, const double* preconditioned,
                     double* direction)
{
  updateDirectionAvx2(pinned, first, last, beta, preconditioned, direction);
  clearUpperHalves();
}
#else
// Elsewhere the scalar passes run; these are never called.
bool available()
{
  return false;
}
void addPairProducts(bool, bool, const std::array<int, 2>*, const std::array<double, 6>*, int, int, const double*,
                     double*)
{
  std::abort();
}
void scaleRows(const double*, int, int, const double*, double*)
{
  std::abort();
}
double curvature(const char*, int, int, const double*, double*)
{
  std::abort();
}
UpdateSums updateIterate(int, int, double, const double*, const Eigen::Matrix3d*, const double*, const double*, double*,
                         double*, double*)
{
  std::abort();
}
void updateDirection(const char*, int, int, double, const double*, double*)
{
  std::abort();
}
#endif
}  // namespace cg_avx2

}  // namespace core
}  // namespace particle_sim
