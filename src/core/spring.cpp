#include "particle_sim/core/spring.h"

#include "particle_sim/core/vector_registers.h"

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

// One spring's force (springForce()), added to its end i (if kAddI) and taken from its end j (if kAddJ);
// its energy (springEnergy()) into *energy when that is not null.
template <bool kAddI, bool kAddJ>
[[gnu::always_inline]] inline void addSpringForce(const Spring* s, const double* xs, const double* vs, double* fs,
                                                  double* energy)
{
  const Eigen::Vector3d f = springForce(Eigen::Vector3d::Map(xs + 3 * s->i), Eigen::Vector3d::Map(xs + 3 * s->j),
                                        Eigen::Vector3d::Map(vs + 3 * s->i), Eigen::Vector3d::Map(vs + 3 * s->j),
                                        s->rest_length, s->stiffness, s->damping);
  if (kAddI) Eigen::Vector3d::Map(fs + 3 * s->i) += f;
  if (kAddJ) Eigen::Vector3d::Map(fs + 3 * s->j) -= f;
  if (energy)
  {
    *energy = springEnergy(Eigen::Vector3d::Map(xs + 3 * s->i), Eigen::Vector3d::Map(xs + 3 * s->j), s->rest_length,
                           s->stiffness);
  }
}

// *sum += values[0], values[1], ... values[count − 1], one after the other (the energies' running sum).
inline void addInOrder(double* sum, const double* values, long count)
{
  for (long k = 0; k < count; ++k)
    *sum += values[k];
}

// addSpringForcesOf()'s scalar form. Which ends is fixed for the whole run, not tested per spring,
// so that a chunk's run costs what the one-thread loop costs (this function over every spring, both
// ends).
//
// Two springs at a time, one in each lane of a pair of doubles: springForce()'s operations, lane by
// lane (|δ| as sqrt((δx² + δy²) + δz²) and the dot product as (a_x b_x + a_y b_y) + a_z b_z, Eigen's
// order), so the same bits, with one square root and three divisions for the two springs instead of
// two and six: the divider bounds this loop while the particles are in cache (a 128² cloth's step,
// 3-9 % faster); beyond that memory does (256²: no change). The forces are then added spring after
// spring, in the order of the list. A pair with a spring of zero length (no direction) takes
// springForce() itself.
//
// With `energy` not null, each spring's energy goes to energy[spring − first], in springEnergy()'s
// operations (the stretch is the force's): the energy of the state costs no pass of its own.
//
// The spring records kSpringsAhead ahead are asked into the cache as the loop goes: beyond the
// second-level cache (a 256² cloth's 15.6 MB of springs) the hardware's own prefetching leaves the
// loop waiting for them (2-6 % of a 256² step; no change while they fit).
constexpr std::ptrdiff_t kSpringsAhead = 32;
template <bool kAddI, bool kAddJ>
[[gnu::always_inline]] inline void addRunForcesScalar(const Spring* first, const Spring* last, const double* xs,
                                                      const double* vs, double* fs, double* energy)
{
  using Pair = Eigen::Array2d;
  const Spring* s = first;
  for (; last - s >= 2; s += 2)
  {
    if (last - s > kSpringsAhead + 1)
    {
      // Both records' starts: every 64-byte line of 40-byte records holds the start of one.
      __builtin_prefetch(s + kSpringsAhead);
      __builtin_prefetch(s + kSpringsAhead + 1);
    }
    const Spring& a = s[0];
    const Spring& b = s[1];
    const double *const xai = xs + 3 * a.i, *const xaj = xs + 3 * a.j;
    const double *const xbi = xs + 3 * b.i, *const xbj = xs + 3 * b.j;
    const Pair dx(xaj[0] - xai[0], xbj[0] - xbi[0]);
    const Pair dy(xaj[1] - xai[1], xbj[1] - xbi[1]);
    const Pair dz(xaj[2] - xai[2], xbj[2] - xbi[2]);
    const Pair length = ((dx * dx + dy * dy) + dz * dz).sqrt();
    if (length(0) == 0.0 || length(1) == 0.0)
    {
      addSpringForce<kAddI, kAddJ>(s, xs, vs, fs, energy ? energy + (s - first) : nullptr);
      addSpringForce<kAddI, kAddJ>(s + 1, xs, vs, fs, energy ? energy + (s + 1 - first) : nullptr);
      continue;
    }
    const Pair ux = dx / length, uy = dy / length, uz = dz / length;
    const double *const vai = vs + 3 * a.i, *const vaj = vs + 3 * a.j;
    const double *const vbi = vs + 3 * b.i, *const vbj = vs + 3 * b.j;
    const Pair along = (Pair(vaj[0] - vai[0], vbj[0] - vbi[0]) * ux + Pair(vaj[1] - vai[1], vbj[1] - vbi[1]) * uy) +
                       Pair(vaj[2] - vai[2], vbj[2] - vbi[2]) * uz;
    const Pair stiffness(a.stiffness, b.stiffness);
    const Pair stretch = length - Pair(a.rest_length, b.rest_length);
    const Pair magnitude = stiffness * stretch + Pair(a.damping, b.damping) * along;
    if (energy)
    {
      const Pair spring_energy = 0.5 * stiffness * stretch * stretch;
      energy[s - first] = spring_energy(0);
      energy[s + 1 - first] = spring_energy(1);
    }
    const Pair fx = magnitude * ux, fy = magnitude * uy, fz = magnitude * uz;
    for (int lane = 0; lane < 2; ++lane)
    {
      const Spring& spring = s[lane];
      if (kAddI)
      {
        double* const fi = fs + 3 * spring.i;
        fi[0] += fx(lane);
        fi[1] += fy(lane);
        fi[2] += fz(lane);
      }
      if (kAddJ)
      {
        double* const fj = fs + 3 * spring.j;
        fj[0] -= fx(lane);
        fj[1] -= fy(lane);
        fj[2] -= fz(lane);
      }
    }
  }
  if (s != last) addSpringForce<kAddI, kAddJ>(s, xs, vs, fs, energy ? energy + (s - first) : nullptr);
}

