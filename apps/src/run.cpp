#include "isochor/app/run.hpp"

#include <dlfcn.h>
#include <omp.h>

#include <chrono>
#include <sstream>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>

#include "isochor/scene/integrator_registry.hpp"
#include "isochor/integrators/interrupt.hpp"
#include "isochor/base/error.hpp"
#include "isochor/core/memory.hpp"
#include "isochor/core/output.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/core/progress.hpp"
#include "isochor/scene/scene_system.hpp"

namespace isochor {

namespace {
// OpenBLAS's threads now; 0 where the BLAS is not OpenBLAS.
int blas_threads() {
  using GetThreads = int (*)();
  auto get = reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  return get ? get() : 0;
}

void write_totals(OutputWriter& w, const RunStats& s) {
  w.set_stat("steps", static_cast<double>(s.steps));
  w.set_stat("residual_evaluations", static_cast<double>(s.residual_evals));
  w.set_stat("jacobian_evaluations", static_cast<double>(s.jacobian_evals));
  w.set_stat("linear_setups", static_cast<double>(s.linear_setups));
  w.set_stat("newton_iterations", static_cast<double>(s.newton_iterations));
  w.set_stat("rejected_steps_newton", static_cast<double>(s.newton_failures));
  w.set_stat("rejected_steps_error_test", static_cast<double>(s.error_test_failures));
  w.set_stat("fresh_factorisations", static_cast<double>(s.fresh_factorisations));
  w.set_stat("reused_jacobians", static_cast<double>(s.reused_jacobians));
  w.set_stat("linear_fallbacks", static_cast<double>(s.linear_fallbacks));
  w.set_stat("retargets", static_cast<double>(s.retargets));
  w.set_stat("wall_seconds", s.wall_seconds);
  w.set_stat("assembly_seconds", s.assembly_seconds);
  w.set_stat("factorisation_seconds", s.factor_seconds);
  w.set_stat("solve_seconds", s.solve_seconds);
  w.set_stat("factor_nnz", s.factor_nnz);
  w.set_stat("symbolic_seconds", s.symbolic_seconds);
  w.set_stat("projection_seconds", s.projection_seconds);
  w.set_stat("linear_iterations", static_cast<double>(s.linear_iterations));
  w.set_stat("line_search_cuts", static_cast<double>(s.line_search_cuts));
  w.set_stat("regularisations", static_cast<double>(s.regularisations));
  w.set_stat("step_halvings", static_cast<double>(s.step_halvings));
  w.set_stat("solver_switches", static_cast<double>(s.solver_switches));
  // The threads the run had: OpenMP's (assembly, CG) and OpenBLAS's (inside CHOLMOD; 0 where
  // the BLAS is not OpenBLAS), for comparing timings.
  w.set_stat("threads", static_cast<double>(omp_get_max_threads()));
  w.set_stat("blas_threads", static_cast<double>(blas_threads()));
  // Peak resident memory of the whole process (getrusage), for the linear-solver benchmarks.
  w.set_stat("peak_memory_mb", peak_memory_mb());
}

// Each frame of the integrator, measured by the scene system and written with its statistics.
// The per-frame series that count from the start of the run: a resumed run adds the values they
// had at the frame it continues from.
const char* const kCumulative[] = {
    "steps",       "newton_iterations", "jacobian_evaluations", "rejected_steps_error_test", "rejected_steps_newton",
    "wall_seconds"};

// Each frame of the integrator, measured by the scene system and written with its statistics. A
// resumed run's integrator starts at the file's last frame (first = its index), which is not
// written again.
// On P ranks only rank 0 has a writer (w null elsewhere); every rank measures the frame (its sums
// are collective), and all of them stop if rank 0 could not write it.
FrameCallback frame_writer(const Scene& sc, SceneSystem& sys, OutputWriter* w, const Ranks* ranks, Progress& bar,
                           RunSummary& summary, bool progress, int first, const std::map<std::string, double>& offsets,
                           const std::function<bool(int, const Frame&)>& on_frame) {
  const auto start = std::chrono::steady_clock::now();
  const bool tets = sys.has_tets();
  // The callback outlives this call: the values of this call by value (a bool parameter taken by
  // reference was read after the call had returned: AddressSanitizer), the caller's objects by reference.
  return [&, start, tets, first, progress, pressure = std::vector<double>(), loads = Points(), contact = Points(),
          poses = std::vector<double>(), scales = std::vector<double>(), activations = std::vector<double>(),
          bones = std::vector<double>(), velocities = Points(),
          multipliers = std::vector<double>()](int j, double t, const VectorXd& q, const VectorXd& v,
                                               const VectorXd& lambda, const RunStats::FrameSample& s) mutable {
    if (first >= 0 && j == 0) return;
    const int k = std::max(first, 0) + j;
    sys.set_state(t, q, v);
    Frame f;
    f.time = t;
    f.positions = &sys.positions();
    velocities = Eigen::Map<const Points>(sys.velocities().data(), 3, sys.positions().cols());
    f.velocities = &velocities;
    multipliers.assign(lambda.data(), lambda.data() + lambda.size());
    f.multipliers = &multipliers;
    f.volumes = sys.volumes();
    f.energy = sys.energies();
    // The frame callback gets the pressures whether or not they are written (the writer takes
    // them only when output.pressure is on).
    if (tets && (sc.output.pressure || on_frame)) {
      sys.pressures(lambda, pressure);
      f.pressure = &pressure;
    }
    if (sys.has_loads()) {
      sys.loads(loads);
      f.loads = &loads;
    }
    if (sys.has_contact()) {
      sys.contact(contact);
      f.contact = &contact;
      sys.collider_poses(poses);
      f.collider_poses = &poses;
      sys.collider_scales(scales);
      f.collider_scales = &scales;
    }
    if (sc.skeleton) {
      bone_poses(sc, t, bones);
      f.bone_poses = &bones;
    }
    if (!sc.muscles.empty()) {
      activations = sys.activations();
      f.activations = &activations;
    }
    if (tets) f.stats.push_back({"inverted_tets", static_cast<double>(sys.inverted_tets())});
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    f.stats.insert(f.stats.end(),
                   {{"steps", static_cast<double>(s.steps)},
                    {"newton_iterations", static_cast<double>(s.newton_iterations)},
                    {"jacobian_evaluations", static_cast<double>(s.jacobian_evals)},
                    {"rejected_steps_error_test", static_cast<double>(s.error_test_failures)},
                    {"rejected_steps_newton", static_cast<double>(s.newton_failures)},
                    {"order", static_cast<double>(s.order)},
                    {sc.integrator.kind == IntegratorKind::statics ? "residual_norm" : "step_size", s.step_size},
                    {"wall_seconds", wall},
                    {"resident_mb", resident_memory_mb()}});
    for (auto& [name, value] : f.stats)
      if (auto it = offsets.find(name); it != offsets.end()) value += it->second;
    std::exception_ptr failed;
    try {
      if (w) w->write_frame(f);
    } catch (...) {
      failed = std::current_exception();
    }
    if (ranks && ranks->max(failed ? 1 : 0) != 0 && !failed) throw Error("rank 0 could not write its frame");
    if (failed) std::rethrow_exception(failed);
    summary.frames = k + 1;
    if (progress) bar.update(k, t);
    if (on_frame && !on_frame(k, f)) throw Interrupted(t, 0);
  };
}

// A resumed run's totals: the cumulative counts from the file at the frame it continues from.
void add_offsets(RunStats& s, const std::map<std::string, double>& off) {
  auto at = [&](const char* name) {
    auto it = off.find(name);
    return it == off.end() ? 0.0 : it->second;
  };
  s.steps += static_cast<long>(at("steps"));
  s.newton_iterations += static_cast<long>(at("newton_iterations"));
  s.jacobian_evals += static_cast<long>(at("jacobian_evaluations"));
  s.error_test_failures += static_cast<long>(at("rejected_steps_error_test"));
  s.newton_failures += static_cast<long>(at("rejected_steps_newton"));
  s.wall_seconds += at("wall_seconds");
}

// The frame times from the one a resumed run continues at (index `first`, time `t`).
std::vector<double> times_from(const std::vector<double>& times, int first, double t, const std::string& path) {
  if (first < 0) return times;
  if (first >= static_cast<int>(times.size()) ||
      std::abs(times[static_cast<std::size_t>(first)] - t) > 1e-9 * (1 + std::abs(t)))
    throw Error(path + ": its frame " + std::to_string(first) + " at t = " + std::to_string(t) +
                " s is not a frame of the scene (cannot be resumed)");
  return {times.begin() + first, times.end()};
}

}  // namespace

namespace {
// While it lives, OpenBLAS (inside CHOLMOD) runs on one thread unless OPENBLAS_NUM_THREADS says
// otherwise: its threads wait for work by spinning, against OpenMP's in the assembly and in CG.
// On 2 idle cores the stiff cube on CHOLMOD took 6.7 s with them and 4.3 s without; the 13^3
// pinned cube on PCG 1.7 s either way (README, "Threads"). The count before is restored after:
// a Python process may share OpenBLAS with numpy. Looked up at run time, so a build against
// another BLAS is untouched.
class BlasOnOneThread {
 public:
  BlasOnOneThread() {
    if (std::getenv("OPENBLAS_NUM_THREADS")) return;
    set_ = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    before_ = blas_threads();
    if (set_ && before_ > 0) set_(1);
  }
  ~BlasOnOneThread() {
    if (set_ && before_ > 0) set_(before_);
  }
  BlasOnOneThread(const BlasOnOneThread&) = delete;
  BlasOnOneThread& operator=(const BlasOnOneThread&) = delete;

