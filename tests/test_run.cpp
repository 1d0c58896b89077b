// Whole runs of mesh scenes on IDA: exact solutions and conservation laws.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>

#include "isochor/integrators/backward_euler.hpp"
#include "isochor/base/error.hpp"
#include "isochor/scene/integrator_registry.hpp"
#include "isochor/scene/mesh_system.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/app/run.hpp"
#include "isochor/app/shell.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {
Scene scene(const std::string& text, const std::vector<std::string>& overrides = {}) {
  return parse_scene(SceneFile::parse(text, "test.toml", overrides));
}
// A demo run with overrides into dir/name.h5: every frame's positions and the /stats totals.
struct DemoRun {
  std::vector<Points> frames;
  std::map<std::string, double> totals;
};
DemoRun run_demo(const std::filesystem::path& dir, const std::string& name, const std::string& demo,
                 const std::vector<std::string>& overrides) {
  const Scene sc = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/" + demo, overrides);
  const RunFile f(run_scene(sc, (dir / (name + ".h5")).string(), false).output);
  DemoRun r;
  for (int k = 0; k < f.num_frames(); ++k) r.frames.push_back(f.positions(k));
  r.totals = f.stat_totals();
  return r;
}
// The ball drop on backward Euler with these overrides, its step matrix solved by CHOLMOD
// ("reduced", [0]) and by PCG ("krylov", [1]).
std::array<DemoRun, 2> ball_on_cholmod_and_pcg(std::vector<std::string> overrides) {
  const auto dir = test::temp_dir();
  overrides.push_back("integrator.kind=backward_euler");
  std::array<DemoRun, 2> r;
  for (int s = 0; s < 2; ++s) {
    const char* solver = s == 0 ? "reduced" : "krylov";
    overrides.push_back(std::string("integrator.linear_solver=") + solver);
    r[s] = run_demo(dir, solver, "ball_drop.toml", overrides);
    overrides.pop_back();
  }
  return r;
}
// The largest distance of a node between two runs' frames (as many frames in both).
double frames_apart(const DemoRun& a, const DemoRun& b) {
  double d = 0;
  for (std::size_t k = 0; k < a.frames.size(); ++k) d = std::max(d, (a.frames[k] - b.frames[k]).cwiseAbs().maxCoeff());
  return d;
}
// The largest distance of a node between two run files' frames, and the largest displacement in
// the first.
std::pair<double, double> apart_and_moved(const RunFile& a, const RunFile& b) {
  double worst = 0, sag = 0;
  for (int k = 0; k < a.num_frames(); ++k) {
    worst = std::max(worst, (a.positions(k) - b.positions(k)).cwiseAbs().maxCoeff());
    sag = std::max(sag, (a.positions(k) - a.rest_positions()).cwiseAbs().maxCoeff());
  }
  return {worst, sag};
}
// a and b moved (more than 0.1 mm) and agree to 1e-6 of that motion; every zone of a holds its
// volume to 1e-10 at every frame.
void expect_same_frames_and_exact_zones(const RunFile& a, const RunFile& b) {
  const auto [worst, sag] = apart_and_moved(a, b);
  EXPECT_GT(sag, 1e-4);
  EXPECT_LT(worst, 1e-6 * sag);
  const auto volumes = a.volumes();
  for (const auto& v : volumes)
    for (std::size_t z = 0; z < v.size(); ++z) EXPECT_NEAR(v[z] / volumes.front()[z], 1.0, 1e-10) << "column " << z;
}
const char* kBox = R"(
[mesh]
shape = "box"
cells = 3
size = [0.1, 0.1, 0.1]
center = [0, 0, 0.5]
[material]
model = "cnh"
E = 46400.0
nu = 0.45
[initial]
velocity = [0.3, -0.2, 1.0]
[frames]
rate = 100.0
duration = 0.3
[integrator]
rtol = 1e-8
atol = 1e-10
)";
// kBox hanging at rest from its top face, with these overrides, on IDA's linear solver `solver`.
Scene hanging_box(std::vector<std::string> overrides, const std::string& solver) {
  overrides.insert(overrides.begin(), "initial.velocity=[0.0, 0.0, 0.0]");
  overrides.push_back("integrator.linear_solver=" + solver);
  return scene(std::string(kBox) + "\n[[boundary]]\nselect = { kind = \"set\", name = \"zmax\" }\n", overrides);
}
}  // namespace

