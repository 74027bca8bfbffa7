#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <functional>
#include <vector>

#include "particle_sim/core/worker_pool.h"

namespace particle_sim
{
namespace core
{
/// Symmetric pairs of off-diagonal blocks that a setup() adds to A's blocks, in their order: pair k
/// adds C_k to blocks (i, j) and (j, i) (`blocks[k]`, in the pattern's block order) of particles
/// ends[k] = (i, j); C_k by its lower triangle (C00, C10, C20, C11, C21, C22). The implicit solver's
/// kept pairs (one a spring), which it need not add to its own blocks first.
struct FinestPairs
{
  int count = 0;
  const std::array<int, 2>* ends = nullptr;
  const std::array<int, 2>* blocks = nullptr;
  const std::array<double, 6>* c = nullptr;
};

/// The symmetric 3x3 block of a lower triangle (C00, C10, C20, C11, C21, C22): a pair's C.
inline Eigen::Matrix3d symmetricBlock(const std::array<double, 6>& c)
{
  Eigen::Matrix3d block;
  block << c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5];
  return block;
}

/// Smoothed-aggregation algebraic multigrid (Vaněk, Mandel & Brezina 1996) as the conjugate
/// gradient's preconditioner for the implicit system of a body of particles: one symmetric cycle
/// approximates A⁻¹ r. Each level lumps strongly coupled neighbouring nodes into aggregates (a
/// particle and its stretch and shear neighbours on the finest level, about 3 × 3 particles of a
/// cloth); the coarse space of an aggregate is spanned by the six rigid-body modes of its particles
/// (three translations, three rotations about its centroid), which a free elastic body does not
/// resist, so that the coarse levels carry the slow bending and swinging that block Jacobi needs
/// hundreds of iterations for.
///
/// Per level: the tentative prolongator P̂ is the modes of each aggregate orthonormalised (Q of a
/// QR, whose R are the modes of the next level's node); P = (I − ω D_L⁻¹ A_L) P̂, smoothed by one
/// damped Jacobi step on the lumped matrix A_L (ω = 4 / (3 ρ(D_L⁻¹ A_L)), ρ from a few power
/// iterations): A without its weak couplings (a cloth's bend springs), each added to its row's
/// diagonal block instead, so that a row's sum is kept and P spreads an aggregate over its strong
/// neighbours only (Vaněk, Mandel & Brezina's filtered matrix: fewer blocks in P, A P and the coarse
/// levels); the next level's matrix is A_c = Pᵀ A P (Galerkin, with A whole). Down to a few nodes,
/// which a dense L D Lᵀ solves. The cycle smooths before the coarse correction and after it, on every
/// level, with kSmoothingSweeps steps of a Chebyshev polynomial in D⁻¹ A (block-diagonal D) that is
/// smallest on [u / 10, u], the high end of the spectrum with u some 1.5 times the estimate of
/// ρ(D⁻¹ A) (chebyshevSteps()), and that stops contracting where damped Jacobi with the damping
/// ω = 4 / (3 ρ) it replaced would: the same smoother both ways, so the cycle is a symmetric
/// positive definite operator, as CG needs. The finest level
/// corrects once from the first coarse level, and every coarse level twice from the level below it
/// (kCoarseVisits: a W-cycle below the first coarse level): the second visit solves for what the
/// first left, the coarse residual r_c − A_c x_c, and adds its answer, so that a level's correction
/// is (2 B − B A_c B) r_c with B the next level's cycle, symmetric again. On the bench's spring cloth
/// (goal 2 of issue 13) the plain V-cycle's iterations grew by 1.44 from 64² to 128² (14.2 → 20.4
/// a step); this cycle's grow by about 1.3, and its step costs less at both sizes; the Chebyshev
/// smoother takes a tenth fewer iterations than two damped Jacobi sweeps at the same cost (README,
/// "Or by multigrid").
///
/// Pinned particles: setup() takes the filtered system (pinned rows and columns cleared, the diagonal
/// kept), their rows of P̂ are zero, and a coarse mode that the pins leave empty is dropped (its
/// column zero, its diagonal one). So the cycle of a filtered residual is zero on pinned rows.
///
/// setPattern() takes the finest level's pattern; the first setup() after it aggregates each level
/// by the strength of its couplings in that first system and lays out every level's patterns and the
/// plans of its Galerkin products (allocates); every setup() computes the numbers for one system and
/// apply() runs a cycle: neither allocates after the first setup(). The passes over a level's
/// nodes in which each node's result is computed alone are shared with setWorkers()' threads by
/// chunks of nodes: the products, the residuals, the smoothing, the prolongation, the restriction
/// (gathered by aggregate), the finest level's copy, the inverse diagonal blocks of A and of the
/// lumped matrix, the power iterations' D⁻¹ products, the tentative prolongator (by aggregate), P's
/// rows, their copy in Pᵀ's order (by aggregate), A P, and the Galerkin product Pᵀ (A P) (by row
/// of A_c, each block summed in the order of the rows of A P). The rest is serial (the power
/// iterations' norms, the coarsest solve). So the same bits at any thread count.
class SmoothedAggregation
{
public:
  /// The finest level's pattern: block rows with sorted columns, the diagonal included (the
  /// implicit solver's), for `particles` particles.
  void setPattern(int particles, const std::vector<int>& row_start, const std::vector<int>& column);
  /// Builds the hierarchy for the 3x3 blocks A (in the pattern's order, symmetric) at positions x [m]:
  /// pinned rows and columns are filtered out. False when the coarsest matrix cannot be factored
  /// (A not positive definite or not finite): apply() must not be called then.
  bool setup(const std::vector<Eigen::Matrix3d>& blocks, const Eigen::Matrix3Xd& x, const std::vector<char>& pinned);
  /// The same for the matrix whose blocks are `blocks` plus `pairs` (FinestPairs), summed as the
  /// solver would sum them in its blocks, in the same order: the same bits.
  bool setup(const std::vector<Eigen::Matrix3d>& blocks, const Eigen::Matrix3Xd& x, const std::vector<char>& pinned,
             const FinestPairs& pairs);
  /// Threads to share the passes over nodes with (null: the calling thread alone); the bits do not
  /// depend on them.
  void setWorkers(WorkerPool* workers) { workers_ = workers; }
  /// Starts the next setup's estimates of ρ(D⁻¹ A) afresh (after a reset: the same bits as a new
  /// solver).
  void forgetHistory();
  /// z = one cycle on r (3 x particles, filtered: zero on pinned rows).
  void apply(const Eigen::Matrix3Xd& r, Eigen::Matrix3Xd& z);
  /// y = Ã x with Ã the filtered matrix of the last setup() (pinned rows and columns cleared, an
  /// identity on their diagonal).
  void multiplyFinest(const Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& y) const;
  /// The finest level's product y = Ã x from outside, on 3 x particles numbers each (x is zero on
  /// pinned rows, and so must y be): the implicit solver's product by the springs' pairs, which reads
  /// a third of the bytes of the 3x3 blocks. apply() (its two residuals on the finest level) and
  /// multiplyFinest() take it while useFinestProduct(true) holds, else the blocks; the setup reads
  /// the blocks either way.
  using FinestProduct = std::function<void(const double* x, double* y)>;
  void setFinestProduct(FinestProduct product) { finest_product_ = std::move(product); }
  void useFinestProduct(bool use) { use_finest_product_ = use && finest_product_; }
  /// Floating-point operations of one apply() (a cycle: on each visit of a level above the coarsest
  /// 2 kSmoothingSweeps smoothings and as many residuals, the restriction and prolongation, and for
  /// a second visit of the next level its residual and sum; the coarsest's solve on each visit) and of
  /// one setup() after the first (the numbers of every level: inverse diagonals, the power
  /// iterations, P̂ and P, A P and Pᵀ A P, the coarsest factorization), a multiply and an add counted
  /// as two, from the hierarchy's sizes: for ImplicitEulerSolver's `auto`, which compares them with
  /// the conjugate gradient's flops. 0 before the first setup().
  double cycleFlops() const;
  double setupFlops() const;
  /// The part of cycleFlops() that is the finest level's smoothings and residuals: block-diagonal
  /// products and products with A (the springs' pairs, when a finest product is set), the kinds of
  /// operation a CG iteration of block Jacobi does (its preconditioner and its product).
  double finestCycleFlops() const;
  /// The number of levels, the finest included (0 before setPattern(), 1 until the first setup()).
  int levels() const { return static_cast<int>(levels_.size()); }
  /// Nodes of level `level` (particles on the finest, aggregates below).
  int nodes(int level) const { return levels_[level].nodes; }
  /// The tentative prolongator's columns at `level`, times the next level's modes (R): the modes of
  /// this level, rebuilt (for tests: P̂ R = B).
  Eigen::VectorXd tentativeTimesCoarseModes(int level, int mode) const;
  /// The near-null-space modes of `level`, mode `mode` (0..5) as a vector: for tests.
  Eigen::VectorXd modes(int level, int mode) const;
  /// The aggregate (the next level's node) that node `node` of `level` belongs to: for tests.
  int aggregateOf(int level, int node) const { return levels_[level].aggregate[node]; }

