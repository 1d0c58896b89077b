// A scene as a ConstrainedSystem plus what a frame of output needs from it: every node's
// position for a state of the unknowns, the energies, the volumes and (tet models) pressures.
// MeshSystem (tet materials) and MassSpringSystem (Hong et al.'s springs) are the two.
#pragma once
#include <array>
#include <functional>
#include <memory>
#include <vector>

#include "isochor/models/assembly.hpp"
#include "isochor/integrators/constrained_system.hpp"
#include "isochor/scene/scene.hpp"

namespace isochor {

class SceneSystem : public ConstrainedSystem {
 public:
  // Positions and velocities of every node for a state (q, v) of the unknowns at time t.
  virtual void set_state(double t, const VectorXd& q, const VectorXd& v) = 0;
  virtual const Points& positions() const = 0;
  // Velocities of every node (3 per node, node by node) at that state.
  virtual const Eigen::VectorXd& velocities() const = 0;
  // Kinetic, elastic (or spring) and external energy at the current state.
  virtual std::array<double, 3> energies() const = 0;
  // Total volume, then each zone's volume, at the current state.
  virtual std::vector<double> volumes() const = 0;
  // The free (unknown) and driven nodes.
  virtual const DofMap& dofs() const = 0;
  // Whether the model simulates tets (not the mass-spring surface): then it has the two below.
  virtual bool has_tets() const = 0;
  // Per-tet pressure at the current state for multipliers lambda.
  virtual void pressures(const VectorXd& /*lambda*/, std::vector<double>& /*p*/) const {}
  // Inverted tets at the current state.
  virtual int inverted_tets() const { return 0; }
  // Whether the scene applies [[load]]s, and the load on every node at the current state (N).
  virtual bool has_loads() const { return false; }
  virtual void loads(Points& /*out*/) const {}
  // Whether the scene has colliders (the ground among them) that push with a force, and that
  // force on every node at the current state (N: contact, damping and friction).
  virtual bool has_contact() const { return false; }
  virtual void contact(Points& /*out*/) const {}
  // Each collider's pose at the current time (Frame::collider_poses).
  virtual void collider_poses(std::vector<double>& /*out*/) const {}
  // Each collider's radius factor at the current time (Frame::collider_scales).
  virtual void collider_scales(std::vector<double>& /*out*/) const {}
  // Each muscle's activation at the current time ([[muscle]]), and a function of time that
  // replaces the scene's activations (one value per muscle, in [0, 1]; empty: the scene's).
  virtual std::vector<double> activations() const { return {}; }
  virtual void set_activation_function(std::function<std::vector<double>(double)> /*f*/) {}
  // A resumed run's start (null: the scene's rest state and initial velocity): initial_state()
  // returns it for the unknowns.
  void set_start(const StartState* start) { start_ = start; }
  const StartState* start() const { return start_; }
  bool starts_from_stored_state() const override { return start_ != nullptr; }
  bool stored_multipliers(VectorXd& lambda) const override {
    if (!start_ || start_->multipliers.size() != num_constraints()) return false;
    lambda = start_->multipliers;
    return true;
  }

 private:
  const StartState* start_ = nullptr;
};

// The scene's system: MassSpringSystem for material.model = "mass_spring", else MeshSystem (split
// over `ranks` where given, ranks.hpp).
std::unique_ptr<SceneSystem> make_scene_system(const Scene& scene, const Ranks* ranks = nullptr);

}  // namespace isochor
