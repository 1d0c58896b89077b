#include "isochor/core/gltf.hpp"

#include <tiny_gltf.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>

#include "isochor/base/error.hpp"
#include "isochor/core/input_file.hpp"

namespace isochor {

namespace {

// A reader of one file's model, whose errors name the file.
struct Reader {
  const tinygltf::Model& m;
  const std::string& path;

  [[noreturn]] void fail(const std::string& what) const { throw Error(path + ": " + what); }

  // Accessor `index` as count x `components` doubles (normalized integers scaled to [0, 1] or
  // [-1, 1]); sparse substitutions applied. Every byte it reads is checked to lie in its buffer.
  std::vector<double> accessor(int index, const std::vector<int>& components, const std::string& use) const {
    const std::string where = "accessor " + std::to_string(index) + " (" + use + ")";
    if (index < 0 || index >= static_cast<int>(m.accessors.size()))
      fail(where + ": no such accessor (the file has " + std::to_string(m.accessors.size()) + ")");
    const tinygltf::Accessor& a = m.accessors[index];
    const int nc = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
    if (std::find(components.begin(), components.end(), nc) == components.end())
      fail(where + ": " + std::to_string(nc) + " components per element, expected " + std::to_string(components[0]));
    const int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
    if (size <= 0) fail(where + ": unknown componentType " + std::to_string(a.componentType));
    // The count is checked against the bytes that hold it before anything is allocated: a view's
    // elements must lie in it, and a sparse accessor without one (zeros but for its substitutions)
    // may not have more elements than the file's buffers have bytes.
    std::vector<double> out;
    if (a.bufferView >= 0) {
      const int given =
          a.bufferView < static_cast<int>(m.bufferViews.size()) ? a.ByteStride(m.bufferViews[a.bufferView]) : 0;
      const auto [data, stride] = view(a.bufferView, a.byteOffset, a.count, nc * size, given, where);
      out.assign(a.count * static_cast<std::size_t>(nc), 0.0);
      for (std::size_t e = 0; e < static_cast<std::size_t>(a.count); ++e)
        for (int c = 0; c < nc; ++c)
          out[e * nc + c] = component(data + e * stride + c * size, a.componentType, a.normalized);
    } else if (!a.sparse.isSparse) {
      fail(where + ": no bufferView and not sparse (expected data)");
    } else {
      std::size_t bytes = 0;
      for (const tinygltf::Buffer& b : m.buffers) bytes += b.data.size();
      if (a.count > bytes)
        fail(where + ": count " + std::to_string(a.count) + " without a bufferView, more elements than the file's " +
             "buffers have bytes (" + std::to_string(bytes) + ")");
      out.assign(a.count * static_cast<std::size_t>(nc), 0.0);
    }
    if (a.sparse.isSparse) sparse(a, nc, size, where, out);
    for (double v : out)
      if (!std::isfinite(v)) fail(where + ": a value that is not finite (NaN or infinite)");
    return out;
  }

  // The bytes of `count` elements of `element` bytes at `offset` in buffer view `bv`, `stride`
  // apart (stride < 0: the view's stride was invalid), after checking that they lie in the view
  // and the view in its buffer.
  std::pair<const unsigned char*, std::size_t> view(int bv, std::size_t offset, std::size_t count, int element,
                                                    int stride, const std::string& where) const {
    if (bv < 0 || bv >= static_cast<int>(m.bufferViews.size()))
      fail(where + ": bufferView " + std::to_string(bv) + " does not exist");
    const tinygltf::BufferView& v = m.bufferViews[bv];
    if (v.buffer < 0 || v.buffer >= static_cast<int>(m.buffers.size()))
      fail(where + ": bufferView " + std::to_string(bv) + " names buffer " + std::to_string(v.buffer) +
           ", which does not exist");
    const std::size_t buffer = m.buffers[v.buffer].data.size();
    if (v.byteOffset > buffer || v.byteLength > buffer - v.byteOffset)
      fail(where + ": bufferView " + std::to_string(bv) + " runs past the end of buffer " + std::to_string(v.buffer) +
           " (" + std::to_string(buffer) + " bytes)");
    if (stride < 0) fail(where + ": bufferView " + std::to_string(bv) + "'s byteStride is not a multiple of its type");
    const std::size_t s = stride > 0 ? static_cast<std::size_t>(stride) : static_cast<std::size_t>(element);
    if (count > 0 && (offset > v.byteLength || (count - 1) > (v.byteLength - offset) / s ||
                      (count - 1) * s + element > v.byteLength - offset))
      fail(where + ": " + std::to_string(count) + " elements run past the end of bufferView " + std::to_string(bv) +
           " (" + std::to_string(v.byteLength) + " bytes)");
    return {m.buffers[v.buffer].data.data() + v.byteOffset + offset, s};
  }

