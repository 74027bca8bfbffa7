#pragma once
// What the performance bench (particle_sim_perf) and its Bullet peer (particle_sim_bullet_peer)
// share, so that their rows are comparable line for line: the timing of a step function (warm-up
// steps, then `repeats` runs of `steps` steps, steady_clock; min, median and max ms per step) and
// the CSV row both write (case, variant, size, elements, times, CG iterations, detail), echoed on
// stderr. Header-only and free of particle_sim and Bullet, so that the peer builds without either.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <iostream>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace particle_sim_bench
{
struct Timing
{
  double min = 0.0, median = 0.0, max = 0.0;  // [ms] per step
};

// The min, median and max of the times per step of several repeats (at least one).
inline Timing summarize(std::vector<double> per_step)
{
  std::sort(per_step.begin(), per_step.end());
  return {per_step.front(), per_step[per_step.size() / 2], per_step.back()};
}

// The time per step [ms] of `steps` calls of `step`.
inline double timeRepeat(const std::function<void()>& step, int steps)
{
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  for (int i = 0; i < steps; ++i)
    step();
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count() / steps;
}

// Runs `warmup` steps, then `repeats` times `steps` steps; the time per step of each repeat.
// `before_repeat`, if given, runs before each repeat, outside its time.
inline Timing timeSteps(const std::function<void()>& step, int warmup, int steps, int repeats,
                        const std::function<void()>& before_repeat = {})
{
  for (int i = 0; i < warmup; ++i)
    step();
  std::vector<double> per_step;
  for (int r = 0; r < repeats; ++r)
  {
    if (before_repeat) before_repeat();
    per_step.push_back(timeRepeat(step, steps));
  }
  return summarize(per_step);
}

// Side by side: `rounds` rounds in which each of the step functions runs `steps` times, one after the
// other, the order shifted by one each round (round r starts with function r mod N), so that a spell
// of load on the machine falls on all of them alike. times[f][r]: function f's time per step [ms] in
// round r.
inline std::vector<std::vector<double>> timeInRounds(const std::vector<std::function<void()>>& step, int steps,
                                                     int rounds)
{
  const int functions = static_cast<int>(step.size());
  std::vector<std::vector<double>> times(functions);
  for (int round = 0; round < rounds; ++round)
  {
    for (int k = 0; k < functions; ++k)
    {
      const int f = (round + k) % functions;
      times[f].push_back(timeRepeat(step[f], steps));
    }
  }
  return times;
}

// One CSV row: case, variant, size (the sweep's parameter), elements (what the cost should grow
// with: particles, segments, springs), timing [ms per step], and free-form detail.
struct Row
{
  std::string case_name, variant;
  double size = 0.0;
  double elements = 0.0;
  Timing timing;
  double iterations = 0.0;  // mean CG iterations per timed step (implicit variants), else 0
  std::string detail;
};

inline const char* kCsvHeader = "case,variant,size,elements,ms_min,ms_median,ms_max,cg_iterations,detail\n";

inline void writeRow(std::ostream& out, const Row& r)
{
  out << r.case_name << ',' << r.variant << ',' << r.size << ',' << r.elements << ',' << r.timing.min << ','
      << r.timing.median << ',' << r.timing.max << ',' << r.iterations << ",\"" << r.detail << "\"\n";
  out.flush();
  std::fprintf(stderr, "%-8s %-34s size %-8g %.4g ms/step (min; median %.4g, max %.4g)%s%s\n", r.case_name.c_str(),
               r.variant.c_str(), r.size, r.timing.min, r.timing.median, r.timing.max, r.detail.empty() ? "" : "; ",
               r.detail.c_str());
}

// The row that says how the program's heap is paged (particle_sim::process::hugePagesReport()): each
// program's times depend on it, so the report prints it beside the machine.
inline void writePagesRow(std::ostream& out, const std::string& program, const std::string& report)
{
  Row row;
  row.case_name = "memory";
  row.variant = program;
  row.detail = report;
  writeRow(out, row);
}

// The command line both share: --out FILE, --quick, --only CASE,... and --help.
struct Options
{
  std::string out_path;           // the CSV to write
  bool quick = false;             // fewer sizes, steps and repeats: a smoke run
  std::vector<std::string> only;  // cases to run (empty: all)
  bool wanted(const char* name) const
  {
    return only.empty() || std::find(only.begin(), only.end(), name) != only.end();
  }
};

// Parses the command line into `options` (out_path keeps its default unless --out is given).
// Returns -1 to go on, or the exit code: 0 after --help, 2 (usage on stderr) after a bad argument.
inline int parseOptions(int argc, char** argv, const char* usage, Options& options)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h")
    {
      std::cout << usage;
      return 0;
    }
    if (arg == "--out" && i + 1 < argc)
      options.out_path = argv[++i];
    else if (arg == "--quick")
      options.quick = true;
    else if (arg == "--only" && i + 1 < argc)
    {
      std::stringstream list(argv[++i]);
      for (std::string name; std::getline(list, name, ',');)
        options.only.push_back(name);
    }
    else
    {
      std::cerr << usage;
      return 2;
    }
  }
  return -1;
}

}  // namespace particle_sim_bench
