// Rigged skeletons (Simbody bones driving mesh nodes): bound nodes follow the closed-form joint
// rotations, their velocities are the time derivatives of their positions, BVH files drive the
// joints, dg/dt of zones with bound nodes, and bad skeleton input.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "isochor/core/bvh.hpp"
#include "isochor/core/gltf.hpp"
#include "isochor/scene/mesh_system.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/core/paint.hpp"
#include "isochor/app/run.hpp"
#include "isochor/scene/scene.hpp"
#include "gltf_builder.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {

const double kDeg = M_PI / 180.0;

// Rodrigues' formula: the rotation by angle a about the unit axis k.
Eigen::Matrix3d rot(Eigen::Vector3d k, double a) {
  k.normalize();
  Eigen::Matrix3d K;
  K << 0, -k.z(), k.y(), k.z(), 0, -k.x(), -k.y(), k.x(), 0;
  return Eigen::Matrix3d::Identity() + std::sin(a) * K + (1 - std::cos(a)) * K * K;
}

const char* kBox = R"(
[mesh]
shape = "box"
size = [1.0, 1.0, 1.0]
cells = 4
center = [0.5, 0.5, 0.5]
[material]
model = "cnh"
mu = 1000.0
lambda = 1000.0
)";

Scene scene(const std::string& skeleton, const std::vector<std::string>& overrides = {}) {
  return parse_scene(SceneFile::parse(std::string(kBox) + skeleton, "skeleton.toml", overrides));
}

// Positions and velocities of every node at t (rest positions where nothing drives them).
void drive(const Scene& s, double t, Points& x, Eigen::VectorXd& v) {
  x = s.mesh.rest_positions();
  v = Eigen::VectorXd::Zero(3 * s.mesh.num_nodes());
  s.drive(t, x, &v);
}

// Velocities of the driven nodes against a central difference of their positions in time.
double velocity_error(const Scene& s, double t) {
  Points x, xp, xm;
  Eigen::VectorXd v, w;
  drive(s, t, x, v);
  const double h = 1e-6;
  drive(s, t + h, xp, w);
  drive(s, t - h, xm, w);
  double worst = 0;
  for (int n : s.driven_nodes())
    worst = std::max(worst, (v.segment<3>(3 * n) - (xp.col(n) - xm.col(n)) / (2 * h)).norm());
  return worst;
}

const char* kPinChain = R"(
[skeleton]
[[skeleton.bone]]
name = "root"
select = { kind = "box", min = [-0.1, -0.1, -0.1], max = [0.3, 1.1, 1.1] }
[[skeleton.bone]]
name = "mid"
parent = "root"
joint = "pin"
origin = [0.5, 0.5, 0.5]
axis = [1.0, 2.0, 2.0]
motion = "sinusoid"
amplitude = [70.0]
frequency = 0.7
phase = 0.3
select = { kind = "box", min = [0.45, -0.1, -0.1], max = [0.55, 1.1, 1.1] }
[[skeleton.bone]]
name = "tip"
parent = "mid"
joint = "pin"
origin = [0.75, 0.25, 0.5]
axis = [0.0, 0.0, 1.0]
motion = "keyframes"
times = [0.0, 0.5, 1.5]
angles = [0.0, 40.0, -30.0]
select = { kind = "box", min = [0.95, -0.1, -0.1], max = [1.1, 1.1, 1.1] }
)";

}  // namespace

TEST(Skeleton, PinChainFollowsTheClosedFormRotations) {
  const Scene s = scene(kPinChain);
  ASSERT_TRUE(s.skeleton);
  const auto& bones = s.skeleton->bones();
  ASSERT_EQ(bones.size(), 3u);
  EXPECT_EQ(bones[0].nodes.size(), 50u);  // the x = 0 and x = 0.25 planes of the 5x5x5 grid
  EXPECT_EQ(bones[1].nodes.size(), 25u);
  EXPECT_EQ(bones[2].nodes.size(), 25u);
  const Eigen::Vector3d o1(0.5, 0.5, 0.5), o2(0.75, 0.25, 0.5);
  const Points& X = s.mesh.rest_positions();
  for (double t : {0.02, 0.17, 0.8, 1.3}) {
    const double a1 = 70 * kDeg * std::sin(2 * M_PI * 0.7 * t + 0.3);
    const double a2 = t <= 0.5 ? 40 * kDeg * t / 0.5 : (40 + (t - 0.5) * (-70)) * kDeg;
    const Eigen::Matrix3d R1 = rot({1, 2, 2}, a1), R2 = rot({0, 0, 1}, a2);
    Points x;
    Eigen::VectorXd v;
    drive(s, t, x, v);
    double worst = 0;
    for (int n : bones[0].nodes) worst = std::max(worst, (x.col(n) - X.col(n)).norm());
    for (int n : bones[1].nodes) worst = std::max(worst, (x.col(n) - (o1 + R1 * (X.col(n) - o1))).norm());
    for (int n : bones[2].nodes)
      worst = std::max(worst, (x.col(n) - (o1 + R1 * (o2 - o1) + R1 * R2 * (X.col(n) - o2))).norm());
    EXPECT_LT(worst, 1e-12) << "t = " << t;
    EXPECT_LT(velocity_error(s, t), 1e-6) << "t = " << t;
  }
  // The root is welded: its nodes never move; the others do.
  Points x;
  Eigen::VectorXd v;
  drive(s, 0.8, x, v);
  EXPECT_GT(v.norm(), 0.1);
  // Repeated evaluation at one t is cached: one realization per distinct time.
  const long before = s.skeleton->realizations();
  drive(s, 0.8, x, v);
  EXPECT_EQ(s.skeleton->realizations(), before);
}

