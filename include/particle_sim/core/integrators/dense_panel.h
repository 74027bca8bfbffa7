#pragma once

namespace particle_sim
{
namespace core
{
/// The dense kernel of SparseBlockLdlt's supernodes, on column-major panels: C −= T Lᵀ on and below
/// C's diagonal (C(i, j) for i ≥ j, where row i and column j count from C's corner; some entries
/// just above the diagonal are made too, and never read). Each entry is its own sum, from zero,
/// of T(i, p) L(j, p) for p = 0, 1, ..., k − 1 in that order, each product fused into the sum
/// (one rounding, std::fma), subtracted from C(i, j) at the end: the AVX2 tiles (8 rows by 4
/// columns of C, with FMA, where the processor has both) and the scalar ones give the same bits.
namespace dense_panel
{
/// Whether this processor runs the AVX2 tiles (x86-64 with AVX2 and FMA).
bool available();

/// C (rows × columns, leading dimension ldc) −= T (rows × k, ldt) Lᵀ (L: columns × k, ldl), on and
/// below the diagonal; with the AVX2 tiles where `avx2` is true (and available()) and k is at most
/// 2048 (a strip of L is packed on the stack), else with the scalar ones.
void subtractLowerProducts(bool avx2, int rows, int columns, int k, const double* t, int ldt, const double* l, int ldl,
                           double* c, int ldc);

/// The same products, each entry (i, j) with i ≥ j subtracted where it belongs instead of into a
/// dense C: at c[column_offset[j] + row_offset[i]] (entries above the diagonal are not written).
/// Each entry's sum is the one subtractLowerProducts() makes, subtracted the same way: the same
/// bits.
void subtractLowerProductsScattered(bool avx2, int rows, int columns, int k, const double* t, int ldt, const double* l,
                                    int ldl, const int* row_offset, const long* column_offset, double* c);

/// column[r] −= t[r] factor for r < n (each entry one multiply and one subtraction, either way).
void subtractScaled(bool avx2, int n, const double* t, double factor, double* column);
/// kept[r] = column[r], then column[r] *= factor, for r < n.
void keepAndScale(bool avx2, int n, double factor, double* column, double* kept);
/// Σ a[r] b[r] for r < n in four sums (r mod 4, up to the last whole four), added as (s0 + s1) +
/// (s2 + s3), then the rest one by one: the same bits either way.
double dot(bool avx2, int n, const double* a, const double* b);
}  // namespace dense_panel
}  // namespace core
}  // namespace particle_sim
