// Conjugate gradients preconditioned by algebraic multigrid (hypre's BoomerAMG, Debian's
// libhypre) on the effective stiffness S: linear_solver = "amg" (sparse_factor.hpp). One rank
// (MPI_COMM_SELF); hypre needs MPI initialised, which is done here when nobody did it before.
#include "isochor/integrators/sparse_factor.hpp"

#ifdef ISOCHOR_HYPRE
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <HYPRE.h>
#include <HYPRE_krylov.h>
#include <HYPRE_parcsr_ls.h>
#include <mpi.h>

#include <cstdlib>
#include <vector>

namespace isochor {

namespace {

void ensure_mpi() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (initialised) return;
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  std::atexit([] {
    int finalised = 0;
    MPI_Finalized(&finalised);
    if (!finalised) MPI_Finalize();
  });
}

class AmgPcg : public SymmetricSolver {
 public:
  // Rows [lo, hi) of S on `comm`: column c of the pattern (both triangles stored) is row c.
  AmgPcg(const SparsePattern& p, Index lo, Index hi, MPI_Comm comm, double tol)
      : tol_(tol), comm_(comm), lo_(lo), hi_(hi), offset_(p.col_ptr[static_cast<std::size_t>(lo)]) {
    ensure_mpi();
    const std::size_t rows = static_cast<std::size_t>(hi - lo);
    rows_.resize(rows);
    ncols_.resize(rows);
    cols_.assign(p.row_ind.begin() + p.col_ptr[static_cast<std::size_t>(lo)],
                 p.row_ind.begin() + p.col_ptr[static_cast<std::size_t>(hi)]);
    for (Index c = lo; c < hi; ++c) {
      rows_[static_cast<std::size_t>(c - lo)] = static_cast<HYPRE_BigInt>(c);
      ncols_[static_cast<std::size_t>(c - lo)] = static_cast<HYPRE_Int>(p.col_ptr[c + 1] - p.col_ptr[c]);
    }
    HYPRE_IJMatrixCreate(comm_, lo, hi - 1, lo, hi - 1, &A_);
    HYPRE_IJMatrixSetObjectType(A_, HYPRE_PARCSR);
    HYPRE_IJMatrixSetRowSizes(A_, ncols_.data());
    HYPRE_IJMatrixInitialize(A_);
    for (HYPRE_IJVector* v : {&b_, &x_}) {
      HYPRE_IJVectorCreate(comm_, lo, hi - 1, v);
      HYPRE_IJVectorSetObjectType(*v, HYPRE_PARCSR);
      HYPRE_IJVectorInitialize(*v);
      HYPRE_IJVectorAssemble(*v);
    }
    nodal_ = p.n % 3 == 0 && lo % 3 == 0 && hi % 3 == 0;
  }
  ~AmgPcg() override {
    destroy_solver();
    HYPRE_IJMatrixDestroy(A_);
    HYPRE_IJVectorDestroy(b_);
    HYPRE_IJVectorDestroy(x_);
  }

