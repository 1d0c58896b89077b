// XPBD (Macklin, Müller and Chentanez 2016; with substeps, Macklin et al. 2019) on a list of local
// constraints: per substep of size h, v += h a_ext, x* = x + h v, then `iterations` Gauss-Seidel
// sweeps over the constraints in a fixed order,
//   dlambda = (-C - alpha~ lambda) / (sum_i w_i |grad_i C|^2 + alpha~),  alpha~ = alpha / h^2,
//   x_i += w_i grad_i C dlambda,  lambda += dlambda,
// then the system's collision projection, and v = (x - x_prev) / h. Points with w = 0 follow the
// system's prescribed positions. Nothing here knows tets: a constraint is its points, value,
// gradient and compliance.
#pragma once
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "isochor/integrators/constrained_system.hpp"
#include "isochor/integrators/integrator.hpp"

namespace isochor {

class ProjectiveSystem {
 public:
  virtual ~ProjectiveSystem() = default;
  virtual int num_points() const = 0;
  // Inverse mass of each point; 0 for points whose position is prescribed.
  virtual const Eigen::VectorXd& inverse_mass() const = 0;
  // Positions and velocities (3 per point) at the start.
  virtual void initial_state(double t0, Eigen::VectorXd& x, Eigen::VectorXd& v) = 0;
  // External acceleration of every point (gravity), 3 per point.
  virtual void external_acceleration(double t, Eigen::VectorXd& a) = 0;
  // Writes the prescribed positions and velocities (w = 0 points) at time t.
  virtual void prescribe(double t, Eigen::VectorXd& x, Eigen::VectorXd& v) = 0;
  virtual int num_constraints() const = 0;
  // Constraint c at positions x: its value; points and gradients (3 per point) into the buffers.
  virtual double constraint(int c, const Eigen::VectorXd& x, std::vector<int>& points, std::vector<double>& grad) = 0;
  // Compliance alpha of constraint c (0: hard).
  virtual double compliance(int c) const = 0;
  // Called once per sweep after the constraints (e.g. zone-volume constraints that need all
  // points at once); returns nothing, may move points with w > 0.
  virtual void after_sweep(double /*h*/, Eigen::VectorXd& /*x*/) {}
  // Collision projection at the end of the sweeps (e.g. points pushed out of the ground).
  virtual void project_collisions(double /*t*/, Eigen::VectorXd& /*x*/) {}
};

struct XpbdOptions {
  double dt = kDefaultFixedStep;  // step between collision detections (a frame's steps are of this size)
  int substeps = 10;              // per step
  int iterations = 1;             // Gauss-Seidel sweeps per substep
  long max_steps = kDefaultMaxSteps;
};

class FixedStepper;

class Xpbd : public SteppingIntegrator {
 public:
  Xpbd(ProjectiveSystem& system, XpbdOptions options);
  ~Xpbd() override;
  // Steps from frame_times.front(); frames between steps are interpolated linearly. The frame
  // callback gets all point positions and velocities (3 per point) and no multipliers.
  RunStats run(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  void begin(const std::vector<double>& frame_times, const FrameCallback& on_frame) override;
  double step(double t_out) override;
  RunStats finish() override;

 private:
  bool substeps(double t, VectorXd& x, VectorXd& v, std::string& reason);
  ProjectiveSystem& sys_;
  XpbdOptions opt_;
  RunStats stats_;
  VectorXd a_, x_prev_, lambda_;  // a step's scratch: accelerations, positions before a substep, multipliers
  std::vector<int> pts_;
  std::vector<double> grad_;
  std::unique_ptr<FixedStepper> stepper_;
};

}  // namespace isochor
