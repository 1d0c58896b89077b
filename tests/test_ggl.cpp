// The GGL residual's Jacobian against finite differences, and the reduced solver against a dense
// LU of the same Jacobian, on a real mesh system (driven nodes, damping, ground, two zones).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <omp.h>
#include <random>

#include "isochor/integrators/ggl.hpp"
#include "isochor/integrators/ida_integrator.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/scene/mesh_system.hpp"
#include "isochor/integrators/sparse_factor.hpp"
#include "block_laplacian.hpp"
#include "ggl_kkt.hpp"

using namespace isochor;

namespace {
SymmetricSolverKind solver_kind(const std::string& name) {
  return name == "pcg"   ? SymmetricSolverKind::pcg
         : name == "amg" ? SymmetricSolverKind::amg
                         : SymmetricSolverKind::cholmod;
}
// Every solver of the effective stiffness this build has (amg: with hypre).
std::vector<std::string> symmetric_solvers() {
  std::vector<std::string> k{"cholmod", "pcg"};
  if (amg_available()) k.push_back("amg");
  return k;
}
}  // namespace

namespace {

const char* kScene = R"(
[mesh]
shape = "box"
cells = 2
size = [0.1, 0.1, 0.1]
center = [0, 0, 0.051]
[material]
model = "cnh"
E = 5000.0
nu = 0.45
[zones]
global = true
[[zones.zone]]
name = "top"
select = { kind = "box", min = [-1, -1, 0.05], max = [1, 1, 1] }
[[boundary]]
select = { kind = "set", name = "xmin" }
kind = "sinusoid"
amplitude = [0.0, 0.01, 0.0]
frequency = 3.0
[contact]
ground = true
stiffness = 1e8
thickness = 0.004
damping = 0.05
[damping]
alpha = 0.5
beta = 0.01
)";

struct Fixture {
  Scene scene;
  MeshSystem sys{scene};
  GglForm form{sys};
  VectorXd y, yp;
  explicit Fixture(const std::string& text = kScene) : scene(parse_scene(SceneFile::parse(text, "ggl.toml"))) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    VectorXd q, v;
    sys.initial_state(0.1, q, v);
    // Perturbed node by node (in the mesh's order, whatever the order of the dofs).
    for (int node = 0; node < scene.mesh.num_nodes(); ++node) {
      const int f = sys.dofs().free_index[node];
      if (f < 0) continue;
      for (int i = 3 * f; i < 3 * f + 3; ++i) {
        q[i] += 0.004 * u(rng);
        v[i] = 0.05 * u(rng);
      }
    }
    const Index n = form.n(), m = form.m();
    y.resize(form.size());
    yp.resize(form.size());
    y << q, v, VectorXd::Constant(m, 0.0), VectorXd::Constant(m, 0.0);
    for (Index i = 0; i < form.size(); ++i) yp[i] = u(rng);
    for (Index j = 0; j < m; ++j) y[2 * n + j] = 50.0 * u(rng);  // pressures
  }
  Eigen::MatrixXd dense_jacobian(double t, double cj) {
    std::vector<double> vals(form.pattern().nnz());
    form.jacobian(t, cj, y.data(), yp.data(), vals.data());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(form.size(), form.size());
    const SparsePattern& p = form.pattern();
    for (Index c = 0; c < p.n; ++c)
      for (Index k = p.col_ptr[c]; k < p.col_ptr[c + 1]; ++k) J(p.row_ind[k], c) = vals[k];
    return J;
  }
};

}  // namespace

TEST(Ggl, JacobianMatchesFiniteDifferencesOfTheResidual) {
  Fixture f;
  const Index n = f.form.n(), m = f.form.m();
  ASSERT_EQ(m, 2);
  // mu != 0 too, so that every block is exercised.
  for (Index j = 0; j < m; ++j) f.y[2 * n + m + j] = 0.3 * (j + 1);
  const double t = 0.1, cj = 250.0, h = 1e-7;
  const Eigen::MatrixXd J = f.dense_jacobian(t, cj);
  Eigen::MatrixXd Jfd(f.form.size(), f.form.size());
  VectorXd rp(f.form.size()), rm(f.form.size());
  for (Index i = 0; i < f.form.size(); ++i) {
    // dF/dy_i + cj dF/dy'_i, by differences along (e_i, cj e_i).
    VectorXd yp1 = f.y, yp2 = f.y, dp1 = f.yp, dp2 = f.yp;
    yp1[i] += h, yp2[i] -= h, dp1[i] += cj * h, dp2[i] -= cj * h;
    f.form.residual(t, yp1.data(), dp1.data(), rp.data());
    f.form.residual(t, yp2.data(), dp2.data(), rm.data());
    Jfd.col(i) = (rp - rm) / (2 * h);
  }
  // Rayleigh's stiffness term leaves out dK/dq v (documented), so compare the rest exactly and
  // that block loosely.
  const double rel = (J - Jfd).norm() / Jfd.norm();
  EXPECT_LT(rel, 1e-4) << rel;
  Eigen::MatrixXd Jd = J, Jfdd = Jfd;
  Jd.block(n, 0, n, n).setZero();
  Jfdd.block(n, 0, n, n).setZero();
  EXPECT_LT((Jd - Jfdd).norm() / Jfdd.norm(), 1e-6);
}

