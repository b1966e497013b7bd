/* Build-time generator: writes an FMU's modelDescription.xml and documentation/index.html from
 * the same variable table (variables.h) that the FMU binary is compiled from.
 *
 * usage: model_description [--fmi3] OUT_DIR DOC_FRAGMENT.html SOURCE_FILE...
 *   OUT_DIR/modelDescription.xml and OUT_DIR/documentation/index.html are written; the source
 *   file names are listed under <SourceFiles> (FMI 2.0) or in OUT_DIR/sources/buildDescription.xml
 *   (FMI 3.0) so another tool can rebuild the binary. --fmi3: the FMI 3.0 description of the same
 *   table (fmu/common/fmi3_layer.c says which FMI 3.0 features the FMUs use).
 */
#include "fmu_table.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef MODEL_GUID
#error "MODEL_GUID must be defined by the build"
#endif

/* SI base-unit exponents of every unit a table may use: kg, m, s, A, rad. */
typedef struct { const char *name; int kg, m, s, A, rad; } UnitDefinition;
static const UnitDefinition UNITS[] = {
    {"1", 0, 0, 0, 0, 0},       {"s", 0, 0, 1, 0, 0},        {"m", 0, 1, 0, 0, 0},
    {"m/s", 0, 1, -1, 0, 0},    {"m/s2", 0, 1, -2, 0, 0},    {"kg", 1, 0, 0, 0, 0},
    {"kg.m2", 1, 2, 0, 0, 0},   {"rad", 0, 0, 0, 0, 1},      {"rad/s", 0, 0, -1, 0, 1},
    {"rad/s2", 0, 0, -2, 0, 1}, {"rad/m", 0, -1, 0, 0, 1},   {"1/s", 0, 0, -1, 0, 0},
    {"1/s2", 0, 0, -2, 0, 0},   {"N", 1, 1, -2, 0, 0},       {"N.m", 1, 2, -2, 0, 0},
    {"N.s/m", 1, 0, -1, 0, 0},  {"N.m.s/rad", 1, 2, -1, 0, -1}, {"A", 0, 0, 0, 1, 0},
    {"V", 1, 2, -3, -1, 0},     {"Ohm", 1, 2, -3, -2, 0},    {"H", 1, 2, -2, -2, 0},
    {"Wb", 1, 2, -2, -1, 0},    {"W", 1, 2, -3, 0, 0},       {"J", 1, 2, -2, 0, 0},
    {"N.m/A", 1, 2, -2, -1, 0}, {"N/A", 1, 1, -2, -1, 0},    {"V.s/m", 1, 1, -2, -1, 0},
    {"A.s/rad", 0, 0, 1, 1, -1}, {"A/rad", 0, 0, 0, 1, -1},  {"V/A", 1, 2, -3, -2, 0},
    {"Hz", 0, 0, -1, 0, 0},     {"A/m", 0, -1, 0, 1, 0},    {"1/A", 0, 0, 0, -1, 0},    {"1/m", 0, -1, 0, 0, 0},    {"kg/m", 1, -1, 0, 0, 0},   {"N/m", 1, 0, -2, 0, 0},    {"N/(m.s)", 1, 0, -3, 0, 0},    {"V/(A.s)", 1, 2, -4, -2, 0},    {"1/(A.s)", 0, 0, -1, -1, 0},    {"A/(m.s)", 0, -1, -1, 1, 0}, {"A.s/m", 0, -1, 1, 1, 0},
    /* the MPC's weights: each makes its term of the cost dimensionless */
    {"1/m2", 0, -2, 0, 0, 0},   {"1/rad2", 0, 0, 0, 0, -2},  {"s2/m2", 0, -2, 2, 0, 0},
    {"s2/rad2", 0, 0, 2, 0, -2}, {"s4/m2", 0, -2, 4, 0, 0},  {"s4/rad2", 0, 0, 4, 0, -2},
};
#define N_UNITS (sizeof UNITS / sizeof UNITS[0])