TEST(Skeleton, UniversalAndBallJointsComposeTheirAxisRotations) {
  const Scene s = scene(R"(
[skeleton]
[[skeleton.bone]]
name = "u"
joint = "universal"
origin = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
axis2 = [0.0, 1.0, 0.0]
motion = "keyframes"
times = [0.0, 1.0]
angles = [0.0, 0.0, 30.0, 60.0]
select = { kind = "box", min = [-0.1, -0.1, -0.1], max = [0.3, 1.1, 1.1] }
[[skeleton.bone]]
name = "b"
joint = "ball"
order = "ZXY"
origin = [1.0, 0.5, 0.5]
motion = "keyframes"
interpolation = "cubic"
times = [0.0, 1.0]
angles = [0.0, 0.0, 0.0, 90.0, 30.0, -45.0]
select = { kind = "box", min = [0.7, -0.1, -0.1], max = [1.1, 1.1, 1.1] }
)");
  const auto& bones = s.skeleton->bones();
  const Points& X = s.mesh.rest_positions();
  const Eigen::Vector3d ob(1.0, 0.5, 0.5);
  for (double t : {0.25, 0.5, 0.9}) {
    const Eigen::Matrix3d Ru = rot({1, 0, 0}, 30 * kDeg * t) * rot({0, 1, 0}, 60 * kDeg * t);
    // Two keyframes with zero end tangents: the cubic Hermite is the smoothstep 3t^2 - 2t^3.
    const double f = 3 * t * t - 2 * t * t * t;
    const Eigen::Matrix3d Rb =
        rot({0, 0, 1}, 90 * kDeg * f) * rot({1, 0, 0}, 30 * kDeg * f) * rot({0, 1, 0}, -45 * kDeg * f);
    Points x;
    Eigen::VectorXd v;
    drive(s, t, x, v);
    double worst = 0;
    for (int n : bones[0].nodes) worst = std::max(worst, (x.col(n) - Ru * X.col(n)).norm());
    for (int n : bones[1].nodes) worst = std::max(worst, (x.col(n) - (ob + Rb * (X.col(n) - ob))).norm());
    EXPECT_LT(worst, 1e-12) << "t = " << t;
    EXPECT_LT(velocity_error(s, t), 1e-6) << "t = " << t;
  }
}

TEST(Skeleton, CapsulesBindTheNearestBone) {
  const Scene s = scene(R"(
[skeleton]
[[skeleton.bone]]
name = "a"
origin = [0.0, 0.5, 0.5]
direction = [1.0, 0.0, 0.0]
length = 0.5
radius = 0.01
[[skeleton.bone]]
name = "b"
parent = "a"
joint = "pin"
axis = [0.0, 1.0, 0.0]
origin = [0.5, 0.5, 0.5]
length = 0.5
start = 0.25
radius = 0.3
)");
  const auto& bones = s.skeleton->bones();
  const Points& X = s.mesh.rest_positions();
  // a: the nodes on its axis segment (x = 0 .. 0.5 on the line y = z = 0.5) but the one at
  // x = 0.5, which lies deeper inside b's capsule (0.25 from b's segment, radius 0.3: 0.05 inside
  // against 0.01); b: every node within 0.3 of the segment x = 0.75 .. 1 on that line.
  EXPECT_EQ(bones[0].nodes.size(), 2u);
  for (int n : bones[0].nodes) EXPECT_NEAR((X.col(n) - Eigen::Vector3d(X(0, n), 0.5, 0.5)).norm(), 0.0, 1e-12);
  for (int n : bones[1].nodes) {
    const double s_ = std::clamp(X(0, n), 0.75, 1.0);
    EXPECT_LE((X.col(n) - Eigen::Vector3d(s_, 0.5, 0.5)).norm(), 0.3 + 1e-12);
  }
  int expected = 0;
  for (int n = 0; n < X.cols(); ++n)
    if ((X.col(n) - Eigen::Vector3d(std::clamp(X(0, n), 0.75, 1.0), 0.5, 0.5)).norm() <= 0.3) ++expected;
  EXPECT_EQ(static_cast<int>(bones[1].nodes.size()), expected);
  EXPECT_GT(expected, 0);
}

