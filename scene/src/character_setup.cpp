#include "isochor/scene/character_setup.hpp"

#include <nanoflann.hpp>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>

#include "isochor/base/error.hpp"
#include "isochor/core/bvh.hpp"
#include "isochor/core/gltf.hpp"
#include "isochor/core/meshing.hpp"

namespace isochor {

namespace {

using KdTree = nanoflann::KDTreeEigenMatrixAdaptor<Points, 3, nanoflann::metric_L2_Simple, false>;

// The wrap's keys: edge_length, wrap_alpha and wrap_offset (m), checked before any work. An alpha
// below a 2000th of the character's size, or tets beyond memory by the soup's own enclosed volume
// (its parts counted where they overlap: an overestimate), stop here: the wrap's cost grows as the
// render mesh's area over alpha^2.
struct WrapSizes {
  double h, alpha, offset;
};
WrapSizes wrap_sizes(const Section& s, const GltfCharacter& c) {
  const Eigen::Vector3d extent = c.vertices.rowwise().maxCoeff() - c.vertices.rowwise().minCoeff();
  const double h = s.number("edge_length", extent.maxCoeff() / 25);
  check_size(s, "edge_length", h);
  const double alpha = s.number("wrap_alpha", h);
  const double offset = s.number("wrap_offset", alpha / 20);
  if (alpha < extent.norm() / 2000)
    s.fail(s.has("wrap_alpha") ? "wrap_alpha" : "edge_length",
           "the wrap's alpha: a " + std::to_string(alpha) + " m ball wraps a " + std::to_string(extent.norm()) +
               " m character into tens of millions of triangles (expected at least a 2000th of its size)");
  check_tets(s, "edge_length", gmsh_tets(std::abs(surface_volume(c.vertices, c.triangles)), h));
  return {h, alpha, offset};
}

// The render mesh wrapped (CGAL's alpha wrap) and the wrap filled with tets of about edge_length.
Mesh wrap_and_fill(const Section& s, const GltfCharacter& c) {
  const WrapSizes w = wrap_sizes(s, c);
  Points x;
  std::vector<Tri> tris;
  alpha_wrap(c.vertices, c.triangles, w.alpha, w.offset, x, tris, c.path);
  check_tets(s, "edge_length", gmsh_tets(std::abs(surface_volume(x, tris)), w.h));
  return mesh_closed_surface(x, std::move(tris), w.h, c.path + " (its alpha wrap)");
}

// Each tet's region: the joint with the largest skin weight at the render vertex nearest its
// centroid, or the region of character.regions that lists that joint (none: no zone).
void region_zones(const Section& s, const GltfCharacter& c, Mesh& mesh) {
  std::map<std::string, std::string> region_of;  // joint -> region
  const Section r = s.table("regions");
  if (r.exists()) {
    for (const std::string& region : r.keys())
      for (const std::string& joint : r.strings(region)) {
        if (std::none_of(c.joints.begin(), c.joints.end(), [&](const GltfJoint& j) { return j.name == joint; }))
          r.fail(region, "\"" + joint + "\" is not a joint of " + c.path);
        if (region_of.count(joint)) r.fail(region, "joint \"" + joint + "\" is in two regions");
        region_of[joint] = region;
      }
  } else {
    for (const GltfJoint& j : c.joints) region_of[j.name] = j.name;
  }
  KdTree tree(3, std::cref(c.vertices), 10);
  const Points& X = mesh.rest_positions();
  for (int e = 0; e < mesh.num_tets(); ++e) {
    const Tet& t = mesh.tets()[e];
    const Eigen::Vector3d m = 0.25 * (X.col(t[0]) + X.col(t[1]) + X.col(t[2]) + X.col(t[3]));
    Eigen::Index v = 0;
    double d2 = 0;
    tree.index->knnSearch(m.data(), 1, &v, &d2);
    int k = 0;
    c.vertex_weights[v].maxCoeff(&k);
    const auto it = region_of.find(c.joints[c.vertex_joints[v][k]].name);
    if (it != region_of.end()) mesh.zones[it->second].push_back(e);
  }
}

// How far each bone turns from its parent over its motion (rad): the largest angle of its keyed
// relative rotations (0 without motion).
double largest_turn(const BoneSpec& b) {
  double angle = 0;
  for (const Eigen::Vector4d& q : b.key_quaternions)
    angle = std::max(angle, 2 * std::acos(std::min(1.0, std::abs(q[0]))));
  return angle;
}

// A capsule kept clear of the joints it meets (its own origin where it has a parent, its
// children's origins), so that the tissue about a joint that bends is free to bend rather than
// held by both bones: its surface stays gap r sin(theta / 2) / sin(45 degrees) from a joint that
// turns by theta at most (gap radii at a right angle, nothing where the joint does not turn). The
// segment is cut at its ends (to a point where too short for both cuts) and the radius where a
// joint is still nearer.
void clear_joints(BoneSpec& b, double clear_from, const std::vector<std::pair<Eigen::Vector3d, double>>& joints) {
  const Eigen::Vector3d a = b.from, e = b.to;
  const double length = (e - a).norm();
  double clear_to = 0;
  for (const auto& [p, c] : joints) clear_to = std::max(clear_to, c);
  const double cut_from = clear_from >= 0 ? b.radius + clear_from : 0,
               cut_to = joints.empty() ? 0 : b.radius + clear_to;
  if (cut_from + cut_to < length) {
    const Eigen::Vector3d u = (e - a) / length;
    b.from = a + cut_from * u;
    b.to = e - cut_to * u;
  } else {
    const double s = cut_from + cut_to > 0 ? cut_from / (cut_from + cut_to) : 0.5;
    b.from = b.to = a + s * (e - a);
  }
  double room = clear_from >= 0 ? b.segment_distance(a) - clear_from : std::numeric_limits<double>::infinity();
  for (const auto& [p, c] : joints) room = std::min(room, b.segment_distance(p) - c);
  b.radius = std::max(0.0, std::min(b.radius, room));
}

// Every bone's capsule cleared (clear_joints) by its motion's turns.
void clear_all_joints(const Section& s, std::vector<BoneSpec>& bones) {
  const double gap = s.number("joint_gap");
  std::vector<double> clear(bones.size());
  for (std::size_t j = 0; j < bones.size(); ++j)
    clear[j] = gap * bones[j].radius * std::sin(largest_turn(bones[j]) / 2) / std::sin(M_PI / 4);
  std::vector<std::vector<std::pair<Eigen::Vector3d, double>>> children(bones.size());
  for (std::size_t j = 0; j < bones.size(); ++j)
    if (bones[j].parent >= 0) children[bones[j].parent].emplace_back(bones[j].origin, clear[j]);
  for (std::size_t j = 0; j < bones.size(); ++j)
    clear_joints(bones[j], bones[j].parent >= 0 ? clear[j] : -1.0, children[j]);
}

// One bone per joint: its origin the joint's rest position, its capsule from there to the mean of
// its children's (a leaf's: to the centroid of the vertices it dominates), its radius `bone_radius`
// times the skin's thickness about it.
std::vector<BoneSpec> joint_bones(const Section& s, const GltfCharacter& c, const Mesh& mesh) {
  const double fraction = s.number("bone_radius");
  const std::vector<Eigen::Matrix4d> G = c.node_globals(-1, 0.0);
  std::vector<BoneSpec> bones(c.joints.size());
  std::vector<int> children(c.joints.size(), 0);
  for (std::size_t j = 0; j < c.joints.size(); ++j) {
    bones[j].name = c.joints[j].name;
    bones[j].parent = c.joints[j].parent;
    bones[j].origin = G[c.joints[j].node].topRightCorner<3, 1>();
    bones[j].from = bones[j].to = bones[j].origin;
  }
  std::vector<Eigen::Vector3d> sum(c.joints.size(), Eigen::Vector3d::Zero());
  for (std::size_t j = 0; j < c.joints.size(); ++j)
    if (const int p = bones[j].parent; p >= 0) {
      sum[p] += bones[j].origin;
      ++children[p];
    }
  // A leaf: towards the centroid of the vertices it dominates (a hand, a head).
  std::vector<Eigen::Vector3d> leaf(c.joints.size(), Eigen::Vector3d::Zero());
  std::vector<int> dominated(c.joints.size(), 0);
  for (std::size_t v = 0; v < c.vertex_weights.size(); ++v) {
    int k = 0;
    c.vertex_weights[v].maxCoeff(&k);
    leaf[c.vertex_joints[v][k]] += c.vertices.col(static_cast<Eigen::Index>(v));
    ++dominated[c.vertex_joints[v][k]];
  }
  for (std::size_t j = 0; j < c.joints.size(); ++j) {
    if (children[j] > 0)
      bones[j].to = sum[j] / children[j];
    else if (dominated[j] > 0)
      bones[j].to = leaf[j] / dominated[j];
  }
  // The skin's thickness about the bone: the median, over five points along its segment, of the
  // distance to the nearest surface node (a leaf's segment may end at the skin).
  const Points& X = mesh.rest_positions();
  for (BoneSpec& b : bones) {
    std::array<double, 5> d;
    d.fill(std::numeric_limits<double>::infinity());
    for (int k = 0; k < 5; ++k) {
      const Eigen::Vector3d p = b.from + (b.to - b.from) * (k / 4.0);
      for (int n : mesh.surface_nodes()) d[k] = std::min(d[k], (X.col(n) - p).norm());
    }
    std::nth_element(d.begin(), d.begin() + 2, d.end());
    b.radius = fraction * d[2];
  }
  return bones;
}

// Each node within a capsule follows the bone it is deepest in. A bone whose capsule holds fewer
// than four nodes (a thin limb on a coarse mesh, a short bone cut back from its joints) takes the
// free nodes nearest its axis up to four, so that every bone moves the tissue about it.
void bind_nodes(std::vector<BoneSpec>& bones, const Mesh& mesh) {
  const Points& X = mesh.rest_positions();
  std::vector<int> owner(static_cast<std::size_t>(mesh.num_nodes()), -1);
  for (int v = 0; v < mesh.num_nodes(); ++v) {
    double best = 0;
    for (std::size_t b = 0; b < bones.size(); ++b) {
      if (bones[b].radius <= 0) continue;
      const double d = bones[b].segment_distance(X.col(v)) - bones[b].radius;
      if (d <= best) best = d, owner[static_cast<std::size_t>(v)] = static_cast<int>(b);
    }
  }
  constexpr int kAtLeast = 4;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    if (bones[b].radius <= 0) continue;
    const auto held = std::count(owner.begin(), owner.end(), static_cast<int>(b));
    std::vector<std::pair<double, int>> nearest;
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if (owner[static_cast<std::size_t>(v)] < 0) nearest.emplace_back(bones[b].segment_distance(X.col(v)), v);
    const auto more = std::min<std::ptrdiff_t>(kAtLeast - held, static_cast<std::ptrdiff_t>(nearest.size()));
    if (more <= 0) continue;
    std::partial_sort(nearest.begin(), nearest.begin() + more, nearest.end());
    for (std::ptrdiff_t k = 0; k < more; ++k) owner[static_cast<std::size_t>(nearest[k].second)] = static_cast<int>(b);
  }
  for (int v = 0; v < mesh.num_nodes(); ++v)
    if (owner[static_cast<std::size_t>(v)] >= 0) bones[owner[static_cast<std::size_t>(v)]].nodes.push_back(v);
}

// The rotation nearest a matrix (its polar factor): a joint's scale is not its motion.
Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& A) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

