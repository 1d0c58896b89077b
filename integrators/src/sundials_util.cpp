#include "sundials_util.hpp"

#include <nvector/nvector_serial.h>

namespace isochor {

N_Vector new_serial_vector(sunindextype n, SUNContext ctx) {
  N_Vector v = check_ptr(N_VNew_Serial(n, ctx), "N_VNew_Serial");
  check(N_VEnableFusedOps_Serial(v, SUNFALSE), "N_VEnableFusedOps_Serial");  // (the default: see the header)
  return v;
}

namespace {
SUNLinearSolver_Type custom_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID custom_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int custom_initialize(SUNLinearSolver) { return SUNLS_SUCCESS; }
sunindextype custom_lastflag(SUNLinearSolver) { return 0; }
int custom_free(SUNLinearSolver S) {
  S->content = nullptr;  // owned by the caller
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}
}  // namespace

SUNLinearSolver make_custom_linear_solver(SUNContext ctx, void* content, CustomSetup setup, CustomSolve solve) {
  SUNLinearSolver S = check_ptr(SUNLinSolNewEmpty(ctx), "SUNLinSolNewEmpty");
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
