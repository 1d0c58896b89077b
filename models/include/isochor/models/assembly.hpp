// Assembly of a mesh's elastic energy, gradient and Hessian over the free degrees of freedom into
// one sparsity pattern built once. Every element keeps a slot map from its local Hessian entries
// to positions in the value array, so that a Hessian evaluation is a plain numeric fill. Elements
// are coloured (no two of a colour share a node) and each colour is filled in parallel (OpenMP)
// without races or allocation.
#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <memory>
#include <vector>

#include "isochor/models/elements.hpp"
#include "isochor/models/material.hpp"
#include "isochor/models/muscle.hpp"
#include "isochor/core/mesh.hpp"
#include "isochor/integrators/sparse_pattern.hpp"

namespace isochor {

// Which nodes are unknowns: free_index[node] is the node's index among the free nodes, or -1 for
// a Dirichlet node. Degree of freedom 3 f + d for free node f and axis d.
struct DofMap {
  std::vector<int> free_index;
  std::vector<int> free_nodes;
  int num_free() const { return static_cast<int>(free_nodes.size()); }
  // The free nodes in the order `order` lists them (a permutation of the nodes; empty: by index).
  static DofMap make(int num_nodes, const std::vector<int>& dirichlet_nodes, const std::vector<int>& order = {});
};

// The columns of `points` sorted along a space-filling (Morton) curve through them: neighbours in
// space are mostly neighbours in the order.
std::vector<int> morton_order(const Points& points);

// The pattern of the free dofs: symmetric (both triangles stored), with 3x3 blocks for every pair
// of free nodes that share one of `elements` (lists of node indices).
using Pattern = SparsePattern;
Pattern pattern_from_elements(const DofMap& dofs, const std::vector<std::vector<int>>& elements);

// Slot maps: for an element of k nodes, (3k)^2 entries, -1 where a row or column is a Dirichlet dof.
std::vector<Index> slot_map(const Pattern& p, const DofMap& dofs, const int* nodes, int k);

// The order of an element pass: the elements cut into chunks of elements near each other, and the
// chunks coloured greedily so that no two chunks
// of one colour share a node. A pass runs colour after colour, the chunks of a colour in parallel,
// each chunk's elements in order: races are impossible, each chunk's scatter stays in cache, and
// every node receives its contributions in the same order whatever the number of threads.
struct ElementSchedule {
  std::vector<int> order;                 // the elements, chunk after chunk
  std::vector<int> chunk_start;           // chunk c: order[chunk_start[c]] .. order[chunk_start[c + 1] - 1]
  std::vector<std::vector<int>> colours;  // the chunks of each colour
};
// centroids (3 x E, optional): elements are first sorted along a space-filling (Morton) curve
// through their centroids, so that a chunk is a compact piece of the mesh; without them, the
// elements' own order, one element per chunk.
ElementSchedule colour_elements(int num_nodes, const std::vector<std::vector<int>>& elements,
                                const Points* centroids = nullptr, int chunk = 64);

// Calls f(k) for every position k of the schedule's order (element s.order[k]), in parallel across
// the chunks of a colour (so f may scatter into nodes without races), and returns the sum of what
// f returns. Per-element data stored by position is read in sequence.
template <class F>
double for_each_coloured(const ElementSchedule& s, F&& f) {
  double sum = 0.0;
  for (const auto& colour : s.colours) {
    const int n = static_cast<int>(colour.size());
#pragma omp parallel for reduction(+ : sum) schedule(static)
    for (int i = 0; i < n; ++i) {
      double part = 0.0;
      for (int k = s.chunk_start[colour[i]]; k < s.chunk_start[colour[i] + 1]; ++k) part += f(k);
      sum += part;
    }
  }
  return sum;
}

struct EpidermisSpec {
  double lambda_e = 0.0, gamma = 1.0;  // off when lambda_e = 0
};

// What one pass over the elements computes from each element's gradient and Hessian (every
// pointer optional): grad += gradient (3 N, all nodes); values += scale H and values2 += scale2 H
// over the free dofs (pattern slots); Kv += v_scale H v (all nodes, v of every node).
struct ElementPass {
  Eigen::VectorXd* grad = nullptr;
  double* values = nullptr;
  double scale = 1.0;
  double* values2 = nullptr;
  double scale2 = 0.0;
  const Eigen::VectorXd* v = nullptr;
  double v_scale = 0.0;
  Eigen::VectorXd* Kv = nullptr;
  // values and values2 get each element's Hessian projected onto the positive semi-definite
  // matrices (its negative eigenvalues set to zero); grad and Kv stay exact.
  bool project = false;
};

class ElasticAssembly {
 public:
  ElasticAssembly(const Mesh& mesh, std::shared_ptr<const Material> material, const DofMap& dofs,
                  EpidermisSpec epidermis = {});

