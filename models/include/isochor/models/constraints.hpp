// Volume constraints: one scalar g_j per zone (sum of the zone's tet volumes minus its rest
// volume, CNH paper eq. (6)), or one for a closed surface (divergence theorem, for the mass-spring
// model). Each supplies g, the sparse gradient G over the free dofs (a fixed pattern per row),
// dg/dt from the velocities of Dirichlet nodes, and the contracted Hessian sum_j lambda_j H_j
// filled into an assembly pattern.
#pragma once
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "isochor/models/assembly.hpp"
#include "isochor/models/constraint_set.hpp"

namespace isochor {

// The zones (indices, increasing) whose volume is, at every configuration, a linear combination
// of the volumes of zones before them: their tet sets' indicator vectors are linearly dependent
// (1-ring zones on a mesh whose nodes four-colour so that each tet has one node of each colour:
// each colour's zones sum to the whole body; the global zone over a partition). Their constraint
// rows would add nothing but a singular KKT matrix. Exact Gaussian elimination of the indicator
// vectors (modulo a 61-bit prime); nullopt where it would touch more than work_limit entries or
// keep more than a quarter of that many.
std::optional<std::vector<int>> redundant_zones(const std::vector<std::vector<int>>& zone_tets, std::size_t work_limit);

class VolumeConstraints : public ConstraintSet {
 public:
  // Zone constraints: each zone a list of tets (zones may overlap); evaluated on each zone's
  // boundary faces (the same volume, interior contributions cancelling exactly).
  static VolumeConstraints zones(const Mesh& mesh, const std::vector<std::vector<int>>& zone_tets, const DofMap& dofs,
                                 const Pattern& pattern);
  // One constraint on the volume enclosed by the mesh's surface triangles.
  static VolumeConstraints surface(const Mesh& mesh, const DofMap& dofs, const Pattern& pattern);

  int size() const override { return static_cast<int>(rest_.size()); }
  double scale(int j) const override { return rest_[j]; }
  // ConstraintSet, on stacked arrays.
  void value(const Points& x, double* g) const override;
  void gradient(const Points& x, std::vector<double>* rows) const override;
  void time_derivative(const Points& x, const Eigen::VectorXd& xdot, double* gt) const override;
  void hessian_times(const Points& x, const Eigen::VectorXd& xdot, std::vector<double>* rows) const override;
  void add_hessian(const Points& x, const double* w, double scale, double* values) const override;
  // p_e -= lambda_j for every zone j holding tet e (the constraint force -lambda_j dV/dx is that
  // of a hydrostatic stress lambda_j I). Zone constraints only.
  void add_pressure(const double* lambda, std::vector<double>& p) const override;
  const std::vector<double>& rest_volumes() const { return rest_; }
  // zones.restore_time: a start whose volumes are not the rest volumes (initial.flatten) cannot
  // hold g = 0, so each target goes from the volume at x0 to the rest volume between t0 and
  // t0 + duration along the quintic smoothstep 10s^3 - 15s^4 + 6s^5 (C^2: its velocity and
  // acceleration vanish at both ends), then stays there. dg/dt carries the target's rate.
  void restore_from(const Points& x0, double t0, double duration);
  void set_time(double t) override;
  // Current volume of each constraint.
  void volumes(const Points& x, Eigen::VectorXd& vol) const;
  // g = volume - rest volume.
  void value(const Points& x, Eigen::VectorXd& g) const {
    g.resize(size());
    value(x, g.data());
  }
  // Row j of G: free dof indices (sorted, fixed) and values.
  const std::vector<Index>& row_dofs(int j) const override { return row_dofs_[j]; }
  void gradient(const Points& x, std::vector<std::vector<double>>& rows) const {
    rows.resize(size());
    gradient(x, rows.data());
  }
  // dg/dt = sum over Dirichlet nodes d of dg/dx_d . v_d (v: velocities of all nodes, 3 N).
  void time_derivative(const Points& x, const Eigen::VectorXd& v, Eigen::VectorXd& gt) const {
    gt.resize(size());
    time_derivative(x, v, gt.data());
  }
  // rows[j] (layout of row_dofs(j)) = (H_j xdot)^T at the free dofs, xdot the velocity of every
  // node (3 N, driven nodes included): d(G v + dg/dt)/dq.
  void hessian_times(const Points& x, const Eigen::VectorXd& xdot, std::vector<std::vector<double>>& rows) const {
    rows.resize(size());
    hessian_times(x, xdot, rows.data());
  }
  // values[slot] += scale * sum_j lambda_j H_j over the free dofs.
  void add_hessian(const Points& x, const Eigen::VectorXd& lambda, double scale, double* values) const {
    add_hessian(x, lambda.data(), scale, values);
  }
  // Full gradient of g_j with respect to every node (3 N), for tests and diagnostics.
  Eigen::VectorXd full_gradient(const Points& x, int j) const;

 private:
  struct Element {
    int nodes[4];  // (origin, a, b, c): nodes[0] = -1 stands for the constraint's origin (origins())
    int constraint;
  };
  std::vector<Element> elements_;
  ElementSchedule colours_;
  std::vector<Index> slots_;  // 144 per element
  std::vector<std::vector<Index>> row_dofs_;
  std::vector<std::vector<int>> row_slot_;  // per element: 12 entries, position in its row or -1
  std::vector<double> rest_;
  std::vector<double> start_offset_, offset_, rate_;  // restore_from: target - rest at t0, now, d/dt now
  double restore_t0_ = 0, restore_duration_ = 0;
  std::vector<std::vector<int>> boundary_nodes_;  // per constraint: the nodes of its faces
  std::vector<std::vector<int>> zone_tets_;       // zone constraints: the tets of each zone
  DofMap dofs_;
  const std::vector<Vec3>& origins(const Points& x) const;  // per constraint, where the origin is now
  mutable std::vector<Vec3> origins_;
  void sum_volumes(const Points& x, double* vol) const;  // each constraint's volume
  Vec12 element_x(const Points& x, const Element& e, const std::vector<Vec3>& origins) const;
  void finish(int num_nodes, const DofMap& dofs, const Pattern& pattern);
};

// One zone per free vertex: the tets of its k-ring (Irving et al. 2007 for k = 1).
std::vector<std::vector<int>> ring_zones(const Mesh& mesh, int k, const DofMap& dofs);
// A partition of the tets into patches about the size of a k-ring: seed nodes at least 2k edges
// apart (greedy, in node order), every node joins its nearest seed (breadth first, ties to the
// earlier seed), so a patch reaches about k edges from its seed; every tet joins the patch of its
// lowest-numbered node. Patches do not overlap, so
// their volumes add up to the total.
std::vector<std::vector<int>> patch_zones(const Mesh& mesh, int k);

}  // namespace isochor