  /// A matrix in block-sparse rows: `rows` x `columns` blocks of row_block x column_block numbers
  /// (row-major), row r's blocks in [start[r], start[r + 1]) with their block columns in `column`.
  struct BlockRows
  {
    int rows = 0, columns = 0, row_block = 0, column_block = 0;
    std::vector<int> start, column;
    std::vector<double> values;
  };
  /// The matrix of `level` as setup() left it (the finest level filtered): for tests.
  BlockRows matrixOf(int level) const;
  /// The smoothed prolongator P from `level` to the next (b x 6 blocks): for tests.
  BlockRows prolongatorOf(int level) const;

  /// Nodes of the coarsest level at most (it is solved by a dense factorization).
  static constexpr int kCoarsestNodes = 24;
  /// Smoothing steps before a level's coarse correction, and as many after it: the degree of the
  /// smoother's Chebyshev polynomial.
  static constexpr int kSmoothingSweeps = 2;
  /// The ratio of the ends of the interval [u / kChebyshevRange, u] of eigenvalues of D⁻¹ A on which
  /// the smoother's polynomial is smallest (the high ones: the low ones are the coarse levels' work).
  static constexpr double kChebyshevRange = 10.0;
  /// The coefficients of the smoother's steps on [u / kChebyshevRange, u], u = `upper`: step k is
  /// keep[k] times the step before plus scale[k] D⁻¹ r (the residual before it), added to x; so that
  /// after the steps the error on an eigenvector of D⁻¹ A with eigenvalue t is scaled by
  /// T_k((θ − t) / δ) / T_k(θ / δ) (T_k Chebyshev's polynomial of degree k = kSmoothingSweeps, θ and δ
  /// the interval's centre and half-width): at most 1 / T_k(θ / δ) in size on the interval, at most 1
  /// for 0 ≤ t ≤ 2 θ.
  struct ChebyshevSteps
  {
    std::array<double, kSmoothingSweeps> keep{}, scale{};
  };
  static ChebyshevSteps chebyshevSteps(double upper);
  /// How many times each coarse level (all but the finest) visits the level below it in one cycle
  /// (once when the coarsest level is too large to factor: visitNext()).
  static constexpr int kCoarseVisits = 2;
  /// The rigid-body modes of a node's aggregate: the coarse block size.
  static constexpr int kModes = 6;

private:
  // One level: its matrix A in b x b blocks (row-major, block-sparse rows with sorted columns), the
  // inverse of its diagonal blocks, its modes (b x 6 a node), and towards the next level the
  // aggregates, the tentative and smoothed prolongators (b x 6 blocks) and the Galerkin plans.
  struct Level
  {
    int nodes = 0;
    int block = 3;  // b: 3 on the finest level, 6 below
    std::vector<int> start, column, diagonal;
    std::vector<double> a, inverse_diagonal, modes;
    // Towards the next level (empty on the coarsest).
    std::vector<int> aggregate;  // per node
    // Per block of A: 1 where the coupling is strong (the diagonal always), 0 where it is weak or
    // zero; whether any weak coupling is not zero (else A_L = A, and P's smoothing takes A's
    // diagonal and ω); A_L's inverse diagonal blocks, its ω and its power iteration's vectors.
    std::vector<char> strong;
    bool has_weak = false;
    std::vector<double> lumped_inverse_diagonal;
    double lumped_omega = 0.0;
    bool lumped_power_started = false;
    Eigen::VectorXd lumped_power, lumped_power_product;
    std::vector<std::vector<int>> members;
    std::vector<double> tentative;  // b x 6 per node: its rows of P̂ (columns of its aggregate)
    std::vector<int> p_start, p_column;
    std::vector<double> p;  // b x 6 per block of P
    // Pᵀ by rows (aggregates): each one's blocks of P (pt_block) and their rows (pt_row), ascending;
    // and a copy of P's blocks in that order (pt_p, b x 6 per block, made after P in each setup), so
    // that the restriction and the Galerkin product read P in order rather than by scattered blocks.
    std::vector<int> pt_start, pt_block, pt_row;
    std::vector<double> pt_p;
    // A P: rows of this level, columns of the next (its pattern, its blocks in `ap`), planned as
    // (block of A, block of P, block of A P) per product, row after row.
    std::vector<int> ap_start, ap_column;
    std::vector<double> ap;
    std::vector<std::array<int, 3>> ap_plan;
    std::vector<int> ap_plan_start;  // per row
    // Pᵀ (A P) into the next level's blocks on and above the diagonal: (block of pt_p, block of A P,
    // block of A_c) per product, by the row of A_c (a row of P's column) and within it by ascending
    // row of A P: each block of A_c sums its products in the order of the rows of A P.
    std::vector<std::array<int, 3>> galerkin_plan;
    std::vector<int> galerkin_plan_start;  // per row of A_c (per node of the next level)
    // This level's blocks below the diagonal with their mirror above it (lower = upperᵀ).
    std::vector<std::array<int, 2>> mirrored;
    // Damped Jacobi's 4 / (3 ρ(D⁻¹ A)): the smoother's reach, and P's smoothing where no coupling is
    // weak; the cycle's smoothing steps (from ω: setupLevel()).
    double omega = 0.0;
    ChebyshevSteps smoother;
    bool power_started = false;  // `power` holds the last setup's eigenvector estimate
    // The cycle's vectors: right-hand side, iterate, residual, the smoother's last step (b a node); a coarse level's
    // first visit's iterate and right-hand side, kept over its second visit; and the power iteration's two.
    Eigen::VectorXd rhs, x, residual, chebyshev_step, first_visit_x, first_visit_rhs, power, power_product;
  };

