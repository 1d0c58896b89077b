// The isochor command line.
#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <atomic>
#include <chrono>
#include <functional>
#include <thread>

#include "isochor/base/error.hpp"
#include "isochor/integrators/interrupt.hpp"
#include "isochor/core/output.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/app/run.hpp"
#include "isochor/app/shell.hpp"
#include "isochor/app/study.hpp"
#ifdef ISOCHOR_MPI
#define OMPI_SKIP_MPICXX 1  // the C interface only
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

using namespace isochor;

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

// SIGINT and SIGTERM ask the run to stop at the next step boundary (interrupt.hpp); a second one
// kills at once (the handler is reset by the first). A full file size limit makes writes fail
// with EFBIG instead of killing the process, so that the output reports it.
void on_signal(int sig) { request_stop(sig); }
void install_signal_handlers() {
  struct sigaction a {};
  a.sa_handler = on_signal;
  sigemptyset(&a.sa_mask);
  a.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &a, nullptr);
  sigaction(SIGTERM, &a, nullptr);
  std::signal(SIGXFSZ, SIG_IGN);
}

// How to continue a run: the command as given, with --resume (and without --overwrite).
std::string resume_command(int argc, char** argv) {
  std::string cmd = "isochor";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--overwrite" || a == "--resume") continue;
    cmd += " " + shell_quoted(a);
  }
  return cmd + " --resume";
}

int cmd_mesh(const std::string& scene_path, const std::vector<std::string>& overrides, std::string out, bool overwrite) {
  Scene sc = load_scene(scene_path, overrides);
  if (out.empty()) {
    std::filesystem::path p(sc.output.path);
    out = (p.parent_path() / (p.stem().string() + "_mesh.h5")).string();
  }
  RunInfo info{sc.file.text_as_run(), scene_path, "mesh", scene_record(sc)};
  OutputWriter w(out, sc.mesh, sc.zones, info, false, overwrite ? OutputWriter::Mode::overwrite : OutputWriter::Mode::create);
  Frame f;
  f.positions = &sc.mesh.rest_positions();
  f.volumes = zone_volumes(sc.mesh, sc.mesh.rest_positions(), sc.zones);
  w.write_frame(f);
  w.set_status("finished");
  w.close();
  const Mesh& m = sc.mesh;
  std::printf("%s: %d nodes, %d tets, %zu surface triangles, volume %.9g", scene_path.c_str(), m.num_nodes(),
              m.num_tets(), m.surface().size(), m.rest_volume());
  if (m.reoriented_tets()) std::printf(", %d tets reoriented", m.reoriented_tets());
  std::printf("\n");
  for (const auto& [name, tets] : sc.zones) std::printf("  zone %-16s %zu tets\n", name.c_str(), tets.size());
  for (const auto& [name, nodes] : m.node_sets) std::printf("  node set %-12s %zu nodes\n", name.c_str(), nodes.size());
  if (sc.skeleton)
    for (const BoneSpec& b : sc.skeleton->bones())
      std::printf("  bone %-16s %zu nodes bound\n", b.name.c_str(), b.nodes.size());
  std::printf("wrote %s and %s\n", out.c_str(), w.xdmf_path().c_str());
  return 0;
}

int study_report(const std::string& dir);

