// The isochor command line: the subcommands and their options (CLI11); the commands themselves
// are in commands.cpp and study_mpi.cpp.
#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <algorithm>
#include <filesystem>
#include <fstream>

#include "commands.hpp"
#include "mpi_ranks.hpp"
#include "isochor/base/error.hpp"
#include "isochor/core/input_file.hpp"
#include "isochor/core/output.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/app/study.hpp"

using namespace isochor;
using namespace isochor::cli;

namespace {

// Every option of every subcommand, and the subcommands, as CLI11 fills them.
struct Line {
  CLI::App* mesh = nullptr;
  CLI::App* run = nullptr;
  CLI::App* info = nullptr;
  CLI::App* infsup = nullptr;
  CLI::App* study = nullptr;
  CLI::App* report = nullptr;
  CLI::App* render = nullptr;
  CLI::App* exporter = nullptr;
  CLI::App* paraview = nullptr;
  CLI::App* obj = nullptr;
  CLI::App* view = nullptr;
  CLI::App* keys = nullptr;
  RunCommand run_cmd;
  StudyCommand study_cmd;
  std::string h5_path, dir, prefix = "frame";
  bool with_blender = false;
  bool study_keys = false;
  std::string group;
  std::vector<std::string> docs;
};

void add_keys(CLI::App& app, Line& l) {
  l.keys = app.add_subcommand(
      "keys",
      "The keys a scene (or study) file may hold: type, unit, default and meaning, as docs/scenes.md lists them");
  l.keys->add_option("group", l.group, "Only the keys of this table (mesh, material, zones, select, integrator, ...)");
  l.keys->add_flag("--study", l.study_keys, "The keys of a study file");
  l.keys->add_option("--docs", l.docs,
                     "Rewrite the key tables of these markdown files (after each `<!-- keys: ... -->`)");
}

// `isochor keys`: the table, or the docs rewritten from it (only where they differ).
int cmd_keys(const Line& l) {
  const KeyTable& table = l.study_keys ? study_keys() : scene_keys();
  if (l.docs.empty()) {
    std::vector<std::string> all, groups;
    for (const KeySpec& k : table.keys())
      if (std::string first(k.name.substr(0, k.name.find('.'))); std::find(all.begin(), all.end(), first) == all.end())
        all.push_back(first);
    for (const std::string& g : all)
      if (l.group.empty() || g == l.group) groups.push_back(g);
    if (groups.empty()) {
      std::string names;
      for (const std::string& g : all) names += (names.empty() ? "" : ", ") + g;
      throw Error("keys: no table named " + l.group + " (expected one of " + names + ")");
    }
    std::fputs(table.markdown(groups).c_str(), stdout);
    return 0;
  }
  for (const std::string& path : l.docs) {
    const std::string text = read_input_file(path, "a markdown file", input_limits::kScene);
    const std::string updated = table.update_docs(text);
    if (updated == text) continue;
    // Whole or not at all: a part file beside it, renamed over it once written.
    const std::string part = path + ".part";
    std::ofstream out(part);
    out << updated;
    out.close();
    std::error_code ec;
    if (out) std::filesystem::rename(part, path, ec);
    if (!out || ec) {
      std::filesystem::remove(part, ec);
      throw Error(path + ": cannot be written (the disk is full?); it is left as it was");
    }
    std::printf("%s: key tables rewritten from %s\n", path.c_str(), table.source().c_str());
  }
  return 0;
}

void add_mesh_and_run(CLI::App& app, Line& l) {
  RunCommand& r = l.run_cmd;
  l.mesh = app.add_subcommand(
      "mesh", "Write the rest configuration of a scene as frame 0 (inspect a mesh before simulating it)");
  l.mesh->add_option("scene", r.scene_path, "Scene file (TOML)")->required();
  l.mesh->add_option("--set", r.overrides, "Override a scene key, e.g. --set mesh.cells=8")->take_all();
  l.mesh->add_option("-o,--output", r.out_path, "Output .h5 (default: output.path with _mesh)");
  l.mesh->add_flag("--overwrite", r.overwrite, "Replace an existing output");

  l.run = app.add_subcommand("run", "Simulate a dynamic scene and write every frame (HDF5 + XDMF)");
  l.run->add_option("scene", r.scene_path, "Scene file (TOML)")->required();
  l.run->add_option("--set", r.overrides, "Override a scene key, e.g. --set integrator.rtol=1e-8")->take_all();
  l.run->add_option("-o,--output", r.out_path, "Output .h5 (default: output.path of the scene)");
  l.run->add_flag("-q,--quiet", r.quiet, "No progress line");
  l.run->add_flag("--overwrite", r.overwrite, "Replace an existing output (else an existing output is an error)");
  l.run->add_flag(
      "--resume", r.resume,
      "Continue a killed, interrupted or failed run from the last complete frame of its output (same scene and --set)");
  l.run->get_option("--overwrite")->excludes("--resume");

  l.infsup = app.add_subcommand(
      "infsup", "The inf-sup constant of a scene's zones (does the zone choice lock on this mesh?), one line");
  l.infsup->add_option("scene", r.scene_path, "Scene file (TOML)")->required();
  l.infsup->add_option("--set", r.overrides, "Override a scene key, e.g. --set zones.patches=3")->take_all();

  l.info = app.add_subcommand("info", "Summarise an output file: mesh, zones, frames, volume drift, solver statistics");
  l.info->add_option("file", l.h5_path, "Output file (.h5)")->required();
}

void add_study(CLI::App& app, Line& l) {
  StudyCommand& s = l.study_cmd;
  l.study = app.add_subcommand(
      "study", "Run a study: every method and sweep of a base scene against a reference; results, charts, report");
  l.study->add_option("study", s.study_path, "Study file (TOML)")->required();
  l.study->add_option("--set", s.overrides, "Override a study key, e.g. --set study.jobs=1")->take_all();
  l.study->add_flag("--resume", s.resume, "Keep cases that already finished");
  l.study->add_flag("--list", s.list,
                    "Print the study's case ids, one per line (the reference first), and run nothing");
  l.study->add_option("--case", s.case_id, "Run exactly this case (an id from --list) into the study's directory");
  l.study->add_flag(
      "--mpi", s.mpi,
      "Under mpirun: each rank runs its share of the cases (skipping those done), rank 0 writes the report");

  l.report = app.add_subcommand("report", "Write a study's charts, results.h5 and report.md from its results");
  l.report->add_option("dir", l.dir, "The study's output directory")->required();
}

// A subcommand that runs a Python tool on a run file, the options after the file passed on.
CLI::App* tool_subcommand(CLI::App& app, Line& l, const char* name, const char* what, const char* footer) {
  CLI::App* c = app.add_subcommand(name, what);
  c->add_option("file", l.h5_path, "Output file (.h5)")->required();
  c->footer(footer);
  c->prefix_command();
  return c;
}

void add_viewers(CLI::App& app, Line& l) {
  l.render = app.add_subcommand("render",
                                "Draw frames of a run to PNG (smooth-shaded surface, up from the scene, coloured by "
                                "deformation, displacement, pressure or zone; --mp4 with ffmpeg)");
  l.render->add_flag("--blender", l.with_blender,
                     "Render with Blender (Cycles on the CPU) through tools/blender/isochor_blender.py");
  l.render->add_option("file", l.h5_path, "Output file (.h5)")->required();
  l.render->footer(
      "Options after the file go to tools/render.py: --frames 0,10,-1|flattest | --every N, "
      "--color deformation|displacement|pressure|zone, --up z|y|-y|a,b,c, --elev, --azim, "
      "--out DIR|FILE.png, --size PIXELS, --loads, --mp4. With --blender, to "
      "tools/blender/isochor_blender.py: --render DIR (default RUN_blender), --frames, --every, "
      "--samples 8, --size 640x480, --mp4, --color zone|pressure|none, --save FILE.blend");
  l.render->prefix_command();

  l.exporter = tool_subcommand(
      app, l, "export",
      "Write a run's surface motion as a point cache (PC2 or MDD) for Blender, Maya, Houdini, or an "
      "animated glTF (.glb) or a USD stage (.usda)",
      "Options after the file go to tools/export.py: --format pc2|mdd|glb|usd, --out FILE, --all-nodes, --surface");
  l.paraview = tool_subcommand(
      app, l, "paraview", "Write a ParaView script that opens a run ready to play (pressure and zones, time, ground)",
      "Options after the file go to tools/paraview.py: --out SCRIPT.py, --up z|y|a,b,c. Then: "
      "paraview --script=SCRIPT.py, or xvfb-run -a pvpython SCRIPT.py --screenshot F.png [--frame K]");
  l.view = tool_subcommand(app, l, "view",
                           "Play a run in the browser: its surface, timeline, colours and charts (a page on 127.0.0.1)",
                           "Options after the file go to tools/view.py: --port N (default: a free one), --no-browser, "
                           "--export DIR [--every K] (a folder that opens from disk). docs/viewer.md");

  l.obj = app.add_subcommand("export-obj", "Write the surface of every frame as an OBJ sequence");
  l.obj->add_option("file", l.h5_path, "Output file (.h5)")->required();
  l.obj->add_option("--dir", l.dir, "Directory for the OBJ files (default: beside the file, <name>_obj)");
  l.obj->add_option("--prefix", l.prefix, "File name prefix");
}

// The parsed subcommand, run.
int dispatch(Line& l, int argc, char** argv) {
  const RunCommand& r = l.run_cmd;
  if (l.mesh->parsed()) return cmd_mesh(r.scene_path, r.overrides, r.out_path, r.overwrite);
  if (l.run->parsed()) return launched_by_mpi() ? cmd_run_on_ranks(r, argc, argv) : cmd_run(r, argc, argv);
  if (l.infsup->parsed()) return cmd_infsup(r.scene_path, r.overrides);
  if (l.study->parsed()) return cmd_study(l.study_cmd);
  if (l.report->parsed()) {
    // Cases run one by one (--case, a Slurm array, GNU parallel): results from what is done.
    if (std::filesystem::exists(std::filesystem::path(l.dir) / "cases.csv")) write_study_results(load_case_list(l.dir));
    return study_report(l.dir);
  }
  if (l.render->parsed() && l.with_blender) return run_blender(l.h5_path, l.render->remaining());
  if (l.render->parsed()) return run_tool("render.py", l.h5_path, l.render->remaining());
  if (l.exporter->parsed()) return run_tool("export.py", l.h5_path, l.exporter->remaining());
  if (l.paraview->parsed()) return run_tool("paraview.py", l.h5_path, l.paraview->remaining());
  if (l.view->parsed()) return run_view(l.h5_path, l.view->remaining());
  if (l.keys->parsed()) return cmd_keys(l);
  if (l.info->parsed()) {
    std::fputs(describe_run(l.h5_path).c_str(), stdout);
    return 0;
  }
  if (l.obj->parsed()) {
    if (l.dir.empty()) {
      std::filesystem::path p(l.h5_path);
      l.dir = (p.parent_path() / (p.stem().string() + "_obj")).string();
    }
    const int n = export_obj_sequence(l.h5_path, l.dir, l.prefix);
    std::printf("wrote %d OBJ files to %s\n", n, l.dir.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // A full file size limit makes writes fail with EFBIG instead of killing the process, so that
  // every command reports it (and removes what it could not finish).
  std::signal(SIGXFSZ, SIG_IGN);
  hdf5_no_cleanup_at_exit();
  CLI::App app{"isochor: volume-preserving simulation of soft, nearly incompressible solids"};
  app.require_subcommand(1);
  // Bad command lines, like bad input, stop with one line.
  app.failure_message(
      [](const CLI::App*, const CLI::Error& e) { return std::string("isochor: ") + e.what() + " (see --help)\n"; });
  app.set_version_flag("--version", std::string(isochor_version()) + " (" + isochor_git_revision() +
                                        ")\ntools: " + isochor::cli::tools_dir());
  Line line;
  add_mesh_and_run(app, line);
  add_study(app, line);
  add_viewers(app, line);
  add_keys(app, line);
  CLI11_PARSE(app, argc, argv);
  try {
    return dispatch(line, argc, argv);
  } catch (const Error& e) {
    std::fprintf(stderr, "isochor: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "isochor: internal error: %s\n", e.what());
    return 2;
  }
}
