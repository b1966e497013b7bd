/* FMU state (FMI 2.0, 2.1.8): an instance's FmuSnapshot taken, restored, freed and serialized,
 * each state tagged with this build's identity and a checksum, and a restored one validated as if
 * its values had been set one by one.
 */
#include "fmu_common.h"
#include "runtime.h"

#include <math.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* FMU state                                                                                   */

/* A state as the importer holds it: a tag that names this build and the snapshot's size and
 * checksum, whether the outputs were current, then the snapshot. The checksum covers every byte
 * that is read back from the tag's end on (the outputs_stale flag and the snapshot). A state pointer is checked by its
 * tag before anything is copied (a pointer from another FMU, or memory that is no state, is
 * refused without reading past the tag: every state is larger than it), and a restored snapshot is
 * validated as if its values had been set one by one. */
typedef struct {
    char magic[8];
    unsigned long long guid_hash, size, checksum;
    int outputs_stale;
} StateTag;

typedef struct {
    StateTag tag;
    FmuSnapshot s;
} StoredState;

static const char STATE_MAGIC[8] = "STEWST1";

#define FNV_OFFSET 1469598103934665603ULL

static unsigned long long fnv1a_from(unsigned long long hash, const void *data, size_t n) {
    const unsigned char *bytes = (const unsigned char *)data;
    for (size_t i = 0; i < n; i++) hash = (hash ^ bytes[i]) * 1099511628211ULL;
    return hash;
}

static unsigned long long fnv1a(const void *data, size_t n) { return fnv1a_from(FNV_OFFSET, data, n); }

/* The snapshot, then the outputs_stale flag. */
static unsigned long long state_checksum(const StoredState *stored) {
    return fnv1a_from(fnv1a(&stored->s, sizeof(FmuSnapshot)), &stored->tag.outputs_stale,
                      sizeof stored->tag.outputs_stale);
}

static void tag_state(StoredState *stored, int outputs_stale) {
    memcpy(stored->tag.magic, STATE_MAGIC, sizeof stored->tag.magic);
    stored->tag.guid_hash = fnv1a(MODEL_GUID, strlen(MODEL_GUID));
    stored->tag.size = sizeof(FmuSnapshot);
    stored->tag.outputs_stale = outputs_stale;
    stored->tag.checksum = state_checksum(stored);
}

/* Is this a state of this build, unaltered? Logs why not. */
static int state_is_ours(FmuInstance *fmu, const char *call, const StoredState *stored, int check_sum) {
    if (memcmp(stored->tag.magic, STATE_MAGIC, sizeof STATE_MAGIC) != 0 ||
        stored->tag.guid_hash != fnv1a(MODEL_GUID, strlen(MODEL_GUID)) || stored->tag.size != sizeof(FmuSnapshot)) {
        LOG_ERROR(fmu, "%s: not a state of this build of %s (%s)", call, MODEL_IDENTIFIER_STRING, MODEL_GUID);
        return 0;
    }
    if (check_sum && (stored->tag.checksum != state_checksum(stored) ||
                      (stored->tag.outputs_stale != 0 && stored->tag.outputs_stale != 1))) {
        LOG_ERROR(fmu, "%s: the state's bytes were altered (checksum mismatch)", call);
        return 0;
    }
    return 1;
}

/* The snapshot now in fmu->s as trustworthy as set values: a valid phase and time, every
 * parameter and input finite and within its bounds, finite internal states and solver memory,
 * and the model's own rules (which also rebuild model data such as a table from the snapshot). */