  const Pattern& pattern() const { return pattern_; }
  const DofMap& dofs() const { return dofs_; }
  // Elastic energy at positions x (all nodes).
  double energy(const Points& x) const;
  // One pass over the elements; returns the energy.
  double evaluate(const Points& x, const ElementPass& pass) const;
  // Energy and its gradient with respect to every node (3 N, Dirichlet nodes included).
  double gradient(const Points& x, Eigen::VectorXd& grad) const;
  // values[slot] += scale * Hessian over the free dofs (values sized pattern().nnz()); with
  // values2, also values2[slot] += scale2 * Hessian from the same element Hessians.
  void add_hessian(const Points& x, double scale, double* values, double scale2 = 0.0, double* values2 = nullptr,
                   bool project = false) const;
  // out += scale * K(x) v over all nodes (Rayleigh damping; v of every node, 3 N).
  void add_hessian_times(const Points& x, const Eigen::VectorXd& v, double scale, Eigen::VectorXd& out) const;
  // Per-tet pressure of the material, -tr(sigma)/3 (for CNH: -lambda U'(J) plus the deviatoric
  // part, which is traceless, so exactly the penalty's volumetric stress).
  void pressures(const Points& x, std::vector<double>& p) const;
  // Number of tets with J <= 0.
  int inverted_tets(const Points& x) const;
  const Material& material() const { return *material_; }
  // Materials per region: tet e (mesh order) takes materials[material_of[e]]; empty lists give
  // every tet the constructor's material back.
  void set_tet_materials(std::vector<std::shared_ptr<const Material>> materials, const std::vector<int>& material_of);
  // Muscles (muscle.hpp): each fibre tet's term is added to its material's; activations per
  // muscle, all 0 until set. A field without muscles removes them.
  void set_fibres(const FibreField& field);
  void set_activations(const std::vector<double>& activation);
  const std::vector<double>& activations() const { return activation_; }
  bool has_fibres() const { return !muscles_.empty(); }
  // On P ranks (ranks.hpp): node_rank[v] is the rank that owns node v. From now on the passes
  // evaluate only the elements with a free node of `rank` (its nodes' gradient entries and
  // Hessian columns are then whole, the others partial), and energies count each element on one
  // rank only, the owner of its lowest-numbered node.
  void keep_rank(const std::vector<int>& node_rank, int rank);

 private:
  // Whether element k (its position in the pass's order) is evaluated on this rank, and its
  // energy E as this rank counts it.
  bool skip_tet(int k) const { return !tet_here_.empty() && !tet_here_[k]; }
  double tet_counted(int k, double E) const { return tet_counted_.empty() || tet_counted_[k] ? E : 0.0; }
  bool skip_tri(int f) const { return !tri_here_.empty() && !tri_here_[f]; }
  double tri_counted(int f, double E) const { return tri_counted_.empty() || tri_counted_[f] ? E : 0.0; }
  std::vector<char> tet_here_, tet_counted_, tri_here_, tri_counted_;  // empty on one process
  // Tet k's material (k its position in the pass's order).
  const Material& material_at(int k) const {
    return tet_material_.empty() ? *material_ : *materials_[tet_material_[k]];
  }
  // Tet k's fibre term (k its position in the pass's order), 0 where it has none.
  double fibre_term(int k, const Vec12& x, Vec12* grad, Mat12* hess, const Vec12* dir, Vec12* hess_dir) const;
  // Tet k's fibre stress, added to P (psi added to *psi).
  void add_fibre_stress(int k, const Mat3& F, Mat3& P, double& psi) const;
  const Mesh& mesh_;
  std::shared_ptr<const Material> material_;
  DofMap dofs_;
  EpidermisSpec epi_;
  // Per tet, at its position in the pass's order (tet_colours_.order maps back to the mesh).
  std::vector<Tet> tets_;
  std::vector<TetShape> shapes_;
  std::vector<double> tri_area_;
  Pattern pattern_;
  ElementSchedule tet_colours_, tri_colours_;
  std::vector<Index> tet_slots_, tri_slots_;  // 144 per tet, 81 per triangle
  // Materials per region (set_tet_materials), per tet at its position in the pass's order.
  std::vector<std::shared_ptr<const Material>> materials_;
  std::vector<int> tet_material_;
  // Fibres, per tet at its position in the pass's order: muscle index (-1: none) and direction.
  std::vector<MuscleLaw> muscles_;
  std::vector<double> activation_;
  std::vector<int> fibre_muscle_;
  std::vector<Vec3> fibre_dir_;
};

// Lumped mass per node: density times a quarter of the volume of every tet around it (with
// tet_density, each tet's own density).
Eigen::VectorXd lumped_mass(const Mesh& mesh, double density, const std::vector<double>* tet_density = nullptr);
// Each node's rest surface area: a third of the area of every surface triangle it is a corner of
// (0 inside); the per-area contact law's weights.
Eigen::VectorXd surface_areas(const Mesh& mesh);

// Tets gathered from Eigen-style views of the positions.
inline Vec12 gather(const Points& x, const Tet& t) {
  Vec12 v;
  for (int k = 0; k < 4; ++k) v.segment<3>(3 * k) = x.col(t[k]);
  return v;
}

}  // namespace isochor