  void sparse(const tinygltf::Accessor& a, int nc, int size, const std::string& where, std::vector<double>& out) const {
    const int n = a.sparse.count;
    if (n < 1 || static_cast<std::size_t>(n) > a.count)
      fail(where + ": sparse count " + std::to_string(n) + ", expected 1 to the accessor's count");
    const int isize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.sparse.indices.componentType));
    if (isize <= 0 || a.sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT)
      fail(where + ": sparse indices of componentType " + std::to_string(a.sparse.indices.componentType) +
           ", expected an unsigned integer type");
    const auto [idx, istride] =
        view(a.sparse.indices.bufferView, a.sparse.indices.byteOffset, n, isize, isize, where + " sparse indices");
    const auto [val, vstride] =
        view(a.sparse.values.bufferView, a.sparse.values.byteOffset, n, nc * size, nc * size, where + " sparse values");
    for (int k = 0; k < n; ++k) {
      const double e = component(idx + k * istride, a.sparse.indices.componentType, false);
      if (e < 0 || e >= a.count)
        fail(where + ": sparse index " + std::to_string(static_cast<long>(e)) + " is out of range (count " +
             std::to_string(a.count) + ")");
      for (int c = 0; c < nc; ++c)
        out[static_cast<std::size_t>(e) * nc + c] =
            component(val + k * vstride + c * size, a.componentType, a.normalized);
    }
  }

  static double component(const unsigned char* p, int type, bool normalized) {
    auto get = [p](auto v) {
      std::memcpy(&v, p, sizeof v);
      return v;
    };
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return get(float{});
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? get(std::uint8_t{}) / 255.0 : get(std::uint8_t{});
      case TINYGLTF_COMPONENT_TYPE_BYTE:
        return normalized ? std::max(get(std::int8_t{}) / 127.0, -1.0) : get(std::int8_t{});
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return normalized ? get(std::uint16_t{}) / 65535.0 : get(std::uint16_t{});
      case TINYGLTF_COMPONENT_TYPE_SHORT:
        return normalized ? std::max(get(std::int16_t{}) / 32767.0, -1.0) : get(std::int16_t{});
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return get(std::uint32_t{});
      case TINYGLTF_COMPONENT_TYPE_INT:
        return get(std::int32_t{});
      default:
        return get(double{});
    }
  }
};

Eigen::Matrix4d trs(const Eigen::Vector3d& t, const Eigen::Vector4d& q, const Eigen::Vector3d& s) {
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  const Eigen::Quaterniond Q(q[3], q[0], q[1], q[2]);
  M.topLeftCorner<3, 3>() = Q.normalized().toRotationMatrix() * s.asDiagonal();
  M.topRightCorner<3, 1>() = t;
  return M;
}

