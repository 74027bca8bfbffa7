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
// A particle's three coordinates in lanes 0-2 of a register, lane 3 zero: a masked load, which
// does not read the number after them (past the array's end for the last particle).
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m256d coordinatesOf(const double* coordinates)
{
  return _mm256_maskload_pd(coordinates, _mm256_set_epi64x(0, -1, -1, -1));
}

// A particle's three coordinates as storeCoordinates() left them: read as it wrote them, two and one,
// so that each read takes its numbers straight from the store before it (a read of all three at
// once could not, and would wait for both stores to reach the cache).
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m256d storedCoordinatesOf(const double* coordinates)
{
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(coordinates)), _mm_load_sd(coordinates + 2), 1);
}

// Lanes 0-2 of a register as a particle's three coordinates.
[[gnu::always_inline]] __attribute__((target("avx2"))) inline void storeCoordinates(double* coordinates, __m256d value)
{
  _mm_storeu_pd(coordinates, _mm256_castpd256_pd128(value));
  _mm_store_sd(coordinates + 2, _mm256_extractf128_pd(value, 1));
}

// Four springs' (x, y, z, 0) differences a, b, c, d as x, y and z, each in the lanes (a, c, b, d).
[[gnu::always_inline]] __attribute__((target("avx2"))) inline void inLanesACBD(__m256d a, __m256d b, __m256d c,
                                                                               __m256d d, __m256d& x, __m256d& y,
                                                                               __m256d& z)
{
  const __m256d ac_xz = _mm256_unpacklo_pd(a, c), bd_xz = _mm256_unpacklo_pd(b, d);  // (a.x, c.x, a.z, c.z), ...
  const __m256d ac_y = _mm256_unpackhi_pd(a, c), bd_y = _mm256_unpackhi_pd(b, d);    // (a.y, c.y, 0, 0), ...
  x = _mm256_permute2f128_pd(ac_xz, bd_xz, 0x20);
  y = _mm256_permute2f128_pd(ac_y, bd_y, 0x20);
  z = _mm256_permute2f128_pd(ac_xz, bd_xz, 0x31);
}

// Four numbers in the lanes (a, c, b, d), by broadcasts and blends (no shuffle).
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m256d laneOrderACBD(const double* a, const double* c,
                                                                                    const double* b, const double* d)
{
  const __m256d ac = _mm256_blend_pd(_mm256_broadcast_sd(a), _mm256_broadcast_sd(c), 0x2);
  const __m256d bd = _mm256_blend_pd(_mm256_broadcast_sd(b), _mm256_broadcast_sd(d), 0x8);
  return _mm256_blend_pd(ac, bd, 0xC);
}

// The force of end i while consecutive springs share it, in registers until the end changes.
struct HeldForce
{
  int particle = -1;  // none
  __m256d force;      // (x, y, z, 0)

  [[gnu::always_inline]] __attribute__((target("avx2"))) inline void store(double* fs)
  {
    if (particle < 0) return;
    storeCoordinates(fs + 3L * particle, force);
    particle = -1;
  }
};

// A spring's force (x, y, z, 0) added to its end i (held) and taken from its end j.
template <bool kAddI, bool kAddJ>
[[gnu::always_inline]] __attribute__((target("avx2"))) inline void addForceOf(const Spring& spring, __m256d force,
                                                                              double* fs, HeldForce& held)
{
  if (kAddI)
  {
    if (spring.i != held.particle)
    {
      held.store(fs);
      held.particle = spring.i;
      held.force = storedCoordinatesOf(fs + 3L * spring.i);
    }
    held.force = _mm256_add_pd(held.force, force);
  }
  if (kAddJ)
  {
    double* const fj = fs + 3L * spring.j;
    storeCoordinates(fj, _mm256_sub_pd(storedCoordinatesOf(fj), force));
  }
}