 private:
  using SetThreads = void (*)(int);
  SetThreads set_ = nullptr;
  int before_ = 0;
};
// Limits before work: the whole run's frames must fit where they are written (positions and
// velocities, 48 bytes per node, and per-tet pressures; the scalars and links of a frame and its
// XDMF entry about 2 KB). A resumed run has written some already and is not refused.
void check_output_room(const Scene& sc, const SceneSystem& sys, const std::string& output) {
  const double frames = static_cast<double>(sc.frames.num_frames());
  const double per_frame = 48.0 * sc.mesh.num_nodes() + (sys.has_loads() ? 24.0 * sc.mesh.num_nodes() : 0.0) +
                           (sys.has_contact() ? 24.0 * sc.mesh.num_nodes() : 0.0) +
                           (sc.output.pressure ? 8.0 * sc.mesh.num_tets() : 0.0) + 2048;
  const double need = frames * per_frame, room = output_room_bytes(output);
  if (need <= room) return;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "%s: the run would write about %.3g GB (%.0f frames of %.3g KB), more than the %.3g GB free there "
                "(expected fewer frames, frames.rate or frames.duration, or another output.path)",
                output.c_str(), need / 1e9, frames, per_frame / 1024, room / 1e9);
  throw Error(buf);
}

// A resumed run: the summary says where it continues, the system starts from the file's last
// complete frame, and the cumulative statistics go on from their values there. False when the
// run had finished (nothing to do).
bool resume_from(const ResumePoint& rp, SceneSystem& sys, RunSummary& summary, StartState& start,
                 std::map<std::string, double>& offsets) {
  summary.frames = rp.frame + 1;
  summary.resumed_from = rp.frame;
  summary.resumed_time = rp.time;
  if (rp.status == "finished") {
    summary.already_finished = true;
    return false;
  }
  start =
      StartState{rp.positions, rp.velocities,
                 Eigen::Map<const VectorXd>(rp.multipliers.data(), static_cast<Eigen::Index>(rp.multipliers.size()))};
  sys.set_start(&start);
  for (const char* name : kCumulative)
    if (auto it = rp.stats.find(name); it != rp.stats.end() && std::isfinite(it->second)) offsets[name] = it->second;
  return true;
}

// RunOptions::activation in place of the scene's curves, each value checked.
void drive_muscles(const Scene& sc, SceneSystem& sys, const std::function<std::vector<double>(double)>& activation) {
  if (sc.muscles.empty()) throw Error(sc.file.name() + ": an activation function, but the scene has no [[muscle]]");
  sys.set_activation_function([&activation, n = sc.muscles.size()](double t) {
    std::vector<double> a = activation(t);
    std::ostringstream why;
    if (a.size() != n)
      why << a.size() << " values at t = " << t << " s (expected one per muscle, " << n << ")";
    else if (auto bad = std::find_if(a.begin(), a.end(), [](double v) { return !(v >= 0 && v <= 1); }); bad != a.end())
      why << *bad << " at t = " << t << " s (expected activations in [0, 1])";
    if (!why.str().empty()) throw Error("the activation function gave " + why.str());
    return a;
  });
}

// A [character]'s mesh is Gmsh's fill of its wrap, which varies with OpenMP's thread count (5,141
// against 5,151 tets at 1 and 2 threads): a run is resumed on the mesh its file holds, the scene
// parsed again around it. Nothing where the file is not a readable run of this scene text: the
// writer then says why it cannot be resumed.
std::optional<Scene> scene_on_run_mesh(const Scene& sc, const std::string& output) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(output, ec)) return std::nullopt;
  const std::string text = sc.file.text_as_run();
  std::optional<Mesh> stored;
  try {
    const RunFile f(output);
    const auto attributes = f.attributes();
    const auto scene = attributes.find("scene");
    if (scene == attributes.end() || scene->second != text) return std::nullopt;
    stored.emplace(f.rest_positions(), f.tets(), output);
  } catch (const Error&) {
    return std::nullopt;
  }
  return parse_scene(SceneFile::parse(text, sc.file.name(), {}, sc.file.directory()), &*stored);
}