/* The model's direct feed-through (MODEL_FEEDTHROUGH in variables.h): per row an output and the
 * inputs it depends on at the same communication point. */
typedef struct { int output; const int *inputs; int count; } Feedthrough;
#define FMU_X_FEEDTHROUGH(output, ...) \
    {VR_##output, (const int[]){__VA_ARGS__}, (int)(sizeof((const int[]){__VA_ARGS__}) / sizeof(int))},
static const Feedthrough FEEDTHROUGH[] = {MODEL_FEEDTHROUGH(FMU_X_FEEDTHROUGH){0, NULL, 0}};
#undef FMU_X_FEEDTHROUGH

/* An output's Unknown element: its dependencies are the inputs of its feed-through row, or none
 * (an empty list: it follows the state alone, not any input at the same communication point). */
static void put_output_unknown(FILE *f, int vr, int me) {
    fprintf(f, "      <Unknown index=\"%d\" dependencies=\"", vr);
    int listed = 0;
    for (const Feedthrough *row = FEEDTHROUGH; row->inputs; row++)
        if (row->output == vr)
            for (int k = 0; k < row->count; k++) fprintf(f, "%s%d", listed++ ? " " : "", row->inputs[k]);
    for (int k = 0; me && k < MODEL_N_STATES; k++) /* Model Exchange: the states too */
        fprintf(f, "%s%d", listed++ ? " " : "", FMU_STATE_VR(k));
    fputs("\"/>\n", f);
}

static const UnitDefinition *find_unit(const char *name) {
    for (size_t i = 0; i < N_UNITS; i++)
        if (strcmp(UNITS[i].name, name) == 0) return &UNITS[i];
    return NULL;
}

static void put_escaped(FILE *f, const char *text) {
    for (; *text; text++) {
        switch (*text) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        default: fputc(*text, f);
        }
    }
}

static const char *causality_name(FmuCausality c) {
    static const char *names[] = {"parameter", "input", "output", "local"};
    return names[c];
}

static const char *variability_name(FmuVariability v) {
    static const char *names[] = {"fixed", "tunable", "discrete", "continuous"};
    return names[v];
}

static const char *type_element(FmuType t) {
    return t == FMU_REAL ? "Real" : t == FMU_INTEGER ? "Integer" : t == FMU_BOOLEAN ? "Boolean" : "String";
}

static int has_start(const FmuVariable *v) { return v->causality != FMU_OUTPUT; }

static void put_number(FILE *f, FmuType type, double value) {
    if (type == FMU_STRING) return; /* Strings start empty */
    if (type == FMU_REAL) fprintf(f, "%.17g", value);
    else if (type == FMU_INTEGER) fprintf(f, "%d", (int)value);
    else fputs(value != 0.0 ? "true" : "false", f);
}

/* A Real variable's unit must be one of UNITS (logged on stderr when not). */
static int unit_defined(const FmuVariable *v) {
    if (v->type != FMU_REAL || find_unit(v->unit)) return 1;
    fprintf(stderr, "model_description: variable '%s' uses unit '%s', which has no definition\n", v->name, v->unit);
    return 0;
}

/* A variable's attributes both FMI versions share: name, value reference, causality, variability,
 * initial and description. */
static void put_header(FILE *f, int vr) {
    const FmuVariable *v = &fmu_variables[vr];
    fprintf(f, " name=\"%s\" valueReference=\"%d\" causality=\"%s\" variability=\"%s\"", v->name, vr,
            causality_name(v->causality),
            (v->type != FMU_REAL && v->variability == FMU_CONTINUOUS) ? "discrete" : variability_name(v->variability));
    if (v->causality == FMU_OUTPUT) fprintf(f, " initial=\"calculated\"");
    fprintf(f, "\n      description=\"");
    put_escaped(f, v->description);
    fputc('"', f);
}