  bool factor(const double* values) override {
    HYPRE_IJMatrixSetValues(A_, static_cast<HYPRE_Int>(rows_.size()), ncols_.data(), rows_.data(), cols_.data(),
                            values + offset_);
    HYPRE_IJMatrixAssemble(A_);
    HYPRE_IJMatrixGetObject(A_, reinterpret_cast<void**>(&parA_));
    // A new hierarchy for the new values (BoomerAMG is set up once per solver object).
    destroy_solver();
    HYPRE_BoomerAMGCreate(&amg_);
    HYPRE_BoomerAMGSetPrintLevel(amg_, 0);
    HYPRE_BoomerAMGSetMaxIter(amg_, 1);  // one V-cycle per preconditioning
    HYPRE_BoomerAMGSetTol(amg_, 0.0);
    if (nodal_) {  // x, y, z of each node (mesh systems): coarsen by node
      HYPRE_BoomerAMGSetNumFunctions(amg_, 3);
      HYPRE_BoomerAMGSetNodal(amg_, 1);
    }
    HYPRE_BoomerAMGSetCoarsenType(amg_, 10);  // HMIS
    HYPRE_BoomerAMGSetInterpType(amg_, 6);    // extended+i
    HYPRE_BoomerAMGSetPMaxElmts(amg_, 4);
    HYPRE_BoomerAMGSetAggNumLevels(amg_, 1);
    HYPRE_BoomerAMGSetStrongThreshold(amg_, 0.5);
    HYPRE_BoomerAMGSetRelaxType(amg_, 6);  // symmetric Gauss-Seidel: keeps the preconditioner symmetric
    HYPRE_BoomerAMGSetNumSweeps(amg_, 1);
    HYPRE_ParCSRPCGCreate(comm_, &pcg_);
    HYPRE_PCGSetTol(pcg_, tol_);
    HYPRE_PCGSetMaxIter(pcg_, 1000);
    HYPRE_PCGSetTwoNorm(pcg_, 1);
    HYPRE_PCGSetPrintLevel(pcg_, 0);
    HYPRE_PCGSetPrecond(pcg_, reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSolve),
                        reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSetup), amg_);
    HYPRE_ParVector b, x;
    HYPRE_IJVectorGetObject(b_, reinterpret_cast<void**>(&b));
    HYPRE_IJVectorGetObject(x_, reinterpret_cast<void**>(&x));
    return HYPRE_ParCSRPCGSetup(pcg_, parA_, b, x) == 0;
  }

  bool solve(const double* b, double* x) override {
    if (!pcg_) return false;
    const HYPRE_Int local = static_cast<HYPRE_Int>(rows_.size());
    if (zero_.empty()) zero_.assign(rows_.size(), 0.0);
    HYPRE_IJVectorSetValues(b_, local, rows_.data(), b + lo_);
    HYPRE_IJVectorSetValues(x_, local, rows_.data(), zero_.data());
    HYPRE_ParVector pb, px;
    HYPRE_IJVectorGetObject(b_, reinterpret_cast<void**>(&pb));
    HYPRE_IJVectorGetObject(x_, reinterpret_cast<void**>(&px));
    HYPRE_ClearAllErrors();
    HYPRE_ParCSRPCGSolve(pcg_, parA_, pb, px);
    HYPRE_Int its = 0;
    HYPRE_PCGGetNumIterations(pcg_, &its);
    iterations_ += its;
    double rel = 0;
    HYPRE_PCGGetFinalRelativeResidualNorm(pcg_, &rel);
    HYPRE_IJVectorGetValues(x_, local, rows_.data(), x + lo_);
    return HYPRE_GetError() == 0 && rel <= tol_ * 1.0001;
  }

  double factor_nnz() const override { return 0; }
  long iterations() const override { return iterations_; }

 private:
  void destroy_solver() {
    if (pcg_) HYPRE_ParCSRPCGDestroy(pcg_);
    if (amg_) HYPRE_BoomerAMGDestroy(amg_);
    pcg_ = amg_ = nullptr;
  }
  double tol_;
  MPI_Comm comm_;
  Index lo_, hi_, offset_;  // the rows held, and where their values start
  bool nodal_ = false;
  std::vector<HYPRE_BigInt> rows_, cols_;
  std::vector<HYPRE_Int> ncols_;
  std::vector<double> zero_;
  HYPRE_IJMatrix A_ = nullptr;
  HYPRE_ParCSRMatrix parA_ = nullptr;
  HYPRE_IJVector b_ = nullptr, x_ = nullptr;
  HYPRE_Solver amg_ = nullptr, pcg_ = nullptr;
  long iterations_ = 0;
};

}  // namespace

std::unique_ptr<SymmetricSolver> make_amg_solver(const SparsePattern& pattern, double tol) {
  return std::make_unique<AmgPcg>(pattern, 0, pattern.n, MPI_COMM_SELF, tol);
}
std::unique_ptr<SymmetricSolver> make_distributed_amg_solver(const SparsePattern& pattern, Index lo, Index hi,
                                                             double tol) {
  return std::make_unique<AmgPcg>(pattern, lo, hi, MPI_COMM_WORLD, tol);
}
bool amg_available() { return true; }

}  // namespace isochor

#else

namespace isochor {
std::unique_ptr<SymmetricSolver> make_amg_solver(const SparsePattern&, double) { return nullptr; }
std::unique_ptr<SymmetricSolver> make_distributed_amg_solver(const SparsePattern&, Index, Index, double) {
  return nullptr;
}
bool amg_available() { return false; }
}  // namespace isochor

#endif
