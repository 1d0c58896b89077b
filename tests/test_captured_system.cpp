// A captured effective stiffness (ISOCHOR_CAPTURE_S, sparse_factor.hpp): the file round trip, bad
// files named, and a capture from a real run checked against what S must be.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "isochor/integrators/ida_integrator.hpp"
#include "isochor/scene/mesh_system.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/integrators/sparse_factor.hpp"

using namespace isochor;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("isochor_capture_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

std::string error_of(const std::string& path) {
  try {
    read_system(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(CapturedSystem, RoundTripsExactlyAndNamesABadFile) {
  const SparsePattern p = SparsePattern::from_entries(3, {{0, 0}, {1, 1}, {2, 2}, {0, 2}, {2, 0}});
  const std::vector<double> values = {4.0, 0.1 + 0.2, -1.0 / 3.0, 5.0, -1.0 / 3.0};
  const std::vector<double> b = {1.0, 2.0, 3.0};
  const std::string path = temp_path("roundtrip.bin");
  write_system(path, p, values.data(), b.data(), 123.5, 0.25);
  EXPECT_FALSE(std::filesystem::exists(path + ".part"));
  const CapturedSystem s = read_system(path);
  EXPECT_EQ(s.pattern.n, 3);
  EXPECT_EQ(s.pattern.col_ptr, p.col_ptr);
  EXPECT_EQ(s.pattern.row_ind, p.row_ind);
  EXPECT_EQ(s.values, values);  // bit for bit
  EXPECT_EQ(s.b, b);
  EXPECT_EQ(s.cj, 123.5);
  EXPECT_EQ(s.t, 0.25);

  // Truncated: one line naming the file.
  const auto size = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, size - 4);
  EXPECT_EQ(error_of(path), path + ": not a captured system (the file ends early)");
  // Not a captured system at all.
  { std::ofstream(path) << "ISOCHOR_ but not S\n"; }
  EXPECT_EQ(error_of(path), path + ": not a captured system (no ISOCHORS header)");
  std::filesystem::remove(path);
  EXPECT_EQ(error_of(path), path + ": cannot open");
}

// The coarse ball in free flight, IDA with the krylov solver, captured at t >= 0.01 s. Whatever
// c_j, damping and zone pressure the step has, S = c_j^2 M + c_j D + K + sum lambda_j H_j applied to
// a rigid translation is c_j^2 M times it: elastic forces, Rayleigh damping (beta K) and the zone
// volume do not change when the body is translated, and nothing touches the ball before 0.03 s.
// So each row sum of S over the x (y, z) columns is c_j^2 times that dof's lumped mass.
TEST(CapturedSystem, ARunsEffectiveStiffnessTranslatesLikeItsMass) {
  Scene scene = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/ball_drop.toml",
                           {"mesh.target_tets=1000", "frames.duration=0.02"});
  MeshSystem sys(scene);
  IdaOptions o;
  o.rtol = 1e-6;
  o.atol_q = 1e-8;
  o.linear_solver = LinearSolverKind::krylov;
  const std::string path = temp_path("run.bin");
  ::setenv("ISOCHOR_CAPTURE_S", ("0.01:" + path).c_str(), 1);
  IdaIntegrator(sys, o).run(scene.frames.times(), [](int, double, const VectorXd&, const VectorXd&, const VectorXd&,
                                                     const RunStats::FrameSample&) {});
  ::unsetenv("ISOCHOR_CAPTURE_S");
  const CapturedSystem s = read_system(path);
  std::filesystem::remove(path);
  EXPECT_GE(s.t, 0.01);
  EXPECT_LE(s.t, 0.03);
  ASSERT_EQ(s.pattern.n, sys.num_dofs());
  ASSERT_GT(s.cj, 0);
  const VectorXd& mass = sys.mass();
  double worst = 0, largest = 0;
  for (int axis = 0; axis < 3; ++axis) {
    VectorXd row_sum = VectorXd::Zero(s.pattern.n);
    for (Index c = axis; c < s.pattern.n; c += 3)  // S is symmetric: the column sum is the row sum
      for (Index k = s.pattern.col_ptr[c]; k < s.pattern.col_ptr[c + 1]; ++k)
        row_sum[s.pattern.row_ind[k]] += s.values[k];
    for (Index i = 0; i < s.pattern.n; ++i) {
      const double expected = i % 3 == axis ? s.cj * s.cj * mass[i] : 0.0;
      worst = std::max(worst, std::abs(row_sum[i] - expected));
      largest = std::max(largest, s.cj * s.cj * mass[i]);
    }
  }
  // Relative to the largest diagonal entry of S, which is K's: the translation cancels it.
  double diag = 0;
  for (Index c = 0; c < s.pattern.n; ++c)
    for (Index k = s.pattern.col_ptr[c]; k < s.pattern.col_ptr[c + 1]; ++k)
      if (s.pattern.row_ind[k] == c) diag = std::max(diag, std::abs(s.values[k]));
  std::printf("c_j %.4g, t %.4g: largest c_j^2 m %.3e, largest diagonal %.3e, worst row-sum error %.3e\n", s.cj, s.t,
              largest, diag, worst);
  EXPECT_GT(diag, 2 * largest);  // K is not negligible next to c_j^2 M: the check has teeth
  EXPECT_LT(worst, 1e-9 * diag);
  // The right-hand side is a real one: finite and not zero.
  double bb = 0;
  for (double v : s.b) bb += v * v;
  EXPECT_TRUE(std::isfinite(bb) && bb > 0);
}