static void put_unit_and_bounds(FILE *f, const FmuVariable *v) {
    if (v->type == FMU_REAL && v->unit[0]) fprintf(f, " unit=\"%s\"", v->unit);
    if (v->type == FMU_BOOLEAN || v->type == FMU_STRING) return;
    if (isfinite(v->min)) { fputs(" min=\"", f); put_number(f, v->type, v->min); fputc('"', f); }
    if (isfinite(v->max)) { fputs(" max=\"", f); put_number(f, v->type, v->max); fputc('"', f); }
}

static void put_units(FILE *f) {
    fprintf(f, "  <UnitDefinitions>\n");
    for (size_t u = 0; u < N_UNITS; u++) {
        int used = 0;
        for (int vr = 1; vr < VR_COUNT; vr++)
            if (fmu_variables[vr].type == FMU_REAL && strcmp(fmu_variables[vr].unit, UNITS[u].name) == 0) used = 1;
        if (!used) continue;
        const UnitDefinition *d = &UNITS[u];
        fprintf(f, "    <Unit name=\"%s\"><BaseUnit", d->name);
        if (d->kg) fprintf(f, " kg=\"%d\"", d->kg);
        if (d->m) fprintf(f, " m=\"%d\"", d->m);
        if (d->s) fprintf(f, " s=\"%d\"", d->s);
        if (d->A) fprintf(f, " A=\"%d\"", d->A);
        if (d->rad) fprintf(f, " rad=\"%d\"", d->rad);
        fprintf(f, "/></Unit>\n");
    }
    fprintf(f, "  </UnitDefinitions>\n");
}

static void put_log_categories(FILE *f) {
    fprintf(f, "  <LogCategories>\n"
               "    <Category name=\"logEvents\" description=\"Events, limits reached, solver notes\"/>\n"
               "    <Category name=\"logStatusWarning\" description=\"Warnings\"/>\n"
               "    <Category name=\"logStatusError\" description=\"Errors: bad input, illegal call sequence, solver failure\"/>\n"
               "    <Category name=\"logAll\" description=\"Everything\"/>\n"
               "  </LogCategories>\n");
}

/* The interface element (CoSimulation, or ModelExchange) with the sources it is built from. */
static void put_interface(FILE *f, int me, int n_sources, char **sources) {
    if (me)
        fprintf(f, "  <ModelExchange modelIdentifier=\"%s\" completedIntegratorStepNotNeeded=\"false\"\n"
                   "    canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" providesDirectionalDerivative=\"false\">\n",
                MODEL_IDENTIFIER_STRING);
    else
        fprintf(f, "  <CoSimulation modelIdentifier=\"%s\" canHandleVariableCommunicationStepSize=\"true\"\n"
                   "    canInterpolateInputs=\"true\" maxOutputDerivativeOrder=\"%d\" canGetAndSetFMUstate=\"true\"\n"
                   "    canSerializeFMUstate=\"true\" providesDirectionalDerivative=\"false\">\n",
                MODEL_IDENTIFIER_STRING, MODEL_MAX_OUTPUT_DERIVATIVE_ORDER);
    fprintf(f, "    <SourceFiles>\n");
    for (int i = 0; i < n_sources; i++) {
        const char *base = strrchr(sources[i], '/');
        base = base ? base + 1 : sources[i];
        if (strlen(base) > 2 && strcmp(base + strlen(base) - 2, ".c") == 0)
            fprintf(f, "      <File name=\"%s\"/>\n", base);
    }
    fprintf(f, "    </SourceFiles>\n  </%s>\n", me ? "ModelExchange" : "CoSimulation");
}

/* Model Exchange's continuous states and their derivatives (fmi2_me.c): ode.x[k] at value
 * reference FMU_STATE_VR(k), der(ode.x[k]) at FMU_DERIVATIVE_VR(k), after the table's variables. */
