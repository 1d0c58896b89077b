// The inf-sup test of zone choices (models/infsup.hpp) against what linear algebra and the
// theory of mixed methods say, and the zones CNH gets by default (scene/zones_setup.hpp).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numeric>

#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/models/constraints.hpp"
#include "isochor/models/infsup.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/scene/zones_setup.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {

std::vector<std::vector<int>> every_tet(const Mesh& m) {
  std::vector<std::vector<int>> z(m.num_tets());
  for (int e = 0; e < m.num_tets(); ++e) z[e] = {e};
  return z;
}

std::vector<std::vector<int>> whole(const Mesh& m) {
  std::vector<int> all(m.num_tets());
  std::iota(all.begin(), all.end(), 0);
  return {all};
}

double beta_of(const std::string& scene, const std::vector<std::string>& set) {
  return zones_infsup(load_scene(scene, set)).beta;
}

}  // namespace

// A zone per tet on a box held on its whole surface: G has more rows than the free dofs have
// columns, so G K^-1 G^T has at least (zones - dofs) zero eigenvalues (its rank is at most the
// number of dofs); the constant pressure is one of them (the integral of div v over the body is 0
// for every v that vanishes on its surface).
TEST(InfSup, MoreZonesThanFreeDofsLeaveZeroModes) {
  const Mesh m = make_box({1, 1, 1}, {3, 3, 3}, {0, 0, 0}, 5);
  const InfSup r = infsup_constant(m, every_tet(m), m.surface_nodes(), {});
  EXPECT_EQ(r.zones, 135);
  EXPECT_EQ(r.dofs, 24);  // the 2 x 2 x 2 interior nodes
  EXPECT_GE(r.zero_modes, 135 - 24);
  EXPECT_LT(r.beta, 1e-6);
  // The global zone alone on the same box: the constant pressure, which no such v sees.
  EXPECT_LT(infsup_constant(m, whole(m), m.surface_nodes(), {}).beta, 1e-6);
}

// Pressures constant on unions of zones are a subspace of those constant on the zones: the
// minimum of the same Rayleigh quotient over a subspace is never lower. The global zone >= pairs
// of 1-ring patches >= 1-ring patches.
TEST(InfSup, CoarserZonesNeverLowerTheConstant) {
  const Mesh m = make_box({2, 1, 1}, {6, 3, 3}, {1, 0, 0}, 6);
  const std::vector<int> held = m.node_sets.at("xmin");
  const auto patches = patch_zones(m, 1);
  std::vector<std::vector<int>> pairs;
  for (std::size_t p = 0; p < patches.size(); p += 2) {
    pairs.push_back(patches[p]);
    if (p + 1 < patches.size()) pairs.back().insert(pairs.back().end(), patches[p + 1].begin(), patches[p + 1].end());
  }
  ASSERT_GT(patches.size(), 4u);
  const double fine = infsup_constant(m, patches, held, {}).beta;
  const double paired = infsup_constant(m, pairs, held, {}).beta;
  const double global = infsup_constant(m, whole(m), held, {}).beta;
  EXPECT_GT(fine, 0.0);
  EXPECT_GE(paired, fine - 1e-12);
  EXPECT_GE(global, paired - 1e-12);
  EXPECT_GT(global, fine + 0.05);
}

// The constant is a property of the geometry: the same for the body rotated (its rollers rotated
// with it, held along a direction that is no axis) and scaled (the norm's L^2 term scales with the
// body's diagonal); and rollers along z equal holding the z components.
TEST(InfSup, RotatedAndScaledBodiesKeepTheirConstant) {
  const Mesh m = make_box({2, 1, 0.5}, {4, 2, 2}, {0, 0, 0}, 6);
  const std::vector<int> clamp = m.node_sets.at("xmin");
  std::vector<std::pair<int, Eigen::Vector3d>> rollers;
  for (int n : m.node_sets.at("zmin")) rollers.emplace_back(n, Eigen::Vector3d::UnitZ());
  const auto zones = patch_zones(m, 1);
  const double beta = infsup_constant(m, zones, clamp, rollers).beta;
  const double free_bottom = infsup_constant(m, zones, clamp, {}).beta;
  EXPECT_GT(std::abs(beta - free_bottom), 1e-6);  // the rollers matter
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Mesh turned(3.5 * R * m.rest_positions(), m.tets());
  std::vector<std::pair<int, Eigen::Vector3d>> turned_rollers;
  for (const auto& [n, d] : rollers) turned_rollers.emplace_back(n, R * d);
  EXPECT_NEAR(infsup_constant(turned, zones, clamp, turned_rollers).beta, beta, 1e-9 * beta);
}