TEST(Skeleton, BvhFileDrivesTheJoints) {
  const auto dir = test::temp_dir();
  test::write_file(dir / "two.bvh", R"(HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Elbow
  {
    OFFSET 0.5 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0.5 0 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.5
0 0 0 0 0 0 0 0 0
0 0 0 10 0 0 45 0 0
0 0 0 20 0 0 90 0 30
)");
  const Bvh b = read_bvh((dir / "two.bvh").string());
  ASSERT_EQ(b.joints.size(), 2u);
  EXPECT_EQ(b.joints[1].parent, 0);
  EXPECT_EQ(b.joints[1].first_channel, 6);
  EXPECT_EQ(b.motion.rows(), 3);
  EXPECT_DOUBLE_EQ(b.motion(2, 8), 30.0);
  const std::string path = test::write_file(dir / "scene.toml", std::string(kBox) + R"(
[skeleton]
bvh = "two.bvh"
[[skeleton.bone]]
name = "hips"
joint = "ball"
motion = "bvh"
bvh_joint = "Hips"
select = { kind = "box", min = [-0.1, -0.1, -0.1], max = [0.3, 1.1, 1.1] }
[[skeleton.bone]]
name = "Elbow"
parent = "hips"
joint = "ball"
motion = "bvh"
origin = [0.5, 0.5, 0.5]
select = { kind = "box", min = [0.7, -0.1, -0.1], max = [1.1, 1.1, 1.1] }
)");
  const Scene s = load_scene(path);
  const auto& bones = s.skeleton->bones();
  const Points& X = s.mesh.rest_positions();
  const Eigen::Vector3d oe(0.5, 0.5, 0.5);
  // At the frame times the cubic keyframes pass through the file's angles: BVH's channel order
  // Z, X, Y is the body-fixed product R_Z R_X R_Y.
  const std::vector<std::pair<Eigen::Matrix3d, Eigen::Matrix3d>> expect = {
      {rot({0, 0, 1}, 10 * kDeg), rot({0, 0, 1}, 45 * kDeg)},
      {rot({0, 0, 1}, 20 * kDeg), rot({0, 0, 1}, 90 * kDeg) * rot({0, 1, 0}, 30 * kDeg)}};
  for (int f = 1; f <= 2; ++f) {
    const auto& [Rh, Re] = expect[f - 1];
    Points x;
    Eigen::VectorXd v;
    drive(s, 0.5 * f, x, v);
    double worst = 0;
    for (int n : bones[0].nodes) worst = std::max(worst, (x.col(n) - Rh * X.col(n)).norm());
    for (int n : bones[1].nodes) worst = std::max(worst, (x.col(n) - (Rh * oe + Rh * Re * (X.col(n) - oe))).norm());
    EXPECT_LT(worst, 1e-12) << "frame " << f;
  }
  EXPECT_LT(velocity_error(s, 0.7), 1e-6);
  // Errors name the file, line and what was expected.
  test::write_file(dir / "bad.bvh", "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Wrotation\n}\n");
  EXPECT_NE(test::error_of([&] { read_bvh((dir / "bad.bvh").string()); }).find("bad.bvh:5: expected a channel"),
            std::string::npos);
  test::write_file(dir / "short.bvh",
                   "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n}\n"
                   "MOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n4 5\n");
  EXPECT_NE(test::error_of([&] { read_bvh((dir / "short.bvh").string()); }).find("frame 1 has 2 values, expected 3"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] {
              load_scene(path, {"skeleton.bone=[{name=\"x\", joint=\"ball\", motion=\"bvh\", bvh_joint=\"Knee\"}]"});
            }).find("\"Knee\" is not a joint of the BVH file"),
            std::string::npos);
}

TEST(Skeleton, ZoneConstraintTimeDerivativeFollowsTheBones) {
  // dg/dt of the global zone with nodes bound to a moving bone: a central difference in time of
  // g at fixed free positions.
  Scene s = scene(kPinChain);
  MeshSystem sys(s);
  Eigen::VectorXd q, v;
  sys.initial_state(0.0, q, v);
  auto g_at = [&](double t) {
    Eigen::VectorXd g;
    sys.constraint(t, q, g);
    return g;
  };
  const double t = 0.4;
  std::vector<std::vector<double>> G;
  Eigen::VectorXd gt;
  sys.constraint_jacobian(t, q, G, &gt);
  const Eigen::VectorXd fd = (g_at(t + 1e-6) - g_at(t - 1e-6)) / 2e-6;
  EXPECT_LT((gt - fd).norm(), 1e-7 * (1 + fd.norm()));
  EXPECT_GT(fd.norm(), 1e-3);  // not vacuous
}

