/* Test FMU: m1 x1'' = -k1 x1 - d1 x1' + F (see variables.h), with F corrected by the coupling FMU's
 * interface Jacobian where it is wired: F + s_x (x1 - x1_seen) + s_v (v1 - v1_seen). */
#include "fmu_common.h"

#include <string.h>

static void rhs(void *ctx, double t, const double *x, double *dxdt) {
    const FmuInstance *fmu = (const FmuInstance *)ctx;
    const ModelVariables *v = &fmu->s.v;
    dxdt[0] = x[1];
    const double force = fmu_input_at(fmu, VR_force, t) +
                         fmu_input_at(fmu, VR_force_position_slope, t) * (x[0] - fmu_input_at(fmu, VR_position_seen, t)) +
                         fmu_input_at(fmu, VR_force_velocity_slope, t) * (x[1] - fmu_input_at(fmu, VR_velocity_seen, t));
    dxdt[1] = (-v->stiffness * x[0] - v->damping * x[1] + force) / v->mass;
}

fmi2Status model_do_step(FmuInstance *fmu, double h) {
    const OdeProblem problem = {MODEL_N_STATES, rhs, 0, NULL, NULL, 0, NULL};
    return fmu_integrate(fmu, &problem, fmu, h, 0.0);
}

void model_initialize(FmuInstance *fmu) {
    memset(&fmu->s.solver, 0, sizeof fmu->s.solver);
    fmu->s.x[0] = fmu->s.v.initial_position;
    fmu->s.x[1] = 0.0;
}

void model_compute_outputs(FmuInstance *fmu) {
    fmu->s.v.position = fmu->s.x[0];
    fmu->s.v.velocity = fmu->s.x[1];
}

fmi2Status model_validate(FmuInstance *fmu) {
    if (fmu->s.v.mass > 0.0) return fmi2OK;
    fmu_log(fmu, fmi2Error, "logStatusError", "parameter 'mass' = %g kg: must be > 0", fmu->s.v.mass);
    return fmi2Error;
}