TEST(Ggl, JacobianWithoutDampingMatchesExactly) {
  Fixture f;
  Scene s2 = parse_scene(SceneFile::parse(kScene, "ggl.toml", {"damping.beta=0.0"}));
  MeshSystem sys2(s2);
  GglForm form(sys2);
  const double t = 0.1, cj = 250.0, h = 1e-7;
  std::vector<double> vals(form.pattern().nnz());
  const Index n = form.n(), m = form.m();
  VectorXd y = f.y;
  for (Index j = 0; j < m; ++j) y[2 * n + m + j] = 0.3 * (j + 1);
  form.jacobian(t, cj, y.data(), f.yp.data(), vals.data());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(form.size(), form.size());
  for (Index c = 0; c < form.pattern().n; ++c)
    for (Index k = form.pattern().col_ptr[c]; k < form.pattern().col_ptr[c + 1]; ++k)
      J(form.pattern().row_ind[k], c) = vals[k];
  Eigen::MatrixXd Jfd(form.size(), form.size());
  VectorXd rp(form.size()), rm(form.size());
  for (Index i = 0; i < form.size(); ++i) {
    VectorXd y1 = y, y2 = y, d1 = f.yp, d2 = f.yp;
    y1[i] += h, y2[i] -= h, d1[i] += cj * h, d2[i] -= cj * h;
    form.residual(t, y1.data(), d1.data(), rp.data());
    form.residual(t, y2.data(), d2.data(), rm.data());
    Jfd.col(i) = (rp - rm) / (2 * h);
  }
  EXPECT_LT((J - Jfd).norm() / Jfd.norm(), 1e-6);
}

namespace {
// The reduced solve (S by `kind`) of a real GGL Jacobian against a dense LU, on random right-hand
// sides: unrefined (what IDA uses) within `unrefined` relative residual; with one step of
// refinement as accurate as a backward-stable dense LU of the same matrix (the GGL matrix is badly
// conditioned at large c_j: even the dense LU leaves ~1e-9).
// retarget: the setup is made at 0.6 c_j (and at 1.5 c_j before that, warm borders) and moved to
// c_j by ReducedSolver::retarget: its values must then equal the Jacobian's at c_j, and its solves
// the same accuracy as a setup at c_j.
void check_reduced_solve(const std::string& kind, double unrefined, bool retarget = false) {
  Fixture f;
  for (double cj : {50.0, 1000.0, 20000.0}) {
    const Eigen::MatrixXd J = f.dense_jacobian(0.1, cj);
    std::vector<double> vals(f.form.pattern().nnz());
    ReducedSolver rs(f.form, solver_kind(kind));
    if (retarget) {
      std::vector<double> exact(vals.size());
      f.form.jacobian(0.1, cj, f.y.data(), f.yp.data(), exact.data());
      f.form.jacobian(0.1, 1.5 * cj, f.y.data(), f.yp.data(), vals.data());
      ASSERT_TRUE(rs.setup(1.5 * cj, vals.data()));
      ASSERT_TRUE(rs.can_retarget());
      ASSERT_TRUE(rs.retarget(0.6 * cj, vals.data()));
      ASSERT_TRUE(rs.retarget(cj, vals.data()));
      EXPECT_EQ(rs.cj(), cj);
      double worst = 0;
      for (std::size_t k = 0; k < vals.size(); ++k)
        worst = std::max(worst, std::abs(vals[k] - exact[k]) / std::max(1.0, std::abs(exact[k])));
      EXPECT_LT(worst, 1e-12) << "cj " << cj;
    } else {
      f.form.jacobian(0.1, cj, f.y.data(), f.yp.data(), vals.data());
      ASSERT_TRUE(rs.setup(cj, vals.data()));
    }
    std::mt19937 rng(5);
    std::normal_distribution<double> nd;
    for (int trial = 0; trial < 3; ++trial) {
      VectorXd b(f.form.size()), x(f.form.size()), x0(f.form.size());
      for (Index i = 0; i < b.size(); ++i) b[i] = nd(rng);
      ASSERT_TRUE(rs.solve(b.data(), x0.data()));
      ASSERT_TRUE(rs.solve(b.data(), x.data(), 1));
      const double res0 = (J * x0 - b).norm() / b.norm(), res = (J * x - b).norm() / b.norm();
      const VectorXd xd = J.partialPivLu().solve(b);
      const double dense = (J * xd - b).norm() / b.norm();
      EXPECT_LT(res0, unrefined) << kind << " cj " << cj;
      EXPECT_LT(res, std::max(1e-10, 3.0 * dense)) << kind << " cj " << cj << " residual " << res;
      EXPECT_LT((x - xd).norm() / xd.norm(), 1e-8) << kind << " cj " << cj;
      std::printf("%s cj %g: residual %.2e, refined %.2e, dense LU %.2e, %ld CG iterations\n", kind.c_str(), cj, res0,
                  res, dense, rs.iterations());
    }
    if (kind == "pcg") {
      EXPECT_GT(rs.iterations(), 0);
    }
  }
}
}  // namespace

