// Runs that survive: resuming an interrupted or killed run, interrupts at step
// boundaries, outputs that are never clobbered, and a full file system that keeps every frame.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/resource.h>

#include <csignal>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "isochor/base/error.hpp"
#include "isochor/integrators/interrupt.hpp"
#include "isochor/core/output.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/app/run.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {
Scene scene(const std::string& text, const std::vector<std::string>& overrides = {}) {
  return parse_scene(SceneFile::parse(text, "test.toml", overrides));
}

// demos/swing.toml: a soft block clamped at one end, swinging down under gravity and ringing.
std::string swing_text() {
  std::ifstream in(std::string(ISOCHOR_SOURCE_DIR) + "/demos/swing.toml");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
const std::string kSwing = swing_text();

struct Frames {
  std::vector<Points> x, v;
};
Frames frames_of(const std::string& path) {
  RunFile f(path);
  Frames out;
  for (int k = 0; k < f.num_frames(); ++k) {
    out.x.push_back(f.positions(k));
    out.v.push_back(f.velocities(k));
  }
  return out;
}
double max_difference(const std::vector<Points>& a, const std::vector<Points>& b, std::size_t from = 0) {
  double worst = 0;
  for (std::size_t k = from; k < a.size(); ++k) worst = std::max(worst, (a[k] - b[k]).cwiseAbs().maxCoeff());
  return worst;
}

RunOptions options(const std::string& path, OutputWriter::Mode mode = OutputWriter::Mode::create) {
  RunOptions o;
  o.output = path;
  o.progress = false;
  o.mode = mode;
  return o;
}

// Runs `sc` into `path`, stopped by the frame callback after frame `stop_after`.
void run_until(const Scene& sc, const std::string& path, int stop_after) {
  RunOptions o = options(path);
  o.on_frame = [stop_after](int k, const Frame&) { return k < stop_after; };
  EXPECT_THROW(run_scene(sc, o), RunInterrupted);
}

// The frames of `sc` run straight through, and run again stopped after frame `stop_after` and
// resumed.
std::pair<Frames, Frames> straight_and_resumed(const Scene& sc, int stop_after) {
  const auto dir = test::temp_dir();
  const std::string straight = (dir / "straight.h5").string(), resumed = (dir / "resumed.h5").string();
  run_scene(sc, options(straight));
  run_until(sc, resumed, stop_after);
  run_scene(sc, options(resumed, OutputWriter::Mode::resume));
  return {frames_of(straight), frames_of(resumed)};
}
}  // namespace

// A run stopped part-way and resumed gives the uninterrupted run's frames to the integration
// tolerance: IDA restarts from the stored frame (a fresh start of its history, so the steps
// differ), and the difference must stay within the uninterrupted run's own error (measured
// against a run at 100 times tighter tolerances).
TEST(Resume, AnInterruptedIdaRunMatchesTheUninterruptedOne) {
  const auto dir = test::temp_dir();
  const Scene sc = scene(kSwing);
  run_scene(sc, options((dir / "ref.h5").string()));
  run_scene(scene(kSwing, {"integrator.rtol=1e-8", "integrator.atol=1e-10"}), options((dir / "tight.h5").string()));
  const std::string path = (dir / "resumed.h5").string();
  run_until(sc, path, 8);
  {
    RunFile f(path);
    EXPECT_EQ(f.num_frames(), 9);
    EXPECT_EQ(f.attributes().at("status"), "interrupted");
  }
  const RunSummary r = run_scene(sc, options(path, OutputWriter::Mode::resume));
  EXPECT_EQ(r.resumed_from, 8);
  EXPECT_EQ(r.frames, 21);
  const Frames ref = frames_of((dir / "ref.h5").string()), tight = frames_of((dir / "tight.h5").string()),
               res = frames_of(path);
  ASSERT_EQ(res.x.size(), ref.x.size());
  const double own_error = max_difference(ref.x, tight.x), resume_error = max_difference(res.x, ref.x);
  std::printf("uninterrupted run against a 100x tighter one: %.3e m; resumed against uninterrupted: %.3e m\n",
              own_error, resume_error);
  EXPECT_TRUE(std::isfinite(resume_error));
  EXPECT_EQ(max_difference({res.x.begin(), res.x.begin() + 9}, {ref.x.begin(), ref.x.begin() + 9}), 0.0);
  EXPECT_GT(max_difference(ref.x, std::vector<Points>(ref.x.size(), ref.x[0])), 100 * own_error);  // it moves
  // Two runs at the same tolerance, each within own_error of the truth, differ by at most twice it.
  EXPECT_LE(resume_error, 2 * own_error);
  RunFile f(path);
  EXPECT_EQ(f.attributes().at("status"), "finished");
  EXPECT_NEAR(f.stat_totals().at("resumed_at"), 0.08, 1e-12);
  EXPECT_EQ(f.stat_totals().count("interrupted_at"), 0u);
  // The cumulative step count continues from the frame resumed at.
  const auto steps = f.stat_series().at("steps");
  for (std::size_t k = 1; k < steps.size(); ++k) EXPECT_GE(steps[k], steps[k - 1]) << k;
}

