// IDA, backward Euler (and semi-implicit), XPBD, Hong's mass-spring step and statics driven a step
// at a time (SteppingIntegrator: begin, step, finish) give the frames that run gives, bit for bit; and an exception
// thrown by the system inside a SUNDIALS callback reaches the caller as itself (it is kept, SUNDIALS is told of an
// unrecoverable failure, and the exception is rethrown when the solver returns), for IDA and for KINSOL statics.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "dae_problems.hpp"
#include "isochor/base/error.hpp"
#include "isochor/integrators/ida_integrator.hpp"
#include "isochor/integrators/statics.hpp"
#include "isochor/scene/integrator_registry.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/scene/scene_system.hpp"

using namespace isochor;
using test::CarAxis;
using test::dae_frames;

namespace {

struct Frames {
  std::vector<int> index;
  std::vector<double> t;
  std::vector<VectorXd> q, v, lambda;
  FrameCallback callback() {
    return [this](int k, double tf, const VectorXd& qf, const VectorXd& vf, const VectorXd& lf,
                  const RunStats::FrameSample&) {
      index.push_back(k);
      t.push_back(tf);
      q.push_back(qf);
      v.push_back(vf);
      lambda.push_back(lf);
    };
  }
};

// Every frame of the stepped run equals the whole run's, bit for bit, and so do the counts.
void expect_the_same_run(const Frames& whole, const RunStats& sa, const Frames& stepped, const RunStats& sb,
                         std::size_t frames) {
  ASSERT_EQ(stepped.t.size(), frames);
  ASSERT_EQ(whole.t.size(), frames);
  for (std::size_t k = 0; k < frames; ++k) {
    EXPECT_EQ(stepped.index[k], static_cast<int>(k));
    EXPECT_EQ(stepped.t[k], whole.t[k]);
    EXPECT_EQ(stepped.q[k], whole.q[k]) << "frame " << k;
    EXPECT_EQ(stepped.v[k], whole.v[k]) << "frame " << k;
    EXPECT_EQ(stepped.lambda[k], whole.lambda[k]) << "frame " << k;
  }
  EXPECT_EQ(sb.steps, sa.steps);
  EXPECT_EQ(sb.newton_iterations, sa.newton_iterations);
}

IdaOptions options() {
  IdaOptions o;
  o.rtol = 1e-7;
  o.atol_q = 1e-9;
  return o;
}

}  // namespace

TEST(IdaSteps, StepByStepGivesTheFramesOfRun) {
  CarAxis whole_problem, stepped_problem;
  const std::vector<double> times = dae_frames(whole_problem.end_time());
  Frames whole, stepped;
  IdaIntegrator a(whole_problem, options());
  const RunStats sa = a.run(times, whole.callback());

  IdaIntegrator b(stepped_problem, options());
  b.begin(times, stepped.callback());
  ASSERT_EQ(stepped.t.size(), 1u);  // frame 0, at the start
  // Targets between frames, on a frame, and past the end: each call reaches at least its target
  // (at most the last frame time) and has delivered exactly the frames at or before that time.
  for (double target : {0.0137, 0.5, 0.5, 1.2345, 2.0, 2.99, 10.0}) {
    const double reached = b.step(target);
    EXPECT_GE(reached, std::min(target, times.back()));
    EXPECT_LE(reached, times.back());
    std::size_t due = 0;
    while (due < times.size() && times[due] <= reached) ++due;
    EXPECT_EQ(stepped.t.size(), due) << "after step(" << target << ") reaching " << reached;
  }
  const RunStats sb = b.finish();
  expect_the_same_run(whole, sa, stepped, sb, times.size());
}

namespace {
// A 48-tet box hanging from its top face under gravity, with the model and integrator given.
Scene hanging_box(const std::string& model, const std::string& integrator, const std::string& frames) {
  return parse_scene(SceneFile::parse(R"(
[mesh]
shape = "box"
cells = 2
[material]
model = ")" + model + R"("
E = 2000.0
nu = 0.3
[[boundary]]
select = { kind = "set", name = "zmax" }
)" + integrator + frames,
                                      "hanging_box.toml"));
}
}  // namespace

