/* Test FMU: F = kc (x2 - x1) + dc (v2 - v1), m2 x2'' = -k2 x2 - F (see variables.h). */
#include "fmu_common.h"

#include <string.h>

static double coupling_force(const FmuInstance *fmu, double t, const double *x) {
    const ModelVariables *v = &fmu->s.v;
    return v->coupling_stiffness * (x[0] - fmu_input_at(fmu, VR_position_1, t)) +
           v->coupling_damping * (x[1] - fmu_input_at(fmu, VR_velocity_1, t));
}

static void rhs(void *ctx, double t, const double *x, double *dxdt) {
    const FmuInstance *fmu = (const FmuInstance *)ctx;
    dxdt[0] = x[1];
    dxdt[1] = (-fmu->s.v.stiffness * x[0] - coupling_force(fmu, t, x)) / fmu->s.v.mass;
}

fmi2Status model_do_step(FmuInstance *fmu, double h) {
    const OdeProblem problem = {MODEL_N_STATES, rhs, 0, NULL, NULL, 0, NULL};
    return fmu_integrate(fmu, &problem, fmu, h, 0.0);
}

void model_initialize(FmuInstance *fmu) {
    memset(&fmu->s.solver, 0, sizeof fmu->s.solver);
    fmu->s.x[0] = fmu->s.x[1] = 0.0;
}

void model_compute_outputs(FmuInstance *fmu) {
    fmu->s.v.force = coupling_force(fmu, fmu->s.time, fmu->s.x);
    fmu->s.v.force_position_slope = -fmu->s.v.coupling_stiffness;
    fmu->s.v.force_velocity_slope = -fmu->s.v.coupling_damping;
    fmu->s.v.position = fmu->s.x[0];
}

fmi2Status model_validate(FmuInstance *fmu) {
    if (fmu->s.v.mass > 0.0) return fmi2OK;
    fmu_log(fmu, fmi2Error, "logStatusError", "parameter 'mass' = %g kg: must be > 0", fmu->s.v.mass);
    return fmi2Error;
}