TEST(Run, FreeFallFollowsTheParabola) {
  const auto dir = test::temp_dir();
  Scene sc = scene(kBox);
  RunSummary r = run_scene(sc, (dir / "fall.h5").string(), false);
  RunFile f(r.output);
  ASSERT_EQ(f.num_frames(), 31);
  const Points X = f.rest_positions();
  const Eigen::Vector3d v0(0.3, -0.2, 1.0), g(0, 0, -9.81);
  double worst = 0;
  for (int k = 0; k < f.num_frames(); ++k) {
    const double t = f.times()[k];
    const Points x = f.positions(k);
    for (int n = 0; n < x.cols(); ++n)
      worst = std::max(worst, (x.col(n) - (X.col(n) + v0 * t + 0.5 * g * t * t)).norm());
  }
  // The body falls 0.14 m; an undeformed body in free fall is followed to the tolerance asked for.
  std::printf("free fall: worst position error %.3e m\n", worst);
  EXPECT_LT(worst, 1e-7) << worst;
  // Every frame keeps the volume.
  for (const auto& v : f.volumes()) EXPECT_NEAR(v[0] / 0.001, 1.0, 1e-10);
}

TEST(Run, UndampedOscillationConservesEnergy) {
  // A soft box hanging from its top face, released at rest under gravity: it oscillates about its
  // sagged equilibrium. Fixed nodes do no work, so K + elastic + gravity energy stays constant.
  const auto dir = test::temp_dir();
  Scene sc = scene(std::string(kBox) + R"(
[[boundary]]
select = { kind = "set", name = "zmax" }
)",
                   {"initial.velocity=[0.0, 0.0, 0.0]", "frames.duration=1.0", "material.E=4640.0"});
  RunSummary r = run_scene(sc, (dir / "osc.h5").string(), false);
  RunFile f(r.output);
  ASSERT_GT(f.num_frames(), 90);
  std::vector<std::array<double, 3>> e = f.energies();
  const double E0 = e[0][0] + e[0][1] + e[0][2];
  double max_kinetic = 0, drift = 0, scale = 0;
  for (const auto& row : e) {
    max_kinetic = std::max(max_kinetic, row[0]);
    scale = std::max(scale, std::abs(row[2] - e[0][2]));
    drift = std::max(drift, std::abs(row[0] + row[1] + row[2] - E0));
  }
  EXPECT_GT(max_kinetic, 0.0);
  // Relative to the energy exchanged (the drop of the gravity potential).
  std::printf("oscillation: energy drift %.3e J of %.3e J exchanged, max kinetic %.3e J\n", drift, scale, max_kinetic);
  EXPECT_LT(drift / scale, 1e-4) << "drift " << drift << " exchanged " << scale;
}

TEST(Run, FailuresNameTheTimeAndKeepTheFrames) {
  const auto dir = test::temp_dir();
  // Too few steps allowed: the run stops early, with the frames so far on disk.
  Scene sc = scene(kBox, {"integrator.max_steps=15"});
  const std::string out = (dir / "fail.h5").string();
  const std::string msg = test::error_of([&] { run_scene(sc, out, false); });
  EXPECT_NE(msg.find("test.toml: integration failed at t = "), std::string::npos) << msg;
  EXPECT_NE(msg.find("integrator.max_steps"), std::string::npos) << msg;
  RunFile f(out);
  EXPECT_GT(f.num_frames(), 0);
  EXPECT_LT(f.num_frames(), 31);
}

TEST(Run, ReducedAndKluSolversGiveTheSameFrames) {
  const auto dir = test::temp_dir();
  const std::vector<std::string> common{"frames.duration=0.2", "material.E=4640.0"};
  const Scene a = hanging_box(common, "klu"), b = hanging_box(common, "reduced");
  RunFile fa(run_scene(a, (dir / "klu.h5").string(), false).output);
  RunFile fb(run_scene(b, (dir / "reduced.h5").string(), false).output);
  ASSERT_EQ(fa.num_frames(), fb.num_frames());
  const auto [worst, sag] = apart_and_moved(fa, fb);
  std::printf("klu vs reduced: largest difference %.3e m, largest displacement %.3e m\n", worst, sag);
  EXPECT_GT(sag, 1e-3);
  // Both are solutions to rtol 1e-8 / atol 1e-10: they agree far below the motion.
  EXPECT_LT(worst, 1e-6 * sag);
  for (const auto& v : fb.volumes()) EXPECT_NEAR(v[0] / 0.001, 1.0, 1e-10);
}

// The global zone over patches that partition the body: its volume is their sum at every shape,
// so it gets no constraint row of its own (before, IDA's KLU refused the singular matrix: "the
// constraints are linearly dependent"). KLU then runs it, every zone (the global one included)
// holds its volume, and the frames are those of `reduced`, which takes the multipliers of
// smallest norm over the dependent rows.
TEST(Run, AZoneThatIsTheSumOfOthersGetsNoRowAndIsKeptAllTheSame) {
  const auto dir = test::temp_dir();
  const std::vector<std::string> common{"frames.duration=0.1", "zones.patches=1", "zones.global=true"};
  const Scene a = hanging_box(common, "klu"), b = hanging_box(common, "reduced");
  ASSERT_EQ(a.redundant_zones.size(), 1u);
  EXPECT_EQ(MeshSystem(a).num_constraints(), static_cast<int>(a.zones.size()) - 1);
  ASSERT_FALSE(a.notes.empty());
  EXPECT_NE(a.notes.back().find("1 of " + std::to_string(a.zones.size()) + " zones"), std::string::npos)
      << a.notes.back();
  RunFile fa(run_scene(a, (dir / "klu.h5").string(), false).output);
  RunFile fb(run_scene(b, (dir / "reduced.h5").string(), false).output);
  ASSERT_EQ(fa.num_frames(), fb.num_frames());
  expect_same_frames_and_exact_zones(fa, fb);
}