static void put_states(FILE *f) {
    for (int k = 0; k < MODEL_N_STATES; k++)
        fprintf(f, "    <!-- %d --><ScalarVariable name=\"ode.x[%d]\" valueReference=\"%d\" causality=\"local\" "
                   "variability=\"continuous\" initial=\"calculated\"\n      description=\"The model's continuous state "
                   "%d (as its Co-Simulation integrates it)\">\n      <Real/>\n    </ScalarVariable>\n",
                FMU_STATE_VR(k), k + 1, FMU_STATE_VR(k), k + 1);
    for (int k = 0; k < MODEL_N_STATES; k++)
        fprintf(f, "    <!-- %d --><ScalarVariable name=\"der(ode.x[%d])\" valueReference=\"%d\" causality=\"local\" "
                   "variability=\"continuous\" initial=\"calculated\"\n      description=\"Its time derivative\">\n"
                   "      <Real derivative=\"%d\"/>\n    </ScalarVariable>\n",
                FMU_DERIVATIVE_VR(k), k + 1, FMU_DERIVATIVE_VR(k), FMU_STATE_VR(k));
}

/* FMI 2.0's modelDescription.xml: Co-Simulation, or (me) Model Exchange, in which the states are
 * variables and the outputs depend on them besides their feed-through inputs (the derivatives on
 * everything: no dependencies given). */
static int write_model_description(const char *path, int me, int n_sources, char **sources) {
    FILE *f = fopen(path, "w");
    if (!f) { perror(path); return 1; }
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    fprintf(f, "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"%s\" guid=\"%s\"\n",
            MODEL_IDENTIFIER_STRING, MODEL_GUID);
    fprintf(f, "  description=\"");
    put_escaped(f, MODEL_DESCRIPTION);
    fprintf(f, "\"\n  version=\"%s\" generationTool=\"stewart-cosim fmu/common/model_description.c\"\n"
               "  variableNamingConvention=\"structured\" numberOfEventIndicators=\"0\">\n",
            MODEL_VERSION);
    put_interface(f, me, n_sources, sources);
    put_units(f);
    put_log_categories(f);
    fprintf(f, "  <DefaultExperiment startTime=\"0\" stopTime=\"%g\" stepSize=\"%g\"/>\n", MODEL_STOP_TIME,
            MODEL_COMMUNICATION_STEP);

    fprintf(f, "  <ModelVariables>\n");
    for (int vr = 1; vr < VR_COUNT; vr++) {
        const FmuVariable *v = &fmu_variables[vr];
        if (!unit_defined(v)) {
            fclose(f);
            return 1;
        }
        fprintf(f, "    <!-- %d --><ScalarVariable", vr);
        put_header(f, vr);
        fprintf(f, ">\n      <%s", type_element(v->type));
        put_unit_and_bounds(f, v);
        if (has_start(v)) { fputs(" start=\"", f); put_number(f, v->type, v->start); fputc('"', f); }
        fprintf(f, "/>\n    </ScalarVariable>\n");
    }
    if (me) put_states(f);
    fprintf(f, "  </ModelVariables>\n  <ModelStructure>\n    <Outputs>\n");
    for (int vr = 1; vr < VR_COUNT; vr++)
        if (fmu_variables[vr].causality == FMU_OUTPUT) put_output_unknown(f, vr, me);
    fprintf(f, "    </Outputs>\n");
    if (me && MODEL_N_STATES > 0) {
        fprintf(f, "    <Derivatives>\n");
        for (int k = 0; k < MODEL_N_STATES; k++) fprintf(f, "      <Unknown index=\"%d\"/>\n", FMU_DERIVATIVE_VR(k));
        fprintf(f, "    </Derivatives>\n");
    }
    fprintf(f, "    <InitialUnknowns>\n");
    for (int vr = 1; vr < VR_COUNT; vr++)
        if (fmu_variables[vr].causality == FMU_OUTPUT) fprintf(f, "      <Unknown index=\"%d\"/>\n", vr);
    for (int k = 0; me && k < MODEL_N_STATES; k++) fprintf(f, "      <Unknown index=\"%d\"/>\n", FMU_STATE_VR(k));
    for (int k = 0; me && k < MODEL_N_STATES; k++) fprintf(f, "      <Unknown index=\"%d\"/>\n", FMU_DERIVATIVE_VR(k));
    fprintf(f, "    </InitialUnknowns>\n  </ModelStructure>\n</fmiModelDescription>\n");
    return fclose(f) != 0;
}