// The nodes' parents and rest transforms, and an order with parents first; a node with two
// parents or a cycle is an error.
void read_nodes(const Reader& r, GltfCharacter& c) {
  const auto& nodes = r.m.nodes;
  c.nodes.resize(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const tinygltf::Node& n = nodes[i];
    GltfCharacter::Node& N = c.nodes[i];
    if (n.matrix.size() == 16) {
      N.has_matrix = true;
      for (int k = 0; k < 16; ++k) N.matrix(k % 4, k / 4) = n.matrix[k];
    }
    if (n.translation.size() == 3)
      N.translation = Eigen::Vector3d(n.translation[0], n.translation[1], n.translation[2]);
    if (n.rotation.size() == 4)
      N.rotation = Eigen::Vector4d(n.rotation[0], n.rotation[1], n.rotation[2], n.rotation[3]);
    if (n.scale.size() == 3) N.scale = Eigen::Vector3d(n.scale[0], n.scale[1], n.scale[2]);
    if (!N.matrix.allFinite() || !N.translation.allFinite() || !N.rotation.allFinite() || !N.scale.allFinite() ||
        (!N.has_matrix && N.rotation.norm() == 0))
      r.fail("node " + std::to_string(i) + ": a transform that is not finite or a zero rotation");
    for (int child : n.children) {
      if (child < 0 || child >= static_cast<int>(nodes.size()))
        r.fail("node " + std::to_string(i) + ": child " + std::to_string(child) + " does not exist");
      if (c.nodes[child].parent >= 0 || child == static_cast<int>(i))
        r.fail("node " + std::to_string(child) + ": has two parents (expected a tree)");
      c.nodes[child].parent = static_cast<int>(i);
    }
  }
  std::vector<int> depth(nodes.size(), -1);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    // Walk iteratively up to the first node whose depth is known, so that a deep chain does not
    // recurse: depths are filled from the top.
    std::vector<int> chain;
    for (int k = static_cast<int>(i); k >= 0 && depth[k] < 0; k = c.nodes[k].parent) {
      chain.push_back(k);
      if (chain.size() > nodes.size()) r.fail("node " + std::to_string(i) + ": its parents form a cycle");
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it)
      depth[*it] = c.nodes[*it].parent < 0 ? 0 : depth[c.nodes[*it].parent] + 1;
  }
  c.node_order.resize(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) c.node_order[i] = static_cast<int>(i);
  std::stable_sort(c.node_order.begin(), c.node_order.end(), [&](int a, int b) { return depth[a] < depth[b]; });
}

// The default scene's nodes (every node without a scene list).
std::vector<int> scene_nodes(const Reader& r, const GltfCharacter& c) {
  std::vector<char> in(c.nodes.size(), r.m.scenes.empty());
  if (!r.m.scenes.empty()) {
    const int s = r.m.defaultScene >= 0 ? r.m.defaultScene : 0;
    if (s >= static_cast<int>(r.m.scenes.size())) r.fail("scene " + std::to_string(s) + " does not exist");
    for (int root : r.m.scenes[s].nodes) {
      if (root < 0 || root >= static_cast<int>(c.nodes.size()))
        r.fail("scene " + std::to_string(s) + ": node " + std::to_string(root) + " does not exist");
      in[root] = 1;
    }
    for (int i : c.node_order)
      if (c.nodes[i].parent >= 0 && in[c.nodes[i].parent]) in[i] = 1;
  }
  std::vector<int> out;
  for (int i : c.node_order)
    if (in[i]) out.push_back(i);
  return out;
}

void read_skin(const Reader& r, int skin, GltfCharacter& c, std::vector<int>& joint_of_skin_index) {
  const tinygltf::Skin& s = r.m.skins[skin];
  const std::string where = "skin " + std::to_string(skin);
  if (s.joints.empty()) r.fail(where + ": has no joints");
  std::vector<int> joint_of_node(c.nodes.size(), -1);
  for (int node : s.joints) {
    if (node < 0 || node >= static_cast<int>(c.nodes.size()))
      r.fail(where + ": joint node " + std::to_string(node) + " does not exist");
    if (joint_of_node[node] >= 0) r.fail(where + ": node " + std::to_string(node) + " is listed twice");
    joint_of_node[node] = 0;
  }
  std::vector<double> ibm;
  if (s.inverseBindMatrices >= 0) {
    ibm = r.accessor(s.inverseBindMatrices, {16}, where + " inverseBindMatrices");
    if (ibm.size() != 16 * s.joints.size())
      r.fail(where + ": " + std::to_string(ibm.size() / 16) + " inverse bind matrices for " +
             std::to_string(s.joints.size()) + " joints");
  }
  // Joints in the node order (parents first), each with its nearest ancestor among the joints.
  std::vector<int> index_in_skin(c.nodes.size(), -1);
  for (std::size_t k = 0; k < s.joints.size(); ++k) index_in_skin[s.joints[k]] = static_cast<int>(k);
  joint_of_skin_index.assign(s.joints.size(), -1);
  for (int node : c.node_order) {
    if (index_in_skin[node] < 0) continue;
    GltfJoint j;
    j.node = node;
    j.name = r.m.nodes[node].name.empty() ? "joint" + std::to_string(c.joints.size()) : r.m.nodes[node].name;
    for (const GltfJoint& other : c.joints)
      if (other.name == j.name) r.fail(where + ": two joints named \"" + j.name + "\" (expected unique joint names)");
    for (int p = c.nodes[node].parent; p >= 0; p = c.nodes[p].parent)
      if (joint_of_node[p] >= 0) {
        j.parent = joint_of_node[p];
        break;
      }
    const int k = index_in_skin[node];
    if (!ibm.empty())
      for (int e = 0; e < 16; ++e) j.inverse_bind(e % 4, e / 4) = ibm[16 * k + e];
    if (std::abs(j.inverse_bind.topLeftCorner<3, 3>().determinant()) < 1e-12)
      r.fail(where + ": the inverse bind matrix of joint \"" + j.name + "\" is singular");
    joint_of_node[node] = static_cast<int>(c.joints.size());
    joint_of_skin_index[k] = static_cast<int>(c.joints.size());
    c.joints.push_back(j);
  }
}

