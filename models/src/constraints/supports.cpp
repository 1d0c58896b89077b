#include "isochor/models/supports.hpp"

#include <cmath>

namespace isochor {

ComponentSupports::ComponentSupports(const Mesh& mesh, std::vector<Row> rows, const DofMap& dofs, double length)
    : mesh_(mesh), rows_(std::move(rows)), length_(length) {
  for (const Row& r : rows_) {
    const Index f = dofs.free_index[r.node];
    dofs_.push_back({3 * f, 3 * f + 1, 3 * f + 2});
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
  for (std::size_t j = 0; j < rows_.size(); ++j) rows[j].assign(rows_[j].dir.data(), rows_[j].dir.data() + 3);
}

void ComponentSupports::time_derivative(const Points&, const Eigen::VectorXd&, double* gt) const {
  for (std::size_t j = 0; j < rows_.size(); ++j) gt[j] = -rate_[j];
}

void ComponentSupports::hessian_times(const Points&, const Eigen::VectorXd&, std::vector<double>* rows) const {
  for (std::size_t j = 0; j < rows_.size(); ++j) rows[j].assign(3, 0.0);
}

}  // namespace isochor