// The totals of a finished run, and its status (resumed_at: NaN unless resumed).
void write_finished(OutputWriter& w, const Scene& sc, const RunSummary& summary, const Ranks* ranks,
                    double resumed_at) {
  write_totals(w, summary.stats);
  // The ranks, and the seconds rank 0 spent exchanging with the others (docs/scale.md).
  const Ranks::Seconds mpi = ranks ? ranks->seconds() : Ranks::Seconds{};
  w.set_stat("ranks", ranks ? ranks->size() : 1);
  w.set_stat("mpi_seconds", mpi.share + mpi.exchange + mpi.reduce);
  w.set_stat("mpi_share_seconds", mpi.share);
  w.set_stat("mpi_halo_seconds", mpi.exchange);
  if (sc.skeleton) {
    w.set_stat("simbody_seconds", summary.simbody_seconds);
    w.set_stat("simbody_realizations", static_cast<double>(sc.skeleton->realizations()));
  }
  if (!std::isnan(resumed_at)) w.set_stat("resumed_at", resumed_at);
  w.set_status("finished");
  w.close();
}

// Rank 0's resume point to every rank.
void share_resume_point(const Ranks& ranks, ResumePoint& rp) {
  std::vector<double> v;
  std::string names = rp.status;
  if (ranks.rank() == 0) {
    v = {static_cast<double>(rp.frame), rp.time, static_cast<double>(rp.positions.cols()),
         static_cast<double>(rp.multipliers.size())};
    v.insert(v.end(), rp.positions.data(), rp.positions.data() + rp.positions.size());
    v.insert(v.end(), rp.velocities.data(), rp.velocities.data() + rp.velocities.size());
    v.insert(v.end(), rp.multipliers.begin(), rp.multipliers.end());
    for (const auto& [name, value] : rp.stats) {
      names += "\n" + name;
      v.push_back(value);
    }
  }
  ranks.broadcast(v);
  ranks.broadcast(names);
  if (ranks.rank() == 0) return;
  const auto N = static_cast<Eigen::Index>(v[2]), m = static_cast<Eigen::Index>(v[3]);
  rp.frame = static_cast<int>(v[0]);
  rp.time = v[1];
  const double* p = v.data() + 4;
  rp.positions = Eigen::Map<const Points>(p, 3, N);
  rp.velocities = Eigen::Map<const Points>(p + 3 * N, 3, N);
  rp.multipliers.assign(p + 6 * N, p + 6 * N + m);
  const double* value = p + 6 * N + m;
  std::istringstream in(names);
  std::getline(in, rp.status);
  for (std::string name; std::getline(in, name);) rp.stats[name] = *value++;
}

