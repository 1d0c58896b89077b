// The glTF character reader: rest pose, skinning and clip sampling against poses computed here by
// hand (rotations about known pivots, the cubic s^3 as a Hermite segment), and a bad file stopping
// with one line that names the file and the accessor, node or animation at fault.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <sstream>

#include "isochor/core/gltf.hpp"
#include "isochor/core/meshing.hpp"
#include "gltf_builder.hpp"
#include "test_util.hpp"

namespace {

using isochor::GltfCharacter;
using isochor::read_gltf;
using isochor::test::error_of;
using isochor::test::GltfBuilder;

// A unit tetrahedron's surface (4 vertices, 4 triangles).
const std::vector<float> kTetra = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
const std::vector<std::uint16_t> kTetraTris = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

std::vector<float> identity_matrices(int n) {
  std::vector<float> m;
  for (int k = 0; k < n; ++k)
    for (int e = 0; e < 16; ++e) m.push_back(e % 5 == 0 ? 1.0f : 0.0f);
  return m;
}

// A mesh node 0 skinned by joint node 1 (weights all on it), with a clip `turn` that rotates the
// joint by 90 degrees about z between t = 0 and t = 1 (LINEAR).
GltfBuilder one_joint() {
  GltfBuilder g;
  const int pos = g.floats(kTetra, "VEC3");
  const int idx = g.add(kTetraTris, "SCALAR", 5123);
  const int joints = g.add(std::vector<std::uint8_t>(16, 0), "VEC4", 5121);
  const int weights = g.floats({1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "VEC4");
  const int ibm = g.floats(identity_matrices(1), "MAT4");
  const int times = g.floats({0, 1}, "SCALAR");
  const float s = static_cast<float>(std::sqrt(0.5));
  const int rot = g.floats({0, 0, 0, 1, 0, 0, s, s}, "VEC4");
  g.nodes = R"([{"mesh":0,"skin":0},{"name":"root"}])";
  g.scenes = "[{\"nodes\":[0,1]}]";
  g.skinned_mesh(pos, joints, weights, idx);
  g.skins = "[{\"joints\":[1],\"inverseBindMatrices\":" + std::to_string(ibm) + "}]";
  g.one_channel_clip("turn", times, rot, 1, "rotation");
  return g;
}

Eigen::Matrix3d rot_z(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

TEST(Gltf, OneJointTurnsItsVerticesAsTheClipSays) {
  const GltfCharacter c = read_gltf(one_joint().write("one.gltf"));
  ASSERT_EQ(c.vertices.cols(), 4);
  ASSERT_EQ(c.triangles.size(), 4u);
  ASSERT_EQ(c.joints.size(), 1u);
  EXPECT_EQ(c.joints[0].name, "root");
  EXPECT_EQ(c.joints[0].parent, -1);
  ASSERT_EQ(c.clips.size(), 1u);
  EXPECT_EQ(c.find_clip("turn"), 0);
  EXPECT_EQ(c.find_clip("0"), 0);
  EXPECT_DOUBLE_EQ(c.clips[0].end, 1.0);
  for (int v = 0; v < 4; ++v)
    for (int d = 0; d < 3; ++d) EXPECT_DOUBLE_EQ(c.vertices(d, v), kTetra[3 * v + d]);
  // LINEAR rotations are slerped: half way is 45 degrees; after the last key the pose holds.
  for (const auto& [t, angle] :
       std::vector<std::pair<double, double>>{{0.5, M_PI / 4}, {1.0, M_PI / 2}, {3.0, M_PI / 2}}) {
    const isochor::Points x = c.skinned(0, t);
    for (int v = 0; v < 4; ++v) EXPECT_LT((x.col(v) - rot_z(angle) * c.vertices.col(v)).norm(), 1e-6) << t;
  }
  EXPECT_NE(error_of([&] { c.find_clip("walk"); }).find("no animation \"walk\" (expected one of \"turn\""),
            std::string::npos);
}

// A chain root -> elbow (elbow 1 above the root), listed child first in the skin, with inverse
// bind matrices the inverses of the joints' rest globals. A vertex weighted half to each joint
// moves half way between the root's pose and the elbow's turn about its own pivot (0, 1, 0).
TEST(Gltf, TwoJointsBlendAboutTheirPivots) {
  GltfBuilder g;
  const int pos = g.floats({1, 2, 0, 0.5f, 1.5f, 0, 0, 0, 0, 0, 0, 1}, "VEC3");
  const int idx = g.add(std::vector<std::uint16_t>{0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2}, "SCALAR", 5123);
  // Skin index 0 is the elbow, 1 the root.
  const int joints = g.add(std::vector<std::uint16_t>{0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "VEC4", 5123);
  const int weights = g.floats({1, 0, 0, 0, 0.5f, 0.5f, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "VEC4");
  std::vector<float> ibm = identity_matrices(2);
  ibm[13] = -1;  // the elbow's inverse bind: a translation by (0, -1, 0), column-major
  const int ibm_acc = g.floats(ibm, "MAT4");
  const int times = g.floats({0, 2}, "SCALAR");
  const float s = static_cast<float>(std::sqrt(0.5));
  const int rot = g.floats({0, 0, 0, 1, 0, 0, s, s}, "VEC4");
  g.nodes = R"([{"mesh":0,"skin":0},{"name":"hip","children":[2]},{"name":"elbow","translation":[0,1,0]}])";
  g.scenes = "[{\"nodes\":[0,1]}]";
  g.skinned_mesh(pos, joints, weights, idx);
  g.skins = "[{\"joints\":[2,1],\"inverseBindMatrices\":" + std::to_string(ibm_acc) + "}]";
  g.one_channel_clip("bend", times, rot, 2, "rotation");
  const GltfCharacter c = read_gltf(g.write("chain.gltf"));
  ASSERT_EQ(c.joints.size(), 2u);
  EXPECT_EQ(c.joints[0].name, "hip");  // parents first, whatever the skin's order
  EXPECT_EQ(c.joints[1].name, "elbow");
  EXPECT_EQ(c.joints[1].parent, 0);
  EXPECT_EQ(c.vertex_joints[0][0], 1);  // skin index 0 (elbow) is joint 1 here
  const Eigen::Vector3d pivot(0, 1, 0);
  const isochor::Points x = c.skinned(0, 2.0);
  const Eigen::Vector3d turned = pivot + rot_z(M_PI / 2) * (c.vertices.col(0) - pivot);
  EXPECT_LT((x.col(0) - turned).norm(), 1e-6);
  const Eigen::Vector3d half = 0.5 * c.vertices.col(1) + 0.5 * (pivot + rot_z(M_PI / 2) * (c.vertices.col(1) - pivot));
  EXPECT_LT((x.col(1) - half).norm(), 1e-6);
  EXPECT_LT((x.col(2) - c.vertices.col(2)).norm(), 1e-12);  // all on the hip, which does not move
  // The elbow's global at t = 1 (45 degrees about its pivot) applied to (1, 0, 0) in its frame.
  const Eigen::Matrix4d G = c.node_globals(0, 1.0)[2];
  EXPECT_LT(((G * Eigen::Vector4d(1, 0, 0, 1)).head<3>() - (pivot + rot_z(M_PI / 4) * Eigen::Vector3d::UnitX())).norm(),
            1e-6);
}

// A scaled and translated root above the joint: the rest vertices are where a viewer draws them.
TEST(Gltf, RestVerticesAreSkinnedInWorldCoordinates) {
  GltfBuilder g = one_joint();
  g.nodes =
      R"([{"mesh":0,"skin":0},{"name":"root","scale":[2,2,2],"translation":[0,0,5],"children":[2]},{"name":"j"}])";
  g.skins = "[{\"joints\":[2],\"inverseBindMatrices\":4}]";
  g.animations.clear();
  const GltfCharacter c = read_gltf(g.write("scaled.gltf"));
  ASSERT_EQ(c.joints.size(), 1u);
  EXPECT_EQ(c.joints[0].name, "j");
  for (int v = 0; v < 4; ++v)
    EXPECT_LT((c.vertices.col(v) -
               (2 * Eigen::Vector3d(kTetra[3 * v], kTetra[3 * v + 1], kTetra[3 * v + 2]) + Eigen::Vector3d(0, 0, 5)))
                  .norm(),
              1e-6);
}

// CUBICSPLINE with the Hermite data of s^3 on [0, 1] (p0 = 0, m0 = 0, p1 = 1, m1 = 3) reproduces
// the cubic; STEP holds the earlier key.
TEST(Gltf, CubicAndStepSamplers) {
  GltfBuilder g = one_joint();
  const int times = g.floats({0, 1}, "SCALAR");
  // Per key: in-tangent, value, out-tangent (VEC3 each).
  const int cubic = g.floats({0, 0, 0, 0, 0, 0, 0, 0, 0, 3, 0, 0, 1, 0, 0, 0, 0, 0}, "VEC3");
  const int step = g.floats({0, 0, 0, 0, 0, 7}, "VEC3");
  g.nodes = R"([{"mesh":0,"skin":0},{"name":"root"},{"name":"other"}])";
  g.scenes = "[{\"nodes\":[0,1,2]}]";
  g.animations = "[{\"name\":\"move\",\"samplers\":[{\"input\":" + std::to_string(times) +
                 ",\"output\":" + std::to_string(cubic) +
                 ",\"interpolation\":\"CUBICSPLINE\"},{\"input\":" + std::to_string(times) +
                 ",\"output\":" + std::to_string(step) +
                 ",\"interpolation\":\"STEP\"}],\"channels\":[{\"sampler\":0,\"target\":{\"node\":1,\"path\":"
                 "\"translation\"}},{\"sampler\":1,\"target\":{\"node\":2,\"path\":\"translation\"}}]}]";
  const GltfCharacter c = read_gltf(g.write("cubic.gltf"));
  for (double t : {0.25, 0.5, 0.9}) {
    const auto G = c.node_globals(0, t);
    EXPECT_NEAR(G[1](0, 3), t * t * t, 1e-6) << t;
    EXPECT_NEAR(G[2](2, 3), 0.0, 1e-12) << t;
  }
  EXPECT_NEAR(c.node_globals(0, 1.0)[2](2, 3), 7.0, 1e-6);
  const std::vector<double> keys = c.clips[0].key_times();
  EXPECT_EQ(keys, (std::vector<double>{0, 1}));
}

// A sparse accessor moves one vertex; a triangle strip gives alternating windings; a mesh without
// a skin is placed by its node.
TEST(Gltf, SparseAccessorsStripsAndUnskinnedMeshes) {
  GltfBuilder g;
  const int sidx = g.add(std::vector<std::uint16_t>{3}, "SCALAR", 5123);
  const int sval = g.floats({0, 0, 4}, "VEC3");
  const int pos = g.floats(kTetra, "VEC3",
                           ",\"sparse\":{\"count\":1,\"indices\":{\"bufferView\":" + std::to_string(sidx) +
                               ",\"componentType\":5123},\"values\":{\"bufferView\":" + std::to_string(sval) + "}}");
  const int strip = g.add(std::vector<std::uint16_t>{0, 1, 2, 3}, "SCALAR", 5123);
  g.nodes = R"([{"mesh":0,"translation":[1,0,0]}])";
  g.meshes = "[{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(pos) +
             "},\"indices\":" + std::to_string(strip) + ",\"mode\":5}]}]";
  const GltfCharacter c = read_gltf(g.write("sparse.gltf"));
  EXPECT_TRUE(c.joints.empty());
  EXPECT_LT((c.vertices.col(3) - Eigen::Vector3d(1, 0, 4)).norm(), 1e-12);
  EXPECT_LT((c.vertices.col(1) - Eigen::Vector3d(2, 0, 0)).norm(), 1e-12);
  ASSERT_EQ(c.triangles.size(), 2u);
  EXPECT_EQ(c.triangles[0], (isochor::Tri{0, 1, 2}));
  EXPECT_EQ(c.triangles[1], (isochor::Tri{2, 1, 3}));
  EXPECT_EQ(c.skinned(-1, 0).cols(), 4);
}

// Each bad file: one line, naming the file and what is at fault.
TEST(Gltf, BadFilesStopWithOneLine) {
  auto expect_error = [](GltfBuilder g, const std::string& name, const std::string& expected) {
    const std::string file = g.write(name);
    const std::string e = error_of([&] { read_gltf(file); });
    EXPECT_NE(e.find(file), std::string::npos) << e;
    EXPECT_NE(e.find(expected), std::string::npos) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  };
  {  // an accessor longer than its view
    GltfBuilder g = one_joint();
    g.accessors[0].replace(g.accessors[0].find("\"count\":4"), 9, "\"count\":9");
    expect_error(g, "long.gltf",
                 "accessor 0 (mesh 0 primitive 0 POSITION): 9 elements run past the end of bufferView 0");
  }
  {  // counts a file cannot hold (found by fuzz.gltf: they were allocated before the check, so
     // 2^63 - 1 threw std::length_error and 2^31 hung filling 16 GB)
    for (const char* huge : {"9223372036854775807", "2147483648"}) {
      GltfBuilder g = one_joint();
      g.accessors[0].replace(g.accessors[0].find("\"count\":4"), 9, std::string("\"count\":") + huge);
      expect_error(g, "huge.gltf",
                   std::string("accessor 0 (mesh 0 primitive 0 POSITION): ") + huge +
                       " elements run past the end of bufferView 0");
    }
  }
  {  // an index past the vertices
    GltfBuilder g = one_joint();
    g.bin[48] = 9;  // the first index (the indices start after 48 bytes of positions)
    expect_error(g, "index.gltf", "mesh 0 primitive 0: index 9 is out of range (4 vertices)");
  }
  {  // a joint index past the skin
    GltfBuilder g = one_joint();
    g.bin[48 + 24] = 3;
    expect_error(g, "joint.gltf", "vertex 0 names joint 3, the skin has 1");
  }
  {  // key times that go back
    GltfBuilder g = one_joint();
    const int back = g.floats({1, 0}, "SCALAR");
    g.animations.replace(g.animations.find("\"input\":5"), 9, "\"input\":" + std::to_string(back));
    expect_error(g, "times.gltf", "animation \"turn\" channel 0: key times not increasing at key 1");
  }
  {  // a node that is its own grandparent
    GltfBuilder g = one_joint();
    g.nodes = R"([{"mesh":0,"skin":0},{"name":"root","children":[2]},{"children":[1]}])";
    expect_error(g, "cycle.gltf", "node 1: its parents form a cycle");
  }
  {  // not glTF at all
    const std::string file = isochor::test::write_file(isochor::test::temp_dir() / "text.gltf", "hello");
    const std::string e = error_of([&] { read_gltf(file); });
    EXPECT_NE(e.find(file + ": cannot be read as glTF"), std::string::npos) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  EXPECT_NE(error_of([] { read_gltf("/nonexistent/walk.glb"); }).find("/nonexistent/walk.glb"), std::string::npos);
}

}  // namespace

namespace {

// The unit cube's surface at `corner`, each face cut into n x n squares (two triangles each,
// outward), without the square `hole` of its top face (-1: none).
void add_cube(const Eigen::Vector3d& corner, int n, int hole, isochor::Points& x, std::vector<isochor::Tri>& tris) {
  std::vector<Eigen::Vector3d> p;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const Eigen::Vector3d u = Eigen::Vector3d::Unit((axis + 1) % 3), v = Eigen::Vector3d::Unit((axis + 2) % 3);
      const Eigen::Vector3d origin = corner + side * Eigen::Vector3d::Unit(axis);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          if (axis == 2 && side == 1 && i * n + j == hole) continue;
          const Eigen::Vector3d a = origin + (u * i + v * j) / n, b = a + u / n, c = a + (u + v) / n, d = a + v / n;
          const int base = static_cast<int>(x.cols() + p.size());
          p.insert(p.end(), {a, b, c, d});
          // u x v is the outward normal on the upper side (side 1): keep the order there.
          if (side == 1)
            tris.insert(tris.end(), {{base, base + 1, base + 2}, {base, base + 2, base + 3}});
          else
            tris.insert(tris.end(), {{base, base + 2, base + 1}, {base, base + 3, base + 2}});
        }
    }
  x.conservativeResize(3, x.cols() + static_cast<Eigen::Index>(p.size()));
  for (std::size_t k = 0; k < p.size(); ++k) x.col(x.cols() - static_cast<Eigen::Index>(p.size() - k)) = p[k];
}

}  // namespace

// An artist's soup: two unit cubes overlapping by half (self-intersecting), each with a 0.1 m
// square hole in its top (open), and a triangle from an edge into the inside (non-manifold: three
// triangles on one edge). The alpha wrap (alpha 0.2 closes the holes) is one closed, outward
// surface around the union, its vertices on the surface `offset` r = 0.01 outside it and its flat
// triangles inside that: its volume lies between the union's (1.5 x 1 x 1) and Steiner's formula
// for the box grown by r, V + A r + (pi/4) L r^2 + (4 pi/3) r^3 (A = 8, L = 14). Gmsh fills it.
// A soup of degenerate triangles has nothing to wrap: one line.
TEST(Wrap, OpenIntersectingNonManifoldSoupsBecomeOneClosedSurface) {
  isochor::Points x(3, 0);
  std::vector<isochor::Tri> tris;
  add_cube(Eigen::Vector3d::Zero(), 10, 55, x, tris);
  add_cube(Eigen::Vector3d(0.5, 0, 0), 10, 44, x, tris);
  x.conservativeResize(3, x.cols() + 1);
  x.col(x.cols() - 1) = Eigen::Vector3d(0.5, 0.5, 0.5);
  tris.push_back({tris[0][0], tris[0][1], static_cast<int>(x.cols() - 1)});
  isochor::Points wx;
  std::vector<isochor::Tri> wt;
  isochor::alpha_wrap(x, tris, 0.2, 0.01, wx, wt, "soup");
  const double V = isochor::surface_volume(wx, wt);
  const double r = 0.01, steiner = 1.5 + 8 * r + M_PI / 4 * 14 * r * r + 4 * M_PI / 3 * r * r * r;
  EXPECT_GT(V, 1.5);
  EXPECT_LT(V, steiner);
  const isochor::Mesh m = isochor::mesh_closed_surface(wx, wt, 0.25, "soup's wrap");
  isochor::test::expect_closed_outward(m);
  double tets = 0;
  for (int e = 0; e < m.num_tets(); ++e) tets += m.rest_volumes()[e];
  EXPECT_NEAR(tets, V, 1e-9 * V);
  isochor::Points flat(3, 3);
  flat << 0, 1, 2, 0, 0, 0, 0, 0, 0;  // three points on a line
  const std::string e = error_of([&] { isochor::alpha_wrap(flat, {{0, 1, 2}}, 0.2, 0.01, wx, wt, "flat.glb"); });
  EXPECT_EQ(e.rfind("flat.glb: ", 0), 0u) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

// The demo character as tools/make_character.py makes it: 21 joints, parents first, the clips
// "walk" (1 s) and "jump" (1.5 s), normalised weights. Its walk keeps the lower foot's ankle at its
// rest height by sinking the hips: at 0.3 s (a key) the left thigh is 20 sin(0.6 pi) degrees
// forward and straight, the right one as far back with its knee bent, so the left ankle is on the
// ground's level (y = 0.08) and 0.84 sin(theta) ahead of the hip (the generator's formulas).
TEST(Gltf, TheDemoCharacterReadsAsItsScriptMadeIt) {
  const GltfCharacter c = read_gltf(std::string(ISOCHOR_SOURCE_DIR) + "/demos/meshes/character.glb");
  ASSERT_EQ(c.joints.size(), 21u);
  EXPECT_EQ(c.joints[0].name, "hips");
  EXPECT_EQ(c.joints[0].parent, -1);
  for (std::size_t j = 1; j < c.joints.size(); ++j) EXPECT_LT(c.joints[j].parent, static_cast<int>(j));
  EXPECT_EQ(c.vertices.cols(), 3058);
  EXPECT_EQ(c.triangles.size(), 6048u);
  for (const Eigen::Vector4d& w : c.vertex_weights) EXPECT_NEAR(w.sum(), 1.0, 1e-6);
  ASSERT_EQ(c.clips.size(), 2u);
  const int walk = c.find_clip("walk"), jump = c.find_clip("jump");
  EXPECT_NEAR(c.clips[walk].end - c.clips[walk].start, 1.0, 1e-6);
  EXPECT_NEAR(c.clips[jump].end - c.clips[jump].start, 1.5, 1e-6);
  int foot = -1;
  for (std::size_t j = 0; j < c.joints.size(); ++j)
    if (c.joints[j].name == "foot_l") foot = c.joints[j].node;
  ASSERT_GE(foot, 0);
  const double theta = 20 * std::sin(0.6 * M_PI) * M_PI / 180;
  const Eigen::Vector3d ankle = c.node_globals(walk, 0.3)[foot].topRightCorner<3, 1>();
  EXPECT_NEAR(ankle.x(), 0.10, 1e-6);
  EXPECT_NEAR(ankle.y(), 0.08, 1e-5);
  EXPECT_NEAR(ankle.z(), 0.84 * std::sin(theta), 1e-5);
}