// Triangles of one primitive: indexed or not, lists, strips and fans; points and lines give none.
std::vector<Tri> primitive_triangles(const Reader& r, const tinygltf::Primitive& p, int vertices,
                                     const std::string& where) {
  std::vector<int> idx;
  if (p.indices >= 0) {
    for (double v : r.accessor(p.indices, {1}, where + " indices")) {
      if (v < 0 || v >= vertices)
        r.fail(where + ": index " + std::to_string(static_cast<long>(v)) + " is out of range (" +
               std::to_string(vertices) + " vertices)");
      idx.push_back(static_cast<int>(v));
    }
  } else {
    for (int v = 0; v < vertices; ++v) idx.push_back(v);
  }
  std::vector<Tri> tris;
  const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
  const int n = static_cast<int>(idx.size());
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    if (n % 3) r.fail(where + ": " + std::to_string(n) + " indices, expected a multiple of 3 for triangles");
    for (int k = 0; k + 2 < n; k += 3) tris.push_back({idx[k], idx[k + 1], idx[k + 2]});
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (int k = 0; k + 2 < n; ++k)
      tris.push_back(k % 2 ? Tri{idx[k + 1], idx[k], idx[k + 2]} : Tri{idx[k], idx[k + 1], idx[k + 2]});
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (int k = 1; k + 1 < n; ++k) tris.push_back({idx[0], idx[k], idx[k + 1]});
  }
  tris.erase(std::remove_if(tris.begin(), tris.end(),
                            [](const Tri& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; }),
             tris.end());
  return tris;
}

// A skinned primitive's vertices at rest (linear blend of the joints' bind transforms, weights
// normalised), and their joints and weights kept on the character.
void skin_at_rest(const Reader& r, const std::string& where, const std::vector<double>& x, const std::vector<double>& J,
                  const std::vector<double>& W, const std::vector<int>& joint_of_skin_index,
                  const std::vector<Eigen::Matrix4d>& bind, GltfCharacter& c, std::vector<Eigen::Vector3d>& xs) {
  const int nv = static_cast<int>(x.size() / 3);
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector4d X(x[3 * v], x[3 * v + 1], x[3 * v + 2], 1.0);
    std::array<int, 4> jv{};
    Eigen::Vector4d wv;
    for (int k = 0; k < 4; ++k) {
      const double jk = J[4 * v + k];
      wv[k] = W[4 * v + k];
      if (wv[k] < 0) r.fail(where + ": vertex " + std::to_string(v) + " has a negative weight");
      if (jk < 0 || jk >= static_cast<double>(joint_of_skin_index.size()))
        r.fail(where + ": vertex " + std::to_string(v) + " names joint " + std::to_string(static_cast<long>(jk)) +
               ", the skin has " + std::to_string(joint_of_skin_index.size()));
      jv[k] = joint_of_skin_index[static_cast<std::size_t>(jk)];
    }
    if (!(wv.sum() > 0)) r.fail(where + ": vertex " + std::to_string(v) + " has weights summing to 0");
    wv /= wv.sum();
    Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
    for (int k = 0; k < 4; ++k) M += wv[k] * bind[jv[k]];
    xs.push_back((M * X).head<3>());
    c.vertex_joints.push_back(jv);
    c.vertex_weights.push_back(wv);
  }
}