// addSpringForcesOf()'s vector form: four springs a, b, c, d at a time, in the lanes (a, c, b, d)
// (inLanesACBD(): unpacking and swapping halves puts them there). Each lane does the scalar form's
// operations in its order (AVX2 without FMA: every product rounded before its sum), so the same
// bits. The four forces are then added spring after spring as in the scalar form, but for end i:
// while consecutive springs share it (a cloth's point starts five of its springs), its force stays
// in a register and is stored once the end changes (the same sums in the same order). Four springs
// with one of zero length take the scalar form.
template <bool kAddI, bool kAddJ>
__attribute__((target("avx2"))) void addRunForcesAvx2(const Spring* first, const Spring* last, const double* xs,
                                                      const double* vs, double* fs, double* energy, double* energy_sum)
{
  const __m256d zero = _mm256_setzero_pd(), half = _mm256_set1_pd(0.5);
  HeldForce held;
  held.force = zero;
  // The energies' running sum (energy_sum's, when it is asked for), kept in a register.
  double energy_so_far = energy_sum ? *energy_sum : 0.0;
  const Spring* s = first;
  for (; last - s >= 4; s += 4)
  {
    if (last - s > kSpringsAhead + 3)
    {
      __builtin_prefetch(s + kSpringsAhead);
      __builtin_prefetch(s + kSpringsAhead + 2);
    }
    const Spring &a = s[0], &b = s[1], &c = s[2], &d = s[3];
    // The eight ends' offsets, each read for the positions and for the velocities.
    const long ai = 3L * a.i, aj = 3L * a.j, bi = 3L * b.i, bj = 3L * b.j;
    const long ci = 3L * c.i, cj = 3L * c.j, di = 3L * d.i, dj = 3L * d.j;
    __m256d dx, dy, dz;
    inLanesACBD(_mm256_sub_pd(coordinatesOf(xs + aj), coordinatesOf(xs + ai)),
                _mm256_sub_pd(coordinatesOf(xs + bj), coordinatesOf(xs + bi)),
                _mm256_sub_pd(coordinatesOf(xs + cj), coordinatesOf(xs + ci)),
                _mm256_sub_pd(coordinatesOf(xs + dj), coordinatesOf(xs + di)), dx, dy, dz);
    const __m256d length = _mm256_sqrt_pd(
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz)));
    if (_mm256_movemask_pd(_mm256_cmp_pd(length, zero, _CMP_EQ_OQ)) != 0)
    {
      held.store(fs);
      for (int k = 0; k < 4; ++k)
        addSpringForce<kAddI, kAddJ>(s + k, xs, vs, fs, energy ? energy + (s + k - first) : nullptr);
      if (energy_sum) addInOrder(&energy_so_far, energy + (s - first), 4);
      continue;
    }
    const __m256d ux = _mm256_div_pd(dx, length), uy = _mm256_div_pd(dy, length), uz = _mm256_div_pd(dz, length);
    __m256d dvx, dvy, dvz;
    inLanesACBD(_mm256_sub_pd(coordinatesOf(vs + aj), coordinatesOf(vs + ai)),
                _mm256_sub_pd(coordinatesOf(vs + bj), coordinatesOf(vs + bi)),
                _mm256_sub_pd(coordinatesOf(vs + cj), coordinatesOf(vs + ci)),
                _mm256_sub_pd(coordinatesOf(vs + dj), coordinatesOf(vs + di)), dvx, dvy, dvz);
    const __m256d along =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dvx, ux), _mm256_mul_pd(dvy, uy)), _mm256_mul_pd(dvz, uz));
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
      if (energy_sum) energy_so_far = (((energy_so_far + four[0]) + four[1]) + four[2]) + four[3];
    }
    // The four forces as (x, y, z, 0), one a register, added spring after spring.
    const __m256d fx = _mm256_mul_pd(magnitude, ux), fy = _mm256_mul_pd(magnitude, uy);
    const __m256d fz = _mm256_mul_pd(magnitude, uz);
    const __m256d xy_ab = _mm256_unpacklo_pd(fx, fy), xy_cd = _mm256_unpackhi_pd(fx, fy);    // (x, y) of a, b; c, d
    const __m256d z_ab = _mm256_unpacklo_pd(fz, zero), z_cd = _mm256_unpackhi_pd(fz, zero);  // (z, 0) of a, b; c, d
    addForceOf<kAddI, kAddJ>(s[0], _mm256_permute2f128_pd(xy_ab, z_ab, 0x20), fs, held);
    addForceOf<kAddI, kAddJ>(s[1], _mm256_permute2f128_pd(xy_ab, z_ab, 0x31), fs, held);
    addForceOf<kAddI, kAddJ>(s[2], _mm256_permute2f128_pd(xy_cd, z_cd, 0x20), fs, held);
    addForceOf<kAddI, kAddJ>(s[3], _mm256_permute2f128_pd(xy_cd, z_cd, 0x31), fs, held);
  }
  held.store(fs);
  for (; s != last; ++s)
  {
    addSpringForce<kAddI, kAddJ>(s, xs, vs, fs, energy ? energy + (s - first) : nullptr);
    if (energy_sum) energy_so_far += energy[s - first];
  }
  if (energy_sum) *energy_sum = energy_so_far;
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
