// A mesh scene as XPBD sees it (Macklin and Müller 2021): every tet gives a deviatoric constraint
// C_D = sqrt(tr F^T F) with compliance 1/(mu V) and a hydrostatic one C_H = det F - gamma with
// compliance 1/(lambda' V), lambda' = lambda + mu, gamma = 1 + mu/lambda' (Smith et al.'s rest
// stability; the energy of `snh_simple`); lambda = infinity (nu = 0.5) makes C_H hard with
// gamma = 1. Zones add one hard zone-volume constraint each, projected after every sweep, and so are
// the components that partial supports hold. Driven nodes have zero inverse mass; the ground is a
// collision plane points are projected onto.
#pragma once
#include "isochor/models/constraints.hpp"
#include "isochor/models/elements.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/integrators/xpbd.hpp"

namespace isochor {

class XpbdMeshSystem : public ProjectiveSystem {
 public:
  explicit XpbdMeshSystem(const Scene& scene);
  int num_points() const override { return scene_.mesh.num_nodes(); }
  const Eigen::VectorXd& inverse_mass() const override { return w_; }
  void initial_state(double t0, Eigen::VectorXd& x, Eigen::VectorXd& v) override;
  const StartState* start = nullptr;  // a resumed run's start (SceneSystem::start)
  void external_acceleration(double t, Eigen::VectorXd& a) override;
  void prescribe(double t, Eigen::VectorXd& x, Eigen::VectorXd& v) override;
  int num_constraints() const override { return 2 * scene_.mesh.num_tets(); }
  double constraint(int c, const Eigen::VectorXd& x, std::vector<int>& points, std::vector<double>& grad) override;
  double compliance(int c) const override { return c % 2 == 0 ? alpha_d_[c / 2] : alpha_h_[c / 2]; }
  void after_sweep(double h, Eigen::VectorXd& x) override;
  void project_collisions(double t, Eigen::VectorXd& x) override;

 private:
  const Scene& scene_;
  DofMap dofs_;
  std::vector<TetShape> shapes_;
  std::vector<double> alpha_d_, alpha_h_;
  double gamma_ = 1.0;
  Eigen::VectorXd w_;
  VolumeConstraints zones_;
  // Nodes of [[boundary]] drivers that hold some components: their held directions and drivers,
  // projected exactly (onto the intersection of the planes d . x = d . (X + u(t))) after every
  // sweep; t_ the substep's time (from prescribe).
  struct Held {
    int node;
    std::vector<Eigen::Vector3d> dirs;
    std::vector<const Driver*> drivers;
  };
  std::vector<Held> held_;
  double t_ = 0.0;
  void hold(double t, Eigen::VectorXd& x, Eigen::VectorXd* v) const;
  void project_zones(Eigen::VectorXd& x);
  std::vector<std::vector<double>> zone_grad_;
  Eigen::VectorXd zone_value_;
};

}  // namespace isochor
