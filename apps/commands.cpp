// The commands of the isochor command line: mesh, run, study, and the launchers of the Python
// tools (tools/) and Blender.
#include "commands.hpp"

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "isochor/app/install.hpp"
#include "isochor/app/run.hpp"
#include "isochor/app/shell.hpp"
#include "isochor/base/error.hpp"
#include "isochor/core/output.hpp"
#include "isochor/integrators/interrupt.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/scene/zones_setup.hpp"

namespace isochor::cli {

std::string tools_dir() {
  static const std::string dir = tools_directory(this_executable_directory(), ISOCHOR_TOOLS_DIR).string();
  return dir;
}

namespace {

std::vector<double> zone_volumes(const Mesh& mesh, const Points& x,
                                 const std::vector<std::pair<std::string, std::vector<int>>>& zones) {
  std::vector<double> v{tets_volume(x, mesh.tets())};
  for (const auto& [name, tets] : zones) {
    double z = 0.0;
    for (int e : tets) {
      const Tet& t = mesh.tets()[e];
      z += tet_signed_volume(x.col(t[0]), x.col(t[1]), x.col(t[2]), x.col(t[3]));
    }
    v.push_back(z);
  }
  return v;
}

// How to continue a run: the command as given, with --resume (and without --overwrite); on P
// ranks behind the launcher that started them (srun under Slurm, else mpirun) with P.
std::string resume_command(int argc, char** argv, const Ranks* ranks) {
  std::string cmd;
  if (ranks && ranks->size() > 1) {
    cmd = std::getenv("SLURM_PROCID") ? "srun -n " : "mpirun -n ";
    cmd += std::to_string(ranks->size());
    cmd += ' ';
  }
  cmd += "isochor";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--overwrite" || a == "--resume") continue;
    cmd += " " + shell_quoted(a);
  }
  return cmd + " --resume";
}

// SIGINT and SIGTERM ask the run to stop at the next step boundary (interrupt.hpp); a second one
// kills at once (the handler is reset by the first). A full file size limit makes writes fail
// with EFBIG instead of killing the process, so that the output reports it.
void on_signal(int sig) { request_stop(sig); }

}  // namespace

void install_signal_handlers() {
  struct sigaction a {};
  a.sa_handler = on_signal;
  sigemptyset(&a.sa_mask);
  a.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &a, nullptr);
  sigaction(SIGTERM, &a, nullptr);
  std::signal(SIGXFSZ, SIG_IGN);
}

int cmd_mesh(const std::string& scene_path, const std::vector<std::string>& overrides, std::string out,
             bool overwrite) {
  Scene sc = load_scene(scene_path, overrides);
  for (const std::string& note : sc.notes) std::fprintf(stderr, "%s: %s\n", scene_path.c_str(), note.c_str());
  if (out.empty()) {
    std::filesystem::path p(sc.output.path);
    out = (p.parent_path() / (p.stem().string() + "_mesh.h5")).string();
  }
  const RunInfo info = run_info(sc, "mesh");
  OutputWriter w(out, sc.mesh, sc.zones, info, false,
                 overwrite ? OutputWriter::Mode::overwrite : OutputWriter::Mode::create);
  Frame f;
  f.positions = &sc.mesh.rest_positions();
  f.volumes = zone_volumes(sc.mesh, sc.mesh.rest_positions(), sc.zones);
  try {
    w.write_frame(f);
    w.set_status("finished");
    w.close();
  } catch (const Error& e) {  // a full disk or a size limit: no partial mesh file is left
    if (w.frames_written() > 0) throw;
    w.discard();
    throw Error(std::string(e.what()) + "; " + out + " was removed");
  }
  const Mesh& m = sc.mesh;
  std::printf("%s: %d nodes, %d tets, %zu surface triangles, volume %.9g", scene_path.c_str(), m.num_nodes(),
              m.num_tets(), m.surface().size(), m.rest_volume());
  if (m.reoriented_tets()) std::printf(", %d tets reoriented", m.reoriented_tets());
  std::printf("\n");
  // The first zones, then a count (a mesh's per-node 1-ring zones are thousands of lines).
  constexpr std::size_t kListedZones = 24;
  for (std::size_t j = 0; j < sc.zones.size() && j < kListedZones; ++j)
    std::printf("  zone %-16s %zu tets\n", sc.zones[j].first.c_str(), sc.zones[j].second.size());
  if (sc.zones.size() > kListedZones) std::printf("  and %zu zones more\n", sc.zones.size() - kListedZones);
  for (const auto& [name, nodes] : m.node_sets) std::printf("  node set %-12s %zu nodes\n", name.c_str(), nodes.size());
  if (sc.skeleton)
    for (const BoneSpec& b : sc.skeleton->bones())
      std::printf("  bone %-16s %zu nodes bound\n", b.name.c_str(), b.nodes.size());
  std::printf("wrote %s and %s\n", out.c_str(), w.xdmf_path().c_str());
  return 0;
}

