// Supports that hold some components of nodes: rollers and symmetry planes (the normal component
// held, the node free in the plane), a face pulled along one axis while it contracts sideways.
// One constraint row per held direction d of a node,
//   g = d . (x_i - X_i - u(t)) = 0,
// u(t) the displacement of the [[boundary]]'s driver (fixed: 0), so the driver acts on the held
// components only and the free ones stay unknowns. The rows are linear in x: their Hessians are
// zero, a Newton step satisfies them exactly, and their multipliers are the support's reaction
// forces along d (N; the force the support exerts is -lambda d, constrained_system.hpp).
#pragma once
#include <vector>

#include <memory>

#include "isochor/models/constraint_set.hpp"
#include "isochor/models/drivers.hpp"

namespace isochor {

class ComponentSupports : public ConstraintSet {
 public:
  struct Row {
    int node;
    Vec3 dir;              // unit
    const Driver* driver;  // its displacement u(t) and velocity
  };
  // rows: every held direction of every partially held (free) node; length: the rows' scale (m).
  ComponentSupports(const Mesh& mesh, std::vector<Row> rows, const DofMap& dofs, double length);
  int size() const override { return static_cast<int>(rows_.size()); }
  const std::vector<Index>& row_dofs(int j) const override { return dofs_[j]; }
  double scale(int) const override { return length_; }
  void set_time(double t) override;
  void value(const Points& x, double* g) const override;
  void gradient(const Points& x, std::vector<double>* rows) const override;
  void time_derivative(const Points& x, const Eigen::VectorXd& xdot, double* gt) const override;
  void hessian_times(const Points& x, const Eigen::VectorXd& xdot, std::vector<double>* rows) const override;
  void add_hessian(const Points&, const double*, double, double*) const override {}
  const std::vector<Row>& rows() const { return rows_; }

 private:
  const Mesh& mesh_;
  std::vector<Row> rows_;
  std::vector<std::vector<Index>> dofs_;  // the components of each row's direction that are not 0
  std::vector<double> target_, rate_;     // d . (X_i + u(t)) and d . u'(t) at the time set
  double length_;
};

}  // namespace isochor