// Backward Euler with frames on step boundaries: a resumed run takes the same steps from the same
// state, and agrees with the uninterrupted one to the Newton tolerance (tightened here to 1e-10
// of each step's displacement, so that Newton's path, which the restart's fresh factorisation
// changes, does not show).
const std::vector<std::string> kBackwardEuler{"integrator.kind=backward_euler", "integrator.dt=2e-3",
                                              "integrator.newton_tol=1e-10"};
TEST(Resume, AnInterruptedBackwardEulerRunRepeatsTheSameSteps) {
  const auto [ref, res] = straight_and_resumed(scene(kSwing, kBackwardEuler), 11);
  ASSERT_EQ(res.x.size(), 21u);
  const double dx = max_difference(res.x, ref.x), dv = max_difference(res.v, ref.v);
  std::printf("backward Euler resumed at frame 11: positions %.3e m, velocities %.3e m/s apart\n", dx, dv);
  EXPECT_LT(dx, 1e-9);
  EXPECT_LT(dv, 1e-6);
}

namespace {
// /frames/activation of a run file: frames x muscles.
std::vector<std::vector<double>> activations_of(const std::string& path) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t d = H5Dopen2(f, "/frames/activation", H5P_DEFAULT);
  const hid_t space = H5Dget_space(d);
  hsize_t dims[2] = {0, 0};
  H5Sget_simple_extent_dims(space, dims, nullptr);
  std::vector<double> flat(dims[0] * dims[1]);
  H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, flat.data());
  H5Sclose(space);
  H5Dclose(d);
  H5Fclose(f);
  std::vector<std::vector<double>> out(dims[0]);
  for (hsize_t k = 0; k < dims[0]; ++k) out[k].assign(flat.begin() + k * dims[1], flat.begin() + (k + 1) * dims[1]);
  return out;
}
}  // namespace

// A muscle's activation is a function of time, so a resumed run goes on with it: the resumed file
// records at every frame what the keys give (linear, 0 -> 0.8 over the run's 0.2 s: 4 t), and,
// on backward Euler, takes the uninterrupted run's steps (as above).
TEST(Resume, AMusclesActivationGoesOnWhereTheRunStopped) {
  const std::string muscle = R"(
[[muscle]]
name = "flexor"
select = { kind = "all" }
direction = [1.0, 0.0, 0.0]
sigma_max = 2e4
activation_keys = { times = [0.0, 0.2], values = [0.0, 0.8] }
)";
  const Scene sc = scene(kSwing + muscle, kBackwardEuler);
  const auto dir = test::temp_dir();
  const std::string straight = (dir / "straight.h5").string(), resumed = (dir / "resumed.h5").string();
  run_scene(sc, options(straight));
  run_until(sc, resumed, 11);
  EXPECT_EQ(activations_of(resumed).size(), 12u);
  run_scene(sc, options(resumed, OutputWriter::Mode::resume));
  const std::vector<double> times = RunFile(resumed).times();
  const auto a = activations_of(resumed);
  ASSERT_EQ(a.size(), 21u);
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].size(), 1u);
    EXPECT_NEAR(a[k][0], 4 * times[k], 1e-12) << "frame " << k;
  }
  const Frames ref = frames_of(straight), res = frames_of(resumed);
  EXPECT_LT(max_difference(res.x, ref.x), 1e-9);
  // The activation moves the tissue: the same run without the muscle ends elsewhere.
  run_scene(scene(kSwing, kBackwardEuler), options((dir / "passive.h5").string()));
  EXPECT_GT((frames_of((dir / "passive.h5").string()).x.back() - ref.x.back()).cwiseAbs().maxCoeff(), 1e-4);
}

