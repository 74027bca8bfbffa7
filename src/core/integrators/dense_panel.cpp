#include "particle_sim/core/integrators/dense_panel.h"

#include "particle_sim/core/integrators/cg_avx2.h"
#include "particle_sim/core/vector_registers.h"

#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <algorithm>
#include <cmath>

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
// The longest sums whose last strip of L can be packed (on the stack: 64 KiB).
constexpr int kMaxPacked = 2048;

// One entry: its products summed from zero in the order of p, each product added to the sum with
// one rounding (a fused multiply-add, as the AVX2 tiles do), then subtracted.
inline void subtractEntry(int k, const double* t, int ldt, const double* l, int ldl, double& c)
{
  double sum = 0.0;
  for (int p = 0; p < k; ++p)
    sum = std::fma(t[static_cast<long>(p) * ldt], l[static_cast<long>(p) * ldl], sum);
  c -= sum;
}

// subtractLowerProducts() entry by entry: column j's entries from the diagonal down.
void subtractLowerProductsScalar(int rows, int columns, int k, const double* t, int ldt, const double* l, int ldl,
                                 const int* row_offset, const long* column_offset, double* c)
{
  for (int j = 0; j < columns; ++j)
  {
    double* const cj = c + column_offset[j];
    for (int i = j; i < rows; ++i)
      subtractEntry(k, t + i, ldt, l + j, ldl, cj[row_offset[i]]);
  }
}

#if defined(__x86_64__)
// The sums of an 8 × 4 tile, T's rows t .. t + 7 against the four columns of a strip of L
// (four numbers a p): at each p, T's eight rows in two registers times each of L's four numbers,
// broadcast, fused into eight 4-lane sums, named so that they stay in registers; each lane is one
// entry's sum in the scalar order. sums[q] holds column q's eight rows. Only the tiles and the
// function that drives them (which multiplies nothing itself) are built with FMA: the passes
// further down are built for AVX2 alone, so that the compiler cannot fuse their multiplies and adds,
// which their scalar forms round twice.
__attribute__((target("avx2,fma"))) void tileSumsAvx2(int k, const double* t, int ldt, const double* strip,
                                                      long strip_stride, double (*sums)[kTileRows])
{
  __m256d u0 = _mm256_setzero_pd(), u1 = u0, u2 = u0, u3 = u0, w0 = u0, w1 = u0, w2 = u0, w3 = u0;
  for (int p = 0; p < k; ++p)
  {
    const double* const tp = t + static_cast<long>(p) * ldt;
    const double* const lp = strip + p * strip_stride;
    const __m256d upper = _mm256_loadu_pd(tp), lower = _mm256_loadu_pd(tp + 4);
    const __m256d l0 = _mm256_broadcast_sd(lp), l1 = _mm256_broadcast_sd(lp + 1);
    const __m256d l2 = _mm256_broadcast_sd(lp + 2), l3 = _mm256_broadcast_sd(lp + 3);
    u0 = _mm256_fmadd_pd(upper, l0, u0);
    w0 = _mm256_fmadd_pd(lower, l0, w0);
    u1 = _mm256_fmadd_pd(upper, l1, u1);
    w1 = _mm256_fmadd_pd(lower, l1, w1);
    u2 = _mm256_fmadd_pd(upper, l2, u2);
    w2 = _mm256_fmadd_pd(lower, l2, w2);
    u3 = _mm256_fmadd_pd(upper, l3, u3);
    w3 = _mm256_fmadd_pd(lower, l3, w3);
  }
  _mm256_store_pd(sums[0], u0);
  _mm256_store_pd(sums[0] + 4, w0);
  _mm256_store_pd(sums[1], u1);
  _mm256_store_pd(sums[1] + 4, w1);
  _mm256_store_pd(sums[2], u2);
  _mm256_store_pd(sums[2] + 4, w2);
  _mm256_store_pd(sums[3], u3);
  _mm256_store_pd(sums[3] + 4, w3);
}

