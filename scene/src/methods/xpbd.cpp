// integrator.kind = "xpbd": Macklin and Müller's constraints on every node of the mesh. XPBD
// moves points, not the scene system's unknowns: each frame is handed on as the free nodes'
// positions and velocities, so that the scene system measures it (energies of the scene's
// material, volumes, pressures) exactly as it measures every other method's frames.
#include "entries.hpp"

#include "isochor/integrators/xpbd.hpp"
#include "isochor/scene/xpbd_system.hpp"

namespace isochor {

void parse_xpbd(const Section& in, IntegratorKind, IntegratorSpec& spec) {
  XpbdOptions& o = spec.xpbd;
  o.dt = parse_dt(in);
  o.substeps = static_cast<int>(in.integer("substeps"));
  o.iterations = static_cast<int>(in.integer("iterations"));
  o.max_steps = parse_max_steps(in);
}

namespace {
class XpbdOnScene : public SteppingIntegrator {
 public:
  XpbdOnScene(const Scene& scene, const SceneSystem& system, XpbdOptions o)
      : system_(system), points_(scene), xpbd_(points_, o), free_(system.dofs().free_nodes) {}
  RunStats run(const std::vector<double>& times, const FrameCallback& on_frame) override {
    begin(times, on_frame);
    step(times.back());
    return finish();
  }
  void begin(const std::vector<double>& times, const FrameCallback& on_frame) override {
    points_.start = system_.start();
    q_.resize(3 * free_.size());
    v_.resize(3 * free_.size());
    xpbd_.begin(times, [this, on_frame](int k, double t, const VectorXd& x, const VectorXd& xv, const VectorXd& lambda,
                                        const RunStats::FrameSample& s) {
      for (std::size_t f = 0; f < free_.size(); ++f) {
        q_.segment<3>(3 * f) = x.segment<3>(3 * free_[f]);
        v_.segment<3>(3 * f) = xv.segment<3>(3 * free_[f]);
      }
      on_frame(k, t, q_, v_, lambda, s);
    });
  }
  double step(double t_out) override { return xpbd_.step(t_out); }
  RunStats finish() override { return xpbd_.finish(); }

 private:
  const SceneSystem& system_;
  XpbdMeshSystem points_;
  Xpbd xpbd_;
  std::vector<int> free_;
  VectorXd q_, v_;  // the free nodes' part of a frame, as the scene system counts its unknowns
};
}  // namespace

std::unique_ptr<Integrator> make_xpbd(const Scene& scene, SceneSystem& system) {
  return std::make_unique<XpbdOnScene>(scene, system, scene.integrator.xpbd);
}

}  // namespace isochor
