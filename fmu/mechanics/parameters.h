/* The mechanics' parameters -> the dynamics core's Platform: the one mapping, used by the FMU
 * (model.c) and, through the platform_core library, by every tool that needs the platform without
 * running the FMU (the master's drive design, neutral pose and static loads). */
#ifndef MECHANICS_PARAMETERS_H
#define MECHANICS_PARAMETERS_H

#include "fmu_table.h"
#include "struct_layout.h"

/* The Platform of the parameters in v (geometry by layout 1 or 2, masses, transmission, gravity,
 * effect switches). Returns 0, or -1 if the layout is impossible. */
int mechanics_platform(const ModelVariables *v, Platform *p);

/* For tools (exported by the platform_core library): every variable's value by value reference,
 * values[vr] for vr = 0 .. count - 1 (entry 0 unused; Integer and Boolean as whole numbers, String
 * ignored), as the FMU would hold them after fmi2SetReal/Integer/Boolean. Returns 0, -1 for an
 * impossible layout, -2 if count is not this build's number of value references
 * (mechanics_value_references()). */
int mechanics_platform_from_values(const double *values, int count, Platform *p);
int mechanics_value_references(void);

/* The layout of Platform, LegGeometry, PlatformDiagnostics and PlatformEnvelope (envelope.h; see
 * struct_layout.h). */
const StructLayout *platform_core_layout(void);

#endif
