// glTF 2.0 characters (.glb or .gltf, read with tinygltf): the triangles of the default scene's
// meshes, their skin (joint hierarchy, inverse bind matrices, four weights per vertex) and the
// animation clips that move the joints. Every accessor is checked against its buffer view and
// buffer before it is read (sparse accessors included); a bad file stops with one line naming the
// file and the accessor, node, skin or animation at fault.
//
// Poses: G_j(t) is joint j's global transform in a clip at time t (the node hierarchy with the
// clip's channels, the nodes' own TRS where a clip has none); the skinning matrix is
// M_j(t) = G_j(t) IBM_j. The rest pose is the nodes' own TRS (no clip), and the rest vertices are
// the skinned vertices there, in world coordinates, so that a character whose bind pose is not its
// rest pose, or whose root is scaled or turned, still starts where a glTF viewer draws it.
#pragma once
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "isochor/core/mesh.hpp"

namespace isochor {

struct GltfJoint {
  std::string name;
  int parent = -1;  // index of the parent joint in GltfCharacter::joints; -1: none of the skin's
  int node = -1;    // the glTF node
  Eigen::Matrix4d inverse_bind = Eigen::Matrix4d::Identity();
};

struct GltfClip {
  std::string name;
  double start = 0, end = 0;  // s: the earliest and latest key of its channels
  struct Channel {
    int node = -1;
    enum class Path { translation, rotation, scale } path = Path::translation;
    enum class Interpolation { linear, step, cubic } interpolation = Interpolation::linear;
    std::vector<double> times;
    std::vector<double> values;  // per key: 3 or 4 components; cubic: in-tangent, value, out-tangent
  };
  std::vector<Channel> channels;
  // Every key time of the clip's channels, sorted and unique.
  std::vector<double> key_times() const;
};

struct GltfCharacter {
  std::string path;
  Points vertices;  // rest pose, world coordinates (skinned where the mesh has a skin)
  std::vector<Tri> triangles;
  std::vector<std::array<int, 4>> vertex_joints;  // indices into joints (empty without a skin)
  std::vector<Eigen::Vector4d> vertex_weights;    // summing to 1
  std::vector<GltfJoint> joints;                  // parents before children
  std::vector<GltfClip> clips;

  // The clip named `name`, or numbered by it ("0", "1", ...); an Error naming the clips otherwise.
  int find_clip(const std::string& name) const;
  // Global transforms of every node at time t of clip `clip` (-1: the rest pose).
  std::vector<Eigen::Matrix4d> node_globals(int clip, double t) const;
  // M_j(t) = G_j(t) IBM_j for every joint.
  std::vector<Eigen::Matrix4d> skin_matrices(int clip, double t) const;
  // Linear blend skinning of the vertices at time t: sum_j w_j M_j(t) M_j(rest)^-1 x_rest.
  Points skinned(int clip, double t) const;

  // The node tree (for poses): each node's parent and rest TRS.
  struct Node {
    int parent = -1;
    Eigen::Vector3d translation = Eigen::Vector3d::Zero(), scale = Eigen::Vector3d::Ones();
    Eigen::Vector4d rotation = Eigen::Vector4d(0, 0, 0, 1);  // x, y, z, w (glTF's order)
    Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity();    // a node given by matrix (no TRS)
    bool has_matrix = false;
  };
  std::vector<Node> nodes;
  std::vector<int> node_order;  // parents before children
};

// Reads a .glb or .gltf file (external buffers relative to it; images are not read).
GltfCharacter read_gltf(const std::string& path);

}  // namespace isochor