TEST(InfSup, DependentZonesAreRefused) {
  const Mesh m = make_box({1, 1, 1}, {3, 3, 3}, {0, 0, 0}, 6);
  auto zones = patch_zones(m, 1);
  zones.push_back(whole(m)[0]);  // their sum
  const std::string e = test::error_of([&] { infsup_constant(m, zones, m.node_sets.at("xmin"), {}); });
  EXPECT_NE(e.find("the zones are linearly dependent"), std::string::npos) << e;
  // More zones than the dense eigenproblem is allowed: refused before any work, naming the count.
  const std::string many = test::error_of([&] { infsup_constant(m, patch_zones(m, 1), {}, {}, 3); });
  EXPECT_NE(many.find("inf-sup: " + std::to_string(patch_zones(m, 1).size()) + " zones (expected at most 3"),
            std::string::npos)
      << many;
}

// Brezzi's condition: a stable choice keeps beta_h as the mesh is refined, an unstable one loses
// it. On Cook's membrane (unstructured tets, plane strain by rollers): 2-ring patches (the
// default) keep it within 15% from h = 4 to h = 2; 1-ring patches lose more than a third.
TEST(InfSup, TwoRingPatchesKeepTheirConstantUnderRefinementOneRingPatchesDoNot) {
  const std::string cook = std::string(ISOCHOR_SOURCE_DIR) + "/demos/cook_membrane.toml";
  const double p2_coarse = beta_of(cook, {"mesh.edge_length=4", "zones.patches=2"});
  const double p2_fine = beta_of(cook, {"mesh.edge_length=2", "zones.patches=2"});
  const double p1_coarse = beta_of(cook, {"mesh.edge_length=4", "zones.patches=1"});
  const double p1_fine = beta_of(cook, {"mesh.edge_length=2", "zones.patches=1"});
  EXPECT_GT(p2_fine, 0.5);
  EXPECT_GT(p2_fine, 0.85 * p2_coarse);
  EXPECT_LT(p1_fine, 0.67 * p1_coarse);
}

// CNH with no zone named gets 2-ring patches and no global zone; `default = "global"` the paper's
// one zone; UNH nothing; patches on a fully driven part are dropped; a beam two cells thick gets
// the note that its patches span its thickness, one eight cells thick does not.
TEST(DefaultZones, CnhGetsTwoRingPatchesAndANoteWhereTheMeshIsTooCoarse) {
  const std::string beam = R"(
[mesh]
shape = "box"
size = [1.0, 0.1, 0.1]
cells = [20, 2, 2]
center = [0.5, 0.0, 0.0]
[material]
mu = 1.0e6
lambda = 1.0e6
)";
  const std::string clamp = "[[boundary]]\nselect = { kind = \"set\", name = \"xmin\" }\n";
  auto scene = [&](std::vector<std::string> set, const std::string* extra = nullptr) {
    return parse_scene(SceneFile::parse(beam + (extra ? *extra : clamp), "beam.toml", std::move(set)));
  };
  const Scene coarse = scene({});
  const auto patches = patch_zones(coarse.mesh, 2);
  ASSERT_EQ(coarse.zones.size(), patches.size());
  for (std::size_t p = 0; p < patches.size(); ++p) EXPECT_EQ(coarse.zones[p].second, patches[p]);
  ASSERT_EQ(coarse.notes.size(), 1u);
  EXPECT_NE(coarse.notes[0].find("2-ring patches are 1.0 across the body's thinnest direction"), std::string::npos)
      << coarse.notes[0];
  EXPECT_TRUE(scene({"mesh.cells=[80, 8, 8]"}).notes.empty());
  const Scene paper = scene({"zones.default=global"});
  ASSERT_EQ(paper.zones.size(), 1u);
  EXPECT_EQ(paper.zones[0].first, "global");
  EXPECT_TRUE(scene({"material.model=unh"}).zones.empty());
  EXPECT_TRUE(scene({"material.model=unh", "zones.default=global"}).zones.empty());
  const std::string bad = test::error_of([&] {
    scene({}, nullptr);
    parse_scene(SceneFile::parse(beam + clamp + "[zones]\ndefault = \"paper\"\n", "beam.toml"));
  });
  EXPECT_NE(bad.find("beam.toml:13: zones.default: expected one of \"patches\", \"global\", got \"paper\""),
            std::string::npos)
      << bad;
  // A locking penalty is named.
  const Scene stiff = scene({"mesh.cells=[80, 8, 8]", "material.lambda=1e8"});
  ASSERT_EQ(stiff.notes.size(), 1u);
  EXPECT_NE(stiff.notes[0].find("material.lambda is 100 mu"), std::string::npos) << stiff.notes[0];
  // The left tenth of the beam held: the patches there (every node driven) are left out.
  const std::string left = "[[boundary]]\nselect = { kind = \"box\", min = [-1, -1, -1], max = [0.3, 1, 1] }\n";
  const Scene held = scene({}, &left);
  EXPECT_LT(held.zones.size(), patches.size());
  std::vector<char> driven(held.mesh.num_nodes(), 0);
  for (int n : held.driven_nodes()) driven[n] = 1;
  for (const auto& [name, tets] : held.zones) {
    bool free = false;
    for (int e : tets)
      for (int n : held.mesh.tets()[e]) free = free || !driven[n];
    EXPECT_TRUE(free) << name;
  }
}

