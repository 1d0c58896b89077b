// Studies: one base scene, methods (named sets of scene overrides), sweeps of keys over values
// (their cartesian product per method), and a reference run. `isochor study` runs every case in
// its own process (a failed case is recorded with its reason), measures each against the
// reference (relative L2 of positions over all frames, of the centroid's path, worst
// zone-volume error) and writes
// results.csv; tools/study_report.py turns that into results.h5, charts and report.md.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace isochor {

struct StudyCase {
  std::string method;                   // the method's name ("reference" for the reference)
  std::string label;                    // unique file stem
  std::vector<std::string> overrides;   // base, then the method's, then the sweep's
  std::vector<std::pair<std::string, double>> sweep;  // key, value
};

struct Study {
  std::string file;
  std::filesystem::path scene;          // the base scene
  std::filesystem::path output;         // directory of the study's results
  int jobs = 2;                         // processes at once
  std::string kind = "work_precision";  // or "stability" (a map over two sweep keys)
  std::vector<StudyCase> cases;         // the reference first
};

Study load_study(const std::string& path, const std::vector<std::string>& overrides = {});

// Runs every case with the isochor executable `exe` (skipping cases whose output is complete when
// `resume`), then writes results.csv. Returns the number of failed cases.
int run_study(const Study& study, const std::string& exe, bool resume, bool progress);

// Recomputes results.csv from the cases' outputs.
void write_study_results(const Study& study);

}  // namespace isochor
