// Selections of nodes (for boundary conditions) and of tets (for zones), as written in a scene:
//   { kind = "all" }
//   { kind = "box", min = [x, y, z], max = [x, y, z] }      nodes inside; tets by centroid
//   { kind = "half_space", point = [..], normal = [..] }     (x - point) . normal >= 0
//   { kind = "surface" }                                     surface nodes; tets with a surface node
//   { kind = "indices", indices = [..] }                     explicit node or tet indices
//   { kind = "k_ring", node = i, k = 1 }                     graph k-ring of nodes; tets of Mesh::tet_ring
//   { kind = "set", name = ".." }                            a named node set or zone of the mesh
#pragma once
#include <string>
#include <vector>

#include "isochor/core/mesh.hpp"

namespace isochor {

class Section;

struct Selection {
  enum class Kind { all, box, half_space, cylinder, surface, indices, k_ring, set };
  Kind kind = Kind::all;
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitZ();  // half_space; cylinder axis
  double radius = 0.0, length = -1.0;  // cylinder (length < 0: unbounded along the axis)
  std::vector<int> indices;
  int node = 0;
  int k = 1;
  std::string name;
  std::string where;  // scene location, for messages

  static Selection parse(const Section& s);
};

// Sorted, unique. An empty result or an index out of range is an error naming `sel.where`.
std::vector<int> select_nodes(const Mesh& mesh, const Selection& sel);
std::vector<int> select_tets(const Mesh& mesh, const Selection& sel);

}  // namespace isochor