// A bar [0, 1] x [-0.2, 0.2]^2 skinned to joint "a" at (0.1, 0, 0) (the corners at x = 0) and its
// child "b" at (0.5, 0, 0) (the corners at x = 1); the clip "bend" turns b by 90 degrees about z and
// lifts a by 0.2 along z over its one second (LINEAR keys); the clip "carry" turns the root a by 90
// degrees about z at a steady rate and lifts it by 0.2 (keys at 0, 0.5 and 1 s): a rigid motion.
std::string bar_character(const std::string& name) {
  test::GltfBuilder g;
  std::vector<float> corners;
  std::vector<std::uint8_t> joints;
  std::vector<float> weights;
  for (int k = 0; k < 8; ++k) {
    const float x = (k & 1) ? 1.0f : 0.0f, y = (k & 2) ? 0.2f : -0.2f, z = (k & 4) ? 0.2f : -0.2f;
    corners.insert(corners.end(), {x, y, z});
    joints.insert(joints.end(), {static_cast<std::uint8_t>(k & 1), 0, 0, 0});
    weights.insert(weights.end(), {1, 0, 0, 0});
  }
  // The cube's 12 triangles, outward (vertex k has bits x, y, z).
  const std::vector<std::uint16_t> tris = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                           2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  const int pos = g.floats(corners, "VEC3");
  const int idx = g.add(tris, "SCALAR", 5123);
  const int jnt = g.add(joints, "VEC4", 5121);
  const int wgt = g.floats(weights, "VEC4");
  std::vector<float> ibm = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -0.1f, 0, 0, 1,
                            1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -0.5f, 0, 0, 1};
  const int ibm_acc = g.floats(ibm, "MAT4");
  const int times = g.floats({0, 1}, "SCALAR");
  const float h = static_cast<float>(std::sqrt(0.5));
  const int rot = g.floats({0, 0, 0, 1, 0, 0, h, h}, "VEC4");
  const int lift = g.floats({0.1f, 0, 0, 0.1f, 0, 0.2f}, "VEC3");
  g.nodes = R"([{"mesh":0,"skin":0},{"name":"a","translation":[0.1,0,0],"children":[2]},)"
            R"({"name":"b","translation":[0.4,0,0]}])";
  g.scenes = R"([{"nodes":[0,1]}])";
  g.skinned_mesh(pos, jnt, wgt, idx);
  g.skins = "[{\"joints\":[1,2],\"inverseBindMatrices\":" + std::to_string(ibm_acc) + "}]";
  g.animations = "[{\"name\":\"bend\",\"samplers\":[{\"input\":" + std::to_string(times) +
                 ",\"output\":" + std::to_string(rot) + "},{\"input\":" + std::to_string(times) +
                 ",\"output\":" + std::to_string(lift) +
                 "}],\"channels\":[{\"sampler\":0,\"target\":{\"node\":2,\"path\":\"rotation\"}},"
                 "{\"sampler\":1,\"target\":{\"node\":1,\"path\":\"translation\"}}]}";
  const int times3 = g.floats({0, 0.5f, 1}, "SCALAR");
  const float c = static_cast<float>(std::cos(M_PI / 8)), s = static_cast<float>(std::sin(M_PI / 8));
  const int turn = g.floats({0, 0, 0, 1, 0, 0, s, c, 0, 0, h, h}, "VEC4");
  const int rise = g.floats({0.1f, 0, 0, 0.1f, 0, 0.1f, 0.1f, 0, 0.2f}, "VEC3");
  g.animations += ",{\"name\":\"carry\",\"samplers\":[{\"input\":" + std::to_string(times3) +
                  ",\"output\":" + std::to_string(turn) + "},{\"input\":" + std::to_string(times3) +
                  ",\"output\":" + std::to_string(rise) +
                  "}],\"channels\":[{\"sampler\":0,\"target\":{\"node\":1,\"path\":\"rotation\"}},"
                  "{\"sampler\":1,\"target\":{\"node\":1,\"path\":\"translation\"}}]}]";
  return g.write(name);
}

Scene character_scene(const std::string& glb, const std::string& extra = "") {
  return parse_scene(
      SceneFile::parse("[character]\nfile = \"" + glb + "\"\nclip = \"bend\"\nedge_length = 0.08\n" +
                           "loop = false\n[material]\nmodel = \"cnh\"\nmu = 1000.0\nlambda = 1000.0\n" +
                           "[zones]\nfrom_mesh = true\nglobal = false\n[frames]\nrate = 10.0\nduration = 2.0\n" + extra,
                       "character.toml"));
}

// The bar character's bones after the half-second blend from rest and the one-second motion
// (t = 1.5 on): b's nodes turned by 90 degrees about z through its joint (0.5, 0, 0), every bound
// node lifted by 0.2 along z; at rest at t = 0.
void expect_bent_and_lifted(const Scene& s, double tolerance) {
  const auto& bones = s.skeleton->bones();
  const Points& X = s.mesh.rest_positions();
  const Eigen::Vector3d pivot(0.5, 0, 0), lift(0, 0, 0.2);
  for (double t : {0.0, 1.5, 1.9}) {
    Points x;
    Eigen::VectorXd v;
    drive(s, t, x, v);
    const double done = t >= 1.5 ? 1.0 : 0.0;
    double worst = 0;
    for (int n : bones[0].nodes) worst = std::max(worst, (x.col(n) - (X.col(n) + done * lift)).norm());
    for (int n : bones[1].nodes) {
      const Eigen::Vector3d turned = pivot + rot({0, 0, 1}, done * M_PI / 2) * (X.col(n) - pivot);
      worst = std::max(worst, (x.col(n) - (turned + done * lift)).norm());
    }
    EXPECT_LT(worst, tolerance) << "t = " << t;
  }
  for (double t : {0.3, 0.8, 1.2}) EXPECT_LT(velocity_error(s, t), 1e-5) << "t = " << t;
}

// The bones follow the clip: after the half-second blend from rest, the clip's end (t = 1.5)
// turns b's nodes by 90 degrees about its joint (0.5, 0, 0) and lifts every bound node by 0.2; the
// driven velocities are the time derivatives of the positions; the render mesh embedded in the
// tets is the input at rest; zones are the joints' regions.
TEST(Character, BonesFollowTheGltfClipAndTheRenderMeshIsEmbedded) {
  const Scene s = character_scene(bar_character("bar.gltf"));
  ASSERT_TRUE(s.skeleton);
  ASSERT_TRUE(s.render);
  const auto& bones = s.skeleton->bones();
  ASSERT_EQ(bones.size(), 2u);
  EXPECT_EQ(bones[0].name, "a");
  EXPECT_EQ(bones[1].parent, 0);
  EXPECT_FALSE(bones[0].nodes.empty());
  EXPECT_FALSE(bones[1].nodes.empty());
  expect_bent_and_lifted(s, 1e-6);  // glTF stores float32: sqrt(1/2) to 3e-8
  for (double t : {0.3, 0.8, 1.2}) EXPECT_LT(velocity_error(s, t), 1e-5) << "t = " << t;
  const Points at_rest = s.render->embedding.positions(s.mesh, s.mesh.rest_positions());
  EXPECT_LT((at_rest - s.render->rest).cwiseAbs().maxCoeff(), 1e-9);
  ASSERT_EQ(s.zones.size(), 2u);
  EXPECT_EQ(s.zones[0].first, "a");
  EXPECT_EQ(s.zones[1].first, "b");
  test::expect_closed_outward(s.mesh);
}