// IDA's "klu" above kMultifrontalRows constraint rows solves the GGL system through its KKT
// matrix, refined against the GGL matrix (ggl_kkt.hpp; its refinement steps are counted as linear
// iterations, which KLU has none of): the same solution as the reduced solver's CHOLMOD on S with
// its dense border, and every zone exact.
TEST(Run, IdaKluOnManyRowsSolvesThroughTheKktMatrixAndGivesTheReducedSolversFrames) {
  const auto dir = test::temp_dir();
  const std::vector<std::string> common{"frames.duration=0.1", "zones.rings=1", "zones.global=false"};
  const Scene a = hanging_box(common, "klu"), b = hanging_box(common, "reduced");
  const int rows = MeshSystem(a).num_constraints();
  std::printf("1-ring zones: %d constraint rows\n", rows);
  EXPECT_GT(rows, 32);  // kMultifrontalRows (integrators/src/umfpack_lu.hpp)
  RunFile fa(run_scene(a, (dir / "kkt.h5").string(), false).output);
  RunFile fb(run_scene(b, (dir / "reduced.h5").string(), false).output);
  ASSERT_EQ(fa.num_frames(), fb.num_frames());
  const auto totals = fa.stat_totals();
  std::printf("refinement steps %.0f, setups on the GGL matrix's own LU %.0f, Newton iterations %.0f\n",
              totals.at("linear_iterations"), totals.at("linear_fallbacks"), totals.at("newton_iterations"));
  EXPECT_GE(totals.at("linear_iterations"), totals.at("newton_iterations"));
  expect_same_frames_and_exact_zones(fa, fb);
}

// linear_solver = "auto" on IDA: block-Jacobi CG on S (krylov: CG iterations, no factor) for a
// mesh with one zone; "klu" for more than 256 constraint rows (one patch zone per 1-ring of a
// 14^3-cell box: above 32 rows that is the GGL system through its KKT matrix, ggl_kkt.hpp), which
// the reduced solvers would carry as dense columns.
TEST(Run, AutoLinearSolverIsKrylovForAFewZonesAndKluForMany) {
  const auto dir = test::temp_dir();
  Scene one = scene(kBox, {"frames.duration=0.02"});
  RunFile f(run_scene(one, (dir / "zone.h5").string(), false).output);
  const auto totals = f.stat_totals();
  std::printf("one zone: CG iterations %.0f, factor entries %.0f\n", totals.at("linear_iterations"),
              totals.at("factor_nnz"));
  EXPECT_GT(totals.at("linear_iterations"), 0.0);
  EXPECT_EQ(totals.at("factor_nnz"), 0.0);

  Scene many = scene(kBox, {"mesh.cells=14", "zones.patches=1", "zones.global=false"});
  MeshSystem sys(many);
  std::printf("patches: %d constraint rows\n", sys.num_constraints());
  EXPECT_GT(sys.num_constraints(), 256);
  EXPECT_EQ(automatic_ida_solver(sys), LinearSolverKind::klu);
  Scene few = scene(kBox, {"mesh.cells=6", "zones.patches=1", "zones.global=false"});
  MeshSystem sys_few(few);
  EXPECT_LE(sys_few.num_constraints(), 256);
  EXPECT_EQ(automatic_ida_solver(sys_few), LinearSolverKind::krylov);
}

TEST(Run, BackwardEulerKeepsTheVolumeAndDissipates) {
  const auto dir = test::temp_dir();
  const std::string base = std::string(kBox) + R"(
[[boundary]]
select = { kind = "set", name = "zmax" }
)";
  for (const char* kind : {"backward_euler", "semi_implicit"}) {
    Scene sc = scene(base, {"initial.velocity=[0.0, 0.0, 0.0]", "frames.duration=0.3", "material.E=4640.0",
                            std::string("integrator.kind=") + kind, "integrator.dt=0.005"});
    RunFile f(run_scene(sc, (dir / (std::string(kind) + ".h5")).string(), false).output);
    ASSERT_EQ(f.num_frames(), 31);
    // Newton to convergence keeps the zone exactly; one Newton step per step (semi-implicit)
    // satisfies only the linearised constraint, so its volume drifts (recorded, not asserted).
    double drift = 0;
    for (const auto& v : f.volumes()) drift = std::max(drift, std::abs(v[0] / 0.001 - 1.0));
    std::printf("%s: worst volume error %.3e\n", kind, drift);
    if (std::string(kind) == "backward_euler") {
      EXPECT_LT(drift, 1e-9);
    }
    // Backward Euler damps: the total energy ends below where it started, by a visible amount.
    const auto e = f.energies();
    const double E0 = e.front()[0] + e.front()[1] + e.front()[2], E1 = e.back()[0] + e.back()[1] + e.back()[2];
    double exchanged = 0;
    for (const auto& row : e) exchanged = std::max(exchanged, std::abs(row[2] - e.front()[2]));
    std::printf("%s: energy %.4e -> %.4e J (exchanged %.3e J)\n", kind, E0, E1, exchanged);
    EXPECT_LT(E1, E0 - 1e-3 * exchanged) << kind;
  }
}