  // Sizes a level's arrays from its pattern.
  static void layOut(Level& level);
  // At the first setup(): aggregates each level by the strength of its couplings, lays out the next
  // level (planNextLevel()) and makes its numbers, down to the coarsest, which it factors.
  bool planAndSetUp(const Eigen::Matrix3Xd& x, const std::vector<char>& pinned);
  // Aggregates `level` (its strong couplings) and lays out the next level, its pattern and the plans.
  void planNextLevel(int level);
  // The finest level's rigid-body modes at positions x.
  void finestModes(const Eigen::Matrix3Xd& x, const std::vector<char>& pinned);
  // The coarsest level's inverse diagonal and factorization.
  bool setUpCoarsest();
  // The numbers of `level` from its matrix: inverse diagonal, ω, P̂ and the next level's modes, P,
  // A P and the next level's A. Templated on the block size.
  template <int B>
  void setupLevel(int level);
  // The tentative prolongator's rows of aggregate `a`'s members on `level` (its modes orthonormalised,
  // Q) and the modes of its node on `next` (R).
  template <int B>
  static void tentativeOfAggregate(Level& level, Level& next, int a);
  template <int B>
  void multiply(const Level& level, const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  // residual = the level's rhs − A x.
  template <int B>
  void residualOf(const Level& level, const Eigen::VectorXd& x, Eigen::VectorXd& residual) const;
  // residualOf() on the finest level through finest_product_.
  void finestResidualOutside(const Eigen::VectorXd& x, Eigen::VectorXd& residual) const;
  // y = A_L x, the level's lumped matrix (its weak blocks applied to x_i instead of x_j).
  template <int B>
  void multiplyLumped(const Level& level, const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  // ω = 4 / (3 ρ(D⁻¹ A)) of the operator `product` (y = A x) whose inverse diagonal blocks are
  // `inverse_diagonal`, ρ by power iterations in `power` and `power_product`; the per-node products
  // shared with `workers`.
  template <int B, typename Product>
  static double smootherDamping(WorkerPool* workers, int nodes, const std::vector<double>& inverse_diagonal,
                                const Product& product, Eigen::VectorXd& power, Eigen::VectorXd& power_product,
                                bool& power_started);
  // One step of the smoother on `level`: its step = keep step + scale D⁻¹ residual, x += step.
  template <int B>
  void chebyshevStep(Level& level, const Eigen::VectorXd& residual, double keep, double scale);
  template <int B>
  void restrictResidual(const Level& level, Eigen::VectorXd& coarse_rhs) const;
  template <int B>
  void prolongAdd(const Level& level, const Eigen::VectorXd& coarse, Eigen::VectorXd& x) const;
  // x = the cycle on `level`'s rhs.
  void cycle(int level);
  // The next level's cycle on its rhs, visited visitsOfNext(level) times from `level`.
  void visitNext(int level);
  // How many times one cycle of `level` visits the next level: kCoarseVisits from a coarse level,
  // else once (see the definition).
  int visitsOfNext(int level) const;
  // The flops of one visit's smoothings and residuals on `level` (kSmoothingSweeps of each, before
  // and after the coarse correction).
  static double smoothingFlops(const Level& level);
  bool factorCoarsest();
  // The finest level's matrix from the solver's blocks and pairs, pinned rows and columns filtered.
  void copyFinest(const std::vector<Eigen::Matrix3d>& blocks, const std::vector<char>& pinned,
                  const FinestPairs& pairs);

  std::vector<Level> levels_;
  bool planned_ = false;      // the levels below the finest are laid out (at the first setup())
  Eigen::MatrixXd coarsest_;  // the coarsest level's matrix, dense
  Eigen::LDLT<Eigen::MatrixXd> coarsest_factor_;
  WorkerPool* workers_ = nullptr;
  FinestProduct finest_product_;     // setFinestProduct()
  bool use_finest_product_ = false;  // useFinestProduct()
};

}  // namespace core
}  // namespace particle_sim