// Every triangle primitive of the default scene's mesh nodes, skinned at rest (or moved by its
// node where the mesh has no skin). One skin at most.
void read_meshes(const Reader& r, GltfCharacter& c) {
  int skin = -1;
  std::vector<int> joint_of_skin_index;
  const std::vector<int> in_scene = scene_nodes(r, c);
  for (int node : in_scene)
    if (r.m.nodes[node].mesh >= 0 && r.m.nodes[node].skin >= 0) {
      const int s = r.m.nodes[node].skin;
      if (s >= static_cast<int>(r.m.skins.size()))
        r.fail("node " + std::to_string(node) + ": skin " + std::to_string(s) + " does not exist");
      if (skin >= 0 && s != skin)
        r.fail("node " + std::to_string(node) + ": a second skin (" + std::to_string(s) + " besides " +
               std::to_string(skin) + "), expected one skinned character");
      skin = s;
    }
  if (skin >= 0) read_skin(r, skin, c, joint_of_skin_index);
  const std::vector<Eigen::Matrix4d> rest = c.node_globals(-1, 0.0);
  std::vector<Eigen::Matrix4d> bind(c.joints.size());
  for (std::size_t j = 0; j < c.joints.size(); ++j) bind[j] = rest[c.joints[j].node] * c.joints[j].inverse_bind;
  std::vector<Eigen::Vector3d> xs;
  for (int node : in_scene) {
    const int mi = r.m.nodes[node].mesh;
    if (mi < 0) continue;
    if (mi >= static_cast<int>(r.m.meshes.size()))
      r.fail("node " + std::to_string(node) + ": mesh " + std::to_string(mi) + " does not exist");
    const bool skinned = r.m.nodes[node].skin >= 0;
    if (skin >= 0 && !skinned)
      r.fail("node " + std::to_string(node) + ": its mesh has no skin while skin " + std::to_string(skin) +
             " skins others (expected every mesh of a character skinned)");
    for (std::size_t pi = 0; pi < r.m.meshes[mi].primitives.size(); ++pi) {
      const tinygltf::Primitive& p = r.m.meshes[mi].primitives[pi];
      const std::string where = "mesh " + std::to_string(mi) + " primitive " + std::to_string(pi);
      const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
        continue;
      const auto pos = p.attributes.find("POSITION");
      if (pos == p.attributes.end()) r.fail(where + ": no POSITION attribute");
      const std::vector<double> x = r.accessor(pos->second, {3}, where + " POSITION");
      const int nv = static_cast<int>(x.size() / 3);
      std::vector<double> J, W;
      if (skinned) {
        const auto j = p.attributes.find("JOINTS_0"), w = p.attributes.find("WEIGHTS_0");
        if (j == p.attributes.end() || w == p.attributes.end())
          r.fail(where + ": skinned without JOINTS_0 and WEIGHTS_0");
        J = r.accessor(j->second, {4}, where + " JOINTS_0");
        W = r.accessor(w->second, {4}, where + " WEIGHTS_0");
        if (J.size() != x.size() / 3 * 4 || W.size() != J.size())
          r.fail(where + ": JOINTS_0 and WEIGHTS_0 have other counts than POSITION (" + std::to_string(nv) + ")");
      }
      const int base = static_cast<int>(xs.size());
      if (!skinned)
        for (int v = 0; v < nv; ++v)
          xs.push_back((rest[node] * Eigen::Vector4d(x[3 * v], x[3 * v + 1], x[3 * v + 2], 1)).head<3>());
      else
        skin_at_rest(r, where, x, J, W, joint_of_skin_index, bind, c, xs);
      for (Tri t : primitive_triangles(r, p, nv, where)) {
        for (int& k : t) k += base;
        c.triangles.push_back(t);
      }
    }
  }
  if (c.triangles.empty()) r.fail("no triangles in the default scene's meshes (expected a mesh to simulate)");
  c.vertices.resize(3, static_cast<Eigen::Index>(xs.size()));
  for (std::size_t v = 0; v < xs.size(); ++v) c.vertices.col(static_cast<Eigen::Index>(v)) = xs[v];
}

