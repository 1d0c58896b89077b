// IDA driven a step at a time (SteppingIntegrator: begin, step, finish) gives the frames that run
// gives, bit for bit; and an exception thrown by the system inside a SUNDIALS callback reaches
// the caller as itself (it is kept, SUNDIALS is told of an unrecoverable failure, and the
// exception is rethrown when the solver returns), for IDA and for KINSOL statics.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "dae_problems.hpp"
#include "isochor/base/error.hpp"
#include "isochor/integrators/ida_integrator.hpp"
#include "isochor/integrators/statics.hpp"

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
  ASSERT_EQ(stepped.t.size(), times.size());
  ASSERT_EQ(whole.t.size(), times.size());
  for (std::size_t k = 0; k < times.size(); ++k) {
    EXPECT_EQ(stepped.index[k], static_cast<int>(k));
    EXPECT_EQ(stepped.t[k], whole.t[k]);
    EXPECT_EQ(stepped.q[k], whole.q[k]) << "frame " << k;
    EXPECT_EQ(stepped.v[k], whole.v[k]) << "frame " << k;
    EXPECT_EQ(stepped.lambda[k], whole.lambda[k]) << "frame " << k;
  }
  EXPECT_EQ(sb.steps, sa.steps);
  EXPECT_EQ(sb.newton_iterations, sa.newton_iterations);
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