// The same for a tile of up to four rows (`rows`; T is not read past them): sums[q][0 .. 3].
__attribute__((target("avx2,fma"))) void tileSums4Avx2(int k, const double* t, int ldt, const double* strip,
                                                       long strip_stride, int rows, double (*sums)[kTileRows])
{
  const __m256i lanes = _mm256_setr_epi64x(0, 1, 2, 3);
  const __m256i mask = _mm256_cmpgt_epi64(_mm256_set1_epi64x(rows), lanes);  // lane < rows
  __m256d u0 = _mm256_setzero_pd(), u1 = u0, u2 = u0, u3 = u0;
  for (int p = 0; p < k; ++p)
  {
    const __m256d column = _mm256_maskload_pd(t + static_cast<long>(p) * ldt, mask);
    const double* const lp = strip + p * strip_stride;
    u0 = _mm256_fmadd_pd(column, _mm256_broadcast_sd(lp), u0);
    u1 = _mm256_fmadd_pd(column, _mm256_broadcast_sd(lp + 1), u1);
    u2 = _mm256_fmadd_pd(column, _mm256_broadcast_sd(lp + 2), u2);
    u3 = _mm256_fmadd_pd(column, _mm256_broadcast_sd(lp + 3), u3);
  }
  _mm256_store_pd(sums[0], u0);
  _mm256_store_pd(sums[1], u1);
  _mm256_store_pd(sums[2], u2);
  _mm256_store_pd(sums[3], u3);
}

// A strip of L: its four rows j .. j + 3, p after p, at strip + p stride. A whole strip is read where
// it lies in L (its four numbers of a p side by side, the next p a column of L further on); the
// last strip of fewer rows (`strip_columns`) is packed side by side into `packed`, zero past them,
// so that the tiles never read past L.
struct Strip
{
  const double* strip;
  long stride;
};
Strip stripOf(int k, const double* l, int ldl, int j, int strip_columns, double* packed)
{
  if (strip_columns == kTileColumns) return {l + j, ldl};
  for (int p = 0; p < k; ++p)
    for (int q = 0; q < kTileColumns; ++q)
      packed[kTileColumns * p + q] = q < strip_columns ? l[j + q + static_cast<long>(p) * ldl] : 0.0;
  return {packed, kTileColumns};
}

// The strips of subtractLowerProducts() in AVX2 tiles: each strip of L (stripOf()), then its tiles of
// eight rows from the strip's diagonal down and the last rows in tiles of up to four, each entry on
// or below the diagonal subtracted where it belongs, four at once where four rows lie one after the
// other in C.
__attribute__((target("avx2,fma"))) void subtractLowerProductsAvx2(int rows, int columns, int k, const double* t,
                                                                   int ldt, const double* l, int ldl,
                                                                   const int* row_offset, const long* column_offset,
                                                                   double* c)
{
  alignas(32) double packed[kTileColumns * kMaxPacked];
  alignas(32) double sums[kTileColumns][kTileRows];
  for (int j = 0; j < columns; j += kTileColumns)
  {
    const int strip_columns = std::min(kTileColumns, columns - j);
    const Strip strip = stripOf(k, l, ldl, j, strip_columns, packed);
    int i = j;
    for (; i + kTileRows <= rows; i += kTileRows)
    {
      tileSumsAvx2(k, t + i, ldt, strip.strip, strip.stride, sums);
      const int* const at = row_offset + i;
      for (int q = 0; q < strip_columns; ++q)
      {
        double* const cq = c + column_offset[j + q];
        const int from = std::max(0, j + q - i);  // the rows on or below the diagonal
        for (int half = 0; half < kTileRows; half += 4)
        {
          if (from <= half && at[half + 3] == at[half] + 3)
          {
            double* const to = cq + at[half];
            _mm256_storeu_pd(to, _mm256_sub_pd(_mm256_loadu_pd(to), _mm256_load_pd(sums[q] + half)));
            continue;
          }
          for (int r = std::max(from, half); r < half + 4; ++r)
            cq[at[r]] -= sums[q][r];
        }
      }
    }
    for (; i < rows; i += 4)
    {
      const int tile_rows = std::min(4, rows - i);
      tileSums4Avx2(k, t + i, ldt, strip.strip, strip.stride, tile_rows, sums);
      for (int q = 0; q < strip_columns; ++q)
      {
        double* const cq = c + column_offset[j + q];
        for (int r = std::max(0, j + q - i); r < tile_rows; ++r)
          cq[row_offset[i + r]] -= sums[q][r];
      }
    }
  }
}