TEST(Ggl, ReducedSolveEqualsADenseSolveWhenMuIsZero) { check_reduced_solve("cholmod", 1e-6); }

// S by block-Jacobi PCG (linear_solver = krylov): its residual tolerance 1e-12 becomes ~1e-6 of
// the GGL system; a relative error of 1e-4 in a Newton correction slows Newton by 1e-4 per
// iteration, nothing against its own contraction (0.04 per iteration, median, on the 16^3 collapse).
TEST(Ggl, KrylovReducedSolveEqualsADenseSolveWhenMuIsZero) { check_reduced_solve("pcg", 1e-4); }

// A krylov setup moved to another c_j (IDA's step changed between Jacobians) solves as a setup
// made there; a direct factor cannot move.
TEST(Ggl, KrylovRetargetedSolveEqualsADenseSolve) { check_reduced_solve("pcg", 1e-4, true); }
// With mu != 0 the reduction leaves sum mu_j H_j out of S (row 2 drops V H_mu dq beside c_j V dq):
// the unrefined solve then errs, relative to the solution, by at most about ||H_mu||_inf / c_j
// (read off the dense Jacobian's q-q block, c_j I + H_mu), and one step of refinement gives the
// dense LU's solution.
TEST(Ggl, ReducedSolveWhereMuIsNotZero) {
  Fixture f;
  const Index n = f.form.n(), m = f.form.m();
  for (Index j = 0; j < m; ++j) f.y[2 * n + m + j] = 20.0 * (j + 1);
  for (double cj : {50.0, 1000.0}) {
    const Eigen::MatrixXd J = f.dense_jacobian(0.1, cj);
    double hmu = 0;
    for (Index i = 0; i < n; ++i) {
      double row = 0;
      for (Index c = 0; c < n; ++c) row += std::abs(J(i, c) - (c == i ? cj : 0.0));
      hmu = std::max(hmu, row);
    }
    ASSERT_GT(hmu, 0.0);
    std::vector<double> vals(f.form.pattern().nnz());
    f.form.jacobian(0.1, cj, f.y.data(), f.yp.data(), vals.data());
    ReducedSolver rs(f.form, solver_kind("cholmod"));
    ASSERT_TRUE(rs.setup(cj, vals.data()));
    std::mt19937 rng(7);
    std::normal_distribution<double> nd;
    VectorXd b(f.form.size()), x0(f.form.size()), x1(f.form.size());
    for (Index i = 0; i < b.size(); ++i) b[i] = nd(rng);
    const VectorXd xd = J.partialPivLu().solve(b);
    ASSERT_TRUE(rs.solve(b.data(), x0.data()));
    ASSERT_TRUE(rs.solve(b.data(), x1.data(), 1));
    const double err0 = (x0 - xd).norm() / xd.norm(), err1 = (x1 - xd).norm() / xd.norm();
    std::printf("cj %g: ||H_mu|| / c_j %.2e, error %.2e, refined %.2e\n", cj, hmu / cj, err0, err1);
    EXPECT_GT(err0, 1e-3 * hmu / cj);  // the left-out term shows
    EXPECT_LT(err0, hmu / cj);
    EXPECT_LT(err1, std::max(1e-9, 10 * err0 * hmu / cj));
  }
}