#if defined(__x86_64__)
// Particles a and b's first two coordinates in one register: (x_a, y_a, x_b, y_b).
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m256d firstTwoOfTwo(const double* base, int a, int b)
{
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(base + 3L * a)), _mm_loadu_pd(base + 3L * b), 1);
}

// Four numbers in the lanes (a, c, b, d), by broadcasts and blends (no shuffle).
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m256d laneOrderACBD(const double* a, const double* c,
                                                                                    const double* b, const double* d)
{
  const __m256d ac = _mm256_blend_pd(_mm256_broadcast_sd(a), _mm256_broadcast_sd(c), 0x2);
  const __m256d bd = _mm256_blend_pd(_mm256_broadcast_sd(b), _mm256_broadcast_sd(d), 0x8);
  return _mm256_blend_pd(ac, bd, 0xC);
}

// addSpringForcesOf()'s vector form: four springs a, b, c, d at a time, in the lanes (a, c, b, d)
// that unpacking two registers of two springs each gives. Each lane does the scalar form's
// operations in its order (AVX2 without FMA: every product rounded before its sum), so the same
// bits. The four forces are then added spring after spring as in the scalar form, but for end i:
// while consecutive springs share it (a cloth's point starts five of its springs), its force stays
// in registers and is stored once the end changes (the same sums in the same order). Four springs
// with one of zero length take the scalar form.
template <bool kAddI, bool kAddJ>
__attribute__((target("avx2"))) void addRunForcesAvx2(const Spring* first, const Spring* last, const double* xs,
                                                      const double* vs, double* fs, double* energy, double* energy_sum)
{
  const __m256d zero = _mm256_setzero_pd(), half = _mm256_set1_pd(0.5);
  alignas(32) double first_two[8];  // the forces' (x, y) of springs a, b, c, d
  alignas(32) double third[4];      // and their z
  int held = -1;                    // the end i whose force is in held_xy and held_z, not yet stored
  __m128d held_xy = _mm_setzero_pd();
  double held_z = 0.0;
  auto store_held = [&] {
    if (held < 0) return;
    _mm_storeu_pd(fs + 3L * held, held_xy);
    fs[3L * held + 2] = held_z;
    held = -1;
  };
  const Spring* s = first;
  for (; last - s >= 4; s += 4)
  {
    if (last - s > kSpringsAhead + 3)
    {
      __builtin_prefetch(s + kSpringsAhead);
      __builtin_prefetch(s + kSpringsAhead + 2);
    }
    const Spring &a = s[0], &b = s[1], &c = s[2], &d = s[3];
    const __m256d delta_ab = _mm256_sub_pd(firstTwoOfTwo(xs, a.j, b.j), firstTwoOfTwo(xs, a.i, b.i));
    const __m256d delta_cd = _mm256_sub_pd(firstTwoOfTwo(xs, c.j, d.j), firstTwoOfTwo(xs, c.i, d.i));
    const __m256d dx = _mm256_unpacklo_pd(delta_ab, delta_cd);
    const __m256d dy = _mm256_unpackhi_pd(delta_ab, delta_cd);
    const __m256d dz =
        _mm256_sub_pd(laneOrderACBD(xs + 3L * a.j + 2, xs + 3L * c.j + 2, xs + 3L * b.j + 2, xs + 3L * d.j + 2),
                      laneOrderACBD(xs + 3L * a.i + 2, xs + 3L * c.i + 2, xs + 3L * b.i + 2, xs + 3L * d.i + 2));
    const __m256d length = _mm256_sqrt_pd(
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz)));
    if (_mm256_movemask_pd(_mm256_cmp_pd(length, zero, _CMP_EQ_OQ)) != 0)
    {
      store_held();
      for (int k = 0; k < 4; ++k)
        addSpringForce<kAddI, kAddJ>(s + k, xs, vs, fs, energy ? energy + (s + k - first) : nullptr);
      if (energy_sum) addInOrder(energy_sum, energy + (s - first), 4);
      continue;
    }
    const __m256d ux = _mm256_div_pd(dx, length), uy = _mm256_div_pd(dy, length), uz = _mm256_div_pd(dz, length);
    const __m256d dv_ab = _mm256_sub_pd(firstTwoOfTwo(vs, a.j, b.j), firstTwoOfTwo(vs, a.i, b.i));
    const __m256d dv_cd = _mm256_sub_pd(firstTwoOfTwo(vs, c.j, d.j), firstTwoOfTwo(vs, c.i, d.i));
    const __m256d dvz =
        _mm256_sub_pd(laneOrderACBD(vs + 3L * a.j + 2, vs + 3L * c.j + 2, vs + 3L * b.j + 2, vs + 3L * d.j + 2),
                      laneOrderACBD(vs + 3L * a.i + 2, vs + 3L * c.i + 2, vs + 3L * b.i + 2, vs + 3L * d.i + 2));
    const __m256d along = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_unpacklo_pd(dv_ab, dv_cd), ux),
                                                      _mm256_mul_pd(_mm256_unpackhi_pd(dv_ab, dv_cd), uy)),
                                        _mm256_mul_pd(dvz, uz));
    // A record's rest length and stiffness lie side by side.
    const __m256d rest_stiffness_ab =
        _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&a.rest_length)), _mm_loadu_pd(&b.rest_length), 1);
    const __m256d rest_stiffness_cd =
        _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&c.rest_length)), _mm_loadu_pd(&d.rest_length), 1);
    const __m256d stiffness = _mm256_unpackhi_pd(rest_stiffness_ab, rest_stiffness_cd);
    const __m256d stretch = _mm256_sub_pd(length, _mm256_unpacklo_pd(rest_stiffness_ab, rest_stiffness_cd));
    const __m256d damping = laneOrderACBD(&a.damping, &c.damping, &b.damping, &d.damping);
    const __m256d magnitude = _mm256_add_pd(_mm256_mul_pd(stiffness, stretch), _mm256_mul_pd(damping, along));
    if (energy)
    {
      const __m256d spring_energy = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(half, stiffness), stretch), stretch);
      double* const four = energy + (s - first);
      _mm256_storeu_pd(four, _mm256_permute4x64_pd(spring_energy, 0xD8));  // lanes a, b, c, d
      if (energy_sum) addInOrder(energy_sum, four, 4);
    }
    const __m256d fx = _mm256_mul_pd(magnitude, ux), fy = _mm256_mul_pd(magnitude, uy);
    _mm256_store_pd(first_two, _mm256_unpacklo_pd(fx, fy));
    _mm256_store_pd(first_two + 4, _mm256_unpackhi_pd(fx, fy));
    _mm256_store_pd(third, _mm256_permute4x64_pd(_mm256_mul_pd(magnitude, uz), 0xD8));
    for (int k = 0; k < 4; ++k)
    {
      const __m128d f_xy = _mm_load_pd(first_two + 2 * k);
      if (kAddI)
      {
        if (s[k].i != held)
        {
          store_held();
          held = s[k].i;
          held_xy = _mm_loadu_pd(fs + 3L * held);
          held_z = fs[3L * held + 2];
        }
        held_xy = _mm_add_pd(held_xy, f_xy);
        held_z += third[k];
      }
      if (kAddJ)
      {
        double* const fj = fs + 3L * s[k].j;
        _mm_storeu_pd(fj, _mm_sub_pd(_mm_loadu_pd(fj), f_xy));
        fj[2] -= third[k];
      }
    }
  }
  store_held();
  for (; s != last; ++s)
  {
    addSpringForce<kAddI, kAddJ>(s, xs, vs, fs, energy ? energy + (s - first) : nullptr);
    if (energy_sum) addInOrder(energy_sum, energy + (s - first), 1);
  }
}
#endif

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