// linear_solver = "auto" moving from PCG to CHOLMOD (the stiff cube of
// BackwardEulerRun.AutomaticSolverSwitchesToCholmodWhereCgIsSlow, which switches after 4-8
// steps): a run resumed after its 6th frame starts on PCG again and switches again, and its frames
// are the uninterrupted run's to the Newton tolerance (1e-6 of each step's few-mm displacement).
TEST(Resume, AnAutomaticSolverChoosesAgainAfterAResume) {
  const Scene sc =
      load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/cube_gravity.toml",
                 {"mesh.cells=8", "frames.duration=0.1", "integrator.kind=backward_euler", "integrator.dt=0.008",
                  "material.model=unh", "material.lambda=9900", "zones.global=false"});
  const auto [ref, res] = straight_and_resumed(sc, 6);
  ASSERT_EQ(res.x.size(), 13u);
  ASSERT_EQ(ref.x.size(), 13u);
  const double dx = max_difference(res.x, ref.x);
  std::printf("auto's backward Euler resumed at frame 6: positions %.3e m apart\n", dx);
  EXPECT_LT(dx, 1e-7);
  EXPECT_GT(max_difference(ref.x, std::vector<Points>(ref.x.size(), ref.x[0])), 1e-3);  // the cube sagged
}

// A killed writer can leave a frame half written: some series a row longer than others. The
// resume drops it, continues from the last complete frame, and the file ends as the
// uninterrupted run's.
TEST(Resume, AKilledRunsHalfWrittenFrameIsDropped) {
  const auto dir = test::temp_dir();
  const Scene sc = scene(kSwing, kBackwardEuler);
  run_scene(sc, options((dir / "ref.h5").string()));
  const std::string path = (dir / "killed.h5").string();
  {
    RunOptions o = options(path);
    o.on_frame = [](int k, const Frame&) {
      if (k == 6) throw std::runtime_error("killed");  // the writer goes away without a word
      return true;
    };
    EXPECT_THROW(run_scene(sc, o), std::runtime_error);
  }
  EXPECT_NE(describe_run(path).find("unfinished: its writer stopped without closing it"), std::string::npos);
  {
    // Frame 7 half written: its time and positions there, nothing else.
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    for (const char* name : {"/frames/time", "/frames/positions"}) {
      const hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
      const hid_t space = H5Dget_space(ds);
      hsize_t dims[3];
      const int rank = H5Sget_simple_extent_dims(space, dims, nullptr);
      ASSERT_EQ(dims[0], 7u);
      dims[0] = 8;
      H5Dset_extent(ds, dims);
      H5Sclose(space);
      H5Dclose(ds);
      (void)rank;
    }
    H5Fclose(f);
  }
  const RunSummary r = run_scene(sc, options(path, OutputWriter::Mode::resume));
  EXPECT_EQ(r.resumed_from, 6);
  const Frames ref = frames_of((dir / "ref.h5").string()), res = frames_of(path);
  ASSERT_EQ(res.x.size(), 21u);
  EXPECT_LT(max_difference(res.x, ref.x), 1e-9);
  EXPECT_EQ(RunFile(path).times(), RunFile((dir / "ref.h5").string()).times());
}

