#include "particle_sim/core/forces/springs.h"

#include <algorithm>
#include <array>
#include <numeric>

namespace particle_sim
{
namespace core
{
namespace
{
// Springs and particles per chunk of a shared loop: about 50 µs of work, so that a loop's handover
// costs a few per cent of it.
constexpr int kSpringsPerChunk = 2048;
constexpr int kParticlesPerChunk = 2048;

// Particles per chunk of the springs' passes shared by chunks of particles: one chunk a thread, in
// whole multiples of kParticleChunkGrain (so that a chunk's forces start on a cache line of their
// own), at least kParticlesPerChunk. The springs across a chunk's edge are computed by both chunks,
// in short runs (along a grid cloth's edge, springs with both ends inside alternate with springs
// with one: at 128² with four chunks, 3426 runs of fewer than 8 springs, 6477 springs in all), so
// each edge costs a few per cent of the pass; a second chunk a thread, for a faster thread to take
// from a slower one, cost more than it evened out (README, "Threads"). Whatever the chunks, each
// particle gets its terms in the one-thread order: the same bits.
constexpr int kParticleChunkGrain = 256;
int particleChunkFor(int particles, int threads)
{
  const int parts = std::max(threads, 1);
  const int per_part = (particles + parts - 1) / parts;
  return std::max(kParticlesPerChunk, (per_part + kParticleChunkGrain - 1) / kParticleChunkGrain * kParticleChunkGrain);
}

// A chunk of springs whose sum a thread is going on with (SpringForces::chunk_next_spring_).
constexpr int kSummingChunk = -1;

std::size_t chunksOf(std::size_t springs)
{
  return (springs + kSpringsPerChunk - 1) / kSpringsPerChunk;
}

}  // namespace

SpringForces::SpringForces(std::vector<Spring> springs)
    : built_(springs), springs_(std::move(springs)), origin_(springs_.size()), kept_energy_(springs_.size())
{
  kept_chunk_energy_.reserve(chunksOf(springs_.size()));
  chunk_next_spring_ = std::make_unique<std::atomic<int>[]>(chunksOf(springs_.size()));
  std::iota(origin_.begin(), origin_.end(), 0);
}

bool SpringForces::sharesForces(const ForceContext& context) const
{
  return context.workers && context.workers->threads() > 1 && static_cast<int>(springs_.size()) > kSpringsPerChunk;
}

void SpringForces::addForces(const ForceContext& context, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                             Eigen::Matrix3Xd& force) const
{
  energy_kept_ = false;
  if (sharesForces(context))
  {
    addForcesShared(*context.workers, x, v, force, nullptr);
    return;
  }
  addSpringForcesOf(springs_.data(), springs_.data() + springs_.size(), x.data(), v.data(), force.data(), nullptr,
                    nullptr, true, true, ImplicitEulerSolver::useAvx2());
}

void SpringForces::addForcesKeepingEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x,
                                          const Eigen::Matrix3Xd& v, Eigen::Matrix3Xd& force) const
{
  energy_kept_ = true;
  energy_kept_by_chunks_ = true;
  if (sharesForces(context))
  {
    kept_energy_.resize(springs_.size());  // sized at construction: tears shrink it, mend() restores it
    const int chunks = static_cast<int>(chunksOf(springs_.size()));
    kept_chunk_energy_.assign(chunks, 0.0);  // reserved at construction: never larger
    for (int m = 0; m < chunks; ++m)
    {
      chunk_next_spring_[m].store(m * kSpringsPerChunk, std::memory_order_relaxed);
    }
    energy_kept_by_chunks_ = addForcesShared(*context.workers, x, v, force, kept_energy_.data());
    if (!energy_kept_by_chunks_) return;  // (the two passes: addKeptEnergy() sums kept_energy_)
    // A chunk whose pieces did not all come in order: its sum goes on, in order, from the first
    // spring the pass did not sum, over the energies the pieces out of order kept (addEnergy()'s sum of
    // the chunk, so the same bits).
    const int springs = static_cast<int>(springs_.size());
    for (int m = 0; m < chunks; ++m)
    {
      const int last = std::min(springs, (m + 1) * kSpringsPerChunk);
      double sum = kept_chunk_energy_[m];
      for (int k = chunk_next_spring_[m].load(std::memory_order_relaxed); k < last; ++k)
        sum += kept_energy_[k];
      kept_chunk_energy_[m] = sum;
    }
    return;
  }
  // One thread: addEnergy()'s chunks of springs, each chunk's energies written to a buffer that
  // stays in the first-level cache and summed in order at once (addEnergy()'s sums, so the same
  // bits), instead of a store a spring and a pass of their own over the springs afterwards.
  kept_chunk_energy_.resize(chunksOf(springs_.size()));  // reserved at construction: never larger
  std::array<double, kSpringsPerChunk> chunk_energy;
  const bool vectorized = ImplicitEulerSolver::useAvx2();
  forEachFixedChunk(nullptr, static_cast<int>(springs_.size()), kSpringsPerChunk, [&](int chunk, int first, int last) {
    double sum = 0.0;
    addSpringForcesOf(springs_.data() + first, springs_.data() + last, x.data(), v.data(), force.data(),
                      chunk_energy.data(), &sum, true, true, vectorized);
    kept_chunk_energy_[chunk] = sum;
  });
}

void SpringForces::addKeptEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const
{
  // tear() and mend(), the only changes of the list, forget what was kept.
  if (!energy_kept_)
  {
    addEnergy(context, x, energy);
    return;
  }
  energy_kept_ = false;
  if (energy_kept_by_chunks_)
  {
    // sumByChunks()'s last sum: chunk after chunk.
    double total = 0.0;
    for (const double chunk : kept_chunk_energy_)
      total += chunk;
    energy += total;
    return;
  }
  // addEnergy()'s sum, term by term: the same chunks in the same order, so the same bits.
  const double* const kept = kept_energy_.data();
  energy += sumByChunks(context.workers, static_cast<int>(springs_.size()), kSpringsPerChunk, chunk_energy_,
                        [kept](int k) { return kept[k]; });
}

bool SpringForces::addForcesShared(WorkerPool& workers, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& v,
                                   Eigen::Matrix3Xd& force, double* energy) const
{
  const int particles = static_cast<int>(x.cols());
  indexEnds(particles, workers.threads());
  if (by_chunks_)
  {
    // Raw pointers, read once: the stores into `force` would otherwise make the compiler reload
    // every container's data pointer for each spring.
    const double* const xs = x.data();
    const double* const vs = v.data();
    double* const fs = force.data();
    const Spring* const all = springs_.data();
    const PairChunks::Run* const runs = chunks_.runs();
    const PairChunks& chunks = chunks_;
    const bool vectorized = ImplicitEulerSolver::useAvx2();
    const int chunk_size = particle_chunk_;
    std::atomic<int>* const next_spring = chunk_next_spring_.get();
    double* const chunk_sums = kept_chunk_energy_.data();
    workers.forEachChunk(particles, chunk_size, [=, &chunks](int begin, int end) {
      std::array<double, kSpringsPerChunk> piece_energy;
      for (int chunk = begin / chunk_size; chunk * chunk_size < end; ++chunk)
      {
        for (int r = chunks.runStart(chunk); r < chunks.runStart(chunk + 1); ++r)
        {
          const PairChunks::Run run = runs[r];
          const Spring* const first = all + run.first;
          const Spring* const last = first + run.count;
          const bool add_i = run.ends != PairChunks::kEndJ, add_j = run.ends != PairChunks::kEndI;
          // A spring's energy is written by the run that holds its end i (one writer a spring).
          if (!energy || !add_i)
          {
            addSpringForcesOf(first, last, xs, vs, fs, nullptr, nullptr, add_i, add_j, vectorized);
            continue;
          }
          // Piece by piece within the chunks of springs: a piece that starts where its chunk's sum
          // stopped goes on with that sum in the pass (claimed while it runs), its energies in a
          // buffer that stays in the first-level cache; one that does not keeps its springs'
          // energies in `energy`, from which the chunk's sum goes on afterwards. The pieces in order
          // are a prefix of the chunk, so every spring after it is in a piece that kept its energy.
          for (int piece = run.first; piece < run.first + run.count;)
          {
            const int m = piece / kSpringsPerChunk;
            const int piece_end = std::min(run.first + run.count, (m + 1) * kSpringsPerChunk);
            int expected = piece;
            const bool in_order =
                next_spring[m].compare_exchange_strong(expected, kSummingChunk, std::memory_order_acquire);
            addSpringForcesOf(all + piece, all + piece_end, xs, vs, fs, in_order ? piece_energy.data() : energy + piece,
                              in_order ? chunk_sums + m : nullptr, add_i, add_j, vectorized);
            if (in_order) next_spring[m].store(piece_end, std::memory_order_release);
            piece = piece_end;
          }
        }
      }
    });
    return true;
  }
  const int springs = static_cast<int>(springs_.size());
  workers.forEachChunk(springs, kSpringsPerChunk, [&](int begin, int end) {
    for (int k = begin; k < end; ++k)
    {
      const Spring& s = springs_[k];
      spring_force_[k] =
          springForce(x.col(s.i), x.col(s.j), v.col(s.i), v.col(s.j), s.rest_length, s.stiffness, s.damping);
      if (energy) energy[k] = springEnergy(x.col(s.i), x.col(s.j), s.rest_length, s.stiffness);
    }
  });
  // Each particle adds +f at its ends i and −f at its ends j, springs ascending: the one-thread
  // loop's additions to that particle, in its order.
  workers.forEachChunk(particles, kParticlesPerChunk, [&](int begin, int end) {
    for (int p = begin; p < end; ++p)
    {
      for (int e = end_start_[p]; e < end_start_[p + 1]; ++e)
      {
        const int end_code = ends_[e];
        const Eigen::Vector3d& f = spring_force_[end_code >> 1];
        if (end_code & 1)
          force.col(p) -= f;
        else
          force.col(p) += f;
      }
    }
  });
  return false;
}

void SpringForces::indexEnds(int particles, int threads) const
{
  const int chunk_size = particleChunkFor(particles, threads);
  const int chunks = (particles + chunk_size - 1) / chunk_size;
  if (ends_valid_ && chunks_.chunks() == chunks && chunk_size == particle_chunk_ &&
      (by_chunks_ || static_cast<int>(end_start_.size()) == particles + 1))
    return;
  particle_chunk_ = chunk_size;
  const int springs = static_cast<int>(springs_.size());
  chunks_.build(
      springs, particles, chunk_size, [this](int k) { return springs_[k].i; }, [this](int k) { return springs_[k].j; });
  if (!mode_decided_)
  {
    // Decided once, from the springs as first indexed (a tear only removes springs).
    by_chunks_ = chunks_.hasLocality();
    mode_decided_ = true;
  }
  if (by_chunks_)
  {
    ends_valid_ = true;
    return;
  }
  // Counting sort of the 2 S ends by particle; filled in spring order, so each particle's ends
  // are ascending.
  spring_force_.resize(springs);
  ends_.resize(2 * static_cast<std::size_t>(springs));
  end_start_.assign(particles + 1, 0);
  for (const Spring& s : springs_)
  {
    ++end_start_[s.i + 1];
    ++end_start_[s.j + 1];
  }
  for (int p = 0; p < particles; ++p)
    end_start_[p + 1] += end_start_[p];
  for (int k = 0; k < springs; ++k)
  {
    const Spring& s = springs_[k];
    ends_[end_start_[s.i]++] = 2 * k;
    ends_[end_start_[s.j]++] = 2 * k + 1;
  }
  // The fill moved each start to the next particle's: shift them back.
  for (int p = particles; p > 0; --p)
    end_start_[p] = end_start_[p - 1];
  end_start_[0] = 0;
  ends_valid_ = true;
}

void SpringForces::coupledPairs(std::vector<std::pair<int, int>>& pairs) const
{
  for (const Spring& spring : springs_)
    pairs.emplace_back(spring.i, spring.j);
}

void SpringForces::bindPattern(const ImplicitEulerSolver& solver)
{
  // Every built spring keeps its blocks in the pattern, torn or not: a tear leaves them zero, so
  // the pattern (and the solver's storage) never changes.
  // After a vertex split the pattern is the springs' as they are (the built ones' blocks may then be
  // missing, −1: mend() is followed by a rebuild of the pattern).
  auto blocks_of = [&solver](const Spring& spring) {
    return std::array<int, 4>{solver.blockIndex(spring.i, spring.i), solver.blockIndex(spring.i, spring.j),
                              solver.blockIndex(spring.j, spring.i), solver.blockIndex(spring.j, spring.j)};
  };
  built_blocks_.clear();
  for (const Spring& spring : built_)
    built_blocks_.push_back(blocks_of(spring));
  blocks_.clear();
  for (const Spring& spring : springs_)
    blocks_.push_back(blocks_of(spring));
}

void SpringForces::splitParticle(int original, int copy, const std::vector<int>& neighbours,
                                 const std::vector<Eigen::Vector3i>& /*triangles*/)
{
  auto joined = [&](int other) { return std::binary_search(neighbours.begin(), neighbours.end(), other); };
  for (Spring& spring : springs_)
  {
    if (spring.i == original && joined(spring.j))
      spring.i = copy;
    else if (spring.j == original && joined(spring.i))
      spring.j = copy;
  }
  ends_valid_ = false;
}

void SpringForces::addJacobians(const ForceContext& context, const Eigen::Matrix3Xd& x,
                                ImplicitEulerSolver& solver) const
{
  // ∂f_i/∂x_i = ∂f_j/∂x_j = −∂f_i/∂x_j = −∂f_j/∂x_i (definite form), alike for v: by their parts
  // along the spring and across it, but for coincident ends (no direction). The parts first, for
  // every spring at once (their square roots and divisions four at a time, shared by chunks between
  // the threads), then the blocks in spring order.
  const int count = static_cast<int>(springs_.size());
  jacobian_parts_.resize(springs_.size());
  const bool vectorized = ImplicitEulerSolver::useAvx2();
  forEachFixedChunk(context.workers, count, kSpringsPerChunk, [&](int, int first, int last) {
    springJacobianPartsOf(springs_.data(), first, last, x.data(), vectorized, jacobian_parts_);
  });
  const SpringJacobianParts& parts = jacobian_parts_;
  if (sharesJacobians(context, solver, static_cast<int>(x.cols())))
  {
    addJacobiansShared(*context.workers, static_cast<int>(x.cols()), solver);
    return;
  }
  for (int s = 0; s < count; ++s)
  {
    const Spring& spring = springs_[s];
    if (!parts.coincident[s])
    {
      solver.addAlongPairBlocks(blocks_[s], Eigen::Vector3d(parts.d_x[s], parts.d_y[s], parts.d_z[s]), parts.along_x[s],
                                parts.isotropic_x[s], -spring.damping);
      continue;
    }
    Eigen::Matrix3d dfdx, dfdv;
    springJacobians(x.col(spring.i), x.col(spring.j), spring.rest_length, spring.stiffness, spring.damping, true, dfdx,
                    dfdv);
    solver.addPairBlocks(blocks_[s], dfdx, dfdv);
  }
}

bool SpringForces::sharesJacobians(const ForceContext& context, const ImplicitEulerSolver& solver, int particles) const
{
  // By chunks of particles (as the forces, addForcesShared()), where the springs have the locality
  // for it and none has coincident ends this step (those take addPairBlocks()).
  if (!sharesForces(context) || !solver.pairEndsShareable()) return false;
  indexEnds(particles, context.workers->threads());
  if (!by_chunks_) return false;
  const std::vector<char>& coincident = jacobian_parts_.coincident;
  return std::find(coincident.begin(), coincident.begin() + static_cast<long>(springs_.size()), 1) ==
         coincident.begin() + static_cast<long>(springs_.size());
}

void SpringForces::addJacobiansShared(WorkerPool& workers, int particles, ImplicitEulerSolver& solver) const
{
  // Each chunk's thread visits the springs that touch its particles, in spring order, and adds to
  // their ends inside the chunk: every particle gets the one-thread loop's terms in its order (its
  // bits); a spring's pair is kept by the run that holds its end i.
  const int first_pair = solver.reservePairs(static_cast<int>(springs_.size()));
  const int chunks = chunks_.chunks();
  jacobian_chunk_changed_.assign(chunks, 0);
  const SpringJacobianParts& parts = jacobian_parts_;
  const int chunk_size = particle_chunk_;
  workers.forEachChunk(particles, chunk_size, [&](int begin, int end) {
    for (int chunk = begin / chunk_size; chunk * chunk_size < end; ++chunk)
    {
      bool changed = false;
      for (int r = chunks_.runStart(chunk); r < chunks_.runStart(chunk + 1); ++r)
      {
        const PairChunks::Run run = chunks_.runs()[r];
        for (int s = run.first; s < run.first + run.count; ++s)
        {
          const Eigen::Vector3d d(parts.d_x[s], parts.d_y[s], parts.d_z[s]);
          const double along_v = -springs_[s].damping;
          if (run.ends == PairChunks::kBothEnds)
            changed |= solver.addAlongPairEnds<true, true>(first_pair + s, blocks_[s], d, parts.along_x[s],
                                                           parts.isotropic_x[s], along_v);
          else if (run.ends == PairChunks::kEndI)
            changed |= solver.addAlongPairEnds<true, false>(first_pair + s, blocks_[s], d, parts.along_x[s],
                                                            parts.isotropic_x[s], along_v);
          else
            solver.addAlongPairEnds<false, true>(first_pair + s, blocks_[s], d, parts.along_x[s], parts.isotropic_x[s],
                                                 along_v);
        }
      }
      jacobian_chunk_changed_[chunk] = changed;
    }
  });
  if (std::find(jacobian_chunk_changed_.begin(), jacobian_chunk_changed_.end(), 1) != jacobian_chunk_changed_.end())
    solver.notePairsChanged();
}

void SpringForces::addStabilityRows(const std::vector<Eigen::Vector3d>& /*rest*/, std::vector<double>& stiffness_rows,
                                    std::vector<double>& damping_rows) const
{
  // C = l − L has |∂C/∂x_i| = |∂C/∂x_j| = 1: each spring adds 2 k (and 2 k_d) at both ends.
  for (const Spring& s : springs_)
  {
    for (int end : {s.i, s.j})
    {
      stiffness_rows[end] += 2.0 * s.stiffness;
      damping_rows[end] += 2.0 * s.damping;
    }
  }
}

void SpringForces::addEnergy(const ForceContext& context, const Eigen::Matrix3Xd& x, double& energy) const
{
  // Summed in fixed chunks of springs (shared between threads), then chunk after chunk: the same
  // bits at any thread count.
  energy +=
      sumByChunks(context.workers, static_cast<int>(springs_.size()), kSpringsPerChunk, chunk_energy_, [&](int k) {
        const Spring& s = springs_[k];
        return springEnergy(x.col(s.i), x.col(s.j), s.rest_length, s.stiffness);
      });
}

void SpringForces::resetConstants()
{
  // The constants alone: a vertex split may have moved a spring's ends to a copy.
  for (std::size_t s = 0; s < springs_.size(); ++s)
  {
    springs_[s].stiffness = built_[origin_[s]].stiffness;
    springs_[s].damping = built_[origin_[s]].damping;
  }
}

void SpringForces::tear(const Eigen::Matrix3Xd& x, double tear_strain, TearRecord& torn)
{
  // One pass that keeps the springs within the tear strain in their order (the force sums keep
  // theirs) and drops the others, with their blocks.
  std::size_t kept = 0;
  for (std::size_t s = 0; s < springs_.size(); ++s)
  {
    const Spring& spring = springs_[s];
    const double length = (x.col(spring.j) - x.col(spring.i)).norm();
    if (spring.rest_length > 0.0 && length > (1.0 + tear_strain) * spring.rest_length)
    {
      torn.springs.emplace_back(spring.i, spring.j);
      continue;
    }
    springs_[kept] = spring;
    origin_[kept] = origin_[s];
    if (!blocks_.empty()) blocks_[kept] = blocks_[s];
    ++kept;
  }
  if (kept != springs_.size()) ends_valid_ = energy_kept_ = false;
  springs_.resize(kept);
  origin_.resize(kept);
  if (!blocks_.empty()) blocks_.resize(kept);
}

void SpringForces::mend()
{
  springs_ = built_;  // with the built constants too (resetConstants() would put them back anyway)
  ends_valid_ = energy_kept_ = false;
  blocks_ = built_blocks_;
  origin_.resize(built_.size());
  std::iota(origin_.begin(), origin_.end(), 0);
}

bool SpringForces::hasClass(SpringClass spring_class) const
{
  for (const Spring& spring : springs_)
  {
    if (spring.spring_class == spring_class) return true;
  }
  return false;
}

void SpringForces::setClassConstants(std::optional<SpringClass> spring_class, double stiffness, double damping)
{
  for (Spring& spring : springs_)
  {
    if (spring_class && spring.spring_class != *spring_class) continue;
    spring.stiffness = stiffness;
    spring.damping = damping;
  }
}

double SpringForces::maxStrain(const Eigen::Matrix3Xd& x) const
{
  double strain = 0.0;
  for (const Spring& s : springs_)
  {
    if (s.spring_class == SpringClass::Bend || s.rest_length == 0.0) continue;
    const double length = (x.col(s.j) - x.col(s.i)).norm();
    strain = std::max(strain, (length - s.rest_length) / s.rest_length);
  }
  return strain;
}

}  // namespace core
}  // namespace particle_sim