// The coarse ball of the CNH paper (demos/ball_drop.toml) through impact and rebound start
// (label long: ctest -L long); the default suite runs the same check on a 1,000-tet ball.
static void ball_keeps_its_volume(const std::vector<std::string>& overrides, int min_tets, int frames) {
  const auto dir = test::temp_dir();
  Scene sc = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/ball_drop.toml", overrides);
  ASSERT_GT(sc.mesh.num_tets(), min_tets);
  RunFile f(run_scene(sc, (dir / "cnh.h5").string(), false).output);
  ASSERT_EQ(f.num_frames(), frames);
  double worst = 0, lowest_z = 1;
  for (int k = 0; k < f.num_frames(); ++k) {
    worst = std::max(worst, std::abs(f.volumes()[k][0] / f.volumes()[0][0] - 1.0));
    lowest_z = std::min(lowest_z, f.positions(k).row(2).minCoeff());
  }
  std::printf("coarse ball, cnh: worst volume error %.3e over %d frames, lowest point z = %.4f m\n", worst,
              f.num_frames(), lowest_z);
  EXPECT_LT(lowest_z, 0.002);  // it did reach the ground (contact layer 2 mm)
  EXPECT_LT(worst, 1e-10);     // every frame projected onto the zone's volume
}
TEST(BallDropLong, CnhKeepsTheVolumeAtEveryFrame) { ball_keeps_its_volume({"frames.duration=0.1"}, 4000, 101); }
TEST(BallDrop, CoarseCnhKeepsTheVolumeAtEveryFrame) {
  ball_keeps_its_volume({"frames.duration=0.05", "mesh.target_tets=1000"}, 500, 51);
}

static void unh_loses_a_fifth(const std::vector<std::string>& extra) {
  const auto dir = test::temp_dir();
  std::vector<std::string> o = {"material.model=unh", "integrator.rtol=1e-4", "integrator.atol=1e-6"};
  o.insert(o.end(), extra.begin(), extra.end());
  Scene sc = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/ball_drop.toml", o);
  EXPECT_TRUE(sc.zones.empty());
  RunFile f(run_scene(sc, (dir / "unh.h5").string(), false).output);
  double lowest = 1;
  for (const auto& v : f.volumes()) lowest = std::min(lowest, v[0] / f.volumes()[0][0]);
  std::printf("coarse ball, unh nu = 0.45: lowest volume %.4f of V0\n", lowest);
  EXPECT_LT(lowest, 0.8);
}
TEST(BallDropLong, UnhAtNu045LosesMoreThanAFifthAtImpact) { unh_loses_a_fifth({"frames.duration=0.1"}); }
TEST(BallDrop, CoarseUnhAtNu045LosesMoreThanAFifthAtImpact) {
  unh_loses_a_fifth({"frames.duration=0.05", "mesh.target_tets=1000"});
}

// The CNH paper's Figure 2 (demos/two_tets.toml), statics with KINSOL.
TEST(Statics, TwoTetsRightTetDoublesWithTheGlobalZone) {
  const auto dir = test::temp_dir();
  const std::string demo = std::string(ISOCHOR_SOURCE_DIR) + "/demos/two_tets.toml";
  Scene cnh = load_scene(demo);
  RunFile f(run_scene(cnh, (dir / "cnh.h5").string(), false).output);
  ASSERT_EQ(f.num_frames(), 11);
  const double V0 = f.volumes()[0][0];
  const Points x = f.positions(10);
  const auto& T = cnh.mesh.tets();
  const double left = tet_signed_volume(x.col(T[0][0]), x.col(T[0][1]), x.col(T[0][2]), x.col(T[0][3]));
  const double right = tet_signed_volume(x.col(T[1][0]), x.col(T[1][1]), x.col(T[1][2]), x.col(T[1][3]));
  EXPECT_NEAR(left, 0.0, 1e-12);  // pressed flat
  for (const auto& v : f.volumes()) EXPECT_NEAR(v[0] / V0, 1.0, 1e-10);
  EXPECT_NEAR(right / (V0 / 2), 2.0, 1e-9);  // the right tet reaches twice its rest volume
  // Without the zone (UNH, nu = 0.495) the volume is lost: more than 40% (the paper: 53%).
  Scene unh = load_scene(demo, {"material.model=unh"});
  RunFile g(run_scene(unh, (dir / "unh.h5").string(), false).output);
  EXPECT_LT(g.volumes().back()[0] / V0, 0.6);
}