// On P ranks: rank 0 opens the output (and reads where a resumed run continues); the others learn
// whether it could, and that point. Null on the ranks that do not write.
std::unique_ptr<OutputWriter> open_output(const Scene& sc, const SceneSystem& sys, const RunOptions& opt,
                                          const std::string& output, ResumePoint& rp) {
  const bool resume = opt.mode == OutputWriter::Mode::resume;
  const Ranks* ranks = opt.ranks;
  std::unique_ptr<OutputWriter> w;
  std::exception_ptr failed;
  if (!ranks || ranks->rank() == 0) try {
      if (!resume) check_output_room(sc, sys, output);
      // (The mass-spring model has no zones: its scene is refused with any.)
      w = std::make_unique<OutputWriter>(output, sc.mesh, sc.zones, run_info(sc, "run"),
                                         sc.output.pressure && sys.has_tets(), opt.mode);
      rp = w->resume_point();
    } catch (...) {
      failed = std::current_exception();
    }
  if (!ranks) {
    if (failed) std::rethrow_exception(failed);
    return w;
  }
  if (ranks->max(failed ? 1 : 0) != 0) {
    if (failed) std::rethrow_exception(failed);
    throw Error(output + ": rank 0 could not open it");
  }
  if (resume) share_resume_point(*ranks, rp);
  return w;
}