// `mpirun -n N isochor study STUDY --mpi`: the cases form one queue, handed out in order (the
// reference first) by rank 0 to whichever rank asks next, as the local executor's threads take
// them; each case runs in its own process. Rank 0 then writes the results and the report. Waits
// poll with a sleep, so that a rank waiting for work or for the others takes no core from those
// running cases (OpenMPI's blocking calls spin).
int study_mpi(const Study& s, const std::string& exe, const std::string& study_path) {
#ifdef ISOCHOR_MPI
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  auto wait = [](MPI_Request& r, MPI_Status* st) {
    for (int done = 0;;) {
      MPI_Test(&r, &done, st);
      if (done) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  };
  if (provided < MPI_THREAD_SERIALIZED && ranks > 1) {
    if (rank == 0) std::fprintf(stderr, "isochor: study --mpi: the MPI library offers no MPI_THREAD_SERIALIZED\n");
    MPI_Finalize();
    return 1;
  }
  if (rank == 0)
    std::fprintf(stderr, "%s: %zu cases over %d MPI ranks, into %s\n", study_path.c_str(), s.cases.size(), ranks,
                 s.output.c_str());
  constexpr int kAsk = 1, kGive = 2;
  const int n = static_cast<int>(s.cases.size());
  std::atomic<int> counter{0};
  std::thread server;
  std::function<int()> next;
  if (rank == 0) {
    // The queue: rank 0's own cases from its main thread, the other ranks' through this thread
    // (the only one of rank 0 that calls MPI until it ends).
    server = std::thread([&] {
      for (int finished = 0; finished < ranks - 1;) {
        int ask = 0;
        MPI_Request r;
        MPI_Status st;
        MPI_Irecv(&ask, 1, MPI_INT, MPI_ANY_SOURCE, kAsk, MPI_COMM_WORLD, &r);
        wait(r, &st);
        int i = counter++;
        if (i >= n) {
          i = -1;
          ++finished;
        }
        MPI_Send(&i, 1, MPI_INT, st.MPI_SOURCE, kGive, MPI_COMM_WORLD);
      }
    });
    next = [&] {
      const int i = counter++;
      return i < n ? i : -1;
    };
  } else {
    next = [&] {
      int ask = 0, i = -1;
      MPI_Send(&ask, 1, MPI_INT, 0, kAsk, MPI_COMM_WORLD);
      MPI_Request r;
      MPI_Irecv(&i, 1, MPI_INT, 0, kGive, MPI_COMM_WORLD, &r);
      wait(r, MPI_STATUS_IGNORE);
      return i;
    };
  }
  int failed = 0;
  try {
    failed = run_study_queue(s, exe, next, true);
  } catch (const Error& e) {
    std::fprintf(stderr, "isochor (rank %d): %s\n", rank, e.what());
    failed = -1;
    if (rank != 0)
      while (next() >= 0) {  // take the rest of the queue without running it, so rank 0 can end
      }
  }
  if (rank == 0) server.join();
  {
    MPI_Request r;
    MPI_Ibarrier(MPI_COMM_WORLD, &r);
    wait(r, MPI_STATUS_IGNORE);
  }
  int all = 0, error = failed < 0 ? 1 : 0, errors = 0;
  MPI_Reduce(&failed, &all, 1, MPI_INT, MPI_SUM, 0, MPI_COMM_WORLD);
  MPI_Allreduce(&error, &errors, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  int rc = errors > 0 ? 1 : 0;
  if (rank == 0 && errors == 0) {
    write_study_results(s);
    rc = study_report(s.output.string());
    std::printf("%s: %zu cases on %d ranks, %d failed (reasons in results.csv); wrote %s/report.md\n",
                study_path.c_str(), s.cases.size(), ranks, all, s.output.c_str());
  }
  MPI_Finalize();
  return rc;
#else
  (void)s, (void)exe;
  throw Error(study_path + ": --mpi needs isochor built with MPI (Debian: apt-get install libopenmpi-dev openmpi-bin, then rebuild)");
#endif
}

// A Python tool of tools/ on a run file, with the options after the file passed on as they are.
int run_tool(const std::string& script, const std::string& h5_path, const std::vector<std::string>& options) {
  if (!std::filesystem::exists(h5_path)) throw Error(h5_path + ": no such file");
  std::string cmd = "/usr/bin/python3 " + shell_quoted(std::string(ISOCHOR_TOOLS_DIR "/") + script) + " " + shell_quoted(h5_path);
  for (const std::string& a : options) cmd += " " + shell_quoted(a);
  return std::system(cmd.c_str()) == 0 ? 0 : 1;
}

// `isochor render --blender`: Blender in the background on tools/blender/isochor_blender.py,
// frames into RUN_blender/ unless --render says otherwise; Blender's own chatter is left out.
int run_blender(const std::string& h5_path, const std::vector<std::string>& options) {
  if (!std::filesystem::exists(h5_path)) throw Error(h5_path + ": no such file");
  if (std::system("command -v blender > /dev/null 2>&1") != 0)
    throw Error("Blender is not installed (Debian 12: apt-get install blender, 3.4; it is optional); "
                "`isochor render` without --blender draws with matplotlib");
  std::filesystem::path p(h5_path);
  std::string cmd = "set -o pipefail; blender -b --python-exit-code 1 --python " +
                    shell_quoted(ISOCHOR_TOOLS_DIR "/blender/isochor_blender.py") + " -- " + shell_quoted(h5_path) +
                    " --render " + shell_quoted((p.parent_path() / (p.stem().string() + "_blender")).string());
  for (const std::string& a : options) cmd += " " + shell_quoted(a);
  cmd += " 2>&1 | grep -E --line-buffered '^(isochor_blender|Error|Traceback|  File|[A-Za-z]*Error)'";
  return std::system(("bash -c " + shell_quoted(cmd)).c_str()) == 0 ? 0 : 1;
}

// Charts, results.h5 and report.md of a study directory (tools/study_report.py).
int study_report(const std::string& dir) {
  if (!std::filesystem::exists(std::filesystem::path(dir) / "results.csv"))
    throw Error(dir + ": no results.csv (expected the output directory of `isochor study`)");
  const std::string cmd = "/usr/bin/python3 " + shell_quoted(ISOCHOR_TOOLS_DIR "/study_report.py") + " " + shell_quoted(dir);
  const int rc = std::system(cmd.c_str());
  if (rc != 0) throw Error(dir + ": the report tool failed (" + cmd + ")");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"isochor: volume-preserving simulation of soft, nearly incompressible solids"};
  app.require_subcommand(1);
  // Bad command lines, like bad input, stop with one line.
  app.failure_message([](const CLI::App*, const CLI::Error& e) { return std::string("isochor: ") + e.what() + " (see --help)\n"; });
  app.set_version_flag("--version", std::string(isochor_version()) + " (" + isochor_git_revision() + ")");

  std::string scene_path, out_path, h5_path, dir, prefix = "frame";
  std::vector<std::string> overrides;

  auto* mesh = app.add_subcommand("mesh", "Write the rest configuration of a scene as frame 0 (inspect a mesh before simulating it)");
  mesh->add_option("scene", scene_path, "Scene file (TOML)")->required();
  mesh->add_option("--set", overrides, "Override a scene key, e.g. --set mesh.cells=8")->take_all();
  mesh->add_option("-o,--output", out_path, "Output .h5 (default: output.path with _mesh)");
  bool overwrite = false, resume_run = false;
  mesh->add_flag("--overwrite", overwrite, "Replace an existing output");

  bool quiet = false;
  auto* run = app.add_subcommand("run", "Simulate a dynamic scene and write every frame (HDF5 + XDMF)");
  run->add_option("scene", scene_path, "Scene file (TOML)")->required();
  run->add_option("--set", overrides, "Override a scene key, e.g. --set integrator.rtol=1e-8")->take_all();
  run->add_option("-o,--output", out_path, "Output .h5 (default: output.path of the scene)");
  run->add_flag("-q,--quiet", quiet, "No progress line");
  run->add_flag("--overwrite", overwrite, "Replace an existing output (else an existing output is an error)");
  run->add_flag("--resume", resume_run,
                "Continue a killed, interrupted or failed run from the last complete frame of its output (same scene and --set)");
  run->get_option("--overwrite")->excludes("--resume");

  auto* info = app.add_subcommand("info", "Summarise an output file: mesh, zones, frames, volume drift, solver statistics");
  info->add_option("file", h5_path, "Output file (.h5)")->required();

  bool resume = false;
  auto* study = app.add_subcommand("study", "Run a study: every method and sweep of a base scene against a reference; results, charts, report");
  study->add_option("study", scene_path, "Study file (TOML)")->required();
  study->add_option("--set", overrides, "Override a study key, e.g. --set study.jobs=1")->take_all();
  study->add_flag("--resume", resume, "Keep cases that already finished");
  bool list_cases = false, use_mpi = false;
  std::string case_id;
  study->add_flag("--list", list_cases, "Print the study's case ids, one per line (the reference first), and run nothing");
  study->add_option("--case", case_id, "Run exactly this case (an id from --list) into the study's directory");
  study->add_flag("--mpi", use_mpi, "Under mpirun: each rank runs its share of the cases (skipping those done), rank 0 writes the report");

  auto* report = app.add_subcommand("report", "Write a study's charts, results.h5 and report.md from its results");
  report->add_option("dir", dir, "The study's output directory")->required();

  auto* render = app.add_subcommand("render", "Draw frames of a run to PNG (smooth-shaded surface, up from the scene, coloured by deformation, displacement, pressure or zone; --mp4 with ffmpeg)");
  bool with_blender = false;
  render->add_flag("--blender", with_blender, "Render with Blender (Cycles on the CPU) through tools/blender/isochor_blender.py");
  render->add_option("file", h5_path, "Output file (.h5)")->required();
  render->footer("Options after the file go to tools/render.py: --frames 0,10,-1|flattest | --every N, "
                 "--color deformation|displacement|pressure|zone, --up z|y|-y|a,b,c, --elev, --azim, "
                 "--out DIR|FILE.png, --size PIXELS, --loads, --mp4. With --blender, to "
                 "tools/blender/isochor_blender.py: --render DIR (default RUN_blender), --frames, --every, "
                 "--samples 8, --size 640x480, --mp4, --color zone|pressure|none, --save FILE.blend");
  render->prefix_command();

  auto* exporter = app.add_subcommand("export", "Write a run's surface motion as a point cache (PC2 or MDD) for Blender, Maya, Houdini");
  exporter->add_option("file", h5_path, "Output file (.h5)")->required();
  exporter->footer("Options after the file go to tools/export.py: --format pc2|mdd, --out FILE, --all-nodes");
  exporter->prefix_command();

  auto* paraview = app.add_subcommand("paraview", "Write a ParaView script that opens a run ready to play (pressure and zones, time, ground)");
  paraview->add_option("file", h5_path, "Output file (.h5)")->required();
  paraview->footer("Options after the file go to tools/paraview.py: --out SCRIPT.py, --up z|y|a,b,c. Then: "
                   "paraview --script=SCRIPT.py, or xvfb-run -a pvpython SCRIPT.py --screenshot F.png [--frame K]");
  paraview->prefix_command();

  auto* obj = app.add_subcommand("export-obj", "Write the surface of every frame as an OBJ sequence");
  obj->add_option("file", h5_path, "Output file (.h5)")->required();
  obj->add_option("--dir", dir, "Directory for the OBJ files (default: beside the file, <name>_obj)");
  obj->add_option("--prefix", prefix, "File name prefix");

  CLI11_PARSE(app, argc, argv);
  try {
    if (mesh->parsed()) return cmd_mesh(scene_path, overrides, out_path, overwrite);
    if (run->parsed()) {
      Scene sc = load_scene(scene_path, overrides);
      install_signal_handlers();
      RunOptions opt;
      opt.output = out_path;
      opt.progress = !quiet;
      opt.mode = resume_run  ? OutputWriter::Mode::resume
                 : overwrite ? OutputWriter::Mode::overwrite
                             : OutputWriter::Mode::create;
      RunSummary r;
      try {
        r = run_scene(sc, opt);
      } catch (const RunInterrupted& e) {
        std::fprintf(stderr, "isochor: %s; continue with: %s\n", e.what(), resume_command(argc, argv).c_str());
        return 128 + e.signal;
      }
      if (r.already_finished) {
        std::printf("%s: finished earlier (%d frames, t = %g s): nothing to resume\n", r.output.c_str(), r.frames, r.resumed_time);
        return 0;
      }
      if (r.resumed_from >= 0)
        std::printf("%s: resumed from frame %d (t = %g s)\n", r.output.c_str(), r.resumed_from, r.resumed_time);
      const RunStats& s = r.stats;
      std::printf("%s: %d frames, %ld steps, %ld Newton iterations, %ld Jacobians, %.2f s wall "
                  "(assembly %.2f, factorisation %.2f, solve %.2f",
                  scene_path.c_str(), r.frames, s.steps, s.newton_iterations, s.jacobian_evals, s.wall_seconds,
                  s.assembly_seconds, s.factor_seconds, s.solve_seconds);
      if (sc.skeleton) std::printf(", Simbody %.2f", r.simbody_seconds);
      std::printf(")");
      if (s.line_search_cuts || s.regularisations || s.step_halvings)
        std::printf("; line search cut %ld updates, %ld matrices shifted, %ld steps halved", s.line_search_cuts,
                    s.regularisations, s.step_halvings);
      std::printf("\nwrote %s\n", r.output.c_str());
      return 0;
    }
    if (study->parsed()) {
      const Study s = load_study(scene_path, overrides);
      const std::string exe = std::filesystem::read_symlink("/proc/self/exe").string();
      if (static_cast<int>(list_cases) + static_cast<int>(!case_id.empty()) + static_cast<int>(use_mpi) + static_cast<int>(resume) > 1)
        throw Error("study: --list, --case, --mpi and --resume exclude each other");
      if (list_cases) {
        for (const StudyCase& c : s.cases) std::printf("%s\n", c.label.c_str());
        return 0;
      }
      if (!case_id.empty()) {
        const int rc = run_study_case(s, case_id, exe, true);
        const std::string how = rc == 0 ? "done" : "FAILED (its log: cases/" + case_id + ".log)";
        std::printf("%s: case %s %s; `isochor report %s` merges the cases done\n", scene_path.c_str(), case_id.c_str(),
                    how.c_str(), s.output.c_str());
        return rc;
      }
      if (use_mpi) return study_mpi(s, exe, scene_path);
      std::fprintf(stderr, "%s: %zu cases (the reference first), %d at a time, into %s\n", scene_path.c_str(),
                   s.cases.size(), s.jobs, s.output.c_str());
      const int failed = run_study(s, exe, resume, true);
      const int rc = study_report(s.output.string());
      std::printf("%s: %zu cases, %d failed (reasons in results.csv); wrote %s/report.md\n", scene_path.c_str(),
                  s.cases.size(), failed, s.output.c_str());
      return rc;
    }
    if (report->parsed()) {
      // Cases run one by one (--case, a Slurm array, GNU parallel): results from what is done.
      if (std::filesystem::exists(std::filesystem::path(dir) / "cases.csv")) write_study_results(load_case_list(dir));
      return study_report(dir);
    }
    if (render->parsed() && with_blender) return run_blender(h5_path, render->remaining());
    if (render->parsed()) return run_tool("render.py", h5_path, render->remaining());
    if (exporter->parsed()) return run_tool("export.py", h5_path, exporter->remaining());
    if (paraview->parsed()) return run_tool("paraview.py", h5_path, paraview->remaining());
    if (info->parsed()) {
      std::fputs(describe_run(h5_path).c_str(), stdout);
      return 0;
    }
    if (obj->parsed()) {
      if (dir.empty()) {
        std::filesystem::path p(h5_path);
        dir = (p.parent_path() / (p.stem().string() + "_obj")).string();
      }
      int n = export_obj_sequence(h5_path, dir, prefix);
      std::printf("wrote %d OBJ files to %s\n", n, dir.c_str());
      return 0;
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "isochor: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "isochor: internal error: %s\n", e.what());
    return 2;
  }
  return 0;
}