void read_animations(const Reader& r, GltfCharacter& c) {
  for (std::size_t a = 0; a < r.m.animations.size(); ++a) {
    const tinygltf::Animation& A = r.m.animations[a];
    GltfClip clip;
    clip.name = A.name.empty() ? std::to_string(a) : A.name;
    clip.start = std::numeric_limits<double>::infinity();
    clip.end = -clip.start;
    for (std::size_t ci = 0; ci < A.channels.size(); ++ci) {
      const tinygltf::AnimationChannel& ch = A.channels[ci];
      const std::string where = "animation \"" + clip.name + "\" channel " + std::to_string(ci);
      if (ch.target_path == "weights") continue;  // morph weights: not a joint's motion
      GltfClip::Channel C;
      if (ch.target_path == "translation")
        C.path = GltfClip::Channel::Path::translation;
      else if (ch.target_path == "rotation")
        C.path = GltfClip::Channel::Path::rotation;
      else if (ch.target_path == "scale")
        C.path = GltfClip::Channel::Path::scale;
      else
        r.fail(where + ": target path \"" + ch.target_path + "\", expected translation, rotation, scale or weights");
      if (ch.target_node < 0 || ch.target_node >= static_cast<int>(c.nodes.size()))
        r.fail(where + ": target node " + std::to_string(ch.target_node) + " does not exist");
      C.node = ch.target_node;
      if (ch.sampler < 0 || ch.sampler >= static_cast<int>(A.samplers.size()))
        r.fail(where + ": sampler " + std::to_string(ch.sampler) + " does not exist");
      const tinygltf::AnimationSampler& s = A.samplers[ch.sampler];
      if (s.interpolation == "STEP")
        C.interpolation = GltfClip::Channel::Interpolation::step;
      else if (s.interpolation == "CUBICSPLINE")
        C.interpolation = GltfClip::Channel::Interpolation::cubic;
      else if (s.interpolation != "LINEAR" && !s.interpolation.empty())
        r.fail(where + ": interpolation \"" + s.interpolation + "\", expected LINEAR, STEP or CUBICSPLINE");
      C.times = r.accessor(s.input, {1}, where + " input");
      if (C.times.empty()) r.fail(where + ": no keys");
      for (std::size_t k = 1; k < C.times.size(); ++k)
        if (!(C.times[k] > C.times[k - 1])) r.fail(where + ": key times not increasing at key " + std::to_string(k));
      const int nc = C.path == GltfClip::Channel::Path::rotation ? 4 : 3;
      C.values = r.accessor(s.output, {nc}, where + " output");
      const std::size_t per = C.interpolation == GltfClip::Channel::Interpolation::cubic ? 3 : 1;
      if (C.values.size() != C.times.size() * nc * per)
        r.fail(where + ": " + std::to_string(C.values.size() / nc) + " output values for " +
               std::to_string(C.times.size()) + " keys (expected " + std::to_string(C.times.size() * per) + ")");
      clip.start = std::min(clip.start, C.times.front());
      clip.end = std::max(clip.end, C.times.back());
      clip.channels.push_back(std::move(C));
    }
    if (clip.channels.empty()) clip.start = clip.end = 0;
    c.clips.push_back(std::move(clip));
  }
}

// Channel value at t (held outside its keys).
Eigen::Vector4d sample(const GltfClip::Channel& C, double t) {
  const int nc = C.path == GltfClip::Channel::Path::rotation ? 4 : 3;
  const bool cubic = C.interpolation == GltfClip::Channel::Interpolation::cubic;
  const int per = cubic ? 3 : 1;
  auto value = [&](std::size_t k, int part) {  // part: 0 in-tangent, 1 value, 2 out-tangent (cubic)
    Eigen::Vector4d v = Eigen::Vector4d::Zero();
    const std::size_t at = (k * per + (cubic ? part : 0)) * nc;
    for (int i = 0; i < nc; ++i) v[i] = C.values[at + i];
    return v;
  };
  const std::size_t n = C.times.size();
  if (t <= C.times.front()) return value(0, 1);
  if (t >= C.times.back()) return value(n - 1, 1);
  const std::size_t k =
      static_cast<std::size_t>(std::upper_bound(C.times.begin(), C.times.end(), t) - C.times.begin()) - 1;
  const double h = C.times[k + 1] - C.times[k], s = (t - C.times[k]) / h;
  Eigen::Vector4d v;
  if (C.interpolation == GltfClip::Channel::Interpolation::step) {
    v = value(k, 1);
  } else if (cubic) {
    const double s2 = s * s, s3 = s2 * s;
    v = (2 * s3 - 3 * s2 + 1) * value(k, 1) + h * (s3 - 2 * s2 + s) * value(k, 2) +
        (-2 * s3 + 3 * s2) * value(k + 1, 1) + h * (s3 - s2) * value(k + 1, 0);
  } else if (nc == 4) {
    const Eigen::Vector4d a = value(k, 1), b = value(k + 1, 1);
    const Eigen::Quaterniond qa(a[3], a[0], a[1], a[2]), qb(b[3], b[0], b[1], b[2]);
    const Eigen::Quaterniond q = qa.normalized().slerp(s, qb.normalized());
    v << q.x(), q.y(), q.z(), q.w();
  } else {
    v = (1 - s) * value(k, 1) + s * value(k + 1, 1);
  }
  if (nc == 4) v.normalize();
  return v;
}

}  // namespace

