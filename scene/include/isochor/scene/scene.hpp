// A scene as the user wrote it, parsed and checked: the mesh, material parameters, zones,
// integrator settings, frames and output. Every key is documented in docs/scenes.md.
#pragma once
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "isochor/models/drivers.hpp"
#include "isochor/models/forces.hpp"
#include "isochor/models/muscle.hpp"
#include "isochor/integrators/backward_euler.hpp"
#include "isochor/integrators/hong_step.hpp"
#include "isochor/integrators/ida_integrator.hpp"
#include "isochor/integrators/integrator.hpp"
#include "isochor/integrators/statics.hpp"
#include "isochor/integrators/xpbd.hpp"
#include "isochor/core/mesh.hpp"
#include "isochor/core/output.hpp"
#include "isochor/core/scene_file.hpp"
#include "isochor/models/skeleton.hpp"

namespace isochor {

enum class MaterialModel { cnh, unh, snh, snh_simple, mass_spring };
const char* to_string(MaterialModel m);

struct MaterialSpec {
  MaterialModel model = MaterialModel::cnh;
  double density = 1000.0;        // kg/m^3
  double mu = 0.0, lambda = 0.0;  // Pa (Lamé parameters, from mu/lambda or E/nu)
  double beta = 1.0;              // CNH penalty shape
  double epsilon = 0.1;           // CNH: J below which alpha~ is extended
  double epidermis_lambda = 0.0;  // Pa m (surface penalty weight); 0: no epidermis
  double epidermis_gamma = 1.0;
  double spring_stiffness = 1000.0;  // mass_spring: N/m, every spring
  double spring_damping = 0.0;       // mass_spring: N s/m, dashpot along every spring
  bool volume_constraint = true;     // mass_spring: keep the enclosed volume
  // [[material.region]]: tets with their own constants (the body's model); a tet in several
  // regions takes the last one's.
  struct Region {
    std::vector<int> tets;
    double mu = 0, lambda = 0, density = 0;
  };
  std::vector<Region> regions;
};

enum class IntegratorKind { ida, statics, backward_euler, semi_implicit, xpbd, mass_spring };
const char* to_string(IntegratorKind k);

// The [integrator] table (every key in docs/scenes.md): the kind, and each integrator's options
// as its own parser read them (models/src/integrators/, integrator_registry.hpp); the chosen
// kind's are used.
struct IntegratorSpec {
  IntegratorKind kind = IntegratorKind::ida;
  IdaOptions ida;
  // IDA's linear_solver = "auto": chosen when the system is built (make_ida: krylov for meshes of
  // 3-dof nodes with at most 256 constraint rows, else klu: automatic_ida_solver).
  bool ida_linear_solver_auto = false;
  StaticOptions statics;
  // Statics' linear_solver = "auto": klu, or reduced (the sparse border) for a system of 3-dof
  // nodes with more than 64 constraint rows (make_statics: automatic_static_solver).
  bool statics_linear_solver_auto = false;
  BackwardEulerOptions backward_euler;  // also the semi-implicit step
  XpbdOptions xpbd;
  HongOptions hong;
  Eigen::Vector3d weights_center = Eigen::Vector3d::Zero();  // mass_spring: Hong's weight zone
  double weights_radius = 0.0;                               // 0: uniform weights
};

struct FramesSpec {
  double rate = 100.0;    // frames per second
  double duration = 1.0;  // s
  int count = 0;          // statics: number of frames (load increments)
  // Frame times 0, 1/rate, ..., duration; statics: pseudo-times 0, 1/(count-1), ..., 1.
  std::vector<double> times() const;
  // How many: times().size() without making them.
  long num_frames() const;
};

struct OutputSpec {
  std::string path;
  bool pressure = false;
};

// Where a resumed run (isochor run --resume) starts instead of the rest state: every node's
// position and velocity at a frame of its file (the driven ones are prescribed anyway).
struct StartState {
  Points positions, velocities;
  Eigen::VectorXd multipliers;  // the constraints' at that frame (empty: computed afresh)
};

struct Scene {
  SceneFile file;
  Mesh mesh;
  MaterialSpec material;
  std::vector<Driver> boundary;  // Dirichlet drivers, in file order
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -9.81);
  double gravity_ramp =
      0.0;  // s (pseudo-time in statics): gravity grows linearly to full at this time; 0: full at once
  // The ground (contact.ground), the [[contact.plane]]s and the [[collider]]s, in that order.
  std::vector<Collider> colliders;
  // [contact.self]: contact between parts of the body (self_contact.hpp); off without the table.
  struct SelfContactSpec {
    bool enabled = false;
    ContactLaw law;
    double exclude = 0;    // m
    double smoothing = 0;  // m: tau of the smoothed minimum distance
  } self_contact;
  std::vector<NodeLoad> loads;               // [[load]]: point loads and tractions (dead loads)
  std::vector<PressureLoad> pressure_loads;  // [[load]] kind = "pressure" (follower loads)
  RayleighDamping damping;
  Eigen::Vector3d initial_velocity = Eigen::Vector3d::Zero();
  Points initial_positions;   // every node's start (initial.flatten, initial.from); empty: the rest positions
  Points initial_velocities;  // every node's start velocity (initial.from); empty: initial_velocity
  // Node n's velocity at the start: a resumed run's, else initial.from's, else initial.velocity.
  Eigen::Vector3d start_velocity(const StartState* start, int n) const {
    if (start) return start->velocities.col(n);
    return initial_velocities.cols() ? Eigen::Vector3d(initial_velocities.col(n)) : initial_velocity;
  }
  std::vector<std::pair<std::string, std::vector<int>>> zones;  // name, sorted tet indices
  // Zones (indices into `zones`, increasing) whose volume is at every configuration a linear
  // combination of the others' (redundant_zones): measured and written like any zone, but given no
  // constraint row, which would only make the KKT matrix singular.
  std::vector<int> redundant_zones;
  double zone_restore_time =
      0.0;                 // zones.restore_time (s): zone targets go from the start's volumes to the rest volumes
  bool keep_zones = true;  // zones.keep: false measures the zones' volumes without constraining them
  IntegratorSpec integrator;
  FramesSpec frames;
  OutputSpec output;
  std::shared_ptr<Skeleton> skeleton;        // [skeleton]: bones that drive their bound nodes; null without
  std::shared_ptr<const RenderMesh> render;  // [character]: its render mesh in the tets; null without
  // [[muscle]]: fibres and activation per muscle (body_setup.hpp); [muscles] activation_scale.
  struct MuscleSpec {
    std::string name;
    std::vector<int> tets;                // sorted
    std::vector<Eigen::Vector3d> fibres;  // unit rest direction per tet of `tets`
    MuscleLaw law;
    ActivationCurve activation;
  };
  std::vector<MuscleSpec> muscles;
  double activation_scale = 1.0;
  // What the user should know about the scene as written (a coarse mesh for its zones): one line
  // each, printed by `isochor run` and `isochor mesh`.
  std::vector<std::string> notes;