// Many zones (1-ring zones on a 3^3-cell box, some dependent ones dropped): IDA's "klu" solves
// the GGL system through the KKT matrix [S G^T; B + c G 0] and G G^T, refined against the GGL
// matrix (ggl_kkt.hpp). Against a dense LU of that matrix, with mu != 0 (H_mu, left out of the
// preconditioner, in J) and at small and large c_j: the answer within the refinement's tolerance
// in the weighted RMS norm it is given (weights 1 / (1e-4 |x| + 1e-8 max |x|) per block: about
// 1e-8 of each block); where the refinement does not converge, J's own LU answers.
TEST(Ggl, KktSolveOfManyZonesEqualsADenseSolve) {
  std::string text = kScene;
  text.replace(text.find("[zones]\nglobal = true"), std::string("[zones]\nglobal = true").size(),
               "[zones]\nglobal = false\nrings = 1");
  text.replace(text.find("cells = 2"), 9, "cells = 3");
  const auto named = text.find("[[zones.zone]]");
  text.erase(named, text.find("[[boundary]]") - named);
  Fixture f(text);
  const Index n = f.form.n(), m = f.form.m();
  ASSERT_GT(m, 32);
  for (Index j = 0; j < m; ++j) f.y[2 * n + m + j] = 2.0 * std::sin(1.0 + j);
  for (double cj : {5.0, 50.0, 1000.0, 20000.0}) {
    const Eigen::MatrixXd J = f.dense_jacobian(0.1, cj);
    std::vector<double> vals(f.form.pattern().nnz());
    f.form.jacobian(0.1, cj, f.y.data(), f.yp.data(), vals.data());
    GglKktSolver solver(f.form);
    ASSERT_TRUE(solver.setup(cj, vals.data()));
    std::mt19937 rng(11);
    std::normal_distribution<double> nd;
    for (int trial = 0; trial < 2; ++trial) {
      VectorXd b(f.form.size()), x(f.form.size()), w(f.form.size());
      for (Index i = 0; i < b.size(); ++i) b[i] = nd(rng);
      const VectorXd xd = J.partialPivLu().solve(b);
      const Index sizes[4] = {n, n, m, m};
      for (Index at = 0, k = 0; k < 4; at += sizes[k++]) {
        const double big = xd.segment(at, sizes[k]).cwiseAbs().maxCoeff();
        for (Index i = at; i < at + sizes[k]; ++i) w[i] = 1.0 / (1e-4 * std::abs(xd[i]) + 1e-8 * big);
      }
      const auto wrms = [&](const VectorXd& e) { return std::sqrt(e.cwiseProduct(w).squaredNorm() / e.size()); };
      const long before = solver.refinements();
      const long fallbacks = solver.fallbacks();
      ASSERT_TRUE(solver.solve(b.data(), x.data(), w.data())) << "cj " << cj;
      const double err = wrms(x - xd);
      std::printf("cj %g: %ld refinement steps, %s, weighted error %.2e\n", cj, solver.refinements() - before,
                  solver.refinements() == before   ? "J's LU"
                  : solver.fallbacks() > fallbacks ? "then J's LU"
                                                   : "converged",
                  err);
      EXPECT_LT(err, GglKktSolver::kRefineTol) << "cj " << cj;
    }
    // The contraction is K against c_j^2 M: at c_j = 5 on this stiff ground the refinement
    // cannot converge and J's LU solves; at 2e4 it converges.
    if (cj == 5.0) {
      EXPECT_EQ(solver.fallbacks(), 1);
    }
    if (cj == 20000.0) {
      EXPECT_EQ(solver.fallbacks(), 0);
    }
  }
}

TEST(Ggl, CholmodSetupCannotRetarget) {
  Fixture f;
  std::vector<double> vals(f.form.pattern().nnz());
  f.form.jacobian(0.1, 100.0, f.y.data(), f.yp.data(), vals.data());
  ReducedSolver rs(f.form, solver_kind("cholmod"));
  ASSERT_TRUE(rs.setup(100.0, vals.data()));
  EXPECT_FALSE(rs.can_retarget());
  EXPECT_EQ(rs.cj(), 100.0);
}