// Every integrator kind, through the scene's registry: stepped to targets between frames,
// on a frame, twice on one time and past the end, each call reaches its target (within 1e-9 of a
// step, the tolerance by which a frame belongs to a step's end) and has delivered exactly the
// frames up to the time it reached; the frames equal run's bit for bit.
TEST(Stepping, EveryKindSteppedGivesTheFramesOfRun) {
  const std::string dynamic = "[frames]\nrate = 200.0\nduration = 0.05\n";
  const struct {
    std::string model, integrator, frames;
  } cases[] = {
      {"cnh", "[integrator]\nkind = \"ida\"\n", dynamic},
      {"cnh", "[integrator]\nkind = \"backward_euler\"\ndt = 1.5e-3\n", dynamic},
      {"snh", "[integrator]\nkind = \"semi_implicit\"\ndt = 1e-4\n", dynamic},
      {"snh_simple", "[integrator]\nkind = \"xpbd\"\ndt = 1e-3\n", dynamic},
      {"mass_spring", "[integrator]\nkind = \"mass_spring\"\ndt = 1e-4\n", dynamic},
      {"cnh", "[integrator]\nkind = \"static\"\n[forces]\ngravity_ramp = 1.0\n", "[frames]\ncount = 6\n"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.model + " " + c.integrator);
    const Scene sc = hanging_box(c.model, c.integrator, c.frames);
    const std::vector<double> times = sc.frames.times();
    auto whole_system = make_scene_system(sc), stepped_system = make_scene_system(sc);
    Frames whole, stepped;
    const RunStats sa = make_integrator(sc, *whole_system)->run(times, whole.callback());
    std::unique_ptr<Integrator> made = make_integrator(sc, *stepped_system);
    auto* b = dynamic_cast<SteppingIntegrator*>(made.get());
    ASSERT_NE(b, nullptr);
    b->begin(times, stepped.callback());
    ASSERT_EQ(stepped.t.size(), 1u);
    const double T = times.back();
    for (double target : {0.137 * T, 0.4 * T, 0.4 * T, times[3], 0.91 * T, 10 * T}) {
      const double reached = b->step(target);
      EXPECT_GE(reached, std::min(target, T) - 1e-9 * 1.5e-3);
      EXPECT_LE(reached, T * (1 + 1e-12) + 1.5e-3);
      std::size_t due = 0;
      while (due < times.size() && times[due] <= reached + 1e-9 * 1.5e-3) ++due;
      EXPECT_EQ(stepped.t.size(), due) << "after step(" << target << ") reaching " << reached;
    }
    const RunStats sb = b->finish();
    expect_the_same_run(whole, sa, stepped, sb, times.size());
    EXPECT_GT(whole.q.back().norm(), 0.0);
    EXPECT_NE(whole.q.back(), whole.q.front());  // it moved: the comparison is not of rest states
  }
}

TEST(Stepping, StepBeforeBeginIsRefused) {
  const Scene sc = hanging_box("cnh", "[integrator]\nkind = \"backward_euler\"\n", "");
  auto system = make_scene_system(sc);
  std::unique_ptr<Integrator> made = make_integrator(sc, *system);
  EXPECT_THROW(dynamic_cast<SteppingIntegrator&>(*made).step(1.0), Error);
}

TEST(IdaSteps, StepBeforeBeginIsRefused) {
  CarAxis problem;
  IdaIntegrator ida(problem, options());
  EXPECT_THROW(ida.step(1.0), Error);
}

namespace {
// The car axis whose force evaluation throws once past t_fail (as a system's own check would).
class ThrowingCarAxis : public CarAxis {
 public:
  explicit ThrowingCarAxis(double t_fail) : t_fail_(t_fail) {}
  void force(double t, const VectorXd& q, const VectorXd& v, VectorXd& f) override {
    if (t > t_fail_) throw Error("the system's own error at t = " + std::to_string(t));
    CarAxis::force(t, q, v, f);
  }
  void add_force_jacobians(double t, const VectorXd& q, const VectorXd& v, double* K, double* D) override {
    if (t > t_fail_) throw Error("the system's own error in its Jacobian");
    CarAxis::add_force_jacobians(t, q, v, K, D);
  }

 private:
  double t_fail_;
};
}  // namespace

TEST(Callbacks, AnExceptionInIdasResidualReachesTheCallerAsItself) {
  for (LinearSolverKind kind : {LinearSolverKind::klu, LinearSolverKind::reduced}) {
    ThrowingCarAxis problem(0.5);
    IdaOptions o = options();
    o.linear_solver = kind;
    IdaIntegrator ida(problem, o);
    Frames frames;
    try {
      ida.run(dae_frames(problem.end_time()), frames.callback());
      ADD_FAILURE() << "no exception";
    } catch (const IntegrationError& e) {
      ADD_FAILURE() << "IDA's failure instead of the system's error: " << e.what();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("the system's own error"), std::string::npos) << e.what();
    }
    // The frames up to the failure were delivered, and none after it.
    ASSERT_FALSE(frames.t.empty());
    EXPECT_LE(frames.t.back(), 0.5 + 1e-12);
    EXPECT_GE(frames.t.back(), 0.4);
    // The integrator can run again (its SUNDIALS objects were released and are made anew).
    ThrowingCarAxis later(100.0);
    IdaIntegrator again(later, o);
    Frames ok;
    again.run(dae_frames(0.1), ok.callback());
    EXPECT_EQ(ok.t.size(), dae_frames(0.1).size());
  }
}

TEST(Callbacks, AnExceptionInKinsolsResidualReachesTheCallerAsItself) {
  ThrowingCarAxis problem(0.5);
  StaticSolver statics(problem, StaticOptions{});
  Frames frames;
  try {
    statics.run({0.0, 0.25, 0.75}, frames.callback());
    ADD_FAILURE() << "no exception";
  } catch (const IntegrationError& e) {
    ADD_FAILURE() << "KINSOL's failure instead of the system's error: " << e.what();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the system's own error"), std::string::npos) << e.what();
  }
  EXPECT_EQ(frames.t.size(), 2u);
}