// The scene times of a motion's keys `taus` (the clip's or the BVH's own times, from `first` over
// `length` seconds): a blend from the rest pose over `blend_in` seconds, then the keys, repeated to
// the run's end when `loop`. A NaN motion time is the rest pose.
std::vector<std::pair<double, double>> key_schedule(const Section& s, const std::vector<double>& taus, double first,
                                                    double length, double duration) {
  const double blend = s.number("blend_in");
  const bool loop = s.boolean("loop", true);
  std::vector<std::pair<double, double>> keys;  // scene time, motion time
  if (blend > 0) keys.emplace_back(0.0, std::numeric_limits<double>::quiet_NaN());
  for (int play = 0;; ++play) {
    const double start = blend + play * length;
    for (double tau : taus) {
      const double t = start + tau - first;
      if (keys.empty() || t > keys.back().first + 1e-9) keys.emplace_back(t, tau);
    }
    if (!loop || length <= 0 || start + length >= duration) break;
  }
  if (keys.size() == 1) keys.emplace_back(keys[0].first + 1.0, keys[0].second);  // one key: held
  return keys;
}

// A pose of the joints: each one's rotation from its rest orientation (world frame) and its
// position.
struct Pose {
  std::vector<Eigen::Matrix3d> R;
  std::vector<Eigen::Vector3d> p;
};