// Backward Euler with many constraints (1-ring zones) factors the whole KKT matrix (KLU up to 32
// rows, UMFPACK above: 2^3 cells with the KKT path from 9 rows on, 3^3 cells, 61 rows, and
// 10 x 4 x 4 cells, 272 rows); with few it eliminates the borders by a Schur complement on
// CHOLMOD's factor. Both solve the same Newton systems, so the frames agree to the Newton tolerance.
TEST(Run, BackwardEulerKktAndSchurPathsAgree) {
  for (const char* cells : {"2", "3", "[10, 4, 4]"}) {
    Scene sc = scene(R"(
[mesh]
shape = "box"
size = [0.1, 0.1, 0.1]
center = [0, 0, 0.05]
[material]
model = "cnh"
mu = 2000.0
lambda = 0.0
[zones]
global = false
rings = 1
[[boundary]]
select = { kind = "set", name = "zmin" }
[integrator]
kind = "backward_euler"
dt = 0.004
newton_tol = 1e-12
[frames]
rate = 50.0
duration = 0.2
)",
                     {std::string("mesh.cells=") + cells});
    const bool small = std::string(cells) == "2";
    MeshSystem sys(sc);
    // KLU (KktFactor::kMultifrontalRows) on the first, UMFPACK on the others.
    EXPECT_EQ(sys.num_constraints() > 32, !small) << sys.num_constraints();
    ASSERT_GT(sys.num_constraints(), 8);
    std::vector<VectorXd> frames[2];
    for (int path = 0; path < 2; ++path) {
      BackwardEulerOptions o;
      o.dt = 0.004;
      o.newton_tol = 1e-12;
      o.schur_max_constraints = path == 0 ? (small ? 8 : 32) : 100000;
      BackwardEuler(sys, o).run(sc.frames.times(), [&](int, double, const VectorXd& q, const VectorXd&, const VectorXd&,
                                                       const RunStats::FrameSample&) { frames[path].push_back(q); });
    }
    ASSERT_EQ(frames[0].size(), frames[1].size());
    double worst = 0, moved = 0;
    for (std::size_t k = 0; k < frames[0].size(); ++k) {
      worst = std::max(worst, (frames[0][k] - frames[1][k]).cwiseAbs().maxCoeff());
      moved = std::max(moved, (frames[0][k] - frames[0][0]).cwiseAbs().maxCoeff());
    }
    EXPECT_GT(moved, 1e-3) << cells;
    EXPECT_LT(worst, 1e-9) << cells;
  }
}

TEST(IdaRun, FixedBottomCubeStartsAtTightTolerances) {
  // The CNH paper's Figure 8 cube (bottom face fixed, gravity, one global zone) at rtol 1e-7: IDA's
  // own first step (0.5 / |y'|, ~1e-10 s here) left the GGL matrix too ill-conditioned for Newton
  // and the run failed at t = 0 (IDA_CONV_FAIL) on 8^3 cells; with the first step set from the
  // position tolerance it runs, and the global volume holds at every frame.
  const auto dir = test::temp_dir();
  Scene sc = load_scene(
      std::string(ISOCHOR_SOURCE_DIR) + "/demos/cube_collapse.toml",
      {"mesh.cells=8", "frames.duration=0.01", "frames.rate=500.0", "integrator.rtol=1e-7", "integrator.atol=1e-10"});
  const RunSummary r = run_scene(sc, (dir / "cube.h5").string(), false);
  EXPECT_EQ(r.frames, 6);
  const RunFile f(r.output);
  const auto V = f.volumes();
  for (const auto& v : V) EXPECT_LT(std::abs(v[1] / V[0][1] - 1), 1e-9);
  // The cube has started to sag: its top moved down, by less than free fall (g t^2 / 2 = 0.49 mm).
  const Points X = f.rest_positions(), x = f.positions(f.num_frames() - 1);
  double top = 0;
  for (int n = 0; n < X.cols(); ++n)
    if (X(2, n) > 0.1 - 1e-9) top = std::min(top, x(2, n) - X(2, n));
  EXPECT_LT(top, -1e-6);
  EXPECT_GT(top, -0.5 * 9.81 * 0.01 * 0.01);
}