int cmd_infsup(const std::string& scene_path, const std::vector<std::string>& overrides) {
  const Scene sc = load_scene(scene_path, overrides);
  const InfSup r = zones_infsup(sc);
  std::printf("%s: %d tets, %d zones, %d free dofs: inf-sup beta_h = %.6g (next %.6g), %d zero modes\n",
              scene_path.c_str(), sc.mesh.num_tets(), r.zones, r.dofs, r.beta, r.beta_next, r.zero_modes);
  return 0;
}

int cmd_run(const RunCommand& c, int argc, char** argv, const Ranks* ranks) {
  Scene sc = load_scene(c.scene_path, c.overrides);
  const bool speaks = !ranks || ranks->rank() == 0;
  if (!c.quiet && speaks)
    for (const std::string& note : sc.notes) std::fprintf(stderr, "%s: %s\n", c.scene_path.c_str(), note.c_str());
  install_signal_handlers();
  RunOptions opt;
  opt.output = c.out_path;
  opt.progress = !c.quiet && speaks;
  opt.ranks = ranks;
  opt.mode = c.resume      ? OutputWriter::Mode::resume
             : c.overwrite ? OutputWriter::Mode::overwrite
                           : OutputWriter::Mode::create;
  RunSummary r;
  try {
    r = run_scene(sc, opt);
  } catch (const RunInterrupted& e) {
    if (speaks)
      std::fprintf(stderr, "isochor: %s; continue with: %s\n", e.what(), resume_command(argc, argv, ranks).c_str());
    return 128 + e.signal;
  }
  if (!speaks) return 0;
  if (r.already_finished) {
    std::printf("%s: finished earlier (%d frames, t = %g s): nothing to resume\n", r.output.c_str(), r.frames,
                r.resumed_time);
    return 0;
  }
  if (r.resumed_from >= 0)
    std::printf("%s: resumed from frame %d (t = %g s)\n", r.output.c_str(), r.resumed_from, r.resumed_time);
  const RunStats& s = r.stats;
  std::printf(
      "%s: %d frames, %ld steps, %ld Newton iterations, %ld Jacobians, %.2f s wall "
      "(assembly %.2f, factorisation %.2f, solve %.2f",
      c.scene_path.c_str(), r.frames, s.steps, s.newton_iterations, s.jacobian_evals, s.wall_seconds,
      s.assembly_seconds, s.factor_seconds, s.solve_seconds);
  if (sc.skeleton) std::printf(", Simbody %.2f", r.simbody_seconds);
  std::printf(")");
  if (ranks) std::printf(" on %d MPI ranks", ranks->size());
  if (s.line_search_cuts || s.regularisations || s.step_halvings)
    std::printf("; line search cut %ld updates, %ld matrices shifted, %ld steps halved", s.line_search_cuts,
                s.regularisations, s.step_halvings);
  std::printf("\nwrote %s\n", r.output.c_str());
  return 0;
}

