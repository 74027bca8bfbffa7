#include "particle_sim/core/spring.h"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace particle_sim
{
namespace core
{
const char* toString(SpringClass spring_class)
{
  switch (spring_class)
  {
    case SpringClass::Stretch:
      return "stretch";
    case SpringClass::Shear:
      return "shear";
    case SpringClass::Bend:
      return "bend";
  }
  return "unknown";
}

bool parseSpringClass(const std::string& text, SpringClass& spring_class)
{
  for (SpringClass candidate : {SpringClass::Stretch, SpringClass::Shear, SpringClass::Bend})
  {
    if (text == toString(candidate))
    {
      spring_class = candidate;
      return true;
    }
  }
  return false;
}

void SpringJacobianParts::resize(std::size_t springs)
{
  for (std::vector<double>* numbers : {&d_x, &d_y, &d_z, &along_x, &isotropic_x})
    numbers->resize(springs);
  coincident.resize(springs);
}

namespace
{
// One spring's parts into its places (the scalar form, and the vector form's last springs).
void partsOfOne(const Spring& spring, int s, const double* x, SpringJacobianParts& parts)
{
  const Eigen::Map<const Eigen::Vector3d> xi(x + 3L * spring.i), xj(x + 3L * spring.j);
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  double along_x = 0.0, isotropic_x = 0.0, along_v = 0.0;
  parts.coincident[s] = !springJacobianParts(xi, xj, spring.rest_length, spring.stiffness, spring.damping, d, along_x,
                                             isotropic_x, along_v);
  if (parts.coincident[s]) return;
  parts.d_x[s] = d.x();
  parts.d_y[s] = d.y();
  parts.d_z[s] = d.z();
  parts.along_x[s] = along_x;
  parts.isotropic_x[s] = isotropic_x;
}

#if defined(__x86_64__)
// Four springs a lane each: x_j − x_i, l = √((Δx² + Δy²) + Δz²) (Eigen's order for a 3-vector's
// norm), d = Δ / l, t = 1 − L / l clamped at 0 as std::max does (t < 0 ? 0 : t, so a −0 and a NaN
// stay), along_x = (−k) (1 − t), isotropic_x = (−k) t. AVX2 without FMA: each product rounded
// before its sum, as in the scalar form.
__attribute__((target("avx2"))) void partsOfFour(const Spring* springs, int first, int last, const double* x,
                                                 SpringJacobianParts& parts)
{
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), negative = _mm256_set1_pd(-0.0);
  int s = first;
  for (; s + 4 <= last; s += 4)
  {
    const Spring* const four = springs + s;
    const double *const i0 = x + 3L * four[0].i, *const i1 = x + 3L * four[1].i, *const i2 = x + 3L * four[2].i,
                        *const i3 = x + 3L * four[3].i;
    const double *const j0 = x + 3L * four[0].j, *const j1 = x + 3L * four[1].j, *const j2 = x + 3L * four[2].j,
                        *const j3 = x + 3L * four[3].j;
    const __m256d delta_x =
        _mm256_sub_pd(_mm256_set_pd(j3[0], j2[0], j1[0], j0[0]), _mm256_set_pd(i3[0], i2[0], i1[0], i0[0]));
    const __m256d delta_y =
        _mm256_sub_pd(_mm256_set_pd(j3[1], j2[1], j1[1], j0[1]), _mm256_set_pd(i3[1], i2[1], i1[1], i0[1]));
    const __m256d delta_z =
        _mm256_sub_pd(_mm256_set_pd(j3[2], j2[2], j1[2], j0[2]), _mm256_set_pd(i3[2], i2[2], i1[2], i0[2]));
    const __m256d squared =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(delta_x, delta_x), _mm256_mul_pd(delta_y, delta_y)),
                      _mm256_mul_pd(delta_z, delta_z));
    const __m256d length = _mm256_sqrt_pd(squared);
    const __m256d rest =
        _mm256_set_pd(four[3].rest_length, four[2].rest_length, four[1].rest_length, four[0].rest_length);
    const __m256d stiffness = _mm256_xor_pd(
        _mm256_set_pd(four[3].stiffness, four[2].stiffness, four[1].stiffness, four[0].stiffness), negative);
    const __m256d unclamped = _mm256_sub_pd(one, _mm256_div_pd(rest, length));
    const __m256d transverse = _mm256_blendv_pd(unclamped, zero, _mm256_cmp_pd(unclamped, zero, _CMP_LT_OQ));
    const int coincident = _mm256_movemask_pd(_mm256_cmp_pd(length, zero, _CMP_EQ_OQ));
    for (int lane = 0; lane < 4; ++lane)
      parts.coincident[s + lane] = static_cast<char>((coincident >> lane) & 1);
    _mm256_storeu_pd(parts.d_x.data() + s, _mm256_div_pd(delta_x, length));
    _mm256_storeu_pd(parts.d_y.data() + s, _mm256_div_pd(delta_y, length));
    _mm256_storeu_pd(parts.d_z.data() + s, _mm256_div_pd(delta_z, length));
    _mm256_storeu_pd(parts.along_x.data() + s, _mm256_mul_pd(stiffness, _mm256_sub_pd(one, transverse)));
    _mm256_storeu_pd(parts.isotropic_x.data() + s, _mm256_mul_pd(stiffness, transverse));
  }
  for (; s < last; ++s)
    partsOfOne(springs[s], s, x, parts);
}
#endif
}  // namespace

bool springPartsVectorized()
{
#if defined(__x86_64__)
  static const bool has_avx2 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has_avx2;
#else
  return false;
#endif
}

void springJacobianPartsOf(const Spring* springs, int first, int last, const double* x, bool vectorized,
                           SpringJacobianParts& parts)
{
#if defined(__x86_64__)
  if (vectorized && springPartsVectorized())
  {
    partsOfFour(springs, first, last, x, parts);
    return;
  }
#endif
  (void)vectorized;
  for (int s = first; s < last; ++s)
    partsOfOne(springs[s], s, x, parts);
}

}  // namespace core
}  // namespace particle_sim
