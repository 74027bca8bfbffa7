#include "particle_sim/core/integrators/dense_panel.h"

#include "particle_sim/core/integrators/cg_avx2.h"

#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <algorithm>

namespace particle_sim
{
namespace core
{
namespace dense_panel
{
namespace
{
constexpr int kTileRows = 8;
constexpr int kTileColumns = 4;
// The longest sums whose strip of L is packed (on the stack: 64 KiB).
constexpr int kMaxPacked = 2048;

// One entry: its products summed from zero in the order of p, then subtracted.
inline void subtractEntry(int k, const double* t, int ldt, const double* l, int ldl, double& c)
{
  double sum = 0.0;
  for (int p = 0; p < k; ++p)
    sum += t[static_cast<long>(p) * ldt] * l[static_cast<long>(p) * ldl];
  c -= sum;
}

// A tile of `rows` × `columns` entries, entry by entry.
void subtractTileScalar(int rows, int columns, int k, const double* t, int ldt, const double* l, int ldl, double* c,
                        int ldc)
{
  for (int j = 0; j < columns; ++j)
    for (int i = 0; i < rows; ++i)
      subtractEntry(k, t + i, ldt, l + j, ldl, c[i + static_cast<long>(j) * ldc]);
}

#if defined(__x86_64__)
// An 8 × 4 tile in eight 4-lane sums, named so that they stay in registers: at each p, T's eight
// rows in two registers times each of L's four numbers, broadcast; each lane is one entry's sum in
// the scalar order. Only C's first `columns` columns are written (L's others are padding).
__attribute__((target("avx2"))) void subtractTileAvx2(int k, const double* t, int ldt, const double* l, int ldl,
                                                      double* c, int ldc, int columns)
{
  __m256d u0 = _mm256_setzero_pd(), u1 = u0, u2 = u0, u3 = u0, w0 = u0, w1 = u0, w2 = u0, w3 = u0;
  for (int p = 0; p < k; ++p)
  {
    const double* const tp = t + static_cast<long>(p) * ldt;
    const double* const lp = l + static_cast<long>(p) * ldl;
    const __m256d upper = _mm256_loadu_pd(tp), lower = _mm256_loadu_pd(tp + 4);
    const __m256d l0 = _mm256_broadcast_sd(lp), l1 = _mm256_broadcast_sd(lp + 1);
    const __m256d l2 = _mm256_broadcast_sd(lp + 2), l3 = _mm256_broadcast_sd(lp + 3);
    u0 = _mm256_add_pd(u0, _mm256_mul_pd(upper, l0));
    w0 = _mm256_add_pd(w0, _mm256_mul_pd(lower, l0));
    u1 = _mm256_add_pd(u1, _mm256_mul_pd(upper, l1));
    w1 = _mm256_add_pd(w1, _mm256_mul_pd(lower, l1));
    u2 = _mm256_add_pd(u2, _mm256_mul_pd(upper, l2));
    w2 = _mm256_add_pd(w2, _mm256_mul_pd(lower, l2));
    u3 = _mm256_add_pd(u3, _mm256_mul_pd(upper, l3));
    w3 = _mm256_add_pd(w3, _mm256_mul_pd(lower, l3));
  }
  const __m256d upper_sums[kTileColumns] = {u0, u1, u2, u3}, lower_sums[kTileColumns] = {w0, w1, w2, w3};
  for (int j = 0; j < columns; ++j)
  {
    double* const cj = c + static_cast<long>(j) * ldc;
    _mm256_storeu_pd(cj, _mm256_sub_pd(_mm256_loadu_pd(cj), upper_sums[j]));
    _mm256_storeu_pd(cj + 4, _mm256_sub_pd(_mm256_loadu_pd(cj + 4), lower_sums[j]));
  }
}

// A tile of up to 4 rows (`rows`: the lanes past them are neither read nor written) × 4 columns, of
// which the first `columns` are written.
__attribute__((target("avx2"))) void subtractTile4Avx2(int k, const double* t, int ldt, const double* l, int ldl,
                                                       double* c, int ldc, int rows, int columns)
{
  const __m256i lanes = _mm256_setr_epi64x(0, 1, 2, 3);
  const __m256i mask = _mm256_cmpgt_epi64(_mm256_set1_epi64x(rows), lanes);  // lane < rows
  __m256d u0 = _mm256_setzero_pd(), u1 = u0, u2 = u0, u3 = u0;
  for (int p = 0; p < k; ++p)
  {
    const __m256d column = _mm256_maskload_pd(t + static_cast<long>(p) * ldt, mask);
    const double* const lp = l + static_cast<long>(p) * ldl;
    u0 = _mm256_add_pd(u0, _mm256_mul_pd(column, _mm256_broadcast_sd(lp)));
    u1 = _mm256_add_pd(u1, _mm256_mul_pd(column, _mm256_broadcast_sd(lp + 1)));
    u2 = _mm256_add_pd(u2, _mm256_mul_pd(column, _mm256_broadcast_sd(lp + 2)));
    u3 = _mm256_add_pd(u3, _mm256_mul_pd(column, _mm256_broadcast_sd(lp + 3)));
  }
  const __m256d sums[kTileColumns] = {u0, u1, u2, u3};
  for (int j = 0; j < columns; ++j)
  {
    double* const cj = c + static_cast<long>(j) * ldc;
    _mm256_maskstore_pd(cj, mask, _mm256_sub_pd(_mm256_maskload_pd(cj, mask), sums[j]));
  }
}

// The strips of subtractLowerProducts() in AVX2 tiles: each strip's four rows of L packed side by
// side, p after p (zero past the last column), then its tiles of eight rows, one of four, and the
// last rows in a masked one.
__attribute__((target("avx2"))) void subtractLowerProductsAvx2(int rows, int columns, int k, const double* t, int ldt,
                                                               const double* l, int ldl, double* c, int ldc)
{
  alignas(32) double packed[kTileColumns * kMaxPacked];
  for (int j = 0; j < columns; j += kTileColumns)
  {
    const int strip_columns = std::min(kTileColumns, columns - j);
    for (int p = 0; p < k; ++p)
      for (int q = 0; q < kTileColumns; ++q)
        packed[kTileColumns * p + q] = q < strip_columns ? l[j + q + static_cast<long>(p) * ldl] : 0.0;
    int i = j;
    for (; i + kTileRows <= rows; i += kTileRows)
      subtractTileAvx2(k, t + i, ldt, packed, kTileColumns, c + i + static_cast<long>(j) * ldc, ldc, strip_columns);
    for (; i < rows; i += kTileRows / 2)
      subtractTile4Avx2(k, t + i, ldt, packed, kTileColumns, c + i + static_cast<long>(j) * ldc, ldc,
                        std::min(kTileRows / 2, rows - i), strip_columns);
  }
}

// The whole fours of subtractScaled() and keepAndScale(): how many entries they did (the callers
// do the rest, entry by entry, as their scalar form does all of them).
__attribute__((target("avx2"))) int subtractScaledAvx2(int n, const double* t, double factor, double* column)
{
  const __m256d f = _mm256_set1_pd(factor);
  int r = 0;
  for (; r + 4 <= n; r += 4)
    _mm256_storeu_pd(column + r, _mm256_sub_pd(_mm256_loadu_pd(column + r), _mm256_mul_pd(_mm256_loadu_pd(t + r), f)));
  return r;
}

__attribute__((target("avx2"))) int keepAndScaleAvx2(int n, double factor, double* column, double* kept)
{
  const __m256d f = _mm256_set1_pd(factor);
  int r = 0;
  for (; r + 4 <= n; r += 4)
  {
    const __m256d value = _mm256_loadu_pd(column + r);
    _mm256_storeu_pd(kept + r, value);
    _mm256_storeu_pd(column + r, _mm256_mul_pd(value, f));
  }
  return r;
}

__attribute__((target("avx2"))) double dotAvx2(int n, const double* a, const double* b)
{
  __m256d sum = _mm256_setzero_pd();
  int r = 0;
  for (; r + 4 <= n; r += 4)
    sum = _mm256_add_pd(sum, _mm256_mul_pd(_mm256_loadu_pd(a + r), _mm256_loadu_pd(b + r)));
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, sum);
  double total = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
  for (; r < n; ++r)
    total += a[r] * b[r];
  return total;
}
#endif
}  // namespace

bool available()
{
  return cg_avx2::available();  // the same processor feature as the CG's passes
}

void subtractLowerProducts(bool avx2, int rows, int columns, int k, const double* t, int ldt, const double* l, int ldl,
                           double* c, int ldc)
{
  // Column strips of four, in each the entries from the strip's diagonal down.
#if defined(__x86_64__)
  if (avx2 && available() && k <= kMaxPacked)
  {
    subtractLowerProductsAvx2(rows, columns, k, t, ldt, l, ldl, c, ldc);
    return;
  }
#endif
  for (int j = 0; j < columns; j += kTileColumns)
    if (j < rows)
      subtractTileScalar(rows - j, std::min(kTileColumns, columns - j), k, t + j, ldt, l + j, ldl,
                         c + j + static_cast<long>(j) * ldc, ldc);
}

void subtractScaled(bool avx2, int n, const double* t, double factor, double* column)
{
  int r = 0;
#if defined(__x86_64__)
  if (avx2 && available()) r = subtractScaledAvx2(n, t, factor, column);
#endif
  for (; r < n; ++r)
    column[r] -= t[r] * factor;
}

void keepAndScale(bool avx2, int n, double factor, double* column, double* kept)
{
  int r = 0;
#if defined(__x86_64__)
  if (avx2 && available()) r = keepAndScaleAvx2(n, factor, column, kept);
#endif
  for (; r < n; ++r)
  {
    kept[r] = column[r];
    column[r] *= factor;
  }
}

double dot(bool avx2, int n, const double* a, const double* b)
{
#if defined(__x86_64__)
  if (avx2 && available()) return dotAvx2(n, a, b);
#endif
  double lanes[4] = {0.0, 0.0, 0.0, 0.0};
  int r = 0;
  for (; r + 4 <= n; r += 4)
    for (int q = 0; q < 4; ++q)
      lanes[q] += a[r + q] * b[r + q];
  double total = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
  for (; r < n; ++r)
    total += a[r] * b[r];
  return total;
}
}  // namespace dense_panel
}  // namespace core
}  // namespace particle_sim