// A stop requested from outside (what the SIGINT and SIGTERM handler does) ends the run at the
// next step boundary, before the next frame, with the frames so far kept and the file marked.
TEST(Resume, AStopRequestEndsTheRunAtTheNextStep) {
  const auto dir = test::temp_dir();
  for (const char* kind : {"ida", "backward_euler", "static"}) {
    std::string text = kSwing;
    if (std::string(kind) == "static") {
      text.replace(text.find("rate = 100.0\nduration = 0.2"), 27, "count = 6");
      ASSERT_EQ(text.find("duration"), std::string::npos) << "demos/swing.toml's [frames] changed";
    }
    std::vector<std::string> o{std::string("integrator.kind=") + kind};
    if (std::string(kind) == "static") o.push_back("forces.gravity_ramp=1");  // load increments
    const Scene sc = scene(text, o);
    const std::string path = (dir / (std::string(kind) + ".h5")).string();
    RunOptions opt = options(path);
    opt.on_frame = [](int k, const Frame&) {
      if (k == 3) request_stop(SIGTERM);
      return true;
    };
    try {
      run_scene(sc, opt);
      ADD_FAILURE() << kind << ": the run did not stop";
    } catch (const RunInterrupted& e) {
      EXPECT_EQ(e.signal, SIGTERM) << kind;
      EXPECT_NE(std::string(e.what()).find("4 frames kept in " + path), std::string::npos) << e.what();
    }
    clear_stop_request();
    RunFile f(path);
    EXPECT_EQ(f.num_frames(), 4) << kind;
    EXPECT_EQ(f.attributes().at("status"), "interrupted");
    EXPECT_EQ(f.stat_totals().at("signal"), SIGTERM);
    EXPECT_GE(f.stat_totals().at("interrupted_at"), f.times().back()) << kind;
    EXPECT_NE(describe_run(path).find("interrupted at t = "), std::string::npos);
  }
}

TEST(Resume, OnlyTheSceneTheFileWasWrittenWith) {
  const auto dir = test::temp_dir();
  const std::string path = (dir / "a.h5").string();
  run_until(scene(kSwing), path, 3);
  const std::string msg =
      test::error_of([&] { run_scene(scene(kSwing, {"material.mu=3e4"}), options(path, OutputWriter::Mode::resume)); });
  EXPECT_NE(msg.find(path + ": was written from a different scene"), std::string::npos) << msg;
  EXPECT_EQ(RunFile(path).num_frames(), 4);  // untouched
  const std::string none = (dir / "none.h5").string();
  EXPECT_NE(test::error_of([&] {
              run_scene(scene(kSwing), options(none, OutputWriter::Mode::resume));
            }).find("no such file to resume"),
            std::string::npos);
  // A finished run resumed does nothing.
  run_scene(scene(kSwing), options(path, OutputWriter::Mode::resume));
  const RunSummary again = run_scene(scene(kSwing), options(path, OutputWriter::Mode::resume));
  EXPECT_TRUE(again.already_finished);
  EXPECT_EQ(again.frames, 21);
}

// A resume reads the same input files as the run did: a mesh script changed since (here only by a
// comment, the same mesh) is refused, naming it; the file is left as it was.
TEST(Resume, OnlyTheInputFilesTheRunRead) {
  const auto dir = test::temp_dir();
  const std::string geo = R"(Point(1) = {0, 0, 0, 0.5}; Point(2) = {0, 1, 0, 0.5}; Point(3) = {0, 1, 1, 0.5};
Point(4) = {0, 0, 1, 0.5}; Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1}; out[] = Extrude{1, 0, 0}{ Surface{1}; };
Physical Volume("block") = {out[1]}; Physical Surface("clamp") = {1};
)";
  test::write_file(dir / "block.geo", geo);
  const std::string text = R"([mesh]