std::vector<double> GltfClip::key_times() const {
  std::vector<double> t;
  for (const Channel& c : channels) t.insert(t.end(), c.times.begin(), c.times.end());
  std::sort(t.begin(), t.end());
  t.erase(std::unique(t.begin(), t.end()), t.end());
  return t;
}

int GltfCharacter::find_clip(const std::string& name) const {
  std::string names;
  for (std::size_t k = 0; k < clips.size(); ++k) {
    if (clips[k].name == name || std::to_string(k) == name) return static_cast<int>(k);
    names += (k ? ", \"" : "\"") + clips[k].name + "\"";
  }
  throw Error(path + ": no animation \"" + name + "\" (" +
              (clips.empty() ? std::string("the file has none") : "expected one of " + names + " or its index") + ")");
}

std::vector<Eigen::Matrix4d> GltfCharacter::node_globals(int clip, double t) const {
  std::vector<Node> local = nodes;
  if (clip >= 0)
    for (const GltfClip::Channel& C : clips[clip].channels) {
      const Eigen::Vector4d v = sample(C, t);
      Node& N = local[C.node];
      if (C.path == GltfClip::Channel::Path::translation) N.translation = v.head<3>();
      if (C.path == GltfClip::Channel::Path::rotation) N.rotation = v;
      if (C.path == GltfClip::Channel::Path::scale) N.scale = v.head<3>();
      N.has_matrix = false;  // an animated node is given by TRS (glTF forbids animating a matrix node)
    }
  std::vector<Eigen::Matrix4d> G(nodes.size());
  for (int i : node_order) {
    const Node& N = local[i];
    const Eigen::Matrix4d L = N.has_matrix ? N.matrix : trs(N.translation, N.rotation, N.scale);
    G[i] = N.parent < 0 ? L : Eigen::Matrix4d(G[N.parent] * L);
  }
  return G;
}

std::vector<Eigen::Matrix4d> GltfCharacter::skin_matrices(int clip, double t) const {
  const std::vector<Eigen::Matrix4d> G = node_globals(clip, t);
  std::vector<Eigen::Matrix4d> M(joints.size());
  for (std::size_t j = 0; j < joints.size(); ++j) M[j] = G[joints[j].node] * joints[j].inverse_bind;
  return M;
}

Points GltfCharacter::skinned(int clip, double t) const {
  if (joints.empty()) return vertices;
  const std::vector<Eigen::Matrix4d> rest = skin_matrices(-1, 0.0), now = skin_matrices(clip, t);
  std::vector<Eigen::Matrix4d> A(joints.size());
  for (std::size_t j = 0; j < joints.size(); ++j) A[j] = now[j] * rest[j].inverse();
  Points x(3, vertices.cols());
  for (Eigen::Index v = 0; v < vertices.cols(); ++v) {
    Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
    for (int k = 0; k < 4; ++k) M += vertex_weights[v][k] * A[vertex_joints[v][k]];
    x.col(v) = (M * vertices.col(v).homogeneous()).head<3>();
  }
  return x;
}

GltfCharacter read_gltf(const std::string& path) {
  check_input_file(path, "a glTF character (.glb or .gltf)", input_limits::kSurface);
  tinygltf::TinyGLTF loader;
  // Images are not read: a character's textures do not move its tissue.
  loader.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                           void*) { return true; },
                        nullptr);
  tinygltf::Model model;
  std::string err, warn;
  std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
  const bool binary = ext == ".glb";
  const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                         : loader.LoadASCIIFromFile(&model, &err, &warn, path);
  if (!ok) {
    std::string line = err.empty() ? std::string("not a glTF file") : err;
    std::replace(line.begin(), line.end(), '\n', ' ');
    while (!line.empty() && line.back() == ' ') line.pop_back();
    throw Error(path + ": cannot be read as glTF (" + line + ")");
  }
  GltfCharacter c;
  c.path = path;
  const Reader r{model, path};
  read_nodes(r, c);
  read_meshes(r, c);
  read_animations(r, c);
  return c;
}

}  // namespace isochor