// The bones' keyed motion from poses at scene times: each joint's rotation relative to its
// parent's as keyed quaternions, its offset from the parent as keyed translations; the root,
// and any joint whose offset moves, free joints, the others ball joints.
void keyed_motion(const std::vector<std::pair<double, Pose>>& poses, double size, std::vector<BoneSpec>& bones) {
  std::vector<double> moved(bones.size(), 0.0);
  for (const auto& [t, pose] : poses)
    for (std::size_t j = 0; j < bones.size(); ++j) {
      BoneSpec& b = bones[j];
      const int a = b.parent;
      const Eigen::Matrix3d Rrel = a < 0 ? pose.R[j] : Eigen::Matrix3d(pose.R[a].transpose() * pose.R[j]);
      Eigen::Quaterniond q(Rrel);
      Eigen::Vector4d v(q.w(), q.x(), q.y(), q.z());
      if (!b.key_quaternions.empty() && v.dot(b.key_quaternions.back()) < 0) v = -v;  // one sign along the keys
      b.key_times.push_back(t);
      b.key_quaternions.push_back(v);
      const Eigen::Vector3d d =
          a < 0 ? Eigen::Vector3d(pose.p[j] - b.origin)
                : Eigen::Vector3d(pose.R[a].transpose() * (pose.p[j] - pose.p[a]) - (b.origin - bones[a].origin));
      b.translation.times.push_back(t);
      b.translation.values.push_back(d);
      moved[j] = std::max(moved[j], d.norm());
    }
  for (std::size_t j = 0; j < bones.size(); ++j) {
    BoneSpec& b = bones[j];
    b.joint = b.parent < 0 || moved[j] > 1e-9 * size ? BoneSpec::Joint::free : BoneSpec::Joint::ball;
    b.translation.kind = Driver::Kind::keyframes_cubic;
  }
}