int cmd_study(const StudyCommand& c) {
  const Study s = load_study(c.study_path, c.overrides);
  const std::string exe = std::filesystem::read_symlink("/proc/self/exe").string();
  if (static_cast<int>(c.list) + static_cast<int>(!c.case_id.empty()) + static_cast<int>(c.mpi) +
          static_cast<int>(c.resume) >
      1)
    throw Error("study: --list, --case, --mpi and --resume exclude each other");
  if (c.list) {
    for (const StudyCase& sc : s.cases) std::printf("%s\n", sc.label.c_str());
    return 0;
  }
  if (!c.case_id.empty()) {
    const int rc = run_study_case(s, c.case_id, exe, true);
    const std::string how = rc == 0 ? "done" : "FAILED (its log: cases/" + c.case_id + ".log)";
    std::printf("%s: case %s %s; `isochor report %s` merges the cases done\n", c.study_path.c_str(), c.case_id.c_str(),
                how.c_str(), s.output.c_str());
    return rc;
  }
  if (c.mpi) return study_mpi(s, exe, c.study_path);
  std::fprintf(stderr, "%s: %zu cases (the reference first), %d at a time, into %s\n", c.study_path.c_str(),
               s.cases.size(), s.jobs, s.output.c_str());
  const int failed = run_study(s, exe, c.resume, true);
  const int rc = study_report(s.output.string());
  std::printf("%s: %zu cases, %d failed (reasons in results.csv); wrote %s/report.md\n", c.study_path.c_str(),
              s.cases.size(), failed, s.output.c_str());
  return rc;
}

// A Python tool of tools/ on a run file, with the options after the file passed on as they are.
int run_tool(const std::string& script, const std::string& h5_path, const std::vector<std::string>& options) {
  if (!std::filesystem::exists(h5_path)) throw Error(h5_path + ": no such file");
  std::string cmd = "/usr/bin/python3 " + shell_quoted(tools_dir() + "/" + script) + " " + shell_quoted(h5_path);
  for (const std::string& a : options) cmd += " " + shell_quoted(a);
  return std::system(cmd.c_str()) == 0 ? 0 : 1;
}

int run_view(const std::string& h5_path, std::vector<std::string> options) {
  options.push_back("--static");
  options.push_back(viewer_directory(this_executable_directory(), ISOCHOR_VIEWER_DIR).string());
  return run_tool("view.py", h5_path, options);
}

// `isochor render --blender`: Blender in the background on tools/blender/isochor_blender.py,
// frames into RUN_blender/ unless --render says otherwise; Blender's own chatter is left out.
int run_blender(const std::string& h5_path, const std::vector<std::string>& options) {
  if (!std::filesystem::exists(h5_path)) throw Error(h5_path + ": no such file");
  if (std::system("command -v blender > /dev/null 2>&1") != 0)
    throw Error(
        "Blender is not installed (Debian 12: apt-get install blender, 3.4; it is optional); "
        "`isochor render` without --blender draws with matplotlib");
  std::filesystem::path p(h5_path);
  std::string cmd = "set -o pipefail; blender -b --python-exit-code 1 --python " +
                    shell_quoted(tools_dir() + "/blender/isochor_blender.py") + " -- " + shell_quoted(h5_path) +
                    " --render " + shell_quoted((p.parent_path() / (p.stem().string() + "_blender")).string());
  for (const std::string& a : options) cmd += " " + shell_quoted(a);
  cmd += " 2>&1 | grep -E --line-buffered '^(isochor_blender|Error|Traceback|  File|[A-Za-z]*Error)'";
  return std::system(("bash -c " + shell_quoted(cmd)).c_str()) == 0 ? 0 : 1;
}

// Charts, results.h5 and report.md of a study directory (tools/study_report.py).
int study_report(const std::string& dir) {
  if (!std::filesystem::exists(std::filesystem::path(dir) / "results.csv"))
    throw Error(dir + ": no results.csv (expected the output directory of `isochor study`)");
  const std::string cmd =
      "/usr/bin/python3 " + shell_quoted(tools_dir() + "/study_report.py") + " " + shell_quoted(dir);
  const int rc = std::system(cmd.c_str());
  if (rc != 0) throw Error(dir + ": the report tool failed (" + cmd + ")");
  return 0;
}

}  // namespace isochor::cli
