// libFuzzer target: node settings and service requests (request_conversions, spring_constants). The work is in
// test/fuzz/fuzz_entries.cpp, shared with the regression replay of the unit tests.
#include <cstddef>
#include <cstdint>

#include "fuzz_entries.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  return particle_sim::fuzz::runRequests(data, size);
}
