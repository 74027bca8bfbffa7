#pragma once
// What a validation test (issue 17: cantilever, drape, catenary, wave speed, chain pendulum) reports
// for docs/validation.md. Each test computes its quantity at three resolutions, asserts the finest
// against the reference within a tolerance derived from the discretisation error (never tuned) and
// that the error shrinks with refinement, then calls writeValidationCase(). When the environment
// variable PARTICLE_SIM_VALIDATION_DIR names a folder (scripts/bench --validation sets it), the case
// is written there as CASE.csv (one row per resolution) and, when given, CASE.dat (plot data,
// whitespace-separated columns) and CASE.gp (a gnuplot script run in that folder that draws
// CASE.png); otherwise nothing is written.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace particle_sim_test
{
// One resolution of a validation case.
struct ValidationRun
{
  std::string resolution;  // as users read it: "16 x 16", "40 segments"
  double value = 0.0;      // the simulated quantity, in the case's unit
  double error = 0.0;      // relative error against the reference, signed: (value - reference) / reference
  double tolerance = 0.0;  // the relative error allowed at this resolution (from the discretisation), > 0
};

struct ValidationCase
{
  std::string id;        // file name stem: "cantilever", "wave_speed"
  std::string title;     // "Cantilever bending length (ASTM D1388)"
  std::string quantity;  // "bending rigidity"
  std::string unit;      // "N·m"
  double reference = 0.0;
  std::string source;               // where the reference comes from (a formula and its citation)
  std::vector<ValidationRun> runs;  // coarse to fine
  std::string plot_data;            // CASE.dat contents, or empty
  std::string plot_script;          // CASE.gp contents, or empty
};

inline std::string csvField(const std::string& text)
{
  std::string quoted = "\"";
  for (char c : text)
    quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// Writes `c` into $PARTICLE_SIM_VALIDATION_DIR when it is set; returns whether it wrote.
inline bool writeValidationCase(const ValidationCase& c)
{
  const char* dir = std::getenv("PARTICLE_SIM_VALIDATION_DIR");
  if (dir == nullptr || *dir == '\0') return false;
  const std::string stem = std::string(dir) + "/" + c.id;
  std::ofstream csv(stem + ".csv");
  csv.precision(10);
  csv << "id,title,quantity,unit,reference,source,resolution,value,error,tolerance\n";
  for (const ValidationRun& r : c.runs)
    csv << csvField(c.id) << ',' << csvField(c.title) << ',' << csvField(c.quantity) << ',' << csvField(c.unit) << ','
        << c.reference << ',' << csvField(c.source) << ',' << csvField(r.resolution) << ',' << r.value << ',' << r.error
        << ',' << r.tolerance << '\n';
  if (!c.plot_data.empty()) std::ofstream(stem + ".dat") << c.plot_data;
  if (!c.plot_script.empty()) std::ofstream(stem + ".gp") << c.plot_script;
  return static_cast<bool>(csv);
}

// Relative error estimates of a sequence of runs refined by `ratio` each time, for a method of formal
// order `order` (Richardson): run i's error is (v_i − v_{i+1}) / (1 − ratio^−order), and the finest
// run's is (v_{n−2} − v_{n−1}) / (ratio^order − 1).
inline std::vector<double> richardsonErrors(const std::vector<double>& values, double reference, double ratio,
                                            double order)
{
  const double r = std::pow(ratio, order);
  std::vector<double> estimates;
  for (std::size_t i = 0; i + 1 < values.size(); ++i)
    estimates.push_back(std::abs(values[i] - values[i + 1]) * r / (r - 1.0) / std::abs(reference));
  const std::size_t n = values.size();
  estimates.push_back(std::abs(values[n - 2] - values[n - 1]) / (r - 1.0) / std::abs(reference));
  return estimates;
}

// Asserts what every case asserts (the finest run within its tolerance, errors shrinking with
// refinement), then reports the case.
inline void checkAndReport(const ValidationCase& c)
{
  ASSERT_EQ(c.runs.size(), 3u);
  const ValidationRun& finest = c.runs.back();
  EXPECT_LE(std::abs(finest.error), finest.tolerance)
      << c.id << " at " << finest.resolution << ": " << finest.value << " " << c.unit << " against " << c.reference;
  for (std::size_t i = 0; i + 1 < c.runs.size(); ++i)
    EXPECT_LT(std::abs(c.runs[i + 1].error), std::abs(c.runs[i].error))
        << c.id << ": the error does not shrink from " << c.runs[i].resolution << " to " << c.runs[i + 1].resolution;
  particle_sim_test::writeValidationCase(c);
}

}  // namespace particle_sim_test
