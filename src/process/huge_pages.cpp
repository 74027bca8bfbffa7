#include "particle_sim/process/huge_pages.h"

#include <gnu/libc-version.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

namespace particle_sim
{
namespace process
{
namespace
{
constexpr const char* kTunable = "glibc.malloc.hugetlb";
constexpr const char* kKernelSetting = "/sys/kernel/mm/transparent_hugepage/enabled";

/// The kernel's transparent-huge-page mode: the bracketed word of kKernelSetting ("always",
/// "madvise" or "never"), or "absent" when the kernel has no such file.
std::string kernelMode()
{
  std::ifstream file(kKernelSetting);
  std::string line;
  if (!std::getline(file, line)) return "absent";
  const std::size_t open = line.find('[');
  const std::size_t close = line.find(']', open);
  if (open == std::string::npos || close == std::string::npos) return "absent";
  return line.substr(open + 1, close - open - 1);
}

/// glibc reads glibc.malloc.hugetlb from 2.35 on; older ones ignore it.
bool glibcKnowsTheTunable()
{
  int major = 0, minor = 0;
  if (std::sscanf(gnu_get_libc_version(), "%d.%d", &major, &minor) != 2) return false;
  return major > 2 || (major == 2 && minor >= 35);
}

std::string environment(const char* name)
{
  const char* value = std::getenv(name);
  return value != nullptr ? value : "";
}

/// The value GLIBC_TUNABLES gives glibc.malloc.hugetlb ("" when it gives none).
std::string tunableValue()
{
  const std::string tunables = environment("GLIBC_TUNABLES");
  const std::string key = std::string(kTunable) + "=";
  const std::size_t at = tunables.find(key);
  if (at == std::string::npos) return "";
  const std::size_t start = at + key.size();
  return tunables.substr(start, tunables.find(':', start) - start);
}

bool optedOut()
{
  return environment("PARTICLE_SIM_HUGE_PAGES") == "0";
}
}  // namespace

void restartWithHugePagesIfAdvised(char** argv)
{
  const std::string tunables = environment("GLIBC_TUNABLES");
  if (optedOut() || tunables.find(kTunable) != std::string::npos || !glibcKnowsTheTunable() ||
      kernelMode() != "madvise")
    return;
  const std::string with_huge_pages = tunables + (tunables.empty() ? "" : ":") + kTunable + "=1";
  if (setenv("GLIBC_TUNABLES", with_huge_pages.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
  // Only a failed execv returns: run on with 4 KiB pages, and say so through the environment as it was.
  if (tunables.empty())
    unsetenv("GLIBC_TUNABLES");
  else
    setenv("GLIBC_TUNABLES", tunables.c_str(), 1);
}

std::string hugePagesReport()
{
  const std::string mode = kernelMode();
  const std::string value = tunableValue();
  std::string report;
  if (value == "1")
    report = "huge pages for the heap (glibc.malloc.hugetlb=1)";
  else if (!value.empty())
    report = "glibc.malloc.hugetlb=" + value;
  else if (optedOut())
    report = "4 KiB pages (PARTICLE_SIM_HUGE_PAGES=0)";
  else if (!glibcKnowsTheTunable())
    report = std::string("4 KiB pages (glibc ") + gnu_get_libc_version() + " has no glibc.malloc.hugetlb)";
  else if (mode == "always")
    report = "huge pages wherever the kernel finds them (it gives them to all memory)";
  else
    report = "4 KiB pages";
  return report + "; kernel transparent huge pages: " + mode;
}
}  // namespace process
}  // namespace particle_sim
