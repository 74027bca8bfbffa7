#pragma once

#include <string>

namespace particle_sim
{
namespace process
{
/// Start-up settings of particle_sim's programs (the node, particle_sim_run, the bench and its
/// Bullet peer), for their main() only: the physics library never calls these, and a program that
/// links it chooses for itself (README, "Huge pages").
///
/// Transparent huge pages for the heap. A step reads the particle and spring arrays from end to end;
/// with 4 KiB pages each array spans hundreds of pages, and in a virtual machine every miss in the
/// TLB costs a two-level page walk. glibc (2.35 and later) backs its heap with 2 MiB pages when
/// GLIBC_TUNABLES holds glibc.malloc.hugetlb=1, but it reads the tunables only when a program
/// starts. So, when
///  - the kernel gives huge pages only to memory that asks for them
///    (/sys/kernel/mm/transparent_hugepage/enabled reads "[madvise]"),
///  - glibc is 2.35 or later,
///  - GLIBC_TUNABLES does not already set glibc.malloc.hugetlb, and
///  - PARTICLE_SIM_HUGE_PAGES is not "0", and
///  - the kernel started the program itself (not valgrind, not ld.so) and without raised privileges
///    (setuid, file capabilities: glibc would drop the tunable),
/// this starts the program again, the same executable (the target of /proc/self/exe) with the same
/// arguments and process id, with glibc.malloc.hugetlb=1 added to GLIBC_TUNABLES and a marker
/// (PARTICLE_SIM_HUGE_PAGES_RESTARTED, removed by the new start) that keeps it from starting a third
/// time. It returns when none of that applies, or when the new start failed (the program then runs
/// with 4 KiB pages). Call it first in main(), before any thread starts.
void restartWithHugePagesIfAdvised(char** argv);

/// One line for reports: whether this process's heap asks for huge pages, and why or why not.
std::string hugePagesReport();
}  // namespace process
}  // namespace particle_sim