// The one-pass force_and_jacobians (elements visited once for the gradient, K, beta K and the
// damping force beta K v) against independent references: the force at v = 0 is minus the
// central differences of the elastic and external energies; the rest is the damping force, exactly
// linear in v: f(q, v) - f(q, 0) = -(alpha M + beta K) v with -df/dv from add_force_jacobians; and
// the Jacobians equal the separate call's.
TEST(MeshSystem, OnePassForceAndJacobiansEqualTheSeparateCalls) {
  Fixture f;
  const Index n = f.form.n();
  const VectorXd q = f.y.head(n), v = f.y.segment(n, n);
  const std::size_t nnz = f.sys.pattern().nnz();
  VectorXd f1, f2;
  std::vector<double> K1(nnz, 0.0), D1(nnz, 0.0), K2(nnz, 0.0), D2(nnz, 0.0);
  f.sys.add_force_jacobians(0.1, q, v, K1.data(), D1.data());
  f.sys.force_and_jacobians(0.1, q, v, f2, K2.data(), D2.data());
  // f(q, 0) against the energies' central differences, at a time when the driven nodes are at
  // rest (the sinusoid's turning point, t = 1/12 s at 3 Hz): Rayleigh's beta K v sees their
  // velocities too.
  const double kRest = 1.0 / 12.0;
  VectorXd f0;
  const VectorXd zero = VectorXd::Zero(n);
  f.sys.force_and_jacobians(kRest, q, zero, f0, nullptr, nullptr);
  auto potential = [&](const VectorXd& qq) {
    f.sys.set_state(kRest, qq, zero);
    const auto e = f.sys.energies();
    return e[1] + e[2];
  };
  VectorXd fd(n);
  const double h = 1e-6;
  for (Index i = 0; i < n; ++i) {
    VectorXd a = q, b = q;
    a[i] += h;
    b[i] -= h;
    fd[i] = -(potential(a) - potential(b)) / (2 * h);
  }
  EXPECT_LT((f0 - fd).norm(), 1e-6 * fd.norm()) << (f0 - fd).norm() << " of " << fd.norm();
  // The damping force: -D v over the pattern (D symmetric, both triangles stored).
  VectorXd fv, Dv = VectorXd::Zero(n);
  std::vector<double> D3(nnz, 0.0);
  f.sys.force_and_jacobians(kRest, q, v, fv, nullptr, D3.data());
  const SparsePattern& p = f.sys.pattern();
  for (Index c = 0; c < p.n; ++c)
    for (Index k = p.col_ptr[c]; k < p.col_ptr[c + 1]; ++k) Dv[p.row_ind[k]] += D3[k] * v[c];
  ASSERT_GT(Dv.norm(), 0.0);
  EXPECT_LT(((fv - f0) + Dv).norm(), 1e-10 * Dv.norm());
  EXPECT_LT((fv - f0).dot(v), 0.0);  // the damping dissipates
  f1 = f2;
  double dk = 0, dd = 0, sk = 0;
  for (std::size_t k = 0; k < nnz; ++k) {
    dk = std::max(dk, std::abs(K1[k] - K2[k]));
    dd = std::max(dd, std::abs(D1[k] - D2[k]));
    sk = std::max(sk, std::abs(K1[k]));
  }
  EXPECT_LT(dk, 1e-12 * sk);
  EXPECT_LT(dd, 1e-12 * sk);
}

// With an inverted element (one node pushed through its opposite face: CNH stays finite there),
// S can be indefinite: the direct reduced solve (CHOLMOD, LDL^T once indefinite) still matches a
// dense LU; so does PCG, which falls back to CHOLMOD for the setup where CG fails.
TEST(Ggl, ReducedSolversWithAnInvertedElement) {
  Fixture f;
  const Index n = f.form.n();
  const Tet& t = f.scene.mesh.tets()[0];
  // Move a free node of tet 0 through the plane of the other three.
  int node = -1, k = 0;
  for (; k < 4; ++k) {
    const auto& free = f.sys.dofs().free_nodes;
    auto it = std::find(free.begin(), free.end(), t[k]);
    if (it != free.end()) {
      node = static_cast<int>(it - free.begin());
      break;
    }
  }
  ASSERT_GE(node, 0);
  const Points& X = f.scene.mesh.rest_positions();
  const Eigen::Vector3d a = X.col(t[(k + 1) % 4]), b = X.col(t[(k + 2) % 4]), c = X.col(t[(k + 3) % 4]);
  const Eigen::Vector3d centroid = (a + b + c) / 3, p = X.col(t[k]);
  f.y.segment<3>(3 * node) = centroid - 0.5 * (p - centroid);  // mirrored to half its height: inverted
  f.sys.set_positions(0.1, f.y.head(n));
  ASSERT_GE(f.sys.inverted_tets(), 1);
  for (double cj : {50.0, 1000.0}) {
    const Eigen::MatrixXd J = f.dense_jacobian(0.1, cj);
    std::vector<double> vals(f.form.pattern().nnz());
    f.form.jacobian(0.1, cj, f.y.data(), f.yp.data(), vals.data());
    ASSERT_TRUE(vals.end() == std::find_if(vals.begin(), vals.end(), [](double v) { return !std::isfinite(v); }));
    std::mt19937 rng(11);
    std::normal_distribution<double> nd;
    VectorXd b(f.form.size());
    for (Index i = 0; i < b.size(); ++i) b[i] = nd(rng);
    const VectorXd xd = J.partialPivLu().solve(b);
    const double dense = (J * xd - b).norm() / b.norm();
    for (const std::string& kind : symmetric_solvers()) {
      ReducedSolver rs(f.form, solver_kind(kind));
      VectorXd x(f.form.size());
      const bool ok = rs.setup(cj, vals.data()) && rs.solve(b.data(), x.data(), 1);
      ASSERT_TRUE(ok) << kind << " cj " << cj;
      const double res = (J * x - b).norm() / b.norm();
      std::printf("%s cj %g: refined residual %.2e, dense LU %.2e, fallbacks %ld\n", kind.c_str(), cj, res, dense,
                  rs.fallbacks());
      EXPECT_LT(res, std::max(1e-10, 3.0 * dense)) << kind << " cj " << cj;
    }
  }
}