file = "block.geo"
[material]
mu = 1.0e4
lambda = 1.0e4
[[boundary]]
select = { kind = "set", name = "clamp" }
[frames]
rate = 100.0
duration = 0.05
)";
  auto block = [&] { return parse_scene(SceneFile::parse(text, "block.toml", {}, dir.string())); };
  const std::string path = (dir / "block.h5").string();
  run_until(block(), path, 2);
  test::write_file(dir / "block.geo", geo + "// a comment\n");
  const std::string msg = test::error_of([&] { run_scene(block(), options(path, OutputWriter::Mode::resume)); });
  EXPECT_NE(msg.find(path + ": the scene's input block.geo changed since the run was written"), std::string::npos)
      << msg;
  EXPECT_EQ(RunFile(path).num_frames(), 3);  // untouched
  test::write_file(dir / "block.geo", geo);  // as it was: the run goes on
  EXPECT_EQ(run_scene(block(), options(path, OutputWriter::Mode::resume)).frames, 6);
}

namespace {
Mesh small_mesh() { return make_box({0.1, 0.1, 0.1}, {2, 2, 2}, Eigen::Vector3d::Zero(), 6); }
}  // namespace

TEST(Outputs, AnExistingOutputIsKeptUnlessOverwriteIsAsked) {
  const auto dir = test::temp_dir();
  const std::string path = (dir / "mine.h5").string();
  { std::ofstream(path) << "a user's own file\n"; }
  const Mesh m = small_mesh();
  const std::string msg = test::error_of([&] { OutputWriter w(path, m, {}, {"", "", "run", {}, {}}, false); });
  EXPECT_NE(msg.find(path + ": exists (pass --overwrite to replace it, or --resume"), std::string::npos) << msg;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "a user's own file");
  // Its sidecar counts as the output too.
  const std::string other = (dir / "other.h5").string();
  { std::ofstream((dir / "other.xdmf").string()) << "x"; }
  EXPECT_NE(test::error_of([&] {
              OutputWriter w(other, m, {}, {"", "", "run", {}, {}}, false);
            }).find("other.xdmf: exists"),
            std::string::npos);
  OutputWriter w(path, m, {}, {"", "", "run", {}, {}}, false, OutputWriter::Mode::overwrite);
  EXPECT_EQ(w.frames_written(), 0);
}

TEST(Outputs, AnXdmfPathIsRefused) {
  const auto dir = test::temp_dir();
  const std::string path = (dir / "run.xdmf").string();
  const std::string msg = test::error_of([&] {
    OutputWriter w(path, small_mesh(), {}, {"", "", "run", {}, {}}, false);
  });
  EXPECT_NE(msg.find("the XDMF sidecar would overwrite the output itself"), std::string::npos) << msg;
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(Outputs, ASecondWriterFailsAtStartAndLeavesTheFirstIntact) {
  const auto dir = test::temp_dir();
  const std::string path = (dir / "shared.h5").string();
  const Mesh m = small_mesh();
  OutputWriter first(path, m, {}, {"", "", "run", {}, {}}, false);
  EXPECT_TRUE(output_is_being_written(path));
  const std::string msg = test::error_of([&] {
    OutputWriter second(path, m, {}, {"", "", "run", {}, {}}, false, OutputWriter::Mode::overwrite);
  });
  EXPECT_NE(msg.find(path + ": another process is writing it"), std::string::npos) << msg;
  Frame f;
  f.positions = &m.rest_positions();
  f.volumes = {m.rest_volume()};
  first.write_frame(f);
  first.close();
  EXPECT_FALSE(output_is_being_written(path));
  EXPECT_EQ(RunFile(path).num_frames(), 1);
}

// The file size limit (ulimit -f) reached part-way: the writer stops before the frame that would
// not fit, says so, and every frame before it reads back exactly as written.
TEST(Outputs, AFullFileSystemStopsTheRunWithEveryFrameBeforeItIntact) {
  const auto dir = test::temp_dir();
  const std::string path = (dir / "full.h5").string();
  const Mesh m = make_box({0.1, 0.1, 0.1}, {8, 8, 8}, Eigen::Vector3d::Zero(), 6);
  std::signal(SIGXFSZ, SIG_IGN);
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  std::string msg;
  int written = 0;
  std::vector<Points> frames;
  {
    OutputWriter w(path, m, {}, {"", "", "run", {}, {}}, false);
    rlimit lim = old;
    lim.rlim_cur = 2 << 20;  // 2 MB: a frame is 8.7 KB of positions and as much of velocities
    ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &lim), 0);
    try {
      for (int k = 0; k < 1000; ++k) {
        Points x = m.rest_positions() * (1.0 + 1e-3 * k);
        Frame f;
        f.time = 0.01 * k;
        f.positions = &x;
        f.velocities = &x;
        f.volumes = {m.rest_volume()};
        w.write_frame(f);
        frames.push_back(x);
        written = k + 1;
      }
    } catch (const Error& e) {
      msg = e.what();
    }
    setrlimit(RLIMIT_FSIZE, &old);
  }
  std::printf("%d frames, then: %s\n", written, msg.c_str());
  EXPECT_GT(written, 10);
  EXPECT_LT(written, 1000);
  EXPECT_NE(
      msg.find(path + ": the file size limit (ulimit -f: 2048 KB) is reached at frame " + std::to_string(written)),
      std::string::npos);
  EXPECT_NE(msg.find("frames 0-" + std::to_string(written - 1) + " are intact"), std::string::npos);
  RunFile f(path);
  ASSERT_EQ(f.num_frames(), written);
  for (int k = 0; k < written; ++k) EXPECT_EQ((f.positions(k) - frames[k]).cwiseAbs().maxCoeff(), 0.0) << k;
}

