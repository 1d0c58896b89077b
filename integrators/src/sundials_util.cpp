#include "sundials_util.hpp"

#include <nvector/nvector_serial.h>

#include <cmath>

namespace isochor {

namespace {
// The weighted sums of squares behind IDA's error test and Newton test, with four partial sums
// so that the additions overlap (SUNDIALS' serial loop waits for each addition, and with the
// mask, branches: on the 16^3 collapse its masked norm was 8% of the run). The mask enters as a
// factor 0 or 1 (IDA's id vector), so the sums are the same up to the order of the additions.
double weighted_squares(const double* x, const double* w, const double* id, sunindextype n) {
  double s[4] = {0, 0, 0, 0};
  sunindextype i = 0;
  for (; i + 4 <= n; i += 4)
    for (int k = 0; k < 4; ++k) {
      const double t = x[i + k] * w[i + k] * (id ? (id[i + k] > 0 ? 1.0 : 0.0) : 1.0);
      s[k] += t * t;
    }
  for (; i < n; ++i) {
    const double t = x[i] * w[i] * (id ? (id[i] > 0 ? 1.0 : 0.0) : 1.0);
    s[0] += t * t;
  }
  return (s[0] + s[1]) + (s[2] + s[3]);
}
sunrealtype wrms_norm(N_Vector x, N_Vector w) {
  const sunindextype n = NV_LENGTH_S(x);
  return std::sqrt(weighted_squares(NV_DATA_S(x), NV_DATA_S(w), nullptr, n) / static_cast<double>(n));
}
sunrealtype wrms_norm_mask(N_Vector x, N_Vector w, N_Vector id) {
  const sunindextype n = NV_LENGTH_S(x);
  return std::sqrt(weighted_squares(NV_DATA_S(x), NV_DATA_S(w), NV_DATA_S(id), n) / static_cast<double>(n));
}
}  // namespace

sun::Vector new_serial_vector(sunindextype n, SUNContext ctx) {
  sun::Vector v(check_ptr(N_VNew_Serial(n, ctx), "N_VNew_Serial"));
  check(N_VEnableFusedOps_Serial(v.get(), SUNFALSE), "N_VEnableFusedOps_Serial");  // (the default: see the header)
  // Clones (IDA's work vectors) copy the operations table.
  v->ops->nvwrmsnorm = wrms_norm;
  v->ops->nvwrmsnormmask = wrms_norm_mask;
  return v;
}

sun::Context sun::make_context(double t, bool quiet) {
  SUNContext ctx = nullptr;
  check(create_context(&ctx), "SUNContext_Create", t);
  sun::Context owned(ctx);
  if (quiet) check(silence_errors(ctx), "SUNContext_ClearErrHandlers", t);
  return owned;
}

namespace {
SUNLinearSolver_Type custom_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID custom_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int custom_initialize(SUNLinearSolver) { return sun::kSuccess; }
sunindextype custom_lastflag(SUNLinearSolver) { return 0; }
int custom_free(SUNLinearSolver S) {
  S->content = nullptr;  // owned by the caller
  SUNLinSolFreeEmpty(S);
  return sun::kSuccess;
}
}  // namespace

sun::LinearSolver make_custom_linear_solver(SUNContext ctx, void* content, CustomSetup setup, CustomSolve solve) {
  sun::LinearSolver S(check_ptr(SUNLinSolNewEmpty(ctx), "SUNLinSolNewEmpty"));
  S->content = content;
  S->ops->gettype = custom_type;
  S->ops->getid = custom_id;
  S->ops->initialize = custom_initialize;
  S->ops->setup = setup;
  S->ops->solve = solve;
  S->ops->lastflag = custom_lastflag;
  S->ops->free = custom_free;
  return S;
}

}  // namespace isochor