/* ---- FMI 3.0: the same table, FMI 3.0's types and structure ---- */

static const char *type_element3(FmuType t) {
    return t == FMU_REAL ? "Float64" : t == FMU_INTEGER ? "Int32" : t == FMU_BOOLEAN ? "Boolean" : "String";
}

/* FMI 3.0 Model Exchange's states and their derivatives (fmi2_me.c), after the table's variables. */
static void put_states3(FILE *f) {
    for (int k = 0; k < MODEL_N_STATES; k++) /* Model Exchange's states and derivatives (fmi2_me.c) */
        fprintf(f, "    <Float64 name=\"ode.x[%d]\" valueReference=\"%d\" causality=\"local\" variability=\"continuous\" "
                   "initial=\"calculated\"\n      description=\"The model's continuous state %d\"/>\n",
                k + 1, FMU_STATE_VR(k), k + 1);
    for (int k = 0; k < MODEL_N_STATES; k++)
        fprintf(f, "    <Float64 name=\"der(ode.x[%d])\" valueReference=\"%d\" causality=\"local\" "
                   "variability=\"continuous\" initial=\"calculated\" derivative=\"%d\"\n      description=\"Its time "
                   "derivative\"/>\n", k + 1, FMU_DERIVATIVE_VR(k), FMU_STATE_VR(k));
}

/* FMI 3.0's ModelStructure: the outputs with their dependencies (value references, which equal the
 * indices here; Model Exchange's on the states too), the state derivatives, the initial unknowns. */
static void put_model_structure3(FILE *f, int me) {
    for (int vr = 1; vr < VR_COUNT; vr++) { /* dependencies: value references in FMI 3.0 (ours equal the indices) */
        if (fmu_variables[vr].causality != FMU_OUTPUT) continue;
        fprintf(f, "    <Output valueReference=\"%d\" dependencies=\"", vr);
        int listed = 0;
        for (const Feedthrough *row = FEEDTHROUGH; row->inputs; row++)
            if (row->output == vr)
                for (int k = 0; k < row->count; k++) fprintf(f, "%s%d", listed++ ? " " : "", row->inputs[k]);
        for (int k = 0; me && k < MODEL_N_STATES; k++) fprintf(f, "%s%d", listed++ ? " " : "", FMU_STATE_VR(k));
        fputs("\"/>\n", f);
    }
    for (int k = 0; me && k < MODEL_N_STATES; k++)
        fprintf(f, "    <ContinuousStateDerivative valueReference=\"%d\"/>\n", FMU_DERIVATIVE_VR(k));
    for (int vr = 1; vr < VR_COUNT; vr++)
        if (fmu_variables[vr].causality == FMU_OUTPUT) fprintf(f, "    <InitialUnknown valueReference=\"%d\"/>\n", vr);
    for (int k = 0; me && k < MODEL_N_STATES; k++)
        fprintf(f, "    <InitialUnknown valueReference=\"%d\"/>\n", FMU_STATE_VR(k));
    for (int k = 0; me && k < MODEL_N_STATES; k++)
        fprintf(f, "    <InitialUnknown valueReference=\"%d\"/>\n", FMU_DERIVATIVE_VR(k));
}

