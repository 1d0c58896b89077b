#include "isochor/integrators/sparse_factor.hpp"
#include "entries.hpp"

#include "isochor/base/error.hpp"

namespace isochor {

const std::vector<IntegratorEntry>& integrator_registry() {
  static const std::vector<IntegratorEntry> r = {
      {IntegratorKind::ida, "ida", parse_ida, make_ida},
      {IntegratorKind::statics, "static", parse_statics, make_statics},
      {IntegratorKind::backward_euler, "backward_euler", parse_backward_euler, make_backward_euler},
      {IntegratorKind::semi_implicit, "semi_implicit", parse_backward_euler, make_backward_euler},
      {IntegratorKind::xpbd, "xpbd", parse_xpbd, make_xpbd},
      {IntegratorKind::mass_spring, "mass_spring", parse_hong, make_hong},
  };
  return r;
}

const IntegratorEntry& integrator_entry(IntegratorKind kind) {
  for (const IntegratorEntry& e : integrator_registry())
    if (e.kind == kind) return e;
  throw Error(std::string("no integrator of kind ") + to_string(kind));
}

const char* to_string(IntegratorKind k) {
  for (const IntegratorEntry& e : integrator_registry())
    if (e.kind == k) return e.name;
  return "?";
}

std::unique_ptr<Integrator> make_integrator(const Scene& scene, SceneSystem& system) {
  return integrator_entry(scene.integrator.kind).make(scene, system);
}

void check_ranks(const Scene& sc) {
  const IntegratorSpec& in = sc.integrator;
  const IntegratorKind k = in.kind;
  const std::string at = sc.file.name() + ": ";
  if (k != IntegratorKind::ida && k != IntegratorKind::backward_euler && k != IntegratorKind::semi_implicit)
    throw Error(at + "integrator.kind = \"" + to_string(k) +
                "\" runs on one process (on MPI ranks: \"ida\", \"backward_euler\" or \"semi_implicit\")");
  const bool automatic =
      k == IntegratorKind::ida ? in.ida_linear_solver_auto : in.backward_euler.automatic_linear_solver;
  const LinearSolverKind ls = k == IntegratorKind::ida ? in.ida.linear_solver : in.backward_euler.linear_solver;
  if (!automatic && ls != LinearSolverKind::krylov && ls != LinearSolverKind::amg)
    throw Error(at + "integrator.linear_solver = \"" + to_string(ls) +
                "\" solves on one process (on MPI ranks: \"krylov\" or \"amg\", or \"auto\" with integrator.kind = "
                "\"ida\" or \"backward_euler\")");
}

long parse_max_steps(const Section& in) { return in.integer("max_steps", kDefaultMaxSteps); }

double parse_dt(const Section& in) { return in.number("dt", kDefaultFixedStep); }

static std::string linear_solver_name(const Section& in) { return in.string("linear_solver"); }

bool linear_solver_is_auto(const Section& in) { return linear_solver_name(in) == "auto"; }

void refuse_option(const Section& in, std::string_view key, const std::string& message) {
  if (in.has(key) && !(in.overridden("kind") && !in.overridden(key))) in.fail(key, message);
}

LinearSolverKind parse_linear_solver(const Section& in, LinearSolverKind automatic) {
  const std::string s = linear_solver_name(in);
  if (s == "amg" && !amg_available())
    in.fail("linear_solver",
            "\"amg\" needs isochor built with hypre and MPI (Debian: apt-get install libhypre-dev "
            "libopenmpi-dev, then rebuild)");
  return s == "klu"       ? LinearSolverKind::klu
         : s == "reduced" ? LinearSolverKind::reduced
         : s == "krylov"  ? LinearSolverKind::krylov
         : s == "amg"     ? LinearSolverKind::amg
                          : automatic;
}

}  // namespace isochor
