// The few places where SUNDIALS 6.4 (Debian 12) and 7.x differ for isochor, behind one name each:
// the context's communicator argument, the success and failure codes that 7.0 moved to
// SUNErrCode, and how a solver's error messages are silenced (7.0 removed *SetErrHandlerFn).
// The types are sunrealtype and sunbooleantype, which both lines have.
#pragma once
#include <sundials/sundials_config.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_nonlinearsolver.h>

#if SUNDIALS_VERSION_MAJOR >= 7
#include <sundials/sundials_errors.h>
#endif

namespace isochor::sun {

#if SUNDIALS_VERSION_MAJOR >= 7
inline int create_context(SUNContext* ctx) { return SUNContext_Create(SUN_COMM_NULL, ctx); }
constexpr int kSuccess = SUN_SUCCESS;
constexpr int kLinearFailUnrecoverable = SUN_ERR_EXT_FAIL;
constexpr int kNonlinearMemNull = SUN_ERR_ARG_CORRUPT;
constexpr int kNonlinearIllInput = SUN_ERR_ARG_INCOMPATIBLE;
// Messages of every solver on this context are dropped: failures are reported by the caller. The
// handler stack must not be left empty, so a handler that does nothing replaces the default one.
inline void ignore_error(int, const char*, const char*, const char*, SUNErrCode, void*, SUNContext) {}
inline int silence_errors(SUNContext ctx) {
  const int flag = SUNContext_ClearErrHandlers(ctx);
  return flag != SUN_SUCCESS ? flag : SUNContext_PushErrHandler(ctx, ignore_error, nullptr);
}
#else
inline int create_context(SUNContext* ctx) { return SUNContext_Create(nullptr, ctx); }
constexpr int kSuccess = SUNLS_SUCCESS;
static_assert(SUNLS_SUCCESS == SUN_NLS_SUCCESS, "one success code for both kinds of solver");
constexpr int kLinearFailUnrecoverable = SUNLS_PACKAGE_FAIL_UNREC;
constexpr int kNonlinearMemNull = SUN_NLS_MEM_NULL;
constexpr int kNonlinearIllInput = SUN_NLS_ILL_INPUT;
// SUNDIALS 6 silences per solver memory (KINSetErrHandlerFn, IDASetErrHandlerFn): nothing here.
inline int silence_errors(SUNContext) { return 0; }
#endif

}  // namespace isochor::sun
