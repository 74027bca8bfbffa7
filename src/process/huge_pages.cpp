#include "particle_sim/process/huge_pages.h"

#include <gnu/libc-version.h>
#include <limits.h>
#include <sys/auxv.h>
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
/// Set for the new start only, so that it never starts again whatever glibc does with the tunable
/// (a secure-execution start drops it, for one).
constexpr const char* kRestartedMarker = "PARTICLE_SIM_HUGE_PAGES_RESTARTED";
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

/// The executable this process runs, when the kernel started it directly: the target of
/// /proc/self/exe, if that is the file the process was started as. "" otherwise, e.g. under
/// valgrind (/proc/self/exe is valgrind's tool) or through the dynamic loader (it is ld.so), where
/// starting /proc/self/exe again would not start the program.
std::string ownExecutable()
{
  char path[PATH_MAX];
  const ssize_t length = readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (length <= 0) return "";
  path[length] = '\0';
  const char* started_as = reinterpret_cast<const char*>(getauxval(AT_EXECFN));
  char started_path[PATH_MAX];
  if (started_as == nullptr || realpath(started_as, started_path) == nullptr) return "";
  return std::strcmp(path, started_path) == 0 ? std::string(path) : std::string();
}
}  // namespace

void restartWithHugePagesIfAdvised(char** argv)
{
  if (!environment(kRestartedMarker).empty())
  {
    unsetenv(kRestartedMarker);
    return;
  }
  const std::string tunables = environment("GLIBC_TUNABLES");
  if (optedOut() || tunables.find(kTunable) != std::string::npos || !glibcKnowsTheTunable() ||
      kernelMode() != "madvise" || getauxval(AT_SECURE) != 0)
    return;
  const std::string executable = ownExecutable();
  if (executable.empty()) return;
  const std::string with_huge_pages = tunables + (tunables.empty() ? "" : ":") + kTunable + "=1";
  // The executable's own path, not /proc/self/exe: the kernel names the process after the path.
  if (setenv("GLIBC_TUNABLES", with_huge_pages.c_str(), 1) == 0 && setenv(kRestartedMarker, "1", 1) == 0)
    execv(executable.c_str(), argv);
  // Only a failed setenv or execv gets here: run on with 4 KiB pages, the environment as it was.
  unsetenv(kRestartedMarker);
  if (tunables.empty())
    unsetenv("GLIBC_TUNABLES");
  else
    setenv("GLIBC_TUNABLES", tunables.c_str(), 1);
}

std::string hugePagesReport()
{
  // The kernel's mode first: it decides whether the tunable matters at all.
  const std::string mode = kernelMode();
  const std::string value = tunableValue();
  std::string report;
  if (mode != "always" && mode != "madvise")
    report = "4 KiB pages (the kernel gives no huge pages)";
  else if (mode == "always")
    report = "huge pages wherever the kernel finds them (it gives them to all memory)";
  else if (!glibcKnowsTheTunable())
    report = std::string("4 KiB pages (glibc ") + gnu_get_libc_version() + " has no glibc.malloc.hugetlb)";
  else if (value == "1")
    report = "huge pages for the heap (glibc.malloc.hugetlb=1)";
  else if (!value.empty())
    report = "glibc.malloc.hugetlb=" + value;
  else if (optedOut())
    report = "4 KiB pages (PARTICLE_SIM_HUGE_PAGES=0)";
  else
    report = "4 KiB pages";
  return report + "; kernel transparent huge pages: " + mode;
}
}  // namespace process
}  // namespace particle_sim