// End to end through the command line: a stiff bar character (mu = 1 MPa, no gravity, Kelvin-Voigt
// damping calming its 2.5 ms elastic modes) carried by its root over the clip "carry" from t = 0
// (no blend), then `isochor export --format glb`. (1) The .glb, read back by the reader, holds one
// mesh per frame equal (float32) to the render mesh carried by the frames' node positions, and its
// animation shows frame k alone between the run's times k and k + 1. (2) Nearly rigid tissue
// follows linear blend skinning, here a rigid motion: each render vertex is where the clip's
// skinning puts it at the clip's keys, to the elastic sag of the turning bar, rho a L^2 / mu ~ 1000 * 2.5 * 0.5^2 /
// 1e6 ~ 6e-4 m (a: the centripetal acceleration at the far end).
TEST(Character, RunExportsAGlbThatFollowsSkinning) {
  const std::string bar = bar_character("bar_run.gltf");
  const std::filesystem::path dir = std::filesystem::path(bar).parent_path();  // temp_dir() empties it
  const std::string body = "[character]\nfile = \"" + bar + "\"\nclip = \"carry\"\nedge_length = 0.08\n" +
                           "loop = false\nblend_in = 0.0\n[material]\nmodel = \"cnh\"\nmu = 1e6\nlambda = 1e6\n" +
                           "[damping]\nbeta = 0.01\n[zones]\nfrom_mesh = true\nglobal = false\n" +
                           "[frames]\nrate = 10.0\nduration = 1.5\n";
  const std::string toml =
      test::write_file(dir / "bar.toml", body + "[output]\npath = \"" + (dir / "bar.h5").string() + "\"\n");
  const std::string bin = ISOCHOR_BINARY, h5 = (dir / "bar.h5").string(), glb = (dir / "bar.glb").string();
  ASSERT_EQ(std::system((bin + " run " + toml + " --overwrite > /dev/null 2>&1").c_str()), 0);
  ASSERT_EQ(std::system((bin + " export " + h5 + " --format glb --out " + glb + " > /dev/null").c_str()), 0);
  const Scene s = parse_scene(SceneFile::parse(body, (dir / "again.toml").string()));
  const RunFile run(h5);
  const GltfCharacter out = read_gltf(glb);
  const GltfCharacter in = read_gltf(bar);
  const int F = run.num_frames(), V = static_cast<int>(s.render->rest.cols());
  ASSERT_EQ(F, 16);
  ASSERT_EQ(out.vertices.cols(), F * V);
  ASSERT_EQ(out.clips.size(), 1u);
  const std::vector<double> times = run.times();
  double worst_copy = 0, worst_skin = 0;
  for (int k = 0; k < F; ++k) {
    const Points x = s.render->embedding.positions(s.mesh, run.positions(k));
    worst_copy = std::max(worst_copy, (out.vertices.middleCols(k * V, V) - x).cwiseAbs().maxCoeff());
    const auto G = out.node_globals(0, times[k] - times[0] + 0.05);  // half way to the next frame
    for (int j = 0; j < F; ++j) EXPECT_NEAR(G[j](0, 0), j == k ? 1.0 : 0.0, 1e-12) << "frame " << k << " node " << j;
    // The bones pass through the clip's keys (and hold its last pose); between keys their C^1
    // cubic eases out of rest where the glTF interpolates linearly (drivers.hpp).
    const bool at_key = std::abs(times[k] - 0.5) < 1e-9 || times[k] > 1.0 - 1e-9;
    if (at_key) worst_skin = std::max(worst_skin, (x - in.skinned(1, times[k])).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_copy, 1e-6 * (1 + s.render->rest.cwiseAbs().maxCoeff()));
  EXPECT_LT(worst_skin, 1e-3) << worst_skin;
  EXPECT_GT((in.skinned(1, 1.0) - in.vertices).norm(), 0.2);  // not vacuous: the bar moved
}

// A character's mesh is Gmsh's fill of its wrap, which varies with the thread count: a run is
// resumed on the mesh its file holds. The run starts on another fill of the same scene (edge
// length 0.12 instead of 0.08: other nodes, as another thread count gives) and stops after frame
// 4; resumed with the scene as it fills now, it goes on with the file's mesh (it was refused: the
// meshes differ), and at the end its bone-bound nodes are where the bones put that mesh's nodes.
// Resumed with another scene text, it is refused as any run is, and the file keeps its frames.
TEST(Character, ARunIsResumedOnTheMeshItsFileHolds) {
  const std::string bar = bar_character("bar_resume.gltf");
  const std::string h5 = (std::filesystem::path(bar).parent_path() / "resume.h5").string();
  auto text_with = [](std::string text, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? text : text.replace(at, from.size(), to);
  };
  const std::string text = text_with(character_scene(bar).file.text_as_run(), "duration = 2.0", "duration = 0.8");
  const Scene s = parse_scene(SceneFile::parse(text, "character.toml"));
  const Scene coarse =
      parse_scene(SceneFile::parse(text_with(text, "edge_length = 0.08", "edge_length = 0.12"), "coarse.toml"));
  ASSERT_NE(coarse.mesh.num_nodes(), s.mesh.num_nodes());
  const Scene first = parse_scene(SceneFile::parse(text, "character.toml"), &coarse.mesh);
  RunOptions o;
  o.output = h5;
  o.on_frame = [](int k, const Frame&) { return k < 4; };
  EXPECT_THROW(run_scene(first, o), RunInterrupted);
  o.on_frame = nullptr;
  o.mode = OutputWriter::Mode::resume;
  {  // another scene text: not parsed on the file's mesh, but refused by the writer, the file kept
    const Scene other =
        parse_scene(SceneFile::parse(text_with(text, "duration = 0.8", "duration = 0.9"), "other.toml"));
    try {
      run_scene(other, o);
      ADD_FAILURE() << "resumed from another scene";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("was written from a different scene"), std::string::npos) << e.what();
    }
    EXPECT_EQ(RunFile(h5).num_frames(), 5);
  }
  const RunSummary r = run_scene(s, o);
  EXPECT_EQ(r.resumed_from, 4);
  const RunFile f(h5);
  ASSERT_EQ(f.num_frames(), 9);
  ASSERT_EQ(f.num_nodes(), coarse.mesh.num_nodes());
  Points x;
  Eigen::VectorXd v;
  drive(first, 0.8, x, v);
  const Points end = f.positions(8), X = f.rest_positions();
  double worst = 0, moved = 0;
  for (const BoneSpec& b : first.skeleton->bones())
    for (int n : b.nodes) {
      worst = std::max(worst, (end.col(n) - x.col(n)).norm());
      moved = std::max(moved, (x.col(n) - X.col(n)).norm());
    }
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(moved, 0.05);  // not vacuous: the bones have moved
}

