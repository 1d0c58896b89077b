// The commands of the isochor command line (apps/main.cpp parses the line and calls them).
#pragma once
#include <string>
#include <vector>

#include "isochor/app/study.hpp"
#include "isochor/integrators/ranks.hpp"

namespace isochor::cli {

// SIGINT and SIGTERM stop a run at the next step boundary; a second one kills at once.
void install_signal_handlers();

// `isochor mesh`: the scene's rest configuration as frame 0.
int cmd_mesh(const std::string& scene_path, const std::vector<std::string>& overrides, std::string out, bool overwrite);

// `isochor infsup`: the discrete inf-sup constant of the scene's zones against its free dofs
// (models/infsup.hpp), one line.
int cmd_infsup(const std::string& scene_path, const std::vector<std::string>& overrides);

// `isochor run`: the scene to its output, a summary line; an interrupted run says how to resume.
struct RunCommand {
  std::string scene_path, out_path;
  std::vector<std::string> overrides;
  bool quiet = false, overwrite = false, resume = false;
};
// ranks: the scene on P MPI ranks (mpi_ranks.hpp); rank 0 prints.
int cmd_run(const RunCommand& c, int argc, char** argv, const Ranks* ranks = nullptr);

// `isochor study`: every case (or one, the list, or over MPI ranks), then the report.
struct StudyCommand {
  std::string study_path, case_id;
  std::vector<std::string> overrides;
  bool resume = false, list = false, mpi = false;
};
int cmd_study(const StudyCommand& c);

// `mpirun -n N isochor study STUDY --mpi` (study_mpi.cpp).
int study_mpi(const Study& s, const std::string& exe, const std::string& study_path);

// The folder of the Python and Blender tools this program runs (tools/ of its source tree, or of
// the package it was installed with).
std::string tools_dir();

// A Python tool of tools/ on a run file, with the options after the file passed on as they are.
int run_tool(const std::string& script, const std::string& h5_path, const std::vector<std::string>& options);
// `isochor view`: tools/view.py with the page this program was built or installed with.
int run_view(const std::string& h5_path, std::vector<std::string> options);
// `isochor render --blender`.
int run_blender(const std::string& h5_path, const std::vector<std::string>& options);
// Charts, results.h5 and report.md of a study directory (tools/study_report.py).
int study_report(const std::string& dir);

}  // namespace isochor::cli
