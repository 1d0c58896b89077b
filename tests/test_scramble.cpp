// The scrambled starts (the XPBD paper's crazy cube): initial.flatten puts every node
// into one plane at a seeded random point, and zones.restore_time lets the zone constraints start
// from the volume that start has and reach the rest volume along a C^2 ramp.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "isochor/base/error.hpp"
#include "isochor/scene/mesh_system.hpp"
#include "isochor/scene/scene.hpp"
#include "test_util.hpp"

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
default = "global"   # one zone, whose target the tests follow
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

// initial.displacement: each listed node starts displaced from its rest position by its row
// (CSV node,ux,uy,uz), the others at rest. A rigid translation of a free body is an equilibrium
// (no strain): the body stays there; a stretch of one node is not: the body moves. Rows that name
// no node, a node twice or a non-finite displacement are refused with the file and row.
TEST(Scramble, DisplacementStartsTheListedNodesDisplaced) {
  const auto dir = test::temp_dir();
  const auto parse = [&](const std::string& csv, std::vector<std::string> set = {}) {
    test::write_file(dir / "u.csv", csv);
    set.insert(set.begin(), {"initial.flatten=none", "initial.displacement=\"u.csv\"", "zones.restore_time=0.0"});
    return parse_scene(SceneFile::parse(kScene, "start.toml", std::move(set), dir.string()));
  };
  const std::vector<std::string> be = {"integrator.kind=backward_euler", "integrator.dt=0.01", "frames.duration=0.2"};
  const Scene one = parse("node,ux,uy,uz\n3,0.01,-0.02,0.5\n", be);
  const Points& X = one.mesh.rest_positions();
  for (Eigen::Index n = 0; n < X.cols(); ++n)
    EXPECT_EQ((one.initial_positions.col(n) - X.col(n)).norm(),
              n == 3 ? Eigen::Vector3d(0.01, -0.02, 0.5).norm() : 0.0);
  std::string all = "node,ux,uy,uz\n";
  for (Eigen::Index n = 0; n < X.cols(); ++n) all += std::to_string(n) + ",0.1,0.2,-0.3\n";
  const Scene translated = parse(all, be);  // MeshSystem keeps a reference to its scene
  MeshSystem moved(translated);
  VectorXd q, v;
  moved.initial_state(0.0, q, v);
  for (Index i = 0; i < q.size(); ++i)
    EXPECT_NEAR(q[i], X(i % 3, moved.dofs().free_nodes[i / 3]) + (i % 3 == 0 ? 0.1 : i % 3 == 1 ? 0.2 : -0.3), 1e-15);
  VectorXd f;
  moved.force(0.0, q, v, f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-9);  // a rigid translation: no elastic force
  const Scene pulled = parse("node,ux,uy,uz\n3,0.01,0.0,0.0\n", be);
  MeshSystem bumped(pulled);
  bumped.initial_state(0.0, q, v);
  bumped.force(0.0, q, v, f);
  EXPECT_GT(f.cwiseAbs().maxCoeff(), 1.0);  // one node pulled out: the mesh pulls it back
  for (const auto& [csv, what] : std::vector<std::pair<std::string, std::string>>{
           {"node,ux,uy,uz\n999,0,0,0\n", "u.csv:2: node 999"},
           {"node,ux,uy,uz\n1,0,0,0\n1,0,0,0\n", "u.csv:3: node 1 is listed twice"},
           {"node,ux,uy\n1,0,0\n", "expected the columns node, ux, uy, uz"}}) {
    const std::string e = test::error_of([&] { parse(csv); });
    EXPECT_NE(e.find("initial.displacement: "), std::string::npos) << e;
    EXPECT_NE(e.find(what), std::string::npos) << e;
  }
  // On IDA the zone must start at its rest volume: one node moved by 0.5 m leaves it far off.
  const std::string ida = test::error_of([&] { parse("node,ux,uy,uz\n3,0.01,-0.02,0.5\n"); });
  EXPECT_NE(ida.find("initial.displacement: the zone global starts"), std::string::npos) << ida;
  const std::string both = test::error_of([&] { parse(all, {"initial.flatten=z"}); });
  EXPECT_NE(both.find("initial.displacement: initial.flatten or initial.from also sets the start"), std::string::npos)
      << both;
}