// A BVH capture of the same motion as the clip "bend", in centimetres and with its own joint names:
// the root "Root" rises 20 cm, "Elbow" (its child, 40 cm along x) turns 90 degrees about z, keyed
// every half second. Mapped onto the bar by character.bvh_joints with bvh_scale = 0.01, the bones
// do what the glTF clip does (the bar's rest bone directions are the capture's: no retargeting).
// Where the capture's rest bones point elsewhere, the character's bones turn to point there.
TEST(Character, ABvhDrivesTheSkeletonByAJointNameMap) {
  const std::string bar = bar_character("bar_bvh.gltf");
  const std::filesystem::path dir = std::filesystem::path(bar).parent_path();
  test::write_file(dir / "bend.bvh",
                   "HIERARCHY\nROOT Root\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation "
                   "Xrotation Yrotation\n JOINT Elbow\n {\n  OFFSET 40 0 0\n  CHANNELS 3 Zrotation Xrotation "
                   "Yrotation\n  End Site\n  {\n   OFFSET 50 0 0\n  }\n }\n}\nMOTION\nFrames: 3\n"
                   "Frame Time: 0.5\n0 0 0 0 0 0 0 0 0\n0 0 10 0 0 0 45 0 0\n0 0 20 0 0 0 90 0 0\n");
  const std::string keys = "bvh = \"bend.bvh\"\nbvh_scale = 0.01\n";
  const std::string table = "[character.bvh_joints]\na = \"Root\"\nb = \"Elbow\"\n";
  auto scene_with = [&](const std::string& character_keys, const std::string& tables) {
    return parse_scene(SceneFile::parse("[character]\nfile = \"bar_bvh.gltf\"\nedge_length = 0.08\nloop = false\n" +
                                            character_keys + "[material]\nmodel = \"cnh\"\nmu = 1000.0\n" +
                                            "lambda = 1000.0\n[frames]\nrate = 10.0\nduration = 2.0\n" + tables,
                                        (dir / "bvh.toml").string(), {}, dir.string()));
  };
  expect_bent_and_lifted(scene_with(keys, table), 1e-9);
  // Retargeting: a capture whose Elbow hangs along +y at rest, standing still, turns the bar's a
  // (whose child lies along +x) by 90 degrees about z through its joint (0.1, 0, 0) to point there.
  test::write_file(
      dir / "still.bvh",
      "HIERARCHY\nROOT Root\n{\n OFFSET 0 0 0\n CHANNELS 3 Zrotation Xrotation Yrotation\n JOINT Elbow\n"
      " {\n  OFFSET 0 40 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 50 0\n"
      "  }\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.5\n0 0 0 0 0 0\n0 0 0 0 0 0\n");
  const Scene still = scene_with("bvh = \"still.bvh\"\n", table);
  Points x;
  Eigen::VectorXd v;
  drive(still, 1.0, x, v);
  const Points& X = still.mesh.rest_positions();
  const Eigen::Vector3d joint(0.1, 0, 0);
  double worst = 0;
  for (int n : still.skeleton->bones()[0].nodes)
    worst = std::max(worst, (x.col(n) - (joint + rot({0, 0, 1}, M_PI / 2) * (X.col(n) - joint))).norm());
  EXPECT_LT(worst, 1e-9);
  auto error = [&](const std::string& k, const std::string& t) { return test::error_of([&] { scene_with(k, t); }); };
  EXPECT_NE(error(keys, "[character.bvh_joints]\na = \"Hips\"\n")
                .find("character.bvh_joints.a: \"Hips\" is not a joint of bend.bvh"),
            std::string::npos);
  EXPECT_NE(error(keys, "[character.bvh_joints]\nhips = \"Root\"\n").find("character.bvh_joints.hips"),
            std::string::npos);
  EXPECT_NE(error(keys, "").find("character.bvh: no joint of the character is named in bend.bvh"), std::string::npos);
  EXPECT_NE(error(keys + "clip = \"bend\"\n", table).find("expected one motion: clip or bvh"), std::string::npos);
}

