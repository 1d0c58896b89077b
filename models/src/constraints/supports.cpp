#include "isochor/models/supports.hpp"

#include <cmath>

namespace isochor {

ComponentSupports::ComponentSupports(const Mesh& mesh, std::vector<Row> rows, const DofMap& dofs, double length)
    : mesh_(mesh), rows_(std::move(rows)), length_(length) {
  // A row is on the components its direction has: an axis (a roller, a symmetry plane, a held
  // component) on one dof, which lets a solver take that dof out of its matrix (bordered.hpp).
  for (const Row& r : rows_) {
    const Index f = dofs.free_index[r.node];
    std::vector<Index> on;
    for (int c = 0; c < 3; ++c)
      if (r.dir[c] != 0.0) on.push_back(3 * f + c);
    dofs_.push_back(std::move(on));
  }
  target_.assign(rows_.size(), 0.0);
  rate_.assign(rows_.size(), 0.0);
  set_time(0.0);
}

void ComponentSupports::set_time(double t) {
  for (std::size_t j = 0; j < rows_.size(); ++j) {
    const Row& r = rows_[j];
    target_[j] = r.dir.dot(mesh_.rest_positions().col(r.node) + r.driver->displacement(t));
    rate_[j] = r.dir.dot(r.driver->velocity(t));
  }
}

void ComponentSupports::value(const Points& x, double* g) const {
  for (std::size_t j = 0; j < rows_.size(); ++j) g[j] = rows_[j].dir.dot(x.col(rows_[j].node)) - target_[j];
}

void ComponentSupports::gradient(const Points&, std::vector<double>* rows) const {
  for (std::size_t j = 0; j < rows_.size(); ++j) {
    rows[j].clear();
    for (Index d : dofs_[j]) rows[j].push_back(rows_[j].dir[d % 3]);
  }
}

void ComponentSupports::time_derivative(const Points&, const Eigen::VectorXd&, double* gt) const {
  for (std::size_t j = 0; j < rows_.size(); ++j) gt[j] = -rate_[j];
}

void ComponentSupports::hessian_times(const Points&, const Eigen::VectorXd&, std::vector<double>* rows) const {
  for (std::size_t j = 0; j < rows_.size(); ++j) rows[j].assign(dofs_[j].size(), 0.0);
}

}  // namespace isochor