static int snapshot_valid(FmuInstance *fmu, const char *call) {
    const FmuSnapshot *s = &fmu->s;
    const int phase = s->phase;
    if (phase != PHASE_INSTANTIATED && phase != PHASE_INITIALIZATION && phase != PHASE_STEP_COMPLETE &&
        phase != PHASE_STEP_FAILED && phase != PHASE_TERMINATED && phase != PHASE_ERROR) {
        LOG_ERROR(fmu, "%s: the state's phase %d is not one of FMI 2.0's", call, phase);
        return 0;
    }
    if (s->continuous_time_mode != 0 && s->continuous_time_mode != (fmu->model_exchange ? 1 : 0)) {
        LOG_ERROR(fmu, "%s: the state's mode %d is not one of this instance's", call, s->continuous_time_mode);
        return 0;
    }
    if (!isfinite(s->time) || !isfinite(s->input_time) || !isfinite(s->stop_time) ||
        !isfinite(s->input_previous_time) || (s->input_previous_valid != 0 && s->input_previous_valid != 1)) {
        LOG_ERROR(fmu, "%s: the state's time is not finite", call);
        return 0;
    }
    for (int vr = 1; vr < VR_COUNT; vr++) {
        const FmuVariable *var = &fmu_variables[vr];
        if (var->causality == FMU_OUTPUT || var->causality == FMU_LOCAL || var->type == FMU_STRING) continue;
        const double value = var->type == FMU_REAL ? *(double *)fmu_value_address(fmu, vr)
                                                   : (double)*(int *)fmu_value_address(fmu, vr);
        if (!isfinite(value) || value < var->min || value > var->max) {
            LOG_ERROR(fmu, "%s: the state's '%s' = %g is outside [%g, %g] %s", call, var->name, value, var->min,
                      var->max, var->unit);
            return 0;
        }
        if (s->input_derivative_given[vr] < 0 || s->input_derivative_given[vr] > 2 ||
            !isfinite(s->input_derivative[vr][0]) || !isfinite(s->input_derivative[vr][1]) ||
            !isfinite(s->input_previous[vr])) {
            LOG_ERROR(fmu, "%s: the state's input derivatives of '%s' are invalid", call, var->name);
            return 0;
        }
    }
    for (int vr = 1; vr < VR_COUNT; vr++)
        if (fmu_variables[vr].type == FMU_STRING &&
            memchr(((FmuText *)fmu_value_address(fmu, vr))->text, '\0', FMU_TEXT_MAX) == NULL) {
            LOG_ERROR(fmu, "%s: the state's '%s' is not a terminated string", call, fmu_variables[vr].name);
            return 0;
        }
#if MODEL_N_STATES > 0
    for (int k = 0; k < MODEL_N_STATES; k++)
        if (!isfinite(s->x[k])) {
            LOG_ERROR(fmu, "%s: the state's internal state %d is not finite", call, k);
            return 0;
        }
#endif
#if MODEL_SHARED_SOLVER
    const OdeSolver *solver = &s->solver;
    if (!(solver->h_next >= 0.0 && solver->h_next <= 1.0) || !(solver->steps >= 0.0) || !(solver->rejected >= 0.0)) {
        LOG_ERROR(fmu, "%s: the state's solver memory is invalid", call);
        return 0;
    }
#endif
    return model_validate(fmu) == fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2GetFMUstate", ANY_LIVE_PHASE)) return fmi2Error;
    if (!state) { LOG_ERROR(fmu, "fmi2GetFMUstate: NULL state pointer"); return fmi2Error; }
    if (*state && !state_is_ours(fmu, "fmi2GetFMUstate", (const StoredState *)*state, 0)) return fmi2Error;
    if (!*state) *state = fmu->callbacks.allocateMemory(1, sizeof(StoredState));
    if (!*state) { LOG_ERROR(fmu, "fmi2GetFMUstate: out of memory"); return fmi2Error; }
    StoredState *stored = (StoredState *)*state;
    memcpy(&stored->s, &fmu->s, sizeof(FmuSnapshot));
    tag_state(stored, fmu->outputs_stale);
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2SetFMUstate", ANY_LIVE_PHASE)) return fmi2Error;
    if (!state) { LOG_ERROR(fmu, "fmi2SetFMUstate: NULL state"); return fmi2Error; }
    const StoredState *stored = (const StoredState *)state;
    if (!state_is_ours(fmu, "fmi2SetFMUstate", stored, 1)) return fmi2Error;
    FmuSnapshot before = fmu->s;
    const int stale_before = fmu->outputs_stale;
    memcpy(&fmu->s, &stored->s, sizeof(FmuSnapshot));
    if (!snapshot_valid(fmu, "fmi2SetFMUstate")) {
        fmu->s = before;
        fmu->outputs_stale = stale_before;
        model_validate(fmu); /* model data back to the instance's own */
        return fmi2Error;
    }
    /* the outputs are the snapshot's own: exactly what they were when the state was taken (the
     * lazy ones recomputed at their next read: the snapshot's may be from before) */
    fmu->outputs_stale = stored->tag.outputs_stale;
    fmu->lazy_outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu) return fmi2Error;
    if (state && *state) {
        if (!state_is_ours(fmu, "fmi2FreeFMUstate", (const StoredState *)*state, 0)) return fmi2Error;
        memset(*state, 0, sizeof(StateTag)); /* a freed state is no state any more */
        fmu->callbacks.freeMemory(*state);
        *state = NULL;
    }
    return fmi2OK;
}

/* Serialized form: the stored state (tag and snapshot) as bytes. */
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2SerializedFMUstateSize", ANY_LIVE_PHASE)) return fmi2Error;
    if (!size) { LOG_ERROR(fmu, "fmi2SerializedFMUstateSize: NULL size"); return fmi2Error; }
    if (state && !state_is_ours(fmu, "fmi2SerializedFMUstateSize", (const StoredState *)state, 0)) return fmi2Error;
    *size = sizeof(StoredState);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2SerializeFMUstate", ANY_LIVE_PHASE)) return fmi2Error;
    if (!state || !bytes || size < sizeof(StoredState)) {
        LOG_ERROR(fmu, "fmi2SerializeFMUstate: NULL state or buffer, or buffer of %zu bytes < %zu", size,
                  sizeof(StoredState));
        return fmi2Error;
    }
    if (!state_is_ours(fmu, "fmi2SerializeFMUstate", (const StoredState *)state, 1)) return fmi2Error;
    memcpy(bytes, state, sizeof(StoredState));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2DeSerializeFMUstate", ANY_LIVE_PHASE)) return fmi2Error;
    if (!bytes || !state || size != sizeof(StoredState)) {
        LOG_ERROR(fmu, "fmi2DeSerializeFMUstate: expected %zu bytes, got %zu", sizeof(StoredState), size);
        return fmi2Error;
    }
    StoredState *copy = (StoredState *)fmu->callbacks.allocateMemory(1, sizeof(StoredState));
    if (!copy) { LOG_ERROR(fmu, "fmi2DeSerializeFMUstate: out of memory"); return fmi2Error; }
    memcpy(copy, bytes, sizeof(StoredState));
    if (!state_is_ours(fmu, "fmi2DeSerializeFMUstate", copy, 1)) {
        fmu->callbacks.freeMemory(copy);
        return fmi2Error;
    }
    if (*state) {
        if (!state_is_ours(fmu, "fmi2DeSerializeFMUstate", (const StoredState *)*state, 0)) {
            fmu->callbacks.freeMemory(copy);
            return fmi2Error;
        }
        memcpy(*state, copy, sizeof(StoredState));
        fmu->callbacks.freeMemory(copy);
    } else {
        *state = copy;
    }
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    LOG_ERROR((FmuInstance *)c, "fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative=false)");
    return fmi2Error;
}