TEST(Character, BadInputNamesTheKey) {
  const std::string bar = bar_character("bar.gltf");
  EXPECT_NE(test::error_of([&] {
              character_scene(bar, "[mesh]\nshape = \"box\"\n");
            }).find("a [character] brings its own mesh and skeleton (expected no [mesh])"),
            std::string::npos);
  const std::string e = test::error_of(
      [&] { parse_scene(SceneFile::parse("[character]\nfile = \"" + bar + "\"\nclip = \"walk\"\n", "c.toml")); });
  EXPECT_NE(e.find("character.clip"), std::string::npos) << e;
  EXPECT_NE(e.find("no animation \"walk\" (expected one of \"bend\""), std::string::npos) << e;
  // Limits before the wrap: an alpha that would make tens of millions of triangles.
  const std::string a = test::error_of(
      [&] { parse_scene(SceneFile::parse("[character]\nfile = \"" + bar + "\"\nwrap_alpha = 1e-5\n", "c.toml")); });
  EXPECT_NE(a.find("character.wrap_alpha: the wrap's alpha"), std::string::npos) << a;
  EXPECT_NE(a.find("expected at least a 2000th of its size"), std::string::npos) << a;
}

TEST(Skeleton, BadInputNamesTheBoneAndWhatWasExpected) {
  auto err = [&](const std::string& text) { return test::error_of([&] { scene(text); }); };
  EXPECT_NE(err("[skeleton]\n[[skeleton.bone]]\nname = \"a\"\nparent = \"b\"\n")
                .find("skeleton.bone[0].parent: \"b\" is not a bone defined above"),
            std::string::npos);
  EXPECT_NE(err("[skeleton]\n[[skeleton.bone]]\nname = \"a\"\norigin = [5.0, 5.0, 5.0]\nradius = 0.1\n")
                .find("skeleton.bone[0].radius: bone \"a\" binds no mesh node"),
            std::string::npos);
  EXPECT_NE(
      err("[skeleton]\n[[skeleton.bone]]\nname = \"a\"\nmotion = \"sinusoid\"\n").find("a weld joint does not move"),
      std::string::npos);
  EXPECT_NE(err("[skeleton]\n[[skeleton.bone]]\nname = \"a\"\njoint = \"pin\"\nmotion = \"keyframes\"\ntimes = [0.0, "
                "1.0]\nangles = [1.0]\n")
                .find("skeleton.bone[0].angles: expected 1 angle (degrees) per keyframe time, 2 numbers in all, got 1"),
            std::string::npos);
  EXPECT_NE(
      err("[[boundary]]\nselect = { kind = \"set\", name = \"xmin\" }\n[skeleton]\n[[skeleton.bone]]\nname = \"a\"\n"
          "select = { kind = \"set\", name = \"xmin\" }\n")
          .find("is already driven by boundary[0]"),
      std::string::npos);
  EXPECT_NE(err("[skeleton]\n").find("a [skeleton] needs at least one [[skeleton.bone]]"), std::string::npos);
}

// The rigged arm (demos/arm_flex.toml) on a coarse mesh, to full flexion: CNH keeps every zone's
// volume at every frame; UNH (nu = 0.45, the same zones measured only) lets them drift; the
// volume squeezed out of the elbow's crease makes the biceps region bulge further with CNH.
namespace {
struct ArmResult {
  double worst_drift = 0;  // max over frames and zones of |V - V0| / V0
  double bulge = 0;        // largest outward displacement of the biceps region's surface at the last frame
};
ArmResult run_arm(const std::vector<std::string>& extra, const std::string& out, double duration = 1.0) {
  // The demo's own mesh: on coarser ones (edge 2-2.5 cm, two elements across the radius) the
  // folding crease reaches the biceps region and its largest displacement is the fold's, not a bulge.
  std::vector<std::string> o = {"frames.duration=" + std::to_string(duration), "frames.rate=10.0"};
  o.insert(o.end(), extra.begin(), extra.end());
  Scene sc = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/arm_flex.toml", o);
  const RunFile f(run_scene(sc, out, false).output);
  ArmResult r;
  const auto V = f.volumes();
  EXPECT_EQ(static_cast<int>(V.size()), static_cast<int>(std::lround(duration * 10)) + 1);
  for (const auto& v : V)
    for (std::size_t z = 1; z < v.size(); ++z) r.worst_drift = std::max(r.worst_drift, std::abs(v[z] / V[0][z] - 1));
  // Outward: away from the humerus' axis (the x axis; that bone is welded, so its axis stays).
  std::vector<char> in_biceps(sc.mesh.num_nodes(), 0), on_surface(sc.mesh.num_nodes(), 0);
  for (const auto& [name, tets] : sc.zones)
    if (name == "biceps")
      for (int e : tets)
        for (int n : sc.mesh.tets()[e]) in_biceps[n] = 1;
  for (const Tri& t : f.surface())
    for (int n : t) on_surface[n] = 1;
  const Points X = f.rest_positions(), x = f.positions(f.num_frames() - 1);
  for (int n = 0; n < X.cols(); ++n)
    if (in_biceps[n] && on_surface[n])
      r.bulge = std::max(r.bulge, x.col(n).tail<2>().norm() - X.col(n).tail<2>().norm());
  return r;
}
}  // namespace

