// What the run file records besides the body (scene_record, /colliders, up): the up direction
// by the rule the viewers document (the ground's normal, else against gravity, else z) and each
// collider's shape, dimensions and rest pose as the scene file gives them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "isochor/core/meshing.hpp"
#include "isochor/scene/scene.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {

const std::string kBox =
    "[mesh]\nshape = \"box\"\nsize = [0.1, 0.1, 0.1]\ncells = 1\n[material]\nmu = 1.0\nlambda = 1.0\n";

SceneRecord record_of(const std::string& rest) {
  return scene_record(parse_scene(SceneFile::parse(kBox + rest, "r.toml")));
}

void expect_up(const SceneRecord& r, double x, double y, double z, const std::string& source) {
  EXPECT_NEAR(r.up[0], x, 1e-15);
  EXPECT_NEAR(r.up[1], y, 1e-15);
  EXPECT_NEAR(r.up[2], z, 1e-15);
  EXPECT_EQ(r.up_source, source);
}

double dimension(const ColliderRecord& c, const std::string& name) {
  for (const auto& [key, value] : c.dimensions)
    if (key == name) return value;
  ADD_FAILURE() << c.name << " has no " << name;
  return 0;
}

}  // namespace

TEST(SceneRecord, UpIsTheGroundsNormalThenAgainstGravityThenZ) {
  // The ground's normal, normalised, even when gravity points elsewhere.
  expect_up(record_of("[forces]\ngravity = [-9.81, 0.0, 0.0]\n[contact]\nground = true\npoint = [0.0, -1.0, "
                      "0.0]\nnormal = [0.0, 2.0, 0.0]\n"),
            0, 1, 0, "the ground's normal");
  expect_up(record_of("[forces]\ngravity = [0.0, -9.81, 0.0]\n"), 0, 1, 0, "against gravity");
  expect_up(record_of("[forces]\ngravity = [3.0, 0.0, -4.0]\n"), -0.6, 0, 0.8, "against gravity");
  expect_up(record_of(""), 0, 0, 1, "against gravity");  // the default gravity is along -z
  expect_up(record_of("[forces]\ngravity = [0.0, 0.0, 0.0]\n"), 0, 0, 1, "z (no ground, no gravity)");
}

TEST(SceneRecord, CollidersKeepTheSceneFilesShapesAndPoses) {
  const SceneRecord r = record_of(
      "[contact]\nground = true\npoint = [0.0, 0.0, -1.0]\n"
      "[[contact.plane]]\npoint = [0.5, 0.0, 0.0]\nnormal = [-1.0, 0.0, 0.0]\n"
      "[[collider]]\nshape = \"capsule\"\nradius = 0.1\nlength = 0.4\ncenter = [1.0, 2.0, 3.0]\naxis = [1.0, 0.0, "
      "0.0]\n"
      "[[collider]]\nshape = \"box\"\nsize = [0.2, 0.4, 0.6]\ncenter = [0.0, 0.0, 2.0]\n"
      "[[collider]]\nshape = \"cylinder\"\nradius = 0.3\nwall = 0.02\nlength = 0.05\n");
  ASSERT_EQ(r.colliders.size(), 5u);
  EXPECT_EQ(r.colliders[0].name, "contact.ground");
  EXPECT_EQ(r.colliders[0].shape, "plane");
  EXPECT_DOUBLE_EQ(r.colliders[0].rest_pose[11], -1.0);  // b = the ground's point
  EXPECT_EQ(r.colliders[1].shape, "plane");
  // A plane's normal is its rest rotation's third column: A(0,2), A(1,2), A(2,2).
  EXPECT_NEAR(r.colliders[1].rest_pose[2], -1.0, 1e-15);
  EXPECT_DOUBLE_EQ(r.colliders[1].rest_pose[9], 0.5);
  const ColliderRecord& capsule = r.colliders[2];
  EXPECT_EQ(capsule.name, "collider[0]");
  EXPECT_EQ(capsule.shape, "capsule");
  EXPECT_DOUBLE_EQ(dimension(capsule, "radius"), 0.1);
  EXPECT_DOUBLE_EQ(dimension(capsule, "length"), 0.4);
  EXPECT_NEAR(capsule.rest_pose[2], 1.0, 1e-15);  // the axis along x
  EXPECT_DOUBLE_EQ(capsule.rest_pose[9], 1.0);
  EXPECT_DOUBLE_EQ(capsule.rest_pose[10], 2.0);
  EXPECT_DOUBLE_EQ(capsule.rest_pose[11], 3.0);
  EXPECT_DOUBLE_EQ(dimension(r.colliders[3], "size_x"), 0.2);
  EXPECT_DOUBLE_EQ(dimension(r.colliders[3], "size_y"), 0.4);
  EXPECT_DOUBLE_EQ(dimension(r.colliders[3], "size_z"), 0.6);
  EXPECT_DOUBLE_EQ(dimension(r.colliders[4], "radius"), 0.3);
  EXPECT_DOUBLE_EQ(dimension(r.colliders[4], "wall"), 0.02);
  EXPECT_DOUBLE_EQ(dimension(r.colliders[4], "length"), 0.05);
}

TEST(SceneRecord, AMeshColliderKeepsItsScaledSurface) {
  // A closed tetrahedron (4 vertices, 4 triangles) scaled by 2: its vertices, scaled, in the record.
  const std::filesystem::path dir = test::temp_dir();
  const std::string file = (dir / "tetra.obj").string();
  std::ofstream(file) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
  const Scene s = parse_scene(SceneFile::parse(
      kBox + "[[collider]]\nshape = \"mesh\"\nfile = \"" + file + "\"\nscale = 2.0\ncenter = [0.0, 0.0, 5.0]\n",
      "m.toml"));
  Points x;
  std::vector<Tri> tris;
  read_surface(file, x, tris);
  const SceneRecord r = scene_record(s);
  ASSERT_EQ(r.colliders.size(), 1u);
  EXPECT_EQ(r.colliders[0].shape, "mesh");
  ASSERT_EQ(r.colliders[0].vertices.cols(), x.cols());
  EXPECT_LT((r.colliders[0].vertices - 2.0 * x).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(r.colliders[0].triangles, tris);
}
