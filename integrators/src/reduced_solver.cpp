// The Newton system of the GGL form, reduced to the effective stiffness S.
// With rhs (r1, r2, r3, r4) and unknowns (dq, dv, dl, dm), V = c M - df/dv, B = d(G v)/dq:
//   row 1:  dv = (c I + H_mu) dq + G^T dm - r1
//   row 2:  S dq + V G^T dm + G^T dl = r2 + V r1,   S = -df/dq + H_lambda + c V   (H_mu left out)
//   row 3:  G dq = r3
//   row 4:  (B + c G) dq + G G^T dm = r4 + G r1
// S is factored by CHOLMOD (SymmetricFactor: METIS ordering, supernodal, LDL^T if indefinite) or
// solved by block-Jacobi PCG (linear_solver = krylov); Z1 = S^-1 G^T and Z2 = S^-1 V G^T turn
// rows 3 and 4 into a dense 2m x 2m system for (dl, dm). Computed directly, (B + c G) Z2 - G G^T
// cancels to O(1/c) of its terms (Z2 ~ G^T / c for large c); with A = S - c V and
// Z3 = S^-1 A G^T, Z2 = (G^T - Z3) / c and the block is ((B G^T - B Z3) / c - G Z3), free of
// that cancellation.
#include <Eigen/Dense>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "isochor/integrators/ggl.hpp"
#include "isochor/integrators/sparse_factor.hpp"
#include "isochor/base/error.hpp"

namespace isochor {

struct ReducedSolver::Impl {
  const GglForm& form;
  Index n, m;
  std::unique_ptr<SymmetricSolver> S;
  std::vector<double> Sx;  // values of S in the system's pattern
  std::vector<double> Ax;  // the v-q block (A), contiguous in that pattern
  // V and c I + H_mu without their zero entries, for the two products of every solve: undamped,
  // V = c M is diagonal, and H_mu lives on the constrained nodes only (a global zone: the surface).
  struct Compact {
    std::vector<Index> ptr, idx, pos;  // pos: the entry's index in the system's pattern
    std::vector<Index> diag;           // per row, its diagonal entry
    std::vector<double> val;
  } Vc, Qc;
  Eigen::MatrixXd Gt, W, Z1, Z2, Z3, Bt, BcG;  // n x m: G^T, A G^T, S^-1 G^T, S^-1 V G^T, S^-1 A G^T, B^T, B^T + c G^T
  Eigen::PartialPivLU<Eigen::MatrixXd> small;
  // Zones whose constraints are linearly dependent (zones.global over patches that partition the
  // mesh: the global volume is the patches' sum) make the 2m x 2m system singular; it is then
  // solved in the least-squares sense with the smallest multipliers (the constraints themselves
  // are consistent, so Newton's update is the same; only the split of the pressure among the
  // dependent zones is chosen).
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> rank_deficient;
  Eigen::VectorXd row_scale, col_scale;
  bool singular = false;
  const double* vals = nullptr;
  double cj = 0;
  // Work vectors, sized once: a solve allocates nothing. tn1, tn2, tm1, tm2 hold products, each
  // evaluated on its own and then combined (the order of the arithmetic of the expressions they replace).
  VectorXd b1, y, dq, tmp, rhs, z, tn1, tn2, tm1, tm2;

  std::string capture_path;  // capture_next: written at the next solve
  double capture_t = 0;
  bool ok = true;  // every solve of S in the current setup/solve succeeded
  // PCG (krylov) falls back to CHOLMOD for the rest of a setup where it fails (S indefinite, e.g.
  // inverted elements, or no convergence): the next setup tries PCG again.
  const bool fallback;
  std::unique_ptr<SymmetricSolver> direct;  // created at the first fallback
  bool use_direct = false;
  long fallbacks = 0;
  bool switch_to_direct() {
    if (!fallback || use_direct) return false;
    if (!direct) direct = make_symmetric_solver(form.system().pattern(), SymmetricSolverKind::cholmod);
    fallbacks++;
    use_direct = direct->factor(Sx.data());
    return use_direct;
  }
  Impl(const GglForm& f, SymmetricSolverKind kind, double pcg_tol)
      : form(f),
        n(f.n()),
        m(f.m()),
        S(make_symmetric_solver(f.system().pattern(), kind, pcg_tol, f.system().partition())),
        fallback(kind != SymmetricSolverKind::cholmod) {
    Sx.resize(f.system().pattern().nnz());
    Ax.resize(Sx.size());
    Gt.setZero(n, m), W.setZero(n, m), Z1.setZero(n, m), Z2.setZero(n, m), Z3.setZero(n, m), Bt.setZero(n, m);
    b1.resize(n), y.resize(n), dq.resize(n), tmp.resize(n), rhs.resize(2 * m), z.resize(2 * m);
    tn1.resize(n), tn2.resize(n), tm1.resize(m), tm2.resize(m);
    BcG.setZero(n, m);
  }