static int write_model_description3(const char *path, int me) {
    FILE *f = fopen(path, "w");
    if (!f) { perror(path); return 1; }
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    fprintf(f, "<fmiModelDescription fmiVersion=\"3.0\" modelName=\"%s\" instantiationToken=\"%s\"\n",
            MODEL_IDENTIFIER_STRING, MODEL_GUID);
    fprintf(f, "  description=\"");
    put_escaped(f, MODEL_DESCRIPTION);
    fprintf(f, "\"\n  version=\"%s\" generationTool=\"stewart-cosim fmu/common/model_description.c\"\n"
               "  variableNamingConvention=\"structured\">\n", MODEL_VERSION);
    if (me)
        fprintf(f, "  <ModelExchange modelIdentifier=\"%s\" needsCompletedIntegratorStep=\"true\"\n"
                   "    canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\"\n"
                   "    providesDirectionalDerivatives=\"false\" providesAdjointDerivatives=\"false\"/>\n",
                MODEL_IDENTIFIER_STRING);
    else
        fprintf(f, "  <CoSimulation modelIdentifier=\"%s\" canHandleVariableCommunicationStepSize=\"true\"\n"
                   "    maxOutputDerivativeOrder=\"%d\" canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\"\n"
                   "    providesDirectionalDerivatives=\"false\" providesAdjointDerivatives=\"false\"\n"
                   "    hasEventMode=\"false\" providesIntermediateUpdate=\"false\"\n"
                   "    canReturnEarlyAfterIntermediateUpdate=\"false\"/>\n",
                MODEL_IDENTIFIER_STRING, MODEL_MAX_OUTPUT_DERIVATIVE_ORDER);
    put_units(f);
    put_log_categories(f);
    fprintf(f, "  <DefaultExperiment startTime=\"0\" stopTime=\"%g\" stepSize=\"%g\"/>\n", MODEL_STOP_TIME,
            MODEL_COMMUNICATION_STEP);
    fprintf(f, "  <ModelVariables>\n    <Float64 name=\"time\" valueReference=\"0\" causality=\"independent\" "
               "variability=\"continuous\"\n      description=\"Simulation time [s]\"/>\n");
    for (int vr = 1; vr < VR_COUNT; vr++) {
        const FmuVariable *v = &fmu_variables[vr];
        if (!unit_defined(v)) {
            fclose(f);
            return 1;
        }
        fprintf(f, "    <%s", type_element3(v->type));
        put_header(f, vr);
        put_unit_and_bounds(f, v);
        if (v->type == FMU_STRING && has_start(v)) {
            fprintf(f, ">\n      <Start value=\"\"/>\n    </String>\n");
            continue;
        }
        if (has_start(v)) { fputs(" start=\"", f); put_number(f, v->type, v->start); fputc('"', f); }
        fprintf(f, "/>\n");
    }
    if (me) put_states3(f);
    for (int vr = 1; !me && vr < VR_COUNT; vr++) { /* each Real input's rate and curvature (FMU_INPUT_DERIVATIVE_VR) */
        const FmuVariable *v = &fmu_variables[vr];
        if (v->causality != FMU_INPUT || v->type != FMU_REAL) continue;
        for (int order = 1; order <= 2; order++)
            fprintf(f, "    <Float64 name=\"fmi.%s.%s\" valueReference=\"%u\" causality=\"input\" "
                       "variability=\"continuous\" start=\"0\"\n      description=\"The %s time derivative of "
                       "%s over the next step, from the communication point (FMI 3.0 has no input derivatives; "
                       "set before each step, as fmi2SetRealInputDerivatives; not set: the input held, or "
                       "extrapolated by fmi.extrapolate_inputs)\"/>\n", order == 1 ? "rate" : "curvature", v->name,
                    FMU_INPUT_DERIVATIVE_VR(vr, order), order == 1 ? "first" : "second", v->name);
    }
    fprintf(f, "  </ModelVariables>\n  <ModelStructure>\n");
    put_model_structure3(f, me);
    fprintf(f, "  </ModelStructure>\n</fmiModelDescription>\n");
    return fclose(f) != 0;
}

/* FMI 3.0 lists the sources in sources/buildDescription.xml. */
static int write_build_description(const char *path, int n_sources, char **sources) {
    FILE *f = fopen(path, "w");
    if (!f) { perror(path); return 1; }
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiBuildDescription fmiVersion=\"3.0\">\n"
               "  <BuildConfiguration modelIdentifier=\"%s\">\n    <SourceFileSet language=\"C99\">\n",
            MODEL_IDENTIFIER_STRING);
    for (int i = 0; i < n_sources; i++) {
        const char *base = strrchr(sources[i], '/');
        base = base ? base + 1 : sources[i];
        if (strlen(base) > 2 && strcmp(base + strlen(base) - 2, ".c") == 0)
            fprintf(f, "      <SourceFile name=\"%s\"/>\n", base);
    }
    fprintf(f, "    </SourceFileSet>\n  </BuildConfiguration>\n</fmiBuildDescription>\n");
    return fclose(f) != 0;
}