template <bool kAddI, bool kAddJ>
void addRunForces(const Spring* first, const Spring* last, const double* x, const double* v, double* force,
                  double* energy, double* energy_sum, bool vectorized)
{
#if defined(__x86_64__)
  if (vectorized && springPartsVectorized())
  {
    addRunForcesAvx2<kAddI, kAddJ>(first, last, x, v, force, energy, energy_sum);
    clearUpperHalves();
    return;
  }
#endif
  (void)vectorized;
  addRunForcesScalar<kAddI, kAddJ>(first, last, x, v, force, energy);
  if (energy_sum) addInOrder(energy_sum, energy, last - first);
}

void addSpringForcesOf(const Spring* first, const Spring* last, const double* x, const double* v, double* force,
                       double* energy, double* energy_sum, bool add_i, bool add_j, bool vectorized)
{
  if (add_i && add_j)
    addRunForces<true, true>(first, last, x, v, force, energy, energy_sum, vectorized);
  else if (add_i)
    addRunForces<true, false>(first, last, x, v, force, energy, energy_sum, vectorized);
  else if (add_j)
    addRunForces<false, true>(first, last, x, v, force, energy, energy_sum, vectorized);
}

void springJacobianPartsOf(const Spring* springs, int first, int last, const double* x, bool vectorized,
                           SpringJacobianParts& parts)
{
#if defined(__x86_64__)
  if (vectorized && springPartsVectorized())
  {
    partsOfFour(springs, first, last, x, parts);
    clearUpperHalves();
    return;
  }
#endif
  (void)vectorized;
  for (int s = first; s < last; ++s)
    partsOfOne(springs[s], s, x, parts);
}

}  // namespace core
}  // namespace particle_sim