// Zones whose volumes follow from the others' at every shape: the indicator vectors of their tet
// sets are linearly dependent. The elimination (modulo a 61-bit prime) against a dense rank in
// doubles (Eigen's full-pivot LU) and, per flagged zone, a least-squares combination of the zones
// before it that reproduces its tets to rounding.
TEST(RedundantZones, AreTheZonesWhoseTetsAreSumsAndDifferencesOfTheOthers) {
  auto dense = [](const std::vector<std::vector<int>>& zones, int tets) {
    Eigen::MatrixXd W = Eigen::MatrixXd::Zero(tets, static_cast<Eigen::Index>(zones.size()));
    for (std::size_t j = 0; j < zones.size(); ++j)
      for (int e : zones[j]) W(e, static_cast<Eigen::Index>(j)) += 1;
    return W;
  };
  for (int per_cube : {5, 6}) {
    const Mesh m = make_box({1.5, 0.3, 0.3}, {10, 2, 2}, {0.75, 0, 0}, per_cube);
    std::vector<std::vector<int>> rings;
    for (int v = 0; v < m.num_nodes(); ++v) rings.push_back(m.tet_ring(v, 1));
    const auto redundant = redundant_zones(rings, 100'000'000);
    ASSERT_TRUE(redundant.has_value());
    const Eigen::MatrixXd W = dense(rings, m.num_tets());
    Eigen::FullPivLU<Eigen::MatrixXd> lu(W);
    EXPECT_EQ(static_cast<Eigen::Index>(redundant->size()), W.cols() - lu.rank()) << per_cube;
    for (int j : *redundant) {
      const Eigen::MatrixXd before = W.leftCols(j);
      const Eigen::VectorXd x = before.colPivHouseholderQr().solve(W.col(j));
      EXPECT_LT((before * x - W.col(j)).norm(), 1e-9) << "zone " << j;
    }
    // Six tets per cube: the nodes four-colour by (i + j + k) mod 4 with one colour per tet
    // corner, so each colour's rings add up to the body (three dependencies).
    if (per_cube == 6) EXPECT_EQ(redundant->size(), 3u);
  }
  const Mesh m = make_box({1, 1, 1}, {3, 3, 3}, {0, 0, 0}, 6);
  auto zones = patch_zones(m, 1);
  EXPECT_TRUE(redundant_zones(zones, 1'000'000)->empty());  // a partition: independent
  zones.push_back(whole(m)[0]);                             // the global zone, their sum
  EXPECT_EQ(*redundant_zones(zones, 1'000'000), std::vector<int>{static_cast<int>(zones.size()) - 1});
  EXPECT_FALSE(redundant_zones(zones, 10).has_value());  // beyond its work limit: not decided
}