RunSummary run_parsed_scene(const Scene& sc, const RunOptions& opt) {
  const BlasOnOneThread blas_on_one_thread;
  RunSummary summary;
  summary.output = opt.output.empty() ? sc.output.path : opt.output;
  const bool resume = opt.mode == OutputWriter::Mode::resume;
  const Ranks* ranks = opt.ranks && opt.ranks->size() > 1 ? opt.ranks : nullptr;
  if (ranks) check_ranks(sc);
  // The systems are built before the file is touched, so that a scene they refuse leaves no
  // output behind; a resumed run's start is handed to them once the file has said where it is.
  const std::unique_ptr<SceneSystem> sys = make_scene_system(sc, ranks);
  if (opt.activation) drive_muscles(sc, *sys, opt.activation);
  const std::unique_ptr<Integrator> integrator = make_integrator(sc, *sys);
  ResumePoint rp;
  RunOptions on_ranks = opt;
  on_ranks.ranks = ranks;
  const std::unique_ptr<OutputWriter> writer = open_output(sc, *sys, on_ranks, summary.output, rp);
  OutputWriter* const w = writer.get();
  std::map<std::string, double> offsets;
  StartState start;
  if (resume && !resume_from(rp, *sys, summary, start, offsets)) return summary;
  const std::vector<double> all_times = sc.frames.times();
  const std::vector<double> times = times_from(all_times, resume ? rp.frame : -1, rp.time, summary.output);
  if (resume && w) w->continue_run();
  Progress bar(sc.file.name(), static_cast<int>(all_times.size()) - 1, times.front(), times.back(),
               opt.progress ? stderr : nullptr, last_step_time);
  // A new output that failed before its first frame is removed (nothing in it to keep or
  // resume); otherwise the file says why it stopped. Returns what the message says of the frames.
  const auto saved = [&] {
    return std::to_string(summary.frames) + (summary.frames == 1 ? " frame" : " frames") + " saved in " +
           summary.output;
  };
  auto finish_failed = [&](const std::string& status, const std::vector<std::pair<std::string, double>>& numbers,
                           const std::string& failure) -> std::string {
    if (!w) return saved();
    if (!resume && w->frames_written() == 0 && status == "failed") {
      w->discard();
      return "no frame was written, so " + summary.output + " was removed";
    }
    // Best effort: the file may be what failed (a full disk).
    try {
      for (const auto& [name, value] : numbers) w->set_stat(name, value);
      if (!failure.empty()) w->set_stat("failure", failure);
      w->set_status(status);
      w->close();
    } catch (...) {
    }
    return saved();
  };
  try {
    summary.stats = integrator->run(times, frame_writer(sc, *sys, w, ranks, bar, summary, opt.progress,
                                                        resume ? rp.frame : -1, offsets, opt.on_frame));
  } catch (const Interrupted& e) {
    add_offsets(summary.stats, offsets);
    finish_failed("interrupted", {{"interrupted_at", e.time}, {"signal", static_cast<double>(e.signal)}}, "");
    bar.finish();
    const std::string how = e.signal == 0         ? "stopped by the frame callback"
                            : e.signal == SIGINT  ? "interrupted by SIGINT"
                            : e.signal == SIGTERM ? "interrupted by SIGTERM"
                                                  : "interrupted by signal " + std::to_string(e.signal);
    throw RunInterrupted(sc.file.name() + ": " + how + " at t = " + std::to_string(e.time) + " s; " +
                             std::to_string(summary.frames) + " frames kept in " + summary.output,
                         e.signal, summary);
  } catch (const IntegrationError& e) {
    const std::string kept = finish_failed("failed", {{"failed_at_time", e.time}}, e.what());
    throw Error(sc.file.name() + ": " + e.what() + "; " + kept);
  } catch (const Error& e) {                         // the output could not be written (a full disk, a size limit)
    if (w && !resume && w->frames_written() == 0) {  // the writer's message says no frame was written
      finish_failed("failed", {}, e.what());
      throw Error(std::string(e.what()) + "; " + summary.output + " was removed");
    }
    finish_failed("failed", {}, e.what());
    throw;
  }
  add_offsets(summary.stats, offsets);
  if (sc.skeleton) summary.simbody_seconds = sc.skeleton->simbody_seconds();
  if (!w) return summary;
  write_finished(*w, sc, summary, ranks, resume ? rp.time : std::numeric_limits<double>::quiet_NaN());
  bar.finish();
  return summary;
}

}  // namespace

RunSummary run_scene(const Scene& sc, const RunOptions& opt) {
  if (opt.mode == OutputWriter::Mode::resume && sc.render)
    if (const std::optional<Scene> again = scene_on_run_mesh(sc, opt.output.empty() ? sc.output.path : opt.output))
      return run_parsed_scene(*again, opt);
  return run_parsed_scene(sc, opt);
}

}  // namespace isochor
