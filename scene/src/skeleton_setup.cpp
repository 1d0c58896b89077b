#include "isochor/scene/skeleton_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "isochor/base/error.hpp"
#include "isochor/core/bvh.hpp"
#include "isochor/core/selection.hpp"
#include "isochor/scene/scene.hpp"

namespace isochor {

namespace {

// Angles of a joint from a BVH joint's rotation channels: the axis order and keyframes (cubic,
// one per BVH frame), unwrapped so that no step between frames exceeds 180 degrees.
void bvh_motion(const Section& b, const Bvh& bvh, const std::string& joint, BoneSpec& bone) {
  const int j = bvh.find(joint);
  if (j < 0) b.fail("bvh_joint", "\"" + joint + "\" is not a joint of the BVH file");
  const BvhJoint& J = bvh.joints[j];
  std::vector<int> channels;
  std::string order;
  for (std::size_t c = 0; c < J.channels.size(); ++c) {
    const int ch = J.channels[c];
    if (ch < BvhJoint::Xrotation) continue;
    channels.push_back(static_cast<int>(c));
    bone.axes.col(static_cast<Eigen::Index>(order.size())) = Eigen::Vector3d::Unit(ch - BvhJoint::Xrotation);
    order += static_cast<char>('X' + (ch - BvhJoint::Xrotation));
  }
  if (channels.size() != 3)
    b.fail("bvh_joint", "\"" + joint + "\" has " + std::to_string(channels.size()) +
                            " rotation channels, expected 3 (a ball joint)");
  bone.motion = bvh_keyframes(bvh, J, channels, M_PI / 180.0);
}

Eigen::Vector3d unit(const Section& b, const std::string& key, const Eigen::Vector3d& fallback) {
  const Eigen::Vector3d v = b.vec3(key, fallback);
  if (v.norm() == 0) b.fail(key, "expected a non-zero vector");
  return v.normalized();
}

// The joint's kind and axes: weld (none), pin (axis), universal (axis, axis2 made orthogonal),
// ball (three body-fixed axes in `order`).
void parse_joint(const Section& b, BoneSpec& bone) {
  const std::string joint = b.string("joint");
  if (joint == "weld") {
    bone.joint = BoneSpec::Joint::weld;
  } else if (joint == "pin") {
    bone.joint = BoneSpec::Joint::pin;
    bone.angles = 1;
    bone.axes.col(0) = unit(b, "axis", Eigen::Vector3d::UnitZ());
  } else if (joint == "universal") {
    bone.joint = BoneSpec::Joint::universal;
    bone.angles = 2;
    bone.axes.col(0) = unit(b, "axis", Eigen::Vector3d::UnitX());
    const Eigen::Vector3d a2 = unit(b, "axis2", Eigen::Vector3d::UnitY());
    const Eigen::Vector3d y = a2 - a2.dot(bone.axes.col(0)) * bone.axes.col(0);
    if (y.norm() < 1e-6) b.fail("axis2", "expected a direction not parallel to axis");
    bone.axes.col(1) = y.normalized();
  } else {
    bone.joint = BoneSpec::Joint::ball;
    bone.angles = 3;
    const std::string order = b.string("order");
    if (order.size() != 3 || order.find_first_not_of("XYZ") != std::string::npos)
      b.fail("order", "expected three axis letters such as \"XYZ\" or \"ZXY\"");
    for (int k = 0; k < 3; ++k) bone.axes.col(k) = Eigen::Vector3d::Unit(order[k] - 'X');
  }
}

// The joint's angles over time: none, keyframes (degrees), a sinusoid, or a BVH joint's channels.
void parse_motion(const Section& s, const Section& b, const std::optional<Bvh>& bvh, BoneSpec& bone) {
  const std::string motion = b.string("motion", "none");
  if (motion != "none" && bone.joint == BoneSpec::Joint::weld)
    b.fail("motion", "a weld joint does not move (expected joint = \"pin\", \"universal\" or \"ball\")");
  const int n = bone.angles;
  const std::string per = std::to_string(n) + (n == 1 ? " angle" : " angles");
  if (motion == "keyframes") {
    bone.motion = parse_keyframes(b, "angles", n, M_PI / 180.0, per + " (degrees)");
  } else if (motion == "sinusoid") {
    const std::vector<double> amp = b.numbers("amplitude");
    if (static_cast<int>(amp.size()) != n) b.fail("amplitude", "expected " + per + " (degrees)");
    bone.motion.kind = Driver::Kind::sinusoid;
    for (int k = 0; k < n; ++k) bone.motion.vector[k] = amp[k] * M_PI / 180.0;
    bone.motion.frequency = b.number("frequency");
    bone.motion.phase = b.number("phase");
  } else if (motion == "bvh") {
    if (!bvh) s.fail("bvh", "missing, bone \"" + bone.name + "\" takes its motion from a BVH file");
    if (bone.joint != BoneSpec::Joint::ball)
      b.fail("joint", "motion = \"bvh\" drives ball joints (expected joint = \"ball\")");
    if (b.has("order")) b.fail("order", "comes from the BVH file's channels with motion = \"bvh\"");
    bvh_motion(b, *bvh, b.string("bvh_joint", bone.name), bone);
  }
}

// One [[skeleton.bone]]: its name and parent (an earlier bone), joint, motion, capsule and the
// nodes it lists by `select`.
BoneSpec parse_bone(const Section& s, const Section& b, const std::optional<Bvh>& bvh, const Mesh& mesh,
                    const std::map<std::string, int>& index) {
  BoneSpec bone;
  bone.name = b.string("name", "");
  if (bone.name.empty() || bone.name == "ground") b.fail("name", "missing, expected a bone name (not \"ground\")");
  if (index.count(bone.name)) b.fail("name", "bone \"" + bone.name + "\" is defined twice");
  const std::string parent = b.string("parent");
  if (parent != "ground") {
    auto it = index.find(parent);
    if (it == index.end())
      b.fail("parent", "\"" + parent + "\" is not a bone defined above (expected \"ground\" or an earlier bone)");
    bone.parent = it->second;
  }
  bone.origin = b.vec3("origin", Eigen::Vector3d::Zero());
  const Eigen::Vector3d direction = unit(b, "direction", Eigen::Vector3d::UnitX());
  double length = b.number("length", 0.0);
  const double start = b.number("start");
  if (start > length && b.has("start")) b.fail("start", "expected start <= length");
  bone.radius = b.number("radius", 0.0);
  parse_joint(b, bone);
  parse_motion(s, b, bvh, bone);
  if (Section sel = b.table("select"); sel.exists()) bone.nodes = select_nodes(mesh, Selection::parse(sel));
  length = std::max(length, start);
  bone.from = b.vec3("from", bone.origin + start * direction);
  bone.to = b.vec3("to", bone.origin + length * direction);
  if ((b.has("from") || b.has("to")) && (b.has("start") || b.has("length") || b.has("direction")))
    b.fail(b.has("from") ? "from" : "to",
           "give the capsule either by from and to or by direction, start and length, not both");
  return bone;
}

// Capsule attachment: each node within radius + attach_distance of some capsule goes to the
// nearest one (by distance beyond the radius). Explicit selections take precedence; a node is
// bound once and never to a bone and a [[boundary]] both.
void bind_nodes(const std::vector<Section>& sections, const Mesh& mesh, const std::vector<int>& driven_by,
                std::vector<BoneSpec>& bones) {
  std::vector<int> bound_to(mesh.num_nodes(), -1);
  for (std::size_t i = 0; i < bones.size(); ++i)
    for (int v : bones[i].nodes) {
      if (bound_to[v] >= 0)
        sections[i].fail("select",
                         "node " + std::to_string(v) + " is already bound to bone \"" + bones[bound_to[v]].name + "\"");
      bound_to[v] = static_cast<int>(i);
    }
  std::vector<double> attach(bones.size());
  std::vector<char> listed(bones.size());  // the bone's nodes are given by `select`
  for (std::size_t i = 0; i < bones.size(); ++i) {
    attach[i] = sections[i].number("attach_distance");
    listed[i] = sections[i].table("select").exists();
  }
  const Points& X = mesh.rest_positions();
  for (int v = 0; v < mesh.num_nodes(); ++v) {
    if (bound_to[v] >= 0) continue;
    double best = std::numeric_limits<double>::infinity();
    int which = -1;
    for (std::size_t i = 0; i < bones.size(); ++i) {
      if (bones[i].radius <= 0 || listed[i]) continue;
      const double d = bones[i].segment_distance(X.col(v)) - bones[i].radius;
      if (d <= attach[i] && d < best) best = d, which = static_cast<int>(i);
    }
    if (which >= 0) bound_to[v] = which, bones[which].nodes.push_back(v);
  }
  for (std::size_t i = 0; i < bones.size(); ++i) {
    std::sort(bones[i].nodes.begin(), bones[i].nodes.end());
    if ((bones[i].radius > 0 || listed[i]) && bones[i].nodes.empty())
      sections[i].fail(
          "radius",
          "bone \"" + bones[i].name +
              "\" binds no mesh node (expected its capsule, the segment from-to with this radius, to hold mesh nodes)");
    for (int v : bones[i].nodes)
      if (driven_by[v] >= 0)
        sections[i].fail(listed[i] ? "select" : "radius", "node " + std::to_string(v) + " of bone \"" + bones[i].name +
                                                              "\" is already driven by boundary[" +
                                                              std::to_string(driven_by[v]) +
                                                              "] (expected each node driven once)");
  }
}

}  // namespace

Driver bvh_keyframes(const Bvh& bvh, const BvhJoint& joint, const std::vector<int>& channels, double rotation_scale) {
  Driver d;
  d.kind = Driver::Kind::keyframes_cubic;
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (Eigen::Index f = 0; f < bvh.motion.rows(); ++f) {
    Eigen::Vector3d a = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < channels.size(); ++k) {
      a[k] = bvh.motion(f, joint.first_channel + channels[k]);
      if (joint.channels[channels[k]] < BvhJoint::Xrotation) continue;
      if (f > 0) a[k] -= 360.0 * std::round((a[k] - previous[k]) / 360.0);
    }
    previous = a;
    for (std::size_t k = 0; k < channels.size(); ++k)
      if (joint.channels[channels[k]] >= BvhJoint::Xrotation) a[k] *= rotation_scale;
    d.times.push_back(static_cast<double>(f) * bvh.frame_time);
    d.values.push_back(a);
  }
  if (d.times.size() == 1) {  // one frame: a constant
    d.times.push_back(bvh.frame_time);
    d.values.push_back(d.values.front());
  }
  return d;
}

std::shared_ptr<Skeleton> parse_skeleton(const Section& s, const SceneFile& file, const Mesh& mesh,
                                         const std::vector<int>& driven_by) {
  const std::vector<Section> bone_sections = s.tables("bone");
  if (!s.exists()) return nullptr;
  if (bone_sections.empty()) s.fail("bone", "missing, a [skeleton] needs at least one [[skeleton.bone]]");
  std::optional<Bvh> bvh;
  if (s.has("bvh")) bvh = read_bvh(file.resolve_path(s.string("bvh", "")));
  std::vector<BoneSpec> bones;
  std::map<std::string, int> index;
  for (const Section& b : bone_sections) {
    BoneSpec bone = parse_bone(s, b, bvh, mesh, index);
    index[bone.name] = static_cast<int>(bones.size());
    bones.push_back(std::move(bone));
  }
  bind_nodes(bone_sections, mesh, driven_by, bones);
  return std::make_shared<Skeleton>(std::move(bones));
}

}  // namespace isochor