// AVX-512's form of subtractLowerProductsAvx2(): tiles of 16 rows (two registers of eight) by the
// strip's four columns, eight 8-lane sums fused at each p. A whole tile is read without masks
// (kWholeTile: no mask is moved into a mask register in the loop, where the move would take a port
// of the 512-bit multiply-adds); in the last tile the rows past the last are masked off (not read,
// not written). Each column's entries on or below the diagonal are then subtracted where they
// belong: eight at once, masked, where the eight rows follow each other in C, else gathered and
// scattered by their row offsets. The same sums in the same order as the other forms: their bits.
template <bool kWholeTile>
__attribute__((target("avx512f,avx512vl,fma"))) inline void tileSumsAvx512(int k, const double* t, int ldt,
                                                                           const double* strip, long strip_stride,
                                                                           __mmask8 upper_rows, __mmask8 lower_rows,
                                                                           __m512d (&upper)[4], __m512d (&lower)[4])
{
  __m512d u0 = _mm512_setzero_pd(), u1 = u0, u2 = u0, u3 = u0, w0 = u0, w1 = u0, w2 = u0, w3 = u0;
  for (int p = 0; p < k; ++p)
  {
    const double* const tp = t + static_cast<long>(p) * ldt;
    const double* const lp = strip + p * strip_stride;
    const __m512d top = kWholeTile ? _mm512_loadu_pd(tp) : _mm512_maskz_loadu_pd(upper_rows, tp);
    const __m512d bottom = kWholeTile ? _mm512_loadu_pd(tp + 8) : _mm512_maskz_loadu_pd(lower_rows, tp + 8);
    const __m512d l0 = _mm512_set1_pd(lp[0]), l1 = _mm512_set1_pd(lp[1]);
    const __m512d l2 = _mm512_set1_pd(lp[2]), l3 = _mm512_set1_pd(lp[3]);
    u0 = _mm512_fmadd_pd(top, l0, u0);
    w0 = _mm512_fmadd_pd(bottom, l0, w0);
    u1 = _mm512_fmadd_pd(top, l1, u1);
    w1 = _mm512_fmadd_pd(bottom, l1, w1);
    u2 = _mm512_fmadd_pd(top, l2, u2);
    w2 = _mm512_fmadd_pd(bottom, l2, w2);
    u3 = _mm512_fmadd_pd(top, l3, u3);
    w3 = _mm512_fmadd_pd(bottom, l3, w3);
  }
  upper[0] = u0, upper[1] = u1, upper[2] = u2, upper[3] = u3;
  lower[0] = w0, lower[1] = w1, lower[2] = w2, lower[3] = w3;
}

// Eight rows' sums subtracted from column cq where `rows` (a mask) says: at offsets[r] each, or as
// one run from offsets[0] where `contiguous`.
__attribute__((target("avx512f,avx512vl"))) inline void subtractEight(double* cq, const int* offsets, __mmask8 rows,
                                                                      bool contiguous, __m512d sums)
{
  if (contiguous)
  {
    double* const to = cq + offsets[0];
    _mm512_mask_storeu_pd(to, rows, _mm512_sub_pd(_mm512_maskz_loadu_pd(rows, to), sums));
    return;
  }
  const __m256i index = _mm256_maskz_loadu_epi32(rows, offsets);
  const __m512d old = _mm512_mask_i32gather_pd(_mm512_setzero_pd(), rows, index, cq, 8);
  _mm512_mask_i32scatter_pd(cq, rows, index, _mm512_sub_pd(old, sums), 8);
}

__attribute__((target("avx512f,avx512vl,fma"))) void subtractLowerProductsAvx512(int rows, int columns, int k,
                                                                                 const double* t, int ldt,
                                                                                 const double* l, int ldl,
                                                                                 const int* row_offset,
                                                                                 const long* column_offset, double* c)
{
  alignas(64) double packed[kTileColumns * kMaxPacked];
  // The first `count` of eight lanes: none for a count of 0 or less, all from 8 on.
  auto firstLanes = [](int count) { return static_cast<__mmask8>(count >= 8 ? 0xff : (1u << std::max(count, 0)) - 1); };
  for (int j = 0; j < columns; j += kTileColumns)
  {
    const int strip_columns = std::min(kTileColumns, columns - j);
    const Strip strip = stripOf(k, l, ldl, j, strip_columns, packed);
    for (int i = j; i < rows; i += 2 * kTileRows)
    {
      const int left = rows - i;
      const __mmask8 upper_rows = firstLanes(left), lower_rows = firstLanes(left - kTileRows);
      __m512d upper[4], lower[4];
      if (left >= 2 * kTileRows)  // a whole tile: its loads need no mask
        tileSumsAvx512<true>(k, t + i, ldt, strip.strip, strip.stride, upper_rows, lower_rows, upper, lower);
      else
        tileSumsAvx512<false>(k, t + i, ldt, strip.strip, strip.stride, upper_rows, lower_rows, upper, lower);
      const int* const at = row_offset + i;
      const int upper_last = std::min(left, kTileRows) - 1, lower_last = std::min(left, 2 * kTileRows) - kTileRows - 1;
      const bool upper_contiguous = at[upper_last] == at[0] + upper_last;
      const bool lower_contiguous = lower_last >= 0 && at[kTileRows + lower_last] == at[kTileRows] + lower_last;
      for (int q = 0; q < strip_columns; ++q)
      {
        double* const cq = c + column_offset[j + q];
        // The rows on or below the diagonal: from row j + q of C on, the tile's row j + q − i.
        const int from = std::max(0, j + q - i);
        subtractEight(cq, at, upper_rows & static_cast<__mmask8>(~firstLanes(from)), upper_contiguous, upper[q]);
        const __mmask8 lower_mask = lower_rows & static_cast<__mmask8>(~firstLanes(from - kTileRows));
        if (lower_mask) subtractEight(cq, at + kTileRows, lower_mask, lower_contiguous, lower[q]);
      }
    }
  }
}