// The diagonal of the render mesh's bounding box (m): the scale a motion is compared with.
double character_size(const GltfCharacter& c) {
  return (c.vertices.rowwise().maxCoeff() - c.vertices.rowwise().minCoeff()).norm();
}

Pose rest_pose(const std::vector<BoneSpec>& bones) {
  Pose rest{std::vector<Eigen::Matrix3d>(bones.size(), Eigen::Matrix3d::Identity()), {}};
  for (const BoneSpec& b : bones) rest.p.push_back(b.origin);
  return rest;
}

// The bones' motion from a glTF clip, sampled at its keys.
void clip_motion(const Section& s, const GltfCharacter& c, int clip, double duration, std::vector<BoneSpec>& bones) {
  std::vector<Eigen::Matrix4d> rest_inv(c.joints.size());
  const std::vector<Eigen::Matrix4d> G0 = c.node_globals(-1, 0.0);
  for (std::size_t j = 0; j < c.joints.size(); ++j) rest_inv[j] = G0[c.joints[j].node].inverse();
  const GltfClip& C = c.clips[clip];
  std::vector<std::pair<double, Pose>> poses;
  for (const auto& [t, tau] : key_schedule(s, C.key_times(), C.start, C.end - C.start, duration)) {
    if (std::isnan(tau)) {
      poses.emplace_back(t, rest_pose(bones));
      continue;
    }
    const std::vector<Eigen::Matrix4d> G = c.node_globals(clip, tau);
    Pose pose;
    for (std::size_t j = 0; j < bones.size(); ++j) {
      const Eigen::Matrix4d& Gj = G[c.joints[j].node];
      pose.R.push_back(nearest_rotation((Gj * rest_inv[j]).topLeftCorner<3, 3>()));
      pose.p.push_back(Gj.topRightCorner<3, 1>());
    }
    poses.emplace_back(t, std::move(pose));
  }
  keyed_motion(poses, character_size(c), bones);
}

