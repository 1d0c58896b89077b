// Points carried by a tet mesh (an artist's render mesh inside the simulation mesh): each point has
// a tet and its barycentric weights there, so that it moves as x = sum_k w_k x_{tet node k}, an
// affine map of the tet's nodes. A point inside the mesh lies in its tet (weights in [0, 1]); one
// outside takes the nearest tet and extrapolates its affine map.
#pragma once

#include <array>
#include <Eigen/Core>
#include <string>
#include <vector>

#include "isochor/core/mesh.hpp"

namespace isochor {

struct Embedding {
  std::vector<int> tet;      // per point
  Eigen::Matrix4Xd weights;  // 4 x points, summing to 1
  // The points where the mesh's nodes are at x.
  Points positions(const Mesh& mesh, const Points& x) const;
};

Embedding embed_points(const Mesh& mesh, const Points& p);

// An artist's mesh carried by the tets (a glTF character's, written to the run file's /render).
struct RenderMesh {
  std::string source;  // the file it came from
  Points rest;         // rest vertices, world coordinates
  std::vector<Tri> triangles;
  Embedding embedding;
  // Its skin, where it has one: each vertex's four bones (rows of the skeleton, /bones) and their
  // weights (summing to 1): linear blend skinning, for comparing the simulation with it.
  std::vector<std::array<int, 4>> skin_bones;
  std::vector<Eigen::Vector4d> skin_weights;
};

}  // namespace isochor