// The whole fours of subtractScaled(): how many entries it did (the caller does the rest, entry by
// entry, as its scalar form does all of them).
__attribute__((target("avx2"))) int subtractScaledAvx2(int n, const double* t, double factor, double* column)
{
  const __m256d f = _mm256_set1_pd(factor);
  int r = 0;
  for (; r + 4 <= n; r += 4)
    _mm256_storeu_pd(column + r, _mm256_sub_pd(_mm256_loadu_pd(column + r), _mm256_mul_pd(_mm256_loadu_pd(t + r), f)));
  return r;
}

// Entries r .. r + 3 done: stored, or (kKeepAndScale) kept, then stored scaled (`kept` is only
// offset when it is kept to: it is null otherwise).
template <bool kKeepAndScale>
__attribute__((target("avx2"))) inline void finishFour(double* out, double* kept, int r, __m256d entry, __m256d scale)
{
  if (kKeepAndScale)
  {
    _mm256_storeu_pd(kept + r, entry);
    entry = _mm256_mul_pd(entry, scale);
  }
  _mm256_storeu_pd(out + r, entry);
}

// The whole fours of subtractScaledColumns() (kKeepAndScale: of subtractScaledColumnsKeepAndScale()),
// eight rows at a time while eight are left, each row's terms column after column in a register:
// how many rows they did.
template <bool kKeepAndScale>
__attribute__((target("avx2"))) int subtractScaledColumnsAvx2(int n, int count, const double* columns, long ld,
                                                              const double* factors, double* out, double scale,
                                                              double* kept)
{
  const __m256d by = _mm256_set1_pd(scale);
  int r = 0;
  for (; r + 8 <= n; r += 8)
  {
    __m256d upper = _mm256_loadu_pd(out + r), lower = _mm256_loadu_pd(out + r + 4);
    for (int c = 0; c < count; ++c)
    {
      const double* const column = columns + c * ld + r;
      const __m256d f = _mm256_broadcast_sd(factors + c);
      upper = _mm256_sub_pd(upper, _mm256_mul_pd(_mm256_loadu_pd(column), f));
      lower = _mm256_sub_pd(lower, _mm256_mul_pd(_mm256_loadu_pd(column + 4), f));
    }
    finishFour<kKeepAndScale>(out, kept, r, upper, by);
    finishFour<kKeepAndScale>(out, kept, r + 4, lower, by);
  }
  for (; r + 4 <= n; r += 4)
  {
    __m256d sum = _mm256_loadu_pd(out + r);
    for (int c = 0; c < count; ++c)
      sum = _mm256_sub_pd(sum, _mm256_mul_pd(_mm256_loadu_pd(columns + c * ld + r), _mm256_broadcast_sd(factors + c)));
    finishFour<kKeepAndScale>(out, kept, r, sum, by);
  }
  return r;
}

// The whole fours of four columns' dots at once (each column its four lane sums, as dotAvx2()), x
// loaded once for the four; the four sums added as dotAvx2() adds them, the rest left to the caller.
__attribute__((target("avx2"))) int dotFourColumnsAvx2(int n, const double* columns, long ld, const double* x,
                                                       double* dots)
{
  __m256d s0 = _mm256_setzero_pd(), s1 = s0, s2 = s0, s3 = s0;
  const double *const c0 = columns, *const c1 = c0 + ld, *const c2 = c1 + ld, *const c3 = c2 + ld;
  int r = 0;
  for (; r + 4 <= n; r += 4)
  {
    const __m256d v = _mm256_loadu_pd(x + r);
    s0 = _mm256_add_pd(s0, _mm256_mul_pd(_mm256_loadu_pd(c0 + r), v));
    s1 = _mm256_add_pd(s1, _mm256_mul_pd(_mm256_loadu_pd(c1 + r), v));
    s2 = _mm256_add_pd(s2, _mm256_mul_pd(_mm256_loadu_pd(c2 + r), v));
    s3 = _mm256_add_pd(s3, _mm256_mul_pd(_mm256_loadu_pd(c3 + r), v));
  }
  alignas(32) double lanes[4][4];
  _mm256_store_pd(lanes[0], s0);
  _mm256_store_pd(lanes[1], s1);
  _mm256_store_pd(lanes[2], s2);
  _mm256_store_pd(lanes[3], s3);
  for (int c = 0; c < 4; ++c)
    dots[c] = (lanes[c][0] + lanes[c][1]) + (lanes[c][2] + lanes[c][3]);
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
#if defined(__x86_64__)
  static const bool fma = __builtin_cpu_supports("fma");
  return fma && cg_avx2::available();  // AVX2 as the CG's passes ask, and FMA
#else
  return false;
#endif
}