// The linear solvers on Jacobians that a real integration asked for: the 1,000-tet ball drop on
// IDA (KLU), through the impact (ground contact active, c_j ~ 1e5 from microsecond steps): two
// Jacobians with contact and two with inverted elements. Each is solved by the reduced solver with
// CHOLMOD and with PCG on random right-hand sides, to a relative residual of 1e-10 or as small as
// a dense LU of the same matrix leaves (3x) where the conditioning does not allow 1e-10.
// The reduced elimination leaves out the terms V sum mu_j H_j (ggl.hpp), which IDA's iterates do
// not make negligible (mu up to ~40 here: unrefined residuals 1e-5 .. 1e-2); each step of
// refinement with the exact J gains 2-3 digits, so three steps reach the dense LU's accuracy.
TEST(Ggl, SolversOnJacobiansCapturedFromABallDrop) {
  Scene scene = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/ball_drop.toml",
                           {"mesh.target_tets=1000", "frames.duration=0.04", "frames.rate=500.0",
                            "damping.beta=0"});  // undamped: the impact inverts tets
  MeshSystem sys(scene);
  struct Captured {
    double t, cj;
    int inverted;
    std::vector<double> y, values;
  };
  std::vector<Captured> captured;
  IdaOptions o;
  o.rtol = 1e-4;
  o.atol_q = 1e-7;
  o.linear_solver = LinearSolverKind::klu;
  GglForm form(sys);
  const Index N = form.size();
  int count = 0, with_contact = 0, with_inverted = 0;
  o.on_jacobian = [&](double t, double cj, const double* y, const double*, const double* values) {
    // The system's state is the one the Jacobian was just evaluated at.
    const int inverted = sys.inverted_tets();
    if (t < 0.0335 || count++ % 3) return;
    if (inverted > 0 ? with_inverted++ >= 2 : with_contact++ >= 2) return;
    captured.push_back(
        {t, cj, inverted, std::vector<double>(y, y + N), std::vector<double>(values, values + form.pattern().nnz())});
  };
  IdaIntegrator(sys, o).run(scene.frames.times(), [](int, double, const VectorXd&, const VectorXd&, const VectorXd&,
                                                     const RunStats::FrameSample&) {});
  ASSERT_EQ(captured.size(), 4u);
  const SparsePattern& p = form.pattern();
  const Index n = form.n();
  for (const Captured& c : captured) {
    // Contact: some node below the contact thickness.
    double lowest = 1e9;
    for (Index i = 2; i < n; i += 3) lowest = std::min(lowest, c.y[i]);
    EXPECT_LT(lowest, scene.colliders.at(0).law.thickness) << "t " << c.t;
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(N, N);
    for (Index col = 0; col < p.n; ++col)
      for (Index k = p.col_ptr[col]; k < p.col_ptr[col + 1]; ++k) J(p.row_ind[k], col) = c.values[k];
    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(J);
    std::mt19937 rng(7);
    std::normal_distribution<double> nd;
    for (const std::string& kind : symmetric_solvers()) {
      ReducedSolver rs(form, solver_kind(kind));
      ASSERT_TRUE(rs.setup(c.cj, c.values.data())) << kind << " t " << c.t;
      for (int trial = 0; trial < 2; ++trial) {
        VectorXd b(N), x(N);
        for (Index i = 0; i < N; ++i) b[i] = nd(rng);
        ASSERT_TRUE(rs.solve(b.data(), x.data(), 3)) << kind;
        const VectorXd xd = lu.solve(b);
        const double res = (J * x - b).norm() / b.norm(), dense = (J * xd - b).norm() / b.norm();
        EXPECT_LT(res, std::max(1e-10, 3.0 * dense)) << kind << " t " << c.t << " cj " << c.cj;
        std::printf("%s t %.5f cj %.3g, %d inverted tets, mu %.3g: residual %.2e, dense LU %.2e\n", kind.c_str(), c.t,
                    c.cj, c.inverted, c.y[2 * n + form.m()], res, dense);
      }
    }
  }
  EXPECT_EQ(with_inverted >= 2, true) << "no Jacobian with inverted elements was captured";
}