// A BVH joint's rotation at frame f: its rotation channels in file order, body-fixed
// (R = R_1 R_2 R_3), and its position channels (the offset where it has none).
void bvh_local(const Bvh& bvh, const BvhJoint& J, Eigen::Index f, Eigen::Matrix3d& R, Eigen::Vector3d& position) {
  R.setIdentity();
  position = J.offset;
  for (std::size_t k = 0; k < J.channels.size(); ++k) {
    const double value = bvh.motion(f, J.first_channel + static_cast<Eigen::Index>(k));
    const int c = J.channels[k];
    if (c >= BvhJoint::Xrotation)
      R = R * Eigen::AngleAxisd(value * M_PI / 180, Eigen::Vector3d::Unit(c - BvhJoint::Xrotation)).toRotationMatrix();
    else
      position[c] = value;
  }
}

// Each joint's BVH joint (-1: none, it turns with its parent): character.bvh_joints, or the
// joints' own names.
std::vector<int> bvh_map(const Section& s, const GltfCharacter& c, const Bvh& bvh, const std::string& file) {
  std::vector<int> map(c.joints.size(), -1);
  const Section m = s.table("bvh_joints");
  if (m.exists()) {
    for (const std::string& joint : m.keys()) {
      const auto it =
          std::find_if(c.joints.begin(), c.joints.end(), [&](const GltfJoint& j) { return j.name == joint; });
      if (it == c.joints.end()) m.fail(joint, "\"" + joint + "\" is not a joint of " + c.path);
      const std::string name = m.string(joint, "");
      map[static_cast<std::size_t>(it - c.joints.begin())] = bvh.find(name);
      if (bvh.find(name) < 0) m.fail(joint, "\"" + name + "\" is not a joint of " + file);
    }
  } else {
    for (std::size_t j = 0; j < c.joints.size(); ++j) map[j] = bvh.find(c.joints[j].name);
  }
  if (std::all_of(map.begin(), map.end(), [](int b) { return b < 0; }))
    s.fail("bvh", "no joint of the character is named in " + file +
                      " (expected character.bvh_joints, the character's joint names mapped to the file's)");
  return map;
}

// The bones' motion from a BVH file's frames, retargeted: a mapped joint turns so that its bone
// points where the BVH bone points (its world rotation from rest is the BVH joint's, times the
// rotation taking the character's rest bone direction to the BVH's rest bone direction, so that
// an A-pose character follows a T-pose capture); the root moves with the BVH root's position
// from its first frame, in metres by `bvh_scale`.
void bvh_motion(const Section& s, const SceneFile& file, const GltfCharacter& c, double duration,
                std::vector<BoneSpec>& bones) {
  const std::string path = file.resolve_path(s.string("bvh", ""));
  const Bvh bvh = read_bvh(path);
  const double scale = s.number("bvh_scale");
  const std::vector<int> map = bvh_map(s, c, bvh, s.string("bvh", ""));
  auto direction = [](const std::vector<Eigen::Vector3d>& to) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& v : to) d += v;
    return d;
  };
  std::vector<Eigen::Matrix3d> align(bones.size(), Eigen::Matrix3d::Identity());
  for (std::size_t j = 0; j < bones.size(); ++j) {
    if (map[j] < 0) continue;
    std::vector<Eigen::Vector3d> mine, theirs;
    for (const BoneSpec& b : bones)
      if (b.parent == static_cast<int>(j)) mine.push_back(b.origin - bones[j].origin);
    for (const BvhJoint& J : bvh.joints)
      if (J.parent == map[j]) theirs.push_back(J.offset);
    const Eigen::Vector3d a = direction(mine), b = direction(theirs);
    if (a.norm() > 0 && b.norm() > 0) align[j] = Eigen::Quaterniond::FromTwoVectors(a, b).toRotationMatrix();
  }
  std::vector<double> taus;
  for (Eigen::Index f = 0; f < bvh.motion.rows(); ++f) taus.push_back(static_cast<double>(f) * bvh.frame_time);
  const int root = map[0];
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  std::vector<std::pair<double, Pose>> poses;
  for (const auto& [t, tau] : key_schedule(s, taus, 0.0, taus.back(), duration)) {
    if (std::isnan(tau)) {
      poses.emplace_back(t, rest_pose(bones));
      continue;
    }
    const auto f = static_cast<Eigen::Index>(std::lround(tau / bvh.frame_time));
    std::vector<Eigen::Matrix3d> world(bvh.joints.size());
    Eigen::Vector3d root_at = Eigen::Vector3d::Zero();
    for (std::size_t b = 0; b < bvh.joints.size(); ++b) {
      Eigen::Matrix3d L;
      Eigen::Vector3d position;
      bvh_local(bvh, bvh.joints[b], f, L, position);
      world[b] = bvh.joints[b].parent < 0 ? L : Eigen::Matrix3d(world[bvh.joints[b].parent] * L);
      if (static_cast<int>(b) == root) root_at = position;
    }
    if (f == 0) start = root_at;
    Pose pose;
    for (std::size_t j = 0; j < bones.size(); ++j) {
      const int a = bones[j].parent;
      pose.R.push_back(map[j] >= 0 ? Eigen::Matrix3d(world[map[j]] * align[j])
                       : a < 0     ? Eigen::Matrix3d::Identity()
                                   : pose.R[a]);
      pose.p.push_back(a < 0 ? Eigen::Vector3d(bones[j].origin + scale * (root_at - start))
                             : Eigen::Vector3d(pose.p[a] + pose.R[a] * (bones[j].origin - bones[a].origin)));
    }
    poses.emplace_back(t, std::move(pose));
  }
  keyed_motion(poses, character_size(c), bones);
}

