// libFuzzer target: OBJ text (parseObj, then a mesh cloth stepped). The work is in
// test/fuzz/fuzz_entries.cpp, shared with the regression replay of the unit tests.
#include <cstddef>
#include <cstdint>

#include "fuzz_entries.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  return particle_sim::fuzz::runObjMesh(data, size);
}
