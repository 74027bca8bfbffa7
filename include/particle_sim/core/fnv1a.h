#pragma once

#include <cstddef>
#include <cstdint>

namespace particle_sim
{
namespace core
{
/// FNV-1a, 64 bits (Fowler, Noll, Vo; IETF draft-eastlake-fnv): its offset basis and prime.
constexpr std::uint64_t kFnv1a64OffsetBasis = 14695981039346656037ULL;
constexpr std::uint64_t kFnv1a64Prime = 1099511628211ULL;

/// The FNV-1a 64 hash of `size` bytes at `data`, continuing from `hash` (start with the offset
/// basis): each byte is XORed in, then the hash is multiplied by the prime (modulo 2^64).
/// Published test vectors: "" → 0xcbf29ce484222325, "a" → 0xaf63dc4c8601ec8c.
inline std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t hash = kFnv1a64OffsetBasis)
{
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i)
    hash = (hash ^ bytes[i]) * kFnv1a64Prime;
  return hash;
}

}  // namespace core
}  // namespace particle_sim
