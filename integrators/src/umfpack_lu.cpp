#include "umfpack_lu.hpp"

#include <umfpack.h>

namespace isochor {

UmfpackLu::UmfpackLu(Index n, const Index* col_ptr, const Index* row_ind)
    : n_(n), col_ptr_(col_ptr), row_ind_(row_ind) {
  static_assert(sizeof(Index) == sizeof(SuiteSparse_long), "UMFPACK's dl interface takes the pattern's indices");
  if (umfpack_dl_symbolic(n_, n_, col_ptr_, row_ind_, nullptr, &symbolic_, nullptr, nullptr) != UMFPACK_OK)
    symbolic_ = nullptr;
}

UmfpackLu::~UmfpackLu() {
  if (numeric_) umfpack_dl_free_numeric(&numeric_);
  if (symbolic_) umfpack_dl_free_symbolic(&symbolic_);
}

bool UmfpackLu::factor(const double* values) {
  if (!symbolic_) return false;
  if (numeric_) umfpack_dl_free_numeric(&numeric_);
  // A singular matrix leaves a factor with a zero pivot (UMFPACK_WARNING_singular_matrix).
  return umfpack_dl_numeric(col_ptr_, row_ind_, values, symbolic_, &numeric_, nullptr, nullptr) == UMFPACK_OK;
}

void UmfpackLu::solve(double* rhs) const {
  // No iterative refinement: it would read the matrix's values, which the caller may have
  // changed since the factorisation it reuses; KLU's solve does none either.
  double control[UMFPACK_CONTROL];
  umfpack_dl_defaults(control);
  control[UMFPACK_IRSTEP] = 0;
  b_.assign(rhs, rhs + n_);
  umfpack_dl_solve(UMFPACK_A, col_ptr_, row_ind_, nullptr, rhs, b_.data(), numeric_, control, nullptr);
}

double UmfpackLu::factor_entries() const {
  SuiteSparse_long lnz = 0, unz = 0, nr = 0, nc = 0, nzud = 0;
  if (!numeric_ || umfpack_dl_get_lunz(&lnz, &unz, &nr, &nc, &nzud, numeric_) != UMFPACK_OK) return 0;
  return static_cast<double>(lnz + unz);
}

}  // namespace isochor