Tiles widestTiles()
{
#if defined(__x86_64__)
  static const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  if (available()) return avx512 ? Tiles::Avx512 : Tiles::Avx2;
#endif
  return Tiles::Scalar;
}

Tiles subtractLowerProducts(Tiles tiles, int rows, int columns, int k, const double* t, int ldt, const double* l,
                            int ldl, const int* row_offset, const long* column_offset, double* c)
{
#if defined(__x86_64__)
  const Tiles widest = widestTiles();
  if (k <= kMaxPacked && tiles == Tiles::Avx512 && widest == Tiles::Avx512)
  {
    subtractLowerProductsAvx512(rows, columns, k, t, ldt, l, ldl, row_offset, column_offset, c);
    clearUpperHalves();
    return Tiles::Avx512;
  }
  if (k <= kMaxPacked && tiles != Tiles::Scalar && widest != Tiles::Scalar)
  {
    subtractLowerProductsAvx2(rows, columns, k, t, ldt, l, ldl, row_offset, column_offset, c);
    clearUpperHalves();
    return Tiles::Avx2;
  }
#else
  (void)tiles;
#endif
  subtractLowerProductsScalar(rows, columns, k, t, ldt, l, ldl, row_offset, column_offset, c);
  return Tiles::Scalar;
}

void subtractScaled(bool avx2, int n, const double* t, double factor, double* column)
{
  int r = 0;
#if defined(__x86_64__)
  if (avx2 && available())
  {
    r = subtractScaledAvx2(n, t, factor, column);
    clearUpperHalves();
  }
#endif
  for (; r < n; ++r)
    column[r] -= t[r] * factor;
}

namespace
{
template <bool kKeepAndScale>
void subtractScaledColumnsOf(bool avx2, int n, int count, const double* columns, long ld, const double* factors,
                             double* out, double scale, double* kept)
{
  int r = 0;
#if defined(__x86_64__)
  if (avx2 && available())
  {
    r = subtractScaledColumnsAvx2<kKeepAndScale>(n, count, columns, ld, factors, out, scale, kept);
    clearUpperHalves();
  }
#endif
  for (; r < n; ++r)
  {
    double entry = out[r];
    for (int c = 0; c < count; ++c)
      entry -= columns[c * ld + r] * factors[c];
    if (kKeepAndScale)
    {
      kept[r] = entry;
      entry *= scale;
    }
    out[r] = entry;
  }
}
}  // namespace

void subtractScaledColumns(bool avx2, int n, int count, const double* columns, long ld, const double* factors,
                           double* out)
{
  subtractScaledColumnsOf<false>(avx2, n, count, columns, ld, factors, out, 1.0, nullptr);
}

void subtractScaledColumnsKeepAndScale(bool avx2, int n, int count, const double* columns, long ld,
                                       const double* factors, double scale, double* out, double* kept)
{
  subtractScaledColumnsOf<true>(avx2, n, count, columns, ld, factors, out, scale, kept);
}

void dotColumns(bool avx2, int n, int count, const double* columns, long ld, const double* x, double* dots)
{
  int c = 0;
#if defined(__x86_64__)
  if (avx2 && available())
    for (; c + 4 <= count; c += 4)
    {
      const int r = dotFourColumnsAvx2(n, columns + c * ld, ld, x, dots + c);
      clearUpperHalves();
      for (int q = c; q < c + 4; ++q)
        for (int rest = r; rest < n; ++rest)
          dots[q] += columns[q * ld + rest] * x[rest];
    }
#endif
  for (; c < count; ++c)
    dots[c] = dot(avx2, n, columns + c * ld, x);
}

double dot(bool avx2, int n, const double* a, const double* b)
{
#if defined(__x86_64__)
  if (avx2 && available())
  {
    const double sum = dotAvx2(n, a, b);
    clearUpperHalves();
    return sum;
  }
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
