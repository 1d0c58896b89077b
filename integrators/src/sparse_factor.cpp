#include "isochor/integrators/sparse_factor.hpp"

#include <cholmod.h>

#include <chrono>

#include <cmath>
#include <cstring>

namespace isochor {

struct SymmetricFactor::Impl {
  Index n;
  cholmod_common c;
  cholmod_sparse* A = nullptr;
  cholmod_factor* L = nullptr;     // the factor of the last factorisation (one of the two below)
  cholmod_factor* Lsup = nullptr;  // supernodal LL^T (BLAS-3)
  cholmod_factor* Lldl = nullptr;  // simplicial LDL^T, for an indefinite matrix
  cholmod_dense *B = nullptr, *X = nullptr, *Y = nullptr, *E = nullptr;
  bool ldlt = false;    // the last factorisation was LDL^T
  bool refuse = false;  // refuse_indefinite(): no LDL^T
  int since_ldlt = 0;   // factorisations in LDL^T mode since LL^T was last tried
  static constexpr int kRetry = 8;
  double analyse = 0;             // seconds in cholmod_l_analyze (METIS ordering and symbolic factorisation)
  double flops = 0, entries = 0;  // of the supernodal LL^T, from its analysis
  cholmod_factor* analyze_ll() {
    cholmod_factor* f = analyze();
    flops = c.fl;
    entries = c.lnz;
    return f;
  }
  cholmod_factor* analyze() {
    const auto t0 = std::chrono::steady_clock::now();
    cholmod_factor* f = cholmod_l_analyze(A, &c);
    analyse += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return f;
  }

  explicit Impl(const SparsePattern& p) : n(p.n) {
    cholmod_l_start(&c);
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_METIS;
    c.postorder = 1;
    c.supernodal = CHOLMOD_AUTO;
    c.print = 0;
    c.error_handler = nullptr;
    A = cholmod_l_allocate_sparse(n, n, p.nnz(), 1, 1, -1, CHOLMOD_REAL, &c);
    std::memcpy(A->p, p.col_ptr.data(), sizeof(Index) * (n + 1));
    std::memcpy(A->i, p.row_ind.data(), sizeof(Index) * p.nnz());
    B = cholmod_l_allocate_dense(n, 1, n, CHOLMOD_REAL, &c);
  }
  ~Impl() {
    for (cholmod_factor** f : {&Lsup, &Lldl})
      if (*f) cholmod_l_free_factor(f, &c);
    cholmod_l_free_sparse(&A, &c);
    for (cholmod_dense** d : {&B, &X, &Y, &E})
      if (*d) cholmod_l_free_dense(d, &c);
    cholmod_l_finish(&c);
  }
};

SymmetricFactor::SymmetricFactor(const SparsePattern& p) : impl_(std::make_unique<Impl>(p)) {}
SymmetricFactor::~SymmetricFactor() = default;

bool SymmetricFactor::factor(const double* values) {
  // Supernodal LL^T while the matrix is positive definite. Once it is not (inverted elements), a
  // simplicial LDL^T (no pivoting, fine while no pivot is zero), which is much slower without
  // BLAS-3 (a 14.7K-dof cube collapsing: 1.2 s per factorisation), so LL^T is tried again every
  // kRetry factorisations: matrices turn definite again once the elements recover.
  Impl& s = *impl_;
  std::memcpy(s.A->x, values, sizeof(double) * s.A->nzmax);
  const bool try_ll = !s.ldlt || ++s.since_ldlt >= Impl::kRetry;
  if (try_ll) {
    if (!s.Lsup) s.Lsup = s.analyze_ll();
    cholmod_l_factorize(s.A, s.Lsup, &s.c);
    s.L = s.Lsup;
    s.ldlt = false;
  }
  if (s.refuse) return s.c.status == CHOLMOD_OK;
  if (!try_ll || s.c.status == CHOLMOD_NOT_POSDEF) {
    if (!s.Lldl) {
      s.c.supernodal = CHOLMOD_SIMPLICIAL;
      s.Lldl = s.analyze();
      s.c.supernodal = CHOLMOD_AUTO;
    }
    s.c.final_ll = 0;
    cholmod_l_factorize(s.A, s.Lldl, &s.c);
    s.L = s.Lldl;
    if (try_ll) s.since_ldlt = 0;  // LL^T just failed: count again from here
    s.ldlt = true;
  }
  return s.c.status == CHOLMOD_OK;
}

bool SymmetricFactor::solve(const double* b, double* x) {
  Impl& s = *impl_;
  if (!s.L || s.c.status != CHOLMOD_OK) return false;  // no usable factor
  std::memcpy(s.B->x, b, sizeof(double) * s.n);
  if (!cholmod_l_solve2(CHOLMOD_A, s.L, s.B, nullptr, &s.X, nullptr, &s.Y, &s.E, &s.c)) return false;
  std::memcpy(x, s.X->x, sizeof(double) * s.n);
  const double* xs = static_cast<const double*>(s.X->x);
  for (Index i = 0; i < s.n; ++i)
    if (!std::isfinite(xs[i])) return false;  // a zero pivot of LDL^T
  return true;
}

bool SymmetricFactor::used_ldlt() const { return impl_->ldlt; }
bool SymmetricFactor::factor_cost(double& flops, double& entries) {
  Impl& s = *impl_;
  if (!s.Lsup) s.Lsup = s.analyze_ll();
  flops = s.flops;
  entries = s.entries;
  return true;
}
void SymmetricFactor::refuse_indefinite() {
  impl_->refuse = true;
  impl_->ldlt = false;
}
double SymmetricFactor::analyse_seconds() const { return impl_->analyse; }

double SymmetricFactor::factor_nnz() const {
  const cholmod_factor* L = impl_->L;
  if (!L) return 0;
  return L->is_super ? static_cast<double>(L->xsize) : static_cast<double>(static_cast<const Index*>(L->p)[L->n]);
}

}  // namespace isochor
