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
#include "isochor/core/gltf.hpp"
#include "isochor/core/meshing.hpp"

namespace isochor {

namespace {

using KdTree = nanoflann::KDTreeEigenMatrixAdaptor<Points, 3, nanoflann::metric_L2_Simple, false>;

// The render mesh wrapped (CGAL's alpha wrap, `wrap_alpha` and `wrap_offset` in metres) and the
// wrap filled with tets of about `edge_length`.
Mesh wrap_and_fill(const Section& s, const GltfCharacter& c) {
  const Eigen::Vector3d extent = c.vertices.rowwise().maxCoeff() - c.vertices.rowwise().minCoeff();
  const double h = s.number("edge_length", extent.maxCoeff() / 25, Range::positive());
  check_size(s, "edge_length", h);
  const double alpha = s.number("wrap_alpha", h, Range::positive());
  const double offset = s.number("wrap_offset", alpha / 20, Range::positive());
  Points x;
  std::vector<Tri> tris;
  alpha_wrap(c.vertices, c.triangles, alpha, offset, x, tris, c.path);
  check_tets(s, "edge_length", gmsh_tets(std::abs(surface_volume(x, tris)), h));
  return mesh_closed_surface(x, std::move(tris), h, c.path + " (its alpha wrap)");
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

// A capsule kept `gap` radii clear of the joints it meets (its own origin where it has a parent,
// its children's origins), so that the tissue about a joint is free to bend rather than held by
// both bones: the segment cut at its ends, to a point where too short for both cuts, and the
// radius cut where a joint is still nearer than (1 + gap) radii.
void clear_joints(BoneSpec& b, bool at_from, const std::vector<Eigen::Vector3d>& joints, double gap) {
  const Eigen::Vector3d a = b.from, e = b.to;
  const double length = (e - a).norm(), clear = (1 + gap) * b.radius;
  const double cut_from = at_from ? clear : 0, cut_to = joints.empty() ? 0 : clear;
  if (cut_from + cut_to < length) {
    const Eigen::Vector3d u = (e - a) / length;
    b.from = a + cut_from * u;
    b.to = e - cut_to * u;
  } else {
    const double s = cut_from + cut_to > 0 ? cut_from / (cut_from + cut_to) : 0.5;
    b.from = b.to = a + s * (e - a);
  }
  double room = at_from ? b.segment_distance(a) : std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : joints) room = std::min(room, b.segment_distance(p));
  b.radius = std::max(0.0, std::min(b.radius, room / (1 + gap)));
}

// One bone per joint: its origin the joint's rest position, its capsule from there to the mean of
// its children's (a leaf's: to the centroid of the vertices it dominates), its radius `bone_radius`
// times the skin's thickness about it.
std::vector<BoneSpec> joint_bones(const Section& s, const GltfCharacter& c, const Mesh& mesh) {
  const double fraction = s.number("bone_radius", 0.5, Range::closed(0.0, 1.0));
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
  const double gap = s.number("joint_gap", 1.0, Range::non_negative());
  std::vector<std::vector<Eigen::Vector3d>> child_joints(bones.size());
  for (const BoneSpec& b : bones)
    if (b.parent >= 0) child_joints[b.parent].push_back(b.origin);
  for (std::size_t j = 0; j < bones.size(); ++j) clear_joints(bones[j], bones[j].parent >= 0, child_joints[j], gap);
  return bones;
}

// Each node within a capsule follows the bone it is deepest in.
void bind_nodes(std::vector<BoneSpec>& bones, const Mesh& mesh) {
  const Points& X = mesh.rest_positions();
  for (int v = 0; v < mesh.num_nodes(); ++v) {
    double best = 0;
    int which = -1;
    for (std::size_t b = 0; b < bones.size(); ++b) {
      if (bones[b].radius <= 0) continue;
      const double d = bones[b].segment_distance(X.col(v)) - bones[b].radius;
      if (d <= best) best = d, which = static_cast<int>(b);
    }
    if (which >= 0) bones[which].nodes.push_back(v);
  }
}

// The rotation nearest a matrix (its polar factor): a joint's scale is not its motion.
Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& A) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

// The scene times of the clip's keys: a blend from the rest pose over `blend_in` seconds, then the
// clip's keys, repeated to the run's end when `loop`.
std::vector<std::pair<double, double>> key_schedule(const Section& s, const GltfClip& clip, double duration) {
  const double blend = s.number("blend_in", 0.5, Range::non_negative());
  const bool loop = s.boolean("loop", true);
  const double length = clip.end - clip.start;
  std::vector<std::pair<double, double>> keys;  // scene time, clip time
  if (blend > 0) keys.emplace_back(0.0, std::numeric_limits<double>::quiet_NaN());
  const std::vector<double> taus = clip.key_times();
  for (int play = 0;; ++play) {
    const double start = blend + play * length;
    for (double tau : taus) {
      const double t = start + tau - clip.start;
      if (keys.empty() || t > keys.back().first + 1e-9) keys.emplace_back(t, tau);
    }
    if (!loop || length <= 0 || start + length >= duration) break;
  }
  if (keys.size() == 1) keys.emplace_back(keys[0].first + 1.0, keys[0].second);  // one key: held
  return keys;
}

// The bones' motion from the clip, sampled at its keys: each joint's rotation relative to its
// parent's as keyed quaternions; the root, and any joint whose offset from its parent moves, free.
void clip_motion(const Section& s, const GltfCharacter& c, int clip, double duration, std::vector<BoneSpec>& bones) {
  std::vector<Eigen::Matrix4d> rest_inv(c.joints.size());
  const std::vector<Eigen::Matrix4d> G0 = c.node_globals(-1, 0.0);
  for (std::size_t j = 0; j < c.joints.size(); ++j) rest_inv[j] = G0[c.joints[j].node].inverse();
  const auto keys = key_schedule(s, c.clips[clip], duration);
  std::vector<double> moved(bones.size(), 0.0);
  for (const auto& [t, tau] : keys) {
    const std::vector<Eigen::Matrix4d> G = std::isnan(tau) ? G0 : c.node_globals(clip, tau);
    std::vector<Eigen::Matrix3d> R(bones.size());
    std::vector<Eigen::Vector3d> p(bones.size());
    for (std::size_t j = 0; j < bones.size(); ++j) {
      const Eigen::Matrix4d& Gj = G[c.joints[j].node];
      R[j] = nearest_rotation((Gj * rest_inv[j]).topLeftCorner<3, 3>());
      p[j] = Gj.topRightCorner<3, 1>();
      BoneSpec& b = bones[j];
      const int a = b.parent;
      const Eigen::Matrix3d Rrel = a < 0 ? R[j] : Eigen::Matrix3d(R[a].transpose() * R[j]);
      Eigen::Quaterniond q(Rrel);
      Eigen::Vector4d v(q.w(), q.x(), q.y(), q.z());
      if (!b.key_quaternions.empty() && v.dot(b.key_quaternions.back()) < 0) v = -v;  // one sign along the keys
      b.key_times.push_back(t);
      b.key_quaternions.push_back(v);
      const Eigen::Vector3d d = a < 0
                                    ? Eigen::Vector3d(p[j] - b.origin)
                                    : Eigen::Vector3d(R[a].transpose() * (p[j] - p[a]) - (b.origin - bones[a].origin));
      b.translation.times.push_back(t);
      b.translation.values.push_back(d);
      moved[j] = std::max(moved[j], d.norm());
    }
  }
  const Eigen::Vector3d extent = c.vertices.rowwise().maxCoeff() - c.vertices.rowwise().minCoeff();
  for (std::size_t j = 0; j < bones.size(); ++j) {
    BoneSpec& b = bones[j];
    b.joint = b.parent < 0 || moved[j] > 1e-9 * extent.norm() ? BoneSpec::Joint::free : BoneSpec::Joint::ball;
    b.translation.kind = Driver::Kind::keyframes_cubic;
  }
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

Character parse_character(const Section& s, const SceneFile& file, double duration) {
  if (!s.has("file")) s.fail("file", "missing, expected a rigged glTF character (.glb or .gltf)");
  const GltfCharacter c = read_gltf(file.resolve_path(s.string("file", "")));
  if (c.joints.empty())
    s.fail("file", "\"" + s.string("file", "") + "\" has no skin (expected a mesh skinned to a skeleton of joints)");
  const std::string clip_name = s.string("clip", "");
  int clip = -1;
  if (!clip_name.empty()) {
    try {
      clip = c.find_clip(clip_name);
    } catch (const Error& e) {
      s.fail("clip", e.what());
    }
  }
  Character out;
  out.mesh = wrap_and_fill(s, c);
  region_zones(s, c, out.mesh);
  out.bones = joint_bones(s, c, out.mesh);
  if (clip >= 0) {
    clip_motion(s, c, clip, duration, out.bones);
  } else {
    for (BoneSpec& b : out.bones) b.joint = BoneSpec::Joint::weld;
  }
  bind_nodes(out.bones, out.mesh);
  prune_zones(out.mesh, out.bones);
  out.render = std::make_shared<RenderMesh>();
  out.render->source = c.path;
  out.render->rest = c.vertices;
  out.render->triangles = c.triangles;
  out.render->embedding = embed_points(out.mesh, c.vertices);
  return out;
}

}  // namespace isochor