// Tets whose four nodes all follow bones move rigidly: their volume needs no constraint row (it
// would be a row of zeros). Zones keep their other tets; a zone left empty is dropped.
void prune_zones(Mesh& mesh, const std::vector<BoneSpec>& bones) {
  std::vector<char> bound(mesh.num_nodes(), 0);
  for (const BoneSpec& b : bones)
    for (int n : b.nodes) bound[n] = 1;
  for (auto it = mesh.zones.begin(); it != mesh.zones.end();) {
    std::vector<int>& tets = it->second;
    tets.erase(std::remove_if(tets.begin(), tets.end(),
                              [&](int e) {
                                const Tet& t = mesh.tets()[e];
                                return bound[t[0]] && bound[t[1]] && bound[t[2]] && bound[t[3]];
                              }),
               tets.end());
    it = tets.empty() ? mesh.zones.erase(it) : std::next(it);
  }
}

}  // namespace

Character parse_character(const Section& s, const SceneFile& file, double duration, const Mesh* filled) {
  if (!s.has("file")) s.fail("file", "missing, expected a rigged glTF character (.glb or .gltf)");
  const GltfCharacter c = read_gltf(file.resolve_path(s.string("file", "")));
  if (c.joints.empty())
    s.fail("file", "\"" + s.string("file", "") + "\" has no skin (expected a mesh skinned to a skeleton of joints)");
  const std::string clip_name = s.string("clip");
  if (!clip_name.empty() && s.has("bvh")) s.fail("bvh", "a clip is given too (expected one motion: clip or bvh)");
  int clip = -1;
  if (!clip_name.empty()) {
    try {
      clip = c.find_clip(clip_name);
    } catch (const Error& e) {
      s.fail("clip", e.what());
    }
  }
  Character out;
  if (filled) {
    wrap_sizes(s, c);  // its keys checked as for a wrap
    out.mesh = Mesh(filled->rest_positions(), filled->tets(), c.path + " (its mesh as run)");
  } else {
    out.mesh = wrap_and_fill(s, c);
  }
  region_zones(s, c, out.mesh);
  out.bones = joint_bones(s, c, out.mesh);
  if (clip >= 0) {
    clip_motion(s, c, clip, duration, out.bones);
  } else if (s.has("bvh")) {
    bvh_motion(s, file, c, duration, out.bones);
  } else {
    for (BoneSpec& b : out.bones) b.joint = BoneSpec::Joint::weld;
  }
  clear_all_joints(s, out.bones);
  bind_nodes(out.bones, out.mesh);
  prune_zones(out.mesh, out.bones);
  out.render = std::make_shared<RenderMesh>();
  out.render->source = c.path;
  out.render->rest = c.vertices;
  out.render->triangles = c.triangles;
  out.render->embedding = embed_points(out.mesh, c.vertices);
  out.render->skin_bones = c.vertex_joints;  // one bone per joint, in the joints' order
  out.render->skin_weights = c.vertex_weights;
  return out;
}

}  // namespace isochor
