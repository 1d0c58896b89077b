// The scrambled starts (the XPBD paper's crazy cube): initial.flatten puts every node
// into one plane at a seeded random point, and zones.restore_time lets the zone constraints start
// from the volume that start has and reach the rest volume along a C^2 ramp.
#include <gtest/gtest.h>

#include <cmath>

#include "isochor/base/error.hpp"
#include "isochor/scene/mesh_system.hpp"
#include "isochor/scene/scene.hpp"

using namespace isochor;

namespace {
const char* kScene = R"(
[mesh]
shape = "box"
size = [0.2, 0.1, 0.1]
cells = [4, 2, 2]
center = [1.0, 2.0, 3.0]

[material]
model = "cnh"
mu = 1000.0
lambda = 1000.0

[forces]
gravity = [0.0, 0.0, 0.0]

[zones]
restore_time = 0.5   # the zones start at volume 0 (IDA refuses a flattened start without it)

[initial]
flatten = "z"
seed = 7

[frames]
rate = 10.0
duration = 1.0
)";

Scene scene(std::vector<std::string> set = {}) {
  return parse_scene(SceneFile::parse(kScene, "scramble.toml", std::move(set)));
}
}  // namespace

TEST(Scramble, FlattenPutsEveryNodeInThePlaneInsideTheBoxAndIsSeeded) {
  const Scene s = scene();
  const Points& X = s.mesh.rest_positions();
  const Points& P = s.initial_positions;
  ASSERT_EQ(P.cols(), X.cols());
  const Eigen::Vector3d lo = X.rowwise().minCoeff(), hi = X.rowwise().maxCoeff();
  for (Eigen::Index n = 0; n < P.cols(); ++n) {
    EXPECT_EQ(P(2, n), 3.0);  // the plane through the centre, normal to z
    for (int d = 0; d < 2; ++d) {
      EXPECT_GE(P(d, n), lo[d]);
      EXPECT_LE(P(d, n), hi[d]);
    }
  }
  // Random, not a squashed copy of the mesh: the in-plane points are far from the rest ones.
  EXPECT_GT((P.topRows(2) - X.topRows(2)).cwiseAbs().maxCoeff(), 0.05);
  EXPECT_EQ((scene().initial_positions - P).norm(), 0.0);                     // same seed: same start
  EXPECT_GT((scene({"initial.seed=8"}).initial_positions - P).norm(), 0.01);  // another seed: another
  EXPECT_EQ(scene({"initial.flatten=none"}).initial_positions.cols(), 0);
  EXPECT_THROW(scene({"initial.flatten=w"}), Error);
  // The system starts there.
  MeshSystem sys(s);
  VectorXd q, v;
  sys.initial_state(0.0, q, v);
  for (Index i = 2; i < q.size(); i += 3) EXPECT_EQ(q[i], 3.0);
}

TEST(Scramble, SpreadMixesTheRandomPointWithTheSquashedRestPosition) {
  // spread = 0: the mesh squashed flat (its rest positions projected into the plane); spread = s:
  // (1 - s) of the way from the random point of spread = 1 to that projection, per node.
  const Scene s = scene();
  const Points& X = s.mesh.rest_positions();
  const Points& random = s.initial_positions;
  const Points flat = scene({"initial.spread=0.0"}).initial_positions;
  const Points mixed = scene({"initial.spread=0.25"}).initial_positions;
  for (Eigen::Index n = 0; n < X.cols(); ++n) {
    EXPECT_EQ(flat(2, n), 3.0);
    EXPECT_EQ(mixed(2, n), 3.0);
    for (int d = 0; d < 2; ++d) {
      EXPECT_EQ(flat(d, n), X(d, n));
      EXPECT_NEAR(mixed(d, n), 0.25 * random(d, n) + 0.75 * X(d, n), 1e-14);
    }
  }
  EXPECT_THROW(scene({"initial.spread=1.5"}), Error);
  EXPECT_THROW(scene({"initial.spread=-0.1"}), Error);
}

TEST(Scramble, RestoreTimeRampsTheZoneTargetFromTheStartToTheRestVolume) {
  // A start with half the rest volume (the box squashed to half its height), restored over 0.4 s.
  Scene s = scene({"initial.flatten=none", "zones.restore_time=0.4"});
  s.initial_positions = s.mesh.rest_positions();
  s.initial_positions.row(2) = (s.initial_positions.row(2).array() - 3.0) * 0.5 + 3.0;
  MeshSystem sys(s);
  ASSERT_EQ(sys.num_constraints(), 1);
  VectorXd q0, v0, g;
  sys.initial_state(0.0, q0, v0);
  const double V0 = s.mesh.rest_volume();
  sys.constraint(0.0, q0, g);
  EXPECT_NEAR(g[0], 0.0, 1e-15);  // consistent at the start
  // Later, at the same positions: g = V(q0) - target(t), the target 10s^3 - 15s^4 + 6s^5 of the way.
  for (double t : {0.1, 0.2, 0.3}) {
    const double u = t / 0.4, p = u * u * u * (10 - 15 * u + 6 * u * u);
    sys.constraint(t, q0, g);
    EXPECT_NEAR(g[0], -(V0 - 0.5 * V0) * p, 1e-15) << t;
  }
  sys.constraint(0.4, q0, g);
  EXPECT_NEAR(g[0], -0.5 * V0, 1e-15);
  sys.constraint(0.9, q0, g);
  EXPECT_NEAR(g[0], -0.5 * V0, 1e-15);  // held at the rest volume after the ramp
  // dg/dt against central differences in time, in the ramp and after it.
  std::vector<std::vector<double>> G;
  VectorXd gt;
  for (double t : {0.05, 0.17, 0.33, 0.6}) {
    G.assign(1, std::vector<double>(sys.constraint_rows()[0].size()));
    sys.constraint_jacobian(t, q0, G, &gt);
    VectorXd gp, gm;
    sys.constraint(t + 1e-6, q0, gp);
    sys.constraint(t - 1e-6, q0, gm);
    const double fd = (gp[0] - gm[0]) / 2e-6;
    EXPECT_NEAR(gt[0], fd, 1e-9 * V0) << t;
    if (t < 0.4) {
      EXPECT_GT(std::abs(fd), 0.1 * V0);  // not vacuous inside the ramp
    }
  }
}