// A write that the system refuses while the file is created (a 1 KB file size limit, SIGXFSZ
// ignored: EFBIG): the error names the file and the system's reason. (HDF5's clean-up at exit
// crashes after such a failed flush; the command line and the Python module turn it off too.)
TEST(Outputs, AWriteErrorNamesTheFileAndTheReason) {
  hdf5_no_cleanup_at_exit();
  const std::string path = (test::temp_dir() / "efbig.h5").string();
  std::signal(SIGXFSZ, SIG_IGN);
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  rlimit lim = old;
  lim.rlim_cur = 1024;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &lim), 0);
  const std::string msg = test::error_of([&] {
    OutputWriter w(path, small_mesh(), {}, {"", "", "run", {}, {}}, false);
  });
  setrlimit(RLIMIT_FSIZE, &old);
  EXPECT_NE(msg.find(path + ": "), std::string::npos) << msg;
  EXPECT_NE(msg.find("File too large"), std::string::npos) << msg;
}

// A device is no output, --overwrite or not (/dev/full: its rename or truncation would replace or
// write the device): refused naming its kind, and the device is left a device.
TEST(Outputs, ADeviceIsNoOutput) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const std::string msg = test::error_of([&] {
    OutputWriter w("/dev/full", small_mesh(), {}, {"", "", "run", {}, {}}, false, OutputWriter::Mode::overwrite);
  });
  EXPECT_EQ(msg, "/dev/full: is a character device, not a regular file (expected a path for the run's output)");
  EXPECT_TRUE(std::filesystem::is_character_file("/dev/full"));
}

// XPBD keeps no state between steps but the positions and velocities: resumed, it repeats the
// same steps exactly.
TEST(Resume, AnInterruptedXpbdRunRepeatsTheSameSteps) {
  std::string text = kSwing;
  text.erase(text.find("[damping]"), std::string("[damping]\nbeta = 1e-3      # s\n").size());
  ASSERT_EQ(text.find("beta"), std::string::npos) << "demos/swing.toml's [damping] changed";
  const auto [ref, res] = straight_and_resumed(scene(text, {"integrator.kind=xpbd", "integrator.dt=2e-3"}), 5);
  ASSERT_EQ(res.x.size(), 21u);
  const double dx = max_difference(res.x, ref.x);
  std::printf("XPBD resumed at frame 5: positions %.3e m apart\n", dx);
  EXPECT_LT(dx, 1e-12);
}
