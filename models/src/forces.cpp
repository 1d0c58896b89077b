#include "isochor/forces.hpp"

#include <algorithm>
#include <map>
#include <set>

namespace isochor {

ExternalPotential::ExternalPotential(Eigen::VectorXd mass, Vec3 gravity, GroundSpec ground, const DofMap& dofs,
                                     const Pattern& pattern)
    : mass_(std::move(mass)), gravity_(gravity), ground_(ground), dofs_(dofs) {
  ground_.normal.normalize();
  diag_slots_.resize(9 * static_cast<std::size_t>(dofs.num_free()));
  for (int f = 0; f < dofs.num_free(); ++f)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) diag_slots_[9 * f + 3 * a + b] = pattern.find(3 * Index(f) + a, 3 * Index(f) + b);
}

double ExternalPotential::energy(const Points& x) const {
  double E = 0.0;
  const Vec3 gravity = g();
  for (int i = 0; i < x.cols(); ++i) {
    E -= mass_[i] * gravity.dot(x.col(i));
    if (ground_.enabled)
      E += ground_energy(ground_.stiffness, ground_.thickness, ground_.point, ground_.normal, x.col(i), nullptr, nullptr);
  }
  return E;
}

double ExternalPotential::add_gradient(const Points& x, Eigen::VectorXd& grad) const {
  double E = 0.0;
  const Vec3 gravity = g();
  for (int i = 0; i < x.cols(); ++i) {
    E -= mass_[i] * gravity.dot(x.col(i));
    grad.segment<3>(3 * i) -= mass_[i] * gravity;
    if (ground_.enabled) {
      Vec3 g;
      E += ground_energy(ground_.stiffness, ground_.thickness, ground_.point, ground_.normal, x.col(i), &g, nullptr);
      grad.segment<3>(3 * i) += g;
    }
  }
  return E;
}

void ExternalPotential::add_hessian(const Points& x, double scale, double* values) const {
  if (!ground_.enabled) return;
  for (int f = 0; f < dofs_.num_free(); ++f) {
    Mat3 H;
    ground_energy(ground_.stiffness, ground_.thickness, ground_.point, ground_.normal, x.col(dofs_.free_nodes[f]),
                  nullptr, &H);
    for (int k = 0; k < 9; ++k) values[diag_slots_[9 * f + k]] += scale * H(k / 3, k % 3);
  }
}

void RayleighDamping::add_force(const ElasticAssembly& a, const Eigen::VectorXd& mass, const Points& x,
                                const Eigen::VectorXd& v, Eigen::VectorXd& f) const {
  for (int i = 0; i < mass.size(); ++i) f.segment<3>(3 * i) -= alpha * mass[i] * v.segment<3>(3 * i);
  if (beta != 0.0) a.add_hessian_times(x, v, -beta, f);
}

void RayleighDamping::add_matrix(const ElasticAssembly& a, const Eigen::VectorXd& mass, const Points& x, double scale,
                                 double* values) const {
  const Pattern& p = a.pattern();
  if (alpha != 0.0)
    for (int f = 0; f < a.dofs().num_free(); ++f)
      for (int d = 0; d < 3; ++d) values[p.find(3 * Index(f) + d, 3 * Index(f) + d)] += scale * alpha * mass[a.dofs().free_nodes[f]];
  if (beta != 0.0) a.add_hessian(x, scale * beta, values);
}

std::vector<Spring> surface_springs(const Points& x, const std::vector<Tri>& surface) {
  std::map<std::pair<int, int>, std::vector<int>> opposite;  // edge -> vertices opposite it
  std::map<int, std::set<int>> nbr;
  for (const Tri& t : surface)
    for (int e = 0; e < 3; ++e) {
      int a = t[e], b = t[(e + 1) % 3];
      opposite[{std::min(a, b), std::max(a, b)}].push_back(t[(e + 2) % 3]);
      nbr[a].insert(b);
      nbr[b].insert(a);
    }
  std::set<std::pair<int, int>> made;
  std::vector<Spring> springs;
  auto add = [&](int a, int b, Spring::Kind k) {
    if (a == b) return;
    auto key = std::make_pair(std::min(a, b), std::max(a, b));
    if (!made.insert(key).second) return;
    springs.push_back({key.first, key.second, (x.col(a) - x.col(b)).norm(), k});
  };
  for (const auto& [e, opp] : opposite) add(e.first, e.second, Spring::structural);
  for (const auto& [e, opp] : opposite)
    if (opp.size() == 2) add(opp[0], opp[1], Spring::shear);
  for (const auto& [b, ns] : nbr)
    for (int a : ns) {
      const Vec3 d = (x.col(b) - x.col(a)).normalized();
      int best = -1;
      double best_cos = 0.5;
      for (int c : ns) {
        if (c == a) continue;
        const double cs = d.dot((x.col(c) - x.col(b)).normalized());
        if (cs > best_cos) best_cos = cs, best = c;
      }
      if (best >= 0) add(a, best, Spring::bending);
    }
  return springs;
}

}  // namespace isochor