static void write_variable_table(FILE *f, FmuCausality causality, const char *title) {
    fprintf(f, "<h2>%s</h2>\n<table>\n<tr><th>name</th><th>type</th><th>unit</th>", title);
    if (causality != FMU_OUTPUT) fprintf(f, "<th>default</th><th>min</th><th>max</th>");
    fprintf(f, "<th>description</th></tr>\n");
    for (int vr = 1; vr < VR_COUNT; vr++) {
        const FmuVariable *v = &fmu_variables[vr];
        if (v->causality != causality) continue;
        fprintf(f, "<tr><td><code>%s</code></td><td>%s%s</td><td>%s</td>", v->name, type_element(v->type),
                v->variability == FMU_TUNABLE ? " (tunable)" : "", v->unit);
        if (causality != FMU_OUTPUT) {
            fputs("<td>", f); put_number(f, v->type, v->start); fputs("</td><td>", f);
            if (isfinite(v->min) && v->type != FMU_BOOLEAN) put_number(f, v->type, v->min);
            fputs("</td><td>", f);
            if (isfinite(v->max) && v->type != FMU_BOOLEAN) put_number(f, v->type, v->max);
            fputs("</td>", f);
        }
        fputs("<td>", f);
        put_escaped(f, v->description);
        fputs("</td></tr>\n", f);
    }
    fprintf(f, "</table>\n");
}

static int write_documentation(const char *path, const char *fragment_path) {
    FILE *fragment = fopen(fragment_path, "r");
    if (!fragment) { perror(fragment_path); return 1; }
    FILE *f = fopen(path, "w");
    if (!f) { perror(path); fclose(fragment); return 1; }
    fprintf(f, "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>%s</title>\n"
               "<style>body{font-family:sans-serif;max-width:60em;margin:auto}"
               "table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px;text-align:left}"
               "code{white-space:nowrap}</style></head><body>\n<h1>%s</h1>\n<p>",
            MODEL_IDENTIFIER_STRING, MODEL_IDENTIFIER_STRING);
    put_escaped(f, MODEL_DESCRIPTION);
    fprintf(f, "</p>\n");
    char buffer[4096];
    size_t n;
    while ((n = fread(buffer, 1, sizeof buffer, fragment)) > 0) fwrite(buffer, 1, n, f);
    fclose(fragment);
    write_variable_table(f, FMU_INPUT, "Inputs");
    write_variable_table(f, FMU_OUTPUT, "Outputs");
    write_variable_table(f, FMU_PARAMETER, "Parameters");
    fprintf(f, "<p>GUID %s; generated from the variable table the binary is compiled from.</p>\n</body></html>\n",
            MODEL_GUID);
    return fclose(f) != 0;
}

int main(int argc, char **argv) {
    const int fmi3 = argc > 1 && strcmp(argv[1], "--fmi3") == 0;
    argc -= fmi3, argv += fmi3;
    const int me = argc > 1 && strcmp(argv[1], "--me") == 0;
    argc -= me, argv += me;
    if (argc < 3) {
        fprintf(stderr, "usage: model_description [--fmi3] [--me] OUT_DIR DOC_FRAGMENT.html SOURCE_FILE...\n");
        return 2;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/modelDescription.xml", argv[1]);
    if (fmi3 ? write_model_description3(path, me) : write_model_description(path, me, argc - 3, argv + 3)) return 1;
    if (fmi3) {
        snprintf(path, sizeof path, "%s/sources/buildDescription.xml", argv[1]);
        if (write_build_description(path, argc - 3, argv + 3)) return 1;
    }
    snprintf(path, sizeof path, "%s/documentation/index.html", argv[1]);
    return write_documentation(path, argv[2]);
}