  // The nonzero entries of the Jacobian block whose entry k of the pattern sits at vals[slot[k]],
  // column by column in the pattern's order (zeros left out change no sum), and every diagonal
  // entry (retarget moves them).
  void compact(const double* vals, const std::vector<Index>& slot, Compact& c) const {
    const SparsePattern& K = form.system().pattern();
    c.ptr.assign(static_cast<std::size_t>(n) + 1, 0);
    c.idx.clear();
    c.pos.clear();
    c.val.clear();
    c.diag.assign(static_cast<std::size_t>(n), -1);
    for (Index i = 0; i < n; ++i) {
      for (Index k = K.col_ptr[i]; k < K.col_ptr[i + 1]; ++k)
        if (const double x = vals[slot[k]]; x != 0.0 || K.row_ind[k] == i) {
          if (K.row_ind[k] == i) c.diag[i] = static_cast<Index>(c.idx.size());
          c.idx.push_back(K.row_ind[k]);
          c.pos.push_back(k);
          c.val.push_back(x);
        }
      c.ptr[i + 1] = static_cast<Index>(c.idx.size());
    }
  }
  // out = X x, X a symmetric block of the Jacobian (v-v: V, v-q: A, q-q: c I + H_mu) by columns
  // (cp, ri, xv): row i of X is its column i, so each out[i] is a gather (parallel, and summed in
  // the same order for any thread count). On P ranks each rank gathers its own rows and shares
  // them.
  void times(const Index* cp, const Index* ri, const double* xv, const double* x, double* out, bool add = false) const {
    const DofPartition* part = form.system().partition();
    const Index lo = part ? part->begin() : 0, hi = part ? part->end() : n;
#pragma omp parallel for schedule(static)
    for (Index i = lo; i < hi; ++i) {
      double sum = 0;
      for (Index k = cp[i]; k < cp[i + 1]; ++k) sum += xv[k] * x[ri[k]];
      out[i] = add ? out[i] + sum : sum;
    }
    if (part) part->ranks->share(out, part->offsets);
  }
  void times(const Compact& X, const double* x, double* out, bool add = false) const {
    times(X.ptr.data(), X.idx.data(), X.val.data(), x, out, add);
  }
  // The m borders for the current S and c_j (W = A G^T, G^T and B^T set): Z1, Z3, Z2 and the
  // 2m x 2m system C. warm: Z1 and Z3 hold S^-1 G^T and S^-1 A G^T of the same setup at c_j /
  // ratio; scaled by 1 / ratio^2 (S ~ c_j^2 M at the small steps where c_j moves most), they
  // start CG.
  void borders(double ratio = 0) {
    for (Index j = 0; j < m; ++j) {
      if (ratio > 0) {
        Z1.col(j) /= ratio * ratio;
        Z3.col(j) /= ratio * ratio;
        solve_S(Gt.col(j).data(), Z1.col(j).data(), true);
        solve_S(W.col(j).data(), Z3.col(j).data(), true);
      } else {
        solve_S(Gt.col(j).data(), Z1.col(j).data());
        solve_S(W.col(j).data(), Z3.col(j).data());
      }
    }
    Z2 = (Gt - Z3) / cj;
    const Eigen::MatrixXd GtG = Gt.transpose() * Gt;
    Eigen::MatrixXd C(2 * m, 2 * m);
    C.topLeftCorner(m, m) = Gt.transpose() * Z1;
    C.topRightCorner(m, m) = (GtG - Gt.transpose() * Z3) / cj;
    BcG = Bt + cj * Gt;
    C.bottomLeftCorner(m, m) = BcG.transpose() * Z1;
    C.bottomRightCorner(m, m) = (Bt.transpose() * Gt - Bt.transpose() * Z3) / cj - Gt.transpose() * Z3;
    small.compute(C);
    // rcond below 1e-17: LU's solution would be rounding. Then C is equilibrated (rows, then
    // columns, to unit largest entries: its blocks differ by powers of c_j) and decomposed with
    // rank revealed at 1e-12.
    singular = !(small.rcond() > 1e-17);
    if (singular) {
      row_scale = C.cwiseAbs().rowwise().maxCoeff().cwiseMax(1e-300).cwiseInverse();
      C = row_scale.asDiagonal() * C;
      col_scale = C.cwiseAbs().colwise().maxCoeff().transpose().cwiseMax(1e-300).cwiseInverse();
      C = C * col_scale.asDiagonal();
      rank_deficient.setThreshold(1e-12);
      rank_deficient.compute(C);
    }
  }
  void solve_S(const double* b, double* x, bool from_guess = false) {
    if (!use_direct && (from_guess ? S->solve_from(b, x) : S->solve(b, x))) return;
    if (use_direct || switch_to_direct()) {
      ok = direct->solve(b, x) && ok;
      return;
    }
    ok = false;
  }
};

ReducedSolver::ReducedSolver(const GglForm& form, SymmetricSolverKind kind, double pcg_tol)
    : impl_(std::make_unique<Impl>(form, kind, pcg_tol)) {}
ReducedSolver::~ReducedSolver() = default;

double ReducedSolver::factor_nnz() const { return impl_->S->factor_nnz(); }
long ReducedSolver::iterations() const { return impl_->S->iterations(); }
long ReducedSolver::fallbacks() const { return impl_->fallbacks; }
double ReducedSolver::analyse_seconds() const { return impl_->S->analyse_seconds(); }
void ReducedSolver::capture_next(const std::string& path, double t) {
  impl_->capture_path = path;
  impl_->capture_t = t;
}

bool ReducedSolver::setup(double cj, const double* vals) {
  Impl& s = *impl_;
  s.vals = vals;
  s.cj = cj;
  const GglForm& f = s.form;
  const Index m = s.m;
  for (std::size_t k = 0; k < f.vq.size(); ++k) {
    s.Ax[k] = vals[f.vq[k]];
    s.Sx[k] = s.Ax[k] + cj * vals[f.vv[k]];
  }
  s.compact(vals, f.vv, s.Vc);
  s.compact(vals, f.qq, s.Qc);
  s.use_direct = false;
  s.ok = true;
  if (!s.S->factor(s.Sx.data()) && !s.switch_to_direct()) return false;
  if (m == 0) return true;
  const auto& rows = f.system().constraint_rows();
  s.Gt.setZero();
  s.Bt.setZero();
  for (Index j = 0; j < m; ++j)
    for (std::size_t k = 0; k < rows[j].size(); ++k) {
      s.Gt(rows[j][k], j) = vals[f.gq[j][k]];
      s.Bt(rows[j][k], j) = vals[f.gvq[j][k]];
    }
  for (Index j = 0; j < m; ++j)
    s.times(f.system().pattern().col_ptr.data(), f.system().pattern().row_ind.data(), s.Ax.data(), s.Gt.col(j).data(),
            s.W.col(j).data());  // A is full: no compact copy for m products
  s.borders();
  return s.ok;
}

double ReducedSolver::cj() const { return impl_->cj; }
bool ReducedSolver::can_retarget() const { return !impl_->use_direct && impl_->S->cheap_factor(); }

bool ReducedSolver::retarget(double cj, double* vals) {
  Impl& s = *impl_;
  if (cj == s.cj) return true;
  if (!can_retarget() || (vals && vals != s.vals))
    throw Error("ReducedSolver::retarget: not after this setup's factor");
  const GglForm& f = s.form;
  const VectorXd& M = f.system().mass();
  const double d = cj - s.cj, ratio = cj / s.cj;
  if (vals) f.shift_cj(d, vals);
  s.cj = cj;
  // The copies move as the Jacobian would: V's diagonal by d M, that of c_j I + H_mu by d (every
  // diagonal entry is in the compact copies). S = A + c_j V changes where V is not zero.
  for (Index i = 0; i < s.n; ++i) {
    s.Vc.val[s.Vc.diag[i]] += d * M[i];
    s.Qc.val[s.Qc.diag[i]] += d;
  }
  for (std::size_t e = 0; e < s.Vc.val.size(); ++e) {
    const Index k = s.Vc.pos[e];
    s.Sx[k] = s.Ax[k] + cj * s.Vc.val[e];
  }
  s.ok = true;
  if (!s.S->refactor(s.Sx.data(), s.Vc.pos) && !s.switch_to_direct()) return false;
  if (s.m) s.borders(s.use_direct ? 0.0 : ratio);
  return s.ok;
}

bool ReducedSolver::solve(const double* b, double* x, int refine) {
  impl_->ok = true;
  solve_once(b, x);
  if (refine <= 0) return impl_->ok;
  const SparsePattern& p = impl_->form.pattern();
  VectorXd r(p.n), dx(p.n);
  for (int it = 0; it < refine; ++it) {
    r = Eigen::Map<const VectorXd>(b, p.n);
    p.add_product(impl_->vals, x, -1.0, r.data());
    solve_once(r.data(), dx.data());
    Eigen::Map<VectorXd>(x, p.n) += dx;
  }
  return impl_->ok;
}

void ReducedSolver::solve_once(const double* b, double* x) {
  Impl& s = *impl_;
  const Index n = s.n, m = s.m;
  Eigen::Map<const VectorXd> r1(b, n), r2(b + n, n), r3(b + 2 * n, m), r4(b + 2 * n + m, m);
  s.times(s.Vc, r1.data(), s.tmp.data());
  s.b1 = r2 + s.tmp;
  if (!s.capture_path.empty()) {  // called from SUNDIALS: report, do not throw
    try {
      write_system(s.capture_path, s.form.system().pattern(), s.Sx.data(), s.b1.data(), s.cj, s.capture_t);
      std::fprintf(stderr, "isochor: captured S (n = %lld, c_j = %.6g, t = %.9g s) in %s\n",
                   static_cast<long long>(s.n), s.cj, s.capture_t, s.capture_path.c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "isochor: ISOCHOR_CAPTURE_S: %s\n", e.what());
    }
    s.capture_path.clear();
  }
  s.solve_S(s.b1.data(), s.y.data());
  // z = (dl, dm).
  const auto dl = s.z.head(m), dm = s.z.tail(m);
  if (m) {
    s.tm1.noalias() = s.Gt.transpose() * s.y;
    s.rhs.head(m) = s.tm1 - r3;
    s.tm1.noalias() = s.BcG.transpose() * s.y;
    s.tm2.noalias() = s.Gt.transpose() * r1;
    s.rhs.tail(m) = s.tm1 - r4 - s.tm2;
    if (s.singular)
      s.z = s.col_scale.cwiseProduct(s.rank_deficient.solve(s.row_scale.cwiseProduct(s.rhs)));
    else
      s.z = s.small.solve(s.rhs);
    s.tn1.noalias() = s.Z1 * dl;
    s.tn2.noalias() = s.Z2 * dm;
    s.dq = s.y - s.tn1 - s.tn2;
  } else {
    s.dq = s.y;
  }
  // Row 1 exactly: dv = (c I + H_mu) dq + G^T dm - r1, with (c I + H_mu) from the q-q block.
  Eigen::Map<VectorXd> dv(x + n, n);
  dv = -r1;
  if (m) {
    s.tn1.noalias() = s.Gt * dm;
    dv += s.tn1;
  }
  s.times(s.Qc, s.dq.data(), dv.data(), true);
  Eigen::Map<VectorXd>(x, n) = s.dq;
  if (m) {
    Eigen::Map<VectorXd>(x + 2 * n, m) = dl;
    Eigen::Map<VectorXd>(x + 2 * n + m, m) = dm;
  }
}

}  // namespace isochor