TEST(IdaRun, BallDropFramesAgreeAcrossLinearSolvers) {
  // The same drop (through the impact: contact, large deformation) with KLU on the whole GGL
  // matrix, the reduced system by CHOLMOD, the reduced system by PCG, PCG with Jacobians reused
  // across c_j changes (integrator.jacobian_age), and PCG stopped at a looser relative residual
  // (integrator.linear_tol = 1e-8 for the default 1e-12): the same frames to the integration
  // tolerance (50 times rtol |x| + atol, |x| ~ 0.5 m).
  const auto dir = test::temp_dir();
  constexpr int R = 5;
  std::vector<Points> frames[R];
  std::map<std::string, double> totals[R];
  const char* solvers[R] = {"klu", "reduced", "krylov", "krylov", "krylov"};
  for (int s = 0; s < R; ++s) {
    Scene sc = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/ball_drop.toml",
                          {"mesh.target_tets=1000", "frames.duration=0.04", "frames.rate=250.0",
                           std::string("integrator.linear_solver=") + solvers[s],
                           std::string("integrator.jacobian_age=") + (s == 3 ? "20" : "0"),
                           std::string("integrator.linear_tol=") + (s == 4 ? "1e-8" : "0")});
    const RunFile f(run_scene(sc, (dir / (std::to_string(s) + ".h5")).string(), false).output);
    ASSERT_EQ(f.num_frames(), 11);
    for (int k = 0; k < f.num_frames(); ++k) frames[s].push_back(f.positions(k));
    totals[s] = f.stat_totals();
  }
  const double tol = 50 * (1e-6 * 0.5 + 1e-8);
  for (int s = 1; s < R; ++s)
    for (int k = 0; k < 11; ++k)
      EXPECT_LT((frames[s][k] - frames[0][k]).cwiseAbs().maxCoeff(), tol)
          << solvers[s] << " run " << s << " frame " << k;
  // Through the impact: the ball has moved and deformed.
  EXPECT_GT((frames[0][10] - frames[0][0]).cwiseAbs().maxCoeff(), 0.3);
  // Reuse replaced assemblies: fewer Jacobians assembled than setups.
  EXPECT_GT(totals[3].at("reused_jacobians"), 0.0);
  EXPECT_EQ(totals[2].at("reused_jacobians"), 0.0);
  EXPECT_LT(totals[3].at("jacobian_evaluations"), totals[2].at("jacobian_evaluations"));
  // The looser CG stop took fewer CG iterations per Newton iteration.
  EXPECT_LT(totals[4].at("linear_iterations") / totals[4].at("newton_iterations"),
            totals[2].at("linear_iterations") / totals[2].at("newton_iterations"));
  // Between setups every solver keeps its matrix at the setup's c_j and scales the correction as
  // IDA does; only a setup that reuses a kept Jacobian (jacobian_age) moves krylov's S to the new
  // c_j in place (ReducedSolver::retarget).
  EXPECT_EQ(totals[2].at("retargets"), 0.0);
  EXPECT_GT(totals[3].at("retargets"), 0.0);
  EXPECT_EQ(totals[1].at("retargets"), 0.0);
}

TEST(BackwardEulerRun, KrylovAndCholmodStepsAgree) {
  // Backward Euler's step matrix solved by CHOLMOD or by block-Jacobi PCG: the same steps to the
  // Newton tolerance (1e-8 |q|, accumulated over 160 steps: 1e-5 m).
  const auto r = ball_on_cholmod_and_pcg(
      {"mesh.target_tets=1000", "frames.duration=0.04", "frames.rate=250.0", "integrator.dt=0.00025"});
  ASSERT_EQ(r[0].frames.size(), 11u);
  ASSERT_EQ(r[1].frames.size(), 11u);
  EXPECT_GT(r[1].totals.at("linear_iterations"), 0.0);
  EXPECT_LT(frames_apart(r[1], r[0]), 1e-5);
}

