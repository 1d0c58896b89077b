// Studies: one base scene, methods (named sets of scene overrides), sweeps of keys over values
// (their cartesian product per method), and a reference run. `isochor study` runs every case in
// its own process (a failed case is recorded with its reason), measures each against the
// reference (relative L2 of positions over all frames, of the centroid's path, worst
// zone-volume error) and writes
// results.csv; tools/study_report.py turns that into results.h5, charts and report.md.
#pragma once
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "isochor/core/key_table.hpp"

namespace isochor {

// The keys a study file may hold (apps/src/study_keys.cpp).
const KeyTable& study_keys();

struct StudyCase {
  std::string method;                                 // the method's name ("reference" for the reference)
  std::string label;                                  // unique file stem
  std::vector<std::string> overrides;                 // base, then the method's, then the sweep's
  std::vector<std::pair<std::string, double>> sweep;  // key, value
  std::filesystem::path scene;                        // the method's own base scene (method.scene); empty: the study's
};

struct Study {
  std::string file;
  std::filesystem::path scene;          // the base scene
  std::filesystem::path output;         // directory of the study's results
  int jobs = 2;                         // processes at once
  std::string kind = "work_precision";  // or "stability" (a map over two sweep keys), "convergence"
  std::string observable;               // [observable] as TOML text (observable.toml), "" if none
  std::vector<StudyCase> cases;         // the reference first
};

Study load_study(const std::string& path, const std::vector<std::string>& overrides = {});

// Runs every case with the isochor executable `exe` (skipping cases whose output is complete when
// `resume`), then writes results.csv. Returns the number of failed cases.
int run_study(const Study& study, const std::string& exe, bool resume, bool progress);

// Recomputes results.csv from the cases' outputs; a case not run yet is marked "missing".
void write_study_results(const Study& study);

// The case list kept in the study's directory (cases.csv: method, label, sweep), written by every
// way of running a study, so that `isochor report DIR` can merge whatever cases are done.
void save_case_list(const Study& study);
Study load_case_list(const std::filesystem::path& dir);

// Runs exactly the case `label` (`isochor study STUDY --case ID`); returns its exit status.
int run_study_case(const Study& study, const std::string& label, const std::string& exe, bool progress);

// Runs the cases that `next_case` hands out (indices into study.cases, -1: no more), one at a
// time, skipping cases already done (`isochor study STUDY --mpi`: a queue shared by the ranks).
// Returns the number of its cases that failed.
int run_study_queue(const Study& study, const std::string& exe, const std::function<int()>& next_case, bool progress);

}  // namespace isochor