// How deep the forearm's tissue (surface nodes at rest x >= 0.34 m, past the elbow's free
// tissue) is inside the upper arm's (tets and surface triangles whose corners are all at rest
// x <= 0.26 m) at frame k: for each such node inside such a deformed tet, its distance to the
// nearest such surface triangle; the deepest (0: none inside).
double forearm_in_upper_arm(const Mesh& mesh, const RunFile& f, int k) {
  const Points X = f.rest_positions(), x = f.positions(k);
  const auto& tets = mesh.tets();
  auto upper = [&](auto corners) {
    for (int n : corners)
      if (X(0, n) > 0.26) return false;
    return true;
  };
  std::vector<char> on_surface(X.cols(), 0);
  for (const Tri& t : f.surface())
    for (int n : t) on_surface[n] = 1;
  double deepest = 0;
  for (int p = 0; p < X.cols(); ++p) {
    if (!on_surface[p] || X(0, p) < 0.34) continue;
    bool inside = false;
    for (const Tet& t : tets) {
      if (!upper(t)) continue;
      Eigen::Matrix3d E;
      for (int c = 0; c < 3; ++c) E.col(c) = x.col(t[c + 1]) - x.col(t[0]);
      const Eigen::Vector3d l = E.partialPivLu().solve(x.col(p) - x.col(t[0]));
      if (l.minCoeff() >= 0 && l.sum() <= 1) {
        inside = true;
        break;
      }
    }
    if (!inside) continue;
    double d = std::numeric_limits<double>::infinity();
    for (const Tri& t : f.surface())
      if (upper(t))
        d = std::min(d, (x.col(p) - closest_on_triangle(x.col(p), x.col(t[0]), x.col(t[1]), x.col(t[2]))).norm());
    deepest = std::max(deepest, d);
  }
  return deepest;
}

// Label long (ctest -L long); the default suite keeps the zone volumes' check over the first
// 0.3 s of the flexion (CNH only).
// Contact between body parts at full flexion: without it the forearm's tissue passes centimetres
// into the upper arm's; with the demo's [contact.self] (k = 2e9 N/m^4 per area, delta = 5 mm) it
// stays out, its deepest point within the contact thickness, at every frame.
TEST(SkeletonLong, ArmFlexWithContactBetweenPartsKeepsTheForearmOut) {
  const auto dir = test::temp_dir();
  const std::vector<std::string> o = {"frames.duration=1.0", "frames.rate=10.0"};
  std::vector<std::string> off = o;
  off.push_back("contact.self.enabled=false");
  const Scene sc_on = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/arm_flex.toml", o);
  const Scene sc_off = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/arm_flex.toml", off);
  const RunFile with(run_scene(sc_on, (dir / "on.h5").string(), false).output);
  const RunFile without(run_scene(sc_off, (dir / "off.h5").string(), false).output);
  ASSERT_EQ(with.num_frames(), 11);
  double on = 0, through = 0;
  for (int k = 0; k < with.num_frames(); ++k) {
    on = std::max(on, forearm_in_upper_arm(sc_on.mesh, with, k));
    through = std::max(through, forearm_in_upper_arm(sc_off.mesh, without, k));
  }
  EXPECT_GT(through, 0.02);  // centimetres through without contact
  EXPECT_LE(on, 0.005);      // within the contact thickness with it
  std::printf("forearm into upper arm, deepest over the flexion: %.1f mm with contact, %.1f mm without\n", 1e3 * on,
              1e3 * through);
}

// The material's own bulge, without contact between parts (with it the forearm presses on the
// biceps region and decides its displacement).
TEST(SkeletonLong, ArmFlexKeepsZoneVolumesAndBulgesWithCnh) {
  const auto dir = test::temp_dir();
  const ArmResult cnh = run_arm({"contact.self.enabled=false"}, (dir / "cnh.h5").string());
  const ArmResult unh =
      run_arm({"contact.self.enabled=false", "material.model=unh", "material.lambda=27000", "zones.keep=false"},
              (dir / "unh.h5").string());
  EXPECT_LT(cnh.worst_drift, 1e-8);
  EXPECT_GT(unh.worst_drift, 1e-3);  // nu = 0.45 loses volume where the elbow squeezes it
  EXPECT_GT(cnh.bulge, unh.bulge);
  EXPECT_GT(cnh.bulge, 0.0);
  std::printf("arm to full flexion: CNH drift %.2e bulge %.4f m; UNH drift %.2e bulge %.4f m\n", cnh.worst_drift,
              cnh.bulge, unh.worst_drift, unh.bulge);
}

TEST(Skeleton, ArmStartingToFlexKeepsZoneVolumesWithCnh) {
  const auto dir = test::temp_dir();
  const ArmResult cnh = run_arm({}, (dir / "cnh.h5").string(), 0.3);
  EXPECT_LT(cnh.worst_drift, 1e-8);
}
