// Writes the seed corpus of the requests fuzz target: one file per fuzz::requestSeeds() entry,
// encoded with the default node settings. Usage: particle_sim_fuzz_request_seeds OUTPUT_FOLDER
#include <cstdio>
#include <fstream>
#include <string>

#include "fuzz_entries.h"

int main(int argc, char** argv)
{
  if (argc != 2)
  {
    std::fprintf(stderr, "usage: %s OUTPUT_FOLDER\n", argv[0]);
    return 2;
  }
  for (const particle_sim::fuzz::RequestSeed& seed : particle_sim::fuzz::requestSeeds())
  {
    const std::vector<std::uint8_t> bytes = particle_sim::fuzz::encodeRequests({}, seed.requests);
    const std::string path = std::string(argv[1]) + "/" + seed.name + ".bin";
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out)
    {
      std::fprintf(stderr, "cannot write %s\n", path.c_str());
      return 1;
    }
  }
  return 0;
}
