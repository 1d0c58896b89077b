// A tetrahedral mesh at rest: node positions, positively oriented tets with their rest volumes,
// the outward boundary surface, named zones (sets of tets) and named node sets, and adjacency.
#pragma once
#include <Eigen/Core>
#include <array>
#include <map>
#include <string>
#include <vector>

namespace isochor {

using Tet = std::array<int, 4>;
using Tri = std::array<int, 3>;
using Points = Eigen::Matrix3Xd;  // column j is node j

// Compressed rows: the neighbours of item i are index[offset[i] .. offset[i+1]).
struct Adjacency {
  std::vector<int> offset;
  std::vector<int> index;
  int size() const { return static_cast<int>(offset.size()) - 1; }
  const int* begin(int i) const { return index.data() + offset[i]; }
  const int* end(int i) const { return index.data() + offset[i + 1]; }
};

double tet_signed_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                         const Eigen::Vector3d& d);

// The outward faces (positively oriented tets) that belong to one tet only, of every tet or of
// the tets listed in `which`: the boundary of that set. `overshared`, when given, receives the face
// shared by the most tets and how many ((a, b, c, count); count > 2: not a manifold).
std::vector<Tri> boundary_faces(const std::vector<Tet>& tets, const std::vector<int>* which = nullptr,
                                std::array<int, 4>* overshared = nullptr);

class Mesh {
 public:
  Mesh() = default;
  // Takes positions and tets, reorders negatively oriented tets, rejects degenerate ones
  // (|V| < 1e-12 of the mean |V|) naming the index, and builds the surface and adjacency.
  // `what` names the source in error messages (a file or a shape).
  Mesh(Points positions, std::vector<Tet> tets, const std::string& what = "mesh");

  int num_nodes() const { return static_cast<int>(X_.cols()); }
  int num_tets() const { return static_cast<int>(tets_.size()); }
  const Points& rest_positions() const { return X_; }
  const std::vector<Tet>& tets() const { return tets_; }
  const std::vector<double>& rest_volumes() const { return volume_; }
  double rest_volume() const { return total_volume_; }
  // Outward oriented boundary triangles (counter-clockwise seen from outside).
  const std::vector<Tri>& surface() const { return surface_; }
  // Sorted indices of the nodes on the surface.
  const std::vector<int>& surface_nodes() const { return surface_nodes_; }
  // Number of tets whose orientation was reversed when the mesh was built.
  int reoriented_tets() const { return reoriented_; }

  const Adjacency& node_tets() const { return node_tets_; }    // tets incident to each node
  const Adjacency& node_nodes() const { return node_nodes_; }  // edge neighbours of each node

  // Nodes within graph distance k of `node` (k = 0: the node itself), sorted.
  std::vector<int> node_ring(int node, int k) const;
  // Tets incident to the nodes of the (k-1)-ring of `node` (k = 1: the tets touching it), sorted.
  std::vector<int> tet_ring(int node, int k) const;

  // Named zones (tet indices, sorted) and node sets (node indices, sorted), e.g. from a mesh file.
  std::map<std::string, std::vector<int>> zones;
  std::map<std::string, std::vector<int>> node_sets;
  // Per-tet data from the mesh file (a .msh file's $ElementData views, by name): `components`
  // numbers per tet, tet after tet; NaN for a tet the file gives no value.
  struct TetField {
    int components = 0;
    std::vector<double> values;
  };
  std::map<std::string, TetField> tet_fields;

 private:
  Points X_;
  std::vector<Tet> tets_;
  std::vector<double> volume_;
  double total_volume_ = 0.0;
  std::vector<Tri> surface_;
  std::vector<int> surface_nodes_;
  int reoriented_ = 0;
  Adjacency node_tets_, node_nodes_;
};

// Volume enclosed by a closed, outward oriented triangle surface (divergence theorem).
double surface_volume(const Points& x, const std::vector<Tri>& surface);
// Sum of signed tet volumes at positions x.
double tets_volume(const Points& x, const std::vector<Tet>& tets);
// How far x is from the rest shape X up to a rigid motion: the largest distance of a node of x,
// moved by the rotation and translation that best fit it onto X (least squares, equal weights:
// Kabsch; a reflection is not a rigid motion), to its rest position, over the diagonal of X's
// bounding box. 0 for a rigidly moved copy; the scrambled starts (initial.flatten) measure recovery.
double rest_shape_error(const Points& X, const Points& x);
// The same fit's root-mean-square and largest node distance, both over X's diagonal (the
// scrambled starts' recovery: tools/recovery.py measures the surface nodes so).
struct ShapeDistance {
  double rms = 0, largest = 0;
};
ShapeDistance rest_shape_distance(const Points& X, const Points& x);

struct SurfaceCheck {
  bool closed = false;           // every edge in exactly two triangles
  bool oriented = false;         // every directed edge at most once
  int boundary_edges = 0;        // edges in one triangle only
  int nonmanifold_edges = 0;     // edges in three or more triangles
  int euler_characteristic = 0;  // V - E + F over the nodes the triangles use
  std::array<int, 2> first_bad_edge{-1, -1};
};
SurfaceCheck check_surface(const std::vector<Tri>& surface);

// Removes nodes used by no tet, renumbering tets and node sets; returns the old index of each kept node.
std::vector<int> compact_unused_nodes(Points& x, std::vector<Tet>& tets,
                                      std::map<std::string, std::vector<int>>* node_sets);

}  // namespace isochor