  // Every node driven by [[boundary]] or bound to a bone, and their positions and velocities at t.
  std::vector<int> driven_nodes() const;
  void drive(double t, Points& x, Eigen::VectorXd* xdot) const;
  // The factor on gravity at time t (forces.gravity_ramp).
  double gravity_scale(double t) const;
  // Each muscle's activation at time t (activation_scale applied, clamped to [0, 1]).
  std::vector<double> activations(double t) const;
  // Sorted distinct times where what the scene prescribes is not smooth in time: drivers', bones'
  // and moving colliders' breakpoints (drivers.hpp), the end of the gravity ramp.
  std::vector<double> breakpoints() const;
};

// Parses a scene file with overrides; every key is checked and unknown keys are errors.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {});
// character_mesh: a [character]'s filled mesh from an earlier run of the scene (parse_character).
Scene parse_scene(SceneFile file, const Mesh* character_mesh = nullptr);
// What the run file records besides the body: the up direction, the colliders and the bones (output.hpp).
SceneRecord scene_record(const Scene& sc);
// What an output of the scene records of it (`command`: "run", "mesh"): its text as run, its file,
// the record above, its inputs' digests and paths (an output never replaces one of them).
RunInfo run_info(const Scene& sc, const std::string& command);
// The skeleton's bones at time t as Frame::bone_poses holds them (12 per bone; empty without one).
void bone_poses(const Scene& sc, double t, std::vector<double>& out);

// Keyframes of a driver or joint: `times`, `per_time` numbers of `key` per time (scaled by `scale`,
// into x, y, z of the values) and `interpolation`; `what` names the numbers in errors. The knots
// may be another key than `times` (an activation keyed by joint angles), scaled by `knot_scale`.
Driver parse_keyframes(const Section& b, const std::string& key, int per_time, double scale, const std::string& what,
                       const std::string& knots = "times", double knot_scale = 1.0);

// What a material means beyond its name, for a user who reads mu as neo-Hooke's: one line for
// "snh" (Smith et al.'s re-parametrisation and its uniaxial curve), empty for the others.
std::string material_note(const MaterialSpec& m);

// A table's elastic constants: mu and lambda (defaults as given) or E and nu, not both.
std::pair<double, double> parse_lame(const Section& s, double mu, double lambda);

// Lamé parameters from Young's modulus and Poisson's ratio.
std::pair<double, double> lame_from_young(double E, double nu);

}  // namespace isochor
