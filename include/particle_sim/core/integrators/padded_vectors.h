#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <memory>
#include <new>

namespace particle_sim
{
namespace core
{
/// One 3-vector per particle, stored four doubles apart (the fourth is padding, zero unless a
/// writer says otherwise) from a 64-byte boundary: each particle's vector is one aligned 256-bit
/// load, and never straddles two cache lines. The layout of the conjugate gradient's iteration
/// vectors, which its AVX2 passes read and write a particle at a time (ImplicitEulerSolver, cg_avx2.h).
class PaddedVectors
{
public:
  static constexpr int kStride = 4;  // doubles per particle

  PaddedVectors() = default;
  PaddedVectors(const PaddedVectors& other) { *this = other; }
  PaddedVectors(PaddedVectors&&) noexcept = default;
  PaddedVectors& operator=(const PaddedVectors& other)
  {
    if (this == &other) return *this;
    setZero(other.count_);
    std::copy(other.data(), other.data() + static_cast<std::size_t>(kStride) * count_, data());
    return *this;
  }
  PaddedVectors& operator=(PaddedVectors&&) noexcept = default;

  /// `count` zero vectors (allocates).
  void setZero(int count)
  {
    data_.reset(new (std::align_val_t(kAlignment)) double[static_cast<std::size_t>(kStride) * count]());
    count_ = count;
  }
  int count() const { return count_; }
  double* data() { return data_.get(); }
  const double* data() const { return data_.get(); }
  Eigen::Map<Eigen::Vector3d> col(int i) { return Eigen::Map<Eigen::Vector3d>(data_.get() + kStride * i); }
  Eigen::Map<const Eigen::Vector3d> col(int i) const
  {
    return Eigen::Map<const Eigen::Vector3d>(data_.get() + kStride * i);
  }

private:
  static constexpr std::size_t kAlignment = 64;
  struct AlignedDelete
  {
    void operator()(double* p) const { ::operator delete[](p, std::align_val_t(kAlignment)); }
  };
  std::unique_ptr<double[], AlignedDelete> data_;
  int count_ = 0;
};

}  // namespace core
}  // namespace particle_sim
