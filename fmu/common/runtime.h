/* What the FMI 2.0 API (fmi2_layer.c) and FMU state (fmu_state.c) share of the runtime
 * (runtime.c): the call-sequence check of the FMI 2.0 state machine, an instance's variable storage
 * and its inputs' extrapolation. Not for models: they call fmu_common.h.
 */
#ifndef FMU_RUNTIME_H
#define FMU_RUNTIME_H

#include "fmu_common.h"

#define LOG_ERROR(fmu, ...) fmu_log((fmu), fmi2Error, "logStatusError", __VA_ARGS__)

#define ANY_LIVE_PHASE                                                                            \
    (PHASE_INSTANTIATED | PHASE_INITIALIZATION | PHASE_STEP_COMPLETE | PHASE_STEP_FAILED |         \
     PHASE_TERMINATED | PHASE_ERROR)
#define AFTER_INITIALIZATION (PHASE_STEP_COMPLETE | PHASE_STEP_FAILED | PHASE_TERMINATED | PHASE_ERROR)

/* The phase's name, as a logged message says it. */
const char *fmu_phase_name(int phase);

/* The call-sequence check: may `call` be made now, in one of `phases`? Logs why not. */
int fmu_allowed(FmuInstance *fmu, const char *call, int phases);

/* Where variable `vr` is stored in the instance's snapshot. */
void *fmu_value_address(FmuInstance *fmu, int vr);

/* At a step's start from t0 (fmi.extrapolate_inputs): each input without a derivative from the
 * master gets one from the FMU itself. */
void fmu_extrapolate_inputs(FmuInstance *fmu, double t0);

/* The resources folder as a native path ending in '/' (allocated by the instance's callbacks), from
 * FMI 2.0's URI (file:///path/, file://localhost/path/, file:/path/, percent-encoded) or FMI 3.0's
 * native path; NULL for anything else (another scheme, none given). */
char *fmu_resources_folder(FmuInstance *fmu, const char *location);

#if MODEL_MODEL_EXCHANGE
/* Model Exchange's state and derivative variables (fmi2_me.c): 1 and the value if vr is one of
 * them, 0 otherwise. */
int fmu_me_value(FmuInstance *fmu, unsigned vr, double *value);
#endif

#endif
