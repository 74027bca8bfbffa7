#pragma once

namespace particle_sim
{
namespace core
{
/// Clears the upper halves of the vector registers (VZEROUPPER). Plain code calls it right after
/// each vector pass (AVX2 or AVX-512: spring.cpp, cg_avx2.cpp, dense_panel.cpp) that it calls, and
/// only where the pass ran (the instruction needs AVX). Plain SSE code that runs while the upper
/// halves are set runs slowly until the next clearing: on the AMD EPYC host of 2026-12-07 the
/// multigrid's Galerkin products took three times as long. The compiler's own clearing at a pass's
/// return is not enough. GCC inserts it only with -fexpensive-optimizations (from -O2 up: the
/// sanitizer build at -O1 had none); GCC 12 left it out on one path even at -O2 (partsOfFour's
/// scalar tail); and a clearing written inside a pass may have the pass's last 256-bit instructions
/// placed after it (GCC 12 at -O1 put curvature's final sum there). Here, after the call, nothing of
/// the pass can follow: a function compiled for AVX2 is never inlined into one compiled without it.
/// Every vector register is declared clobbered, so that no build keeps a value in one across it.
/// Test VectorState checks every pass.
inline void clearUpperHalves()
{
#if defined(__x86_64__)
  asm volatile("vzeroupper" ::
                   : "xmm0", "xmm1", "xmm2", "xmm3", "xmm4", "xmm5", "xmm6", "xmm7", "xmm8", "xmm9", "xmm10", "xmm11",
                     "xmm12", "xmm13", "xmm14", "xmm15");
#endif
}
}  // namespace core
}  // namespace particle_sim
