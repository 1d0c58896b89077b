// Contact between parts of one body: every surface node against the deformed surface
// of the body away from itself. Its energy is the ground's law on the node's distance d to the
// surface triangles that are not near it at rest (no vertex within `exclude` of the node in the
// rest state, so a node does not touch its own neighbourhood):
//   k/3 (delta - d)^3 when d < delta (per node, or times the node's rest surface area),
// d the smoothed minimum of the distances d_i to those triangles, d = -tau log sum exp(-d_i/tau)
// (tau = `smoothing`): one term per node (a node near an edge is not counted twice), and C^1
// where the nearest triangle changes in a concave fold (the exact minimum's gradient jumps there).
// The gradient moves the node and the triangles' corners (by the closest points' barycentric
// weights); the Jacobian keeps the scene's fixed pattern: only the 3x3 blocks of the node (exact)
// and of each corner (Gauss-Newton, 2 k p w^2 n n^T) on themselves, so Newton's iterations are
// those of an approximate Jacobian where contact is active (docs/decisions.md measures it). Candidates come from a k-d
// tree (nanoflann) over the deformed surface's triangle centroids, rebuilt at each evaluation.
#pragma once
#include <memory>
#include <vector>

#include "isochor/models/assembly.hpp"
#include "isochor/models/colliders.hpp"

namespace isochor {

class SelfContact {
 public:
  SelfContact(const Mesh& mesh, const ContactLaw& law, double exclude, const DofMap& dofs, const Pattern& pattern,
              Eigen::VectorXd area = {}, double smoothing = 0.0);
  ~SelfContact();
  // grad += gradient (every node, 3 N); returns the energy.
  double add_gradient(const Points& x, Eigen::VectorXd& grad) const;
  // values += scale * the Gauss-Newton diagonal blocks (free nodes).
  void add_hessian(const Points& x, double scale, double* values) const;
  // out += the contact force on every node (with the damping's for velocities xdot, if given).
  void add_forces(const Points& x, const Eigen::VectorXd* xdot, Points& out) const;
  // Normal damping (law.damping = alpha > 0, Hunt & Crossley's form as the ground's): with the
  // approach rate sdot = n . (v_node - sum_i w_i v_corner_i), the force -k alpha p^2 sdot n on
  // the node and its opposite, times w_i, on the corners. grad += -f (every node, 3 N).
  void add_damping(const Points& x, const Eigen::VectorXd& xdot, Eigen::VectorXd& grad) const;
  // -df/dv into the free nodes' own 3x3 blocks (k alpha p^2 n n^T on the node, times w_i^2 on the
  // corners); -df/dx is left out (an approximate Jacobian, as the elastic part's corners).
  void add_damping_jacobian(const Points& x, double* neg_dfdv) const;
  bool damped() const { return law_.damping > 0; }

 private:
  struct Term {
    Tri tri;
    Vec3 weights;  // of the closest point on the triangle
    Vec3 n;        // unit, from the closest point to the node
    double d;      // distance
    double omega;  // its share of the smoothed minimum's gradient
    Mat3 H;        // d2 d_i / dx_node2
  };
  struct Pair {
    int node;
    double d;  // the smoothed minimum
    Vec3 n;    // its gradient with respect to the node, sum omega_i n_i
    std::vector<Term> terms;
  };
  // The non-excluded triangles within reach of every surface node whose smoothed distance is
  // below delta, from the kept candidates. A residual and its Jacobian (gradient, Hessian,
  // damping) ask at the same x: the pairs are made once per configuration and kept.
  const std::vector<Pair>& pairs(const Points& x) const;
  // The candidates of each triangle within `radius` at the surface nodes' positions xs (a k-d
  // tree search), kept with xs until some surface node has moved more than half the skin.
  void find_candidates(const Points& xs, double radius) const;
  const Mesh& mesh_;
  ContactLaw law_;
  double exclude2_;
  DofMap dofs_;
  std::vector<Index> diag_slots_;  // 9 per free node
  Eigen::VectorXd area_;
  double tau_ = 0;  // smoothing of the minimum distance, m
  mutable Points cached_x_;
  mutable std::vector<Pair> cached_;
  std::vector<int> surface_index_;                    // a node's place among the surface nodes, or -1
  mutable Points ref_;                                // the surface nodes where the candidates were found
  mutable std::vector<std::vector<int>> candidates_;  // per surface triangle, surface-node places
};

}  // namespace isochor
