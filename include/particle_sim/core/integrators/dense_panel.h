#pragma once

namespace particle_sim
{
namespace core
{
/// The dense kernels of SparseBlockLdlt's supernodes, on column-major panels.
namespace dense_panel
{
/// Whether this processor runs the AVX2 tiles (x86-64 with AVX2 and FMA).
bool available();

/// The forms of subtractLowerProducts(), which give the same bits: entry by entry, in AVX2 tiles of
/// 8 rows by 4 columns, or in AVX-512 tiles of 16 rows by 4 columns.
enum class Tiles
{
  Scalar,
  Avx2,
  Avx512,
};
/// The widest form this processor runs: AVX-512 where it has AVX-512F and AVX-512VL besides AVX2 and
/// FMA, AVX2 where it has those, else scalar.
Tiles widestTiles();

/// C −= T Lᵀ on and below the diagonal (T: rows × k, leading dimension ldt; L: columns × k, ldl):
/// entry (i, j) for i ≥ j at c[column_offset[j] + row_offset[i]], so that a dense C (row_offset[i]
/// = i, column_offset[j] = j ldc) and rows scattered over other panels (a supernode's update of
/// those above it) take one kernel; row_offset ascending. Entries above the diagonal are not written.
/// Each entry is its own sum, from zero, of T(i, p) L(j, p) for p = 0, 1, ..., k − 1 in that order,
/// each product fused into the sum (one rounding, std::fma), subtracted at the end: every form gives
/// the same bits. `tiles` asks for a form, which runs where the processor has it (else the widest one
/// below it that it has; the scalar one where k exceeds 2048, as a strip of L is packed on the
/// stack); the form that ran is returned.
Tiles subtractLowerProducts(Tiles tiles, int rows, int columns, int k, const double* t, int ldt, const double* l,
                            int ldl, const int* row_offset, const long* column_offset, double* c);

/// column[r] −= t[r] factor for r < n (each entry one multiply and one subtraction, either way).
void subtractScaled(bool avx2, int n, const double* t, double factor, double* column);
/// out[r] −= columns[c ld + r] factors[c] for r < n, c = 0, 1, ..., count − 1 in that order: the
/// bits of subtractScaled() column after column, each entry kept in a register meanwhile.
void subtractScaledColumns(bool avx2, int n, int count, const double* columns, long ld, const double* factors,
                           double* out);
/// subtractScaledColumns(), then kept[r] = out[r] and out[r] *= scale, in one pass (a panel's
/// column: T's kept, L's scaled by the pivot's inverse).
void subtractScaledColumnsKeepAndScale(bool avx2, int n, int count, const double* columns, long ld,
                                       const double* factors, double scale, double* out, double* kept);
/// Σ a[r] b[r] for r < n in four sums (r mod 4, up to the last whole four), added as (s0 + s1) +
/// (s2 + s3), then the rest one by one: the same bits either way.
double dot(bool avx2, int n, const double* a, const double* b);
/// dots[c] = dot(avx2, n, columns + c ld, x) for c < count, four columns at a time (x read once for
/// the four): the same bits.
void dotColumns(bool avx2, int n, int count, const double* columns, long ld, const double* x, double* dots);
}  // namespace dense_panel
}  // namespace core
}  // namespace particle_sim