// The cost of a factorisation from CHOLMOD's analysis, on a dense n x n matrix: column j of L has
// n - j entries, so n(n+1)/2 entries and sum_j (n - j)^2 = n(n+1)(2n+1)/6 flops (CHOLMOD's count).
TEST(SymmetricFactor, FactorCostOfADenseMatrix) {
  const Index n = 40;
  SparsePattern p;
  p.n = n;
  p.col_ptr.push_back(0);
  for (Index c = 0; c < n; ++c) {
    for (Index r = 0; r < n; ++r) p.row_ind.push_back(r);
    p.col_ptr.push_back(static_cast<Index>(p.row_ind.size()));
  }
  SymmetricFactor f(p);
  double flops = 0, entries = 0;
  ASSERT_TRUE(f.factor_cost(flops, entries));
  EXPECT_EQ(entries, n * (n + 1) / 2.0);
  EXPECT_EQ(flops, n * (n + 1) * (2 * n + 1) / 6.0);
  double none = 0;
  EXPECT_FALSE(make_symmetric_solver(p, SymmetricSolverKind::pcg)->factor_cost(none, none));
}

// The fraction of a pattern's entries whose row and column lie in different halves of the dofs:
// what a thread that owns one half of the rows reads of the other's half in a product.
static double cross_half_fraction(const SparsePattern& p) {
  long cross = 0;
  for (Index c = 0; c < p.n; ++c)
    for (Index k = p.col_ptr[c]; k < p.col_ptr[c + 1]; ++k) cross += (c < p.n / 2) != (p.row_ind[k] < p.n / 2);
  return static_cast<double>(cross) / static_cast<double>(p.nnz());
}

// A scene's free nodes follow a Morton curve through the rest positions: the halves of the dof
// range are two compact pieces of the ball, whose shared face crosses a few percent of the
// matrix entries (a random numbering would cross half of them). Every free node once.
TEST(MeshSystem, DofsOfNeighbouringNodesAreNeighbours) {
  Scene scene = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/ball_drop.toml", {"mesh.target_tets=3000"});
  MeshSystem sys(scene);
  const DofMap& d = sys.dofs();
  std::vector<int> seen(scene.mesh.num_nodes(), 0);
  for (int n : d.free_nodes) seen.at(n)++;
  for (int n = 0; n < scene.mesh.num_nodes(); ++n) EXPECT_EQ(seen[n] + (d.free_index[n] < 0), 1) << "node " << n;
  const double scene_order = cross_half_fraction(sys.pattern());
  std::vector<std::vector<int>> tets;
  for (const Tet& t : scene.mesh.tets()) tets.push_back({t[0], t[1], t[2], t[3]});
  const double file_order =
      cross_half_fraction(pattern_from_elements(DofMap::make(scene.mesh.num_nodes(), scene.driven_nodes()), tets));
  std::printf("entries across the halves: %.3f in the scene's order, %.3f in the mesher's\n", scene_order, file_order);
  EXPECT_LT(scene_order, 0.1);
}