TEST(BackwardEulerRun, PcgStoppedEarlyKeepsTheSteps) {
  // The pinned cube at 8^3 cells (1,944 free dofs) over 1 s. Newton's test measures its own
  // contraction and stops on its estimated error, so a CG stopped at a relative residual of 1e-4
  // (the default) moves work from CG to Newton, not error into the frames: at the demo's Newton
  // tolerance (1e-5 of each step's displacement) its frames are as close to those of a tight run
  // (CHOLMOD, Newton to 1e-10) as CHOLMOD's own are, and so are those of PCG to 1e-12. (Which
  // matrices are kept depends on each solver's estimated costs, so the three take different
  // Newton paths within that tolerance.)
  const auto dir = test::temp_dir();
  const char* solvers[4] = {"reduced", "krylov", "krylov", "reduced"};
  const char* tols[4] = {"0", "1e-12", "0", "0"};
  const char* newton[4] = {"1e-5", "1e-5", "1e-5", "1e-10"};
  DemoRun r[4];
  std::map<std::string, double> totals[4];
  for (int s = 0; s < 4; ++s) {
    r[s] =
        run_demo(dir, std::to_string(s), "pinned_cube.toml",
                 {"mesh.cells=8", "frames.duration=1.0", std::string("integrator.linear_solver=") + solvers[s],
                  std::string("integrator.linear_tol=") + tols[s], std::string("integrator.newton_tol=") + newton[s]});
    ASSERT_EQ(r[s].frames.size(), 61u);
    totals[s] = r[s].totals;
  }
  EXPECT_EQ(totals[0].at("linear_iterations"), 0.0);
  ASSERT_GT(totals[1].at("linear_iterations"), 0.0);
  ASSERT_GT(totals[2].at("linear_iterations"), 0.0);
  const auto per_newton = [&](int s) { return totals[s].at("linear_iterations") / totals[s].at("newton_iterations"); };
  std::printf("CG iterations per Newton iteration: %.1f at 1e-12, %.1f at the default\n", per_newton(1), per_newton(2));
  EXPECT_LT(per_newton(2), 0.7 * per_newton(1));
  const double direct = frames_apart(r[0], r[3]), exact = frames_apart(r[1], r[3]), loose = frames_apart(r[2], r[3]);
  std::printf("largest distance to the tight run's frames: %.2e m (CHOLMOD), %.2e m (PCG to 1e-12), %.2e m (default)\n",
              direct, exact, loose);
  // "As close": within half as much again as the direct solver's distance, which Newton's
  // tolerance alone sets.
  EXPECT_LT(exact, 1.5 * direct);
  EXPECT_LT(loose, 1.5 * direct);
  // The cube moves by decimetres, so the bounds above are not met by standing still.
  EXPECT_GT((r[0].frames[60] - r[0].frames[0]).cwiseAbs().maxCoeff(), 0.05);
}

TEST(BackwardEulerRun, AutomaticSolverFollowsTheMeshSize) {
  // linear_solver = "auto": CHOLMOD below 1,300 free dofs (6^3 cells: 882), PCG above (8^3:
  // 1,944), CHOLMOD again without the line search (PCG could then fail on an indefinite matrix).
  const auto dir = test::temp_dir();
  int runs = 0;
  const auto cg_iterations = [&](std::vector<std::string> sets) {
    sets.push_back("frames.duration=0.1");
    Scene sc = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/pinned_cube.toml", sets);
    return RunFile(run_scene(sc, (dir / (std::to_string(++runs) + ".h5")).string(), false).output)
        .stat_totals()
        .at("linear_iterations");
  };
  EXPECT_EQ(cg_iterations({"mesh.cells=6"}), 0.0);
  EXPECT_GT(cg_iterations({"mesh.cells=8"}), 0.0);
  EXPECT_EQ(cg_iterations({"mesh.cells=8", "integrator.line_search=false"}), 0.0);
}

TEST(BackwardEulerRun, AutomaticSolverSwitchesToCholmodWhereCgIsSlow) {
  // linear_solver = "auto" starts on PCG above 1,300 free dofs, then estimates both solvers' cost
  // per Newton iteration from what the steps counted. The Figure 8 cube at 8^3 cells (2,187 dofs)
  // in UNH at lambda = 9,900 Pa = 99 mu and 8 ms steps: CG takes ~180 iterations per solve, while
  // one CHOLMOD factor serves ~10 Newton iterations, so auto moves to CHOLMOD once (measured: 0.14
  // s against PCG's 0.28 s) and its CG iterations stop there. The frames stay those of CHOLMOD
  // alone, to the Newton tolerance (1e-6 of each step's few-mm displacement, over 13 steps).
  const auto dir = test::temp_dir();
  const char* solvers[3] = {"reduced", "krylov", "auto"};
  DemoRun r[3];
  for (int s = 0; s < 3; ++s) {
    r[s] = run_demo(dir, solvers[s], "cube_gravity.toml",
                    {"mesh.cells=8", "frames.duration=0.1", "integrator.kind=backward_euler", "integrator.dt=0.008",
                     "material.model=unh", "material.lambda=9900", "zones.global=false",
                     std::string("integrator.linear_solver=") + solvers[s]});
    ASSERT_EQ(r[s].frames.size(), 13u);
  }
  EXPECT_EQ(r[0].totals.at("solver_switches"), 0.0);
  EXPECT_EQ(r[1].totals.at("solver_switches"), 0.0);
  EXPECT_EQ(r[2].totals.at("solver_switches"), 1.0);
  // PCG ran only for the first steps: CG iterations over 100 per Newton iteration alone, fewer
  // than half of PCG's over the whole run.
  const double cg_alone = r[1].totals.at("linear_iterations") / r[1].totals.at("newton_iterations");
  std::printf("CG iterations per Newton iteration, PCG alone: %.1f; auto: %.0f of PCG's %.0f\n", cg_alone,
              r[2].totals.at("linear_iterations"), r[1].totals.at("linear_iterations"));
  EXPECT_GT(cg_alone, 100.0);
  EXPECT_GT(r[2].totals.at("linear_iterations"), 0.0);
  EXPECT_LT(r[2].totals.at("linear_iterations"), 0.5 * r[1].totals.at("linear_iterations"));
  const double apart = frames_apart(r[2], r[0]);
  std::printf("auto's frames from CHOLMOD's: %.2e m\n", apart);
  EXPECT_LT(apart, 1e-7);
  EXPECT_GT((r[0].frames[12] - r[0].frames[0]).cwiseAbs().maxCoeff(), 1e-3);  // the cube sagged
}