// Block-Jacobi PCG cuts the rows into chunks of nodes fixed by the size alone and sums dot
// products chunk by chunk in order: one thread and two give the same iterates, bit for bit. The
// matrix: a 7-point Laplacian on a 16^3 grid of nodes (4,096 nodes, 8 chunks) times a positive
// definite 3x3 block, plus the identity; the residual is checked with Eigen's own product.
TEST(BlockJacobiPcg, SameIteratesOnOneThreadAndOnTwo) {
  const Eigen::SparseMatrix<double> S = test::block_laplacian(16);
  const SparsePattern p = test::pattern_of(S);
  VectorXd b(p.n);
  std::mt19937 rng(3);
  std::normal_distribution<double> nd;
  for (Index i = 0; i < p.n; ++i) b[i] = nd(rng);
  const int threads = omp_get_max_threads();
  VectorXd x[2];
  long iterations[2];
  for (int run = 0; run < 2; ++run) {
    omp_set_num_threads(run + 1);
    auto solver = make_symmetric_solver(p, SymmetricSolverKind::pcg, 1e-10);
    ASSERT_TRUE(solver->factor(S.valuePtr()));
    x[run].resize(p.n);
    ASSERT_TRUE(solver->solve(b.data(), x[run].data()));
    iterations[run] = solver->iterations();
  }
  omp_set_num_threads(threads);
  EXPECT_EQ(iterations[0], iterations[1]);
  EXPECT_EQ((x[0] - x[1]).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE((b - S * x[0]).norm() / b.norm(), 1e-10 * (1 + 1e-6));
  EXPECT_GT(iterations[0], 5);  // an iteration, not a lucky first guess
}

// CHOLMOD's factor: supernodal LL^T while the matrix is positive definite, simplicial LDL^T when
// it is not, and LL^T again within 8 factorisations once the matrix is definite again (the slow
// LDL^T must not stay for the rest of a run after one indefinite matrix). Every solve exact.
TEST(SymmetricFactor, BackToLLtOnceTheMatrixIsDefiniteAgain) {
  const int k = 16, n = k * k * k;  // 7-point Laplacian on a k^3 grid: eigenvalues in (0, 12)
  auto id = [&](int i, int j, int l) { return (i * k + j) * k + l; };
  std::vector<std::vector<Index>> cols(n);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j)
      for (int l = 0; l < k; ++l) {
        const int a = id(i, j, l);
        cols[a].push_back(a);
        if (i > 0) cols[a].push_back(id(i - 1, j, l));
        if (i + 1 < k) cols[a].push_back(id(i + 1, j, l));
        if (j > 0) cols[a].push_back(id(i, j - 1, l));
        if (j + 1 < k) cols[a].push_back(id(i, j + 1, l));
        if (l > 0) cols[a].push_back(id(i, j, l - 1));
        if (l + 1 < k) cols[a].push_back(id(i, j, l + 1));
        std::sort(cols[a].begin(), cols[a].end());
      }
  SparsePattern p;
  p.n = n;
  p.col_ptr.push_back(0);
  for (const auto& c : cols) {
    p.row_ind.insert(p.row_ind.end(), c.begin(), c.end());
    p.col_ptr.push_back(static_cast<Index>(p.row_ind.size()));
  }
  // values of L + shift I
  auto values = [&](double shift) {
    std::vector<double> v(p.nnz());
    for (Index c = 0; c < n; ++c)
      for (Index q = p.col_ptr[c]; q < p.col_ptr[c + 1]; ++q) v[q] = p.row_ind[q] == c ? 6.0 + shift : -1.0;
    return v;
  };
  auto residual = [&](const std::vector<double>& v, const VectorXd& x, const VectorXd& b) {
    VectorXd r = -b;
    for (Index c = 0; c < n; ++c)
      for (Index q = p.col_ptr[c]; q < p.col_ptr[c + 1]; ++q) r[p.row_ind[q]] += v[q] * x[c];
    return r.norm() / b.norm();
  };
  SymmetricFactor f(p);
  const VectorXd b = VectorXd::LinSpaced(n, -1.0, 2.0);
  VectorXd x(n);
  const std::vector<double> spd = values(0.5), indefinite = values(-6.03);  // -6.03: between eigenvalues
  ASSERT_TRUE(f.factor(spd.data()));
  EXPECT_FALSE(f.used_ldlt());
  f.solve(b.data(), x.data());
  EXPECT_LT(residual(spd, x, b), 1e-12);
  ASSERT_TRUE(f.factor(indefinite.data()));
  EXPECT_TRUE(f.used_ldlt());
  f.solve(b.data(), x.data());
  EXPECT_LT(residual(indefinite, x, b), 1e-9);
  int back = -1;
  for (int t = 1; t <= 8; ++t) {
    ASSERT_TRUE(f.factor(spd.data()));
    f.solve(b.data(), x.data());
    EXPECT_LT(residual(spd, x, b), 1e-12) << "factorisation " << t;
    if (!f.used_ldlt() && back < 0) back = t;
  }
  EXPECT_EQ(back, 8);  // LL^T retried at the 8th factorisation after the switch, and kept
  EXPECT_FALSE(f.used_ldlt());
  // Refusing indefinite matrices (backward Euler's line search shifts them instead): the
  // indefinite matrix is no longer factored and leaves no usable factor; a definite one still is.
  f.refuse_indefinite();
  EXPECT_FALSE(f.factor(indefinite.data()));
  EXPECT_FALSE(f.used_ldlt());
  EXPECT_FALSE(f.solve(b.data(), x.data()));
  const std::vector<double> barely = values(-0.05);  // L's smallest eigenvalue: 6 - 6 cos(pi/(k+1)) = 0.102
  ASSERT_TRUE(f.factor(barely.data()));
  ASSERT_TRUE(f.solve(b.data(), x.data()));
  EXPECT_LT(residual(barely, x, b), 1e-9);
}