TEST(BackwardEulerRun, CholmodShiftsAnIndefiniteStepMatrixAsPcgDoes) {
  // The 2K-tet ball at 1 ms through its impact: with the line search an indefinite step matrix
  // is shifted by more inertia (PCG stops on it). CHOLMOD used to factor it by LDL^T instead; the
  // line search then cut its directions to 1/8-1/128 and the run failed at 37 ms ("Newton did not
  // converge in 30 iterations"). Now CHOLMOD refuses it too: both solvers run through 50 ms, shift
  // matrices, and give the same frames to the Newton tolerance (1e-6 of each step's ~1 cm,
  // over 50 steps).
  const auto r = ball_on_cholmod_and_pcg({"mesh.target_tets=2000", "frames.duration=0.05", "integrator.dt=0.001"});
  for (int s = 0; s < 2; ++s) {
    ASSERT_EQ(r[s].frames.size(), 51u) << (s == 0 ? "CHOLMOD" : "PCG");
    EXPECT_GT(r[s].totals.at("regularisations"), 0.0) << (s == 0 ? "CHOLMOD" : "PCG");
  }
  const double apart = frames_apart(r[1], r[0]);
  std::printf("CHOLMOD's frames from PCG's: %.2e m\n", apart);
  EXPECT_LT(apart, 1e-6);
  EXPECT_GT((r[0].frames[50] - r[0].frames[0]).cwiseAbs().maxCoeff(), 0.3);  // the ball fell and hit the ground
}

TEST(Statics, TheSameEquilibriaWithEveryLinearSolver) {
  // KINSOL's Newton steps through KLU on the KKT matrix, through CHOLMOD on its n x n block with
  // the borders by a Schur complement, and through PCG on that block: each solve is exact to
  // rounding (PCG to 1e-12 relative residual), so the iterates and the converged equilibria agree
  // to far below KINSOL's tolerance. The cantilever under gravity with four zone patches (m = 4).
  const auto dir = test::temp_dir();
  std::vector<Points> frames[3];
  std::map<std::string, double> totals[3];
  const char* solvers[3] = {"klu", "reduced", "krylov"};
  for (int s = 0; s < 3; ++s) {
    Scene sc =
        load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/cantilever_zones.toml",
                   {"zones.global=false", "zones.patches=2", std::string("integrator.linear_solver=") + solvers[s]});
    const RunFile f(run_scene(sc, (dir / (std::string(solvers[s]) + ".h5")).string(), false).output);
    ASSERT_EQ(f.num_frames(), 11);
    for (int k = 0; k < f.num_frames(); ++k) frames[s].push_back(f.positions(k));
    totals[s] = f.stat_totals();
  }
  for (int s = 1; s < 3; ++s) {
    for (int k = 0; k < 11; ++k)
      EXPECT_LT((frames[s][k] - frames[0][k]).cwiseAbs().maxCoeff(), 1e-9) << solvers[s] << " frame " << k;
    EXPECT_EQ(totals[s].at("newton_iterations"), totals[0].at("newton_iterations")) << solvers[s];
  }
  EXPECT_GT(totals[2].at("linear_iterations"), 0.0);
  // The beam bends: the tip comes down by decimetres (docs/demos.md: 0.596 m for these patches).
  EXPECT_GT((frames[0][10] - frames[0][0]).cwiseAbs().maxCoeff(), 0.3);
}

// The one quoting function: every word comes back from /bin/sh as it went in (quotes, spaces,
// expansions, a newline, the empty word), and words the shell takes literally stay unquoted
// (the resume command that isochor prints stays readable).
TEST(ShellQuoting, WordsComeBackFromTheShellUnchanged) {
  const std::vector<std::string> words = {"it's", "a b", "$HOME", "`id`", "\\",        "a\nb",
                                          "",     "*",   "'",     "''x'", "out/run.h5"};
  for (const std::string& w : words) {
    const std::string cmd = "printf %s " + shell_quoted(w);
    FILE* p = popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    std::string out;
    for (int c; (c = std::fgetc(p)) != EOF;) out += static_cast<char>(c);
    EXPECT_EQ(pclose(p), 0) << cmd;
    EXPECT_EQ(out, w) << cmd;
  }
  EXPECT_EQ(shell_quoted("demos/ball_drop.toml"), "demos/ball_drop.toml");
  EXPECT_EQ(shell_quoted("material.mu=2e3"), "material.mu=2e3");
}
