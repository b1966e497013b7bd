/* The system FMU's description (resources/system.txt, written by cosim/engine/system_fmu.py; its
 * layout in docs/guide/engine.md) read into a System: the nested FMUs' binaries loaded and their
 * functions bound, each instance's coupled outputs and inputs, values, the coupling's plan, the
 * outer variables; then the step kernel's struct set up over arrays of the system's own. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
#else
#include <dlfcn.h>
#endif

#include "system.h"

/* ---- the description (resources/system.txt) ---- */

typedef struct {
    char *text, *at;
    int failed;
    long line;          /* the line of the token read last (1: the first) */
    int ended_line;     /* the token read last ended its line */
    long failed_line;   /* where the description first went wrong */
} Reader;

static void fail(Reader *r) {
    if (!r->failed) r->failed_line = r->line;
    r->failed = 1;
}

static const char *token(Reader *r) {
    r->line += r->ended_line;
    r->ended_line = 0;
    while (*r->at == ' ' || *r->at == '\n' || *r->at == '\r' || *r->at == '\t')
        if (*r->at++ == '\n') r->line++;
    if (!*r->at) { fail(r); return ""; }
    const char *start = r->at;
    while (*r->at && *r->at != ' ' && *r->at != '\n' && *r->at != '\r' && *r->at != '\t') r->at++;
    if (*r->at == '\n') r->ended_line = 1;
    if (*r->at) *r->at++ = '\0';
    return start;
}

static void expect(Reader *r, const char *word) {
    if (strcmp(token(r), word) != 0) fail(r);
}

static long integer(Reader *r) {
    char *end;
    const char *t = token(r);
    const long value = strtol(t, &end, 10);
    if (end == t || *end) fail(r);
    return value;
}

static double real(Reader *r) {
    char *end;
    const char *t = token(r);
    const double value = strtod(t, &end);
    if (end == t || *end) fail(r);
    return value;
}

static int hex(char c) {
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
}

/* A text token ('=' and the text percent-encoded), decoded; "@resources/" at its start stands for
 * the outer FMU's resources folder (a file the system's values name travels there). */
static char *text(System *s, Reader *r) {
    const char *t = token(r);
    if (*t++ != '=') {
        fail(r);
        return NULL;
    }
    static const char prefix[] = "@resources/";
    const size_t base = strncmp(t, prefix, sizeof prefix - 1) == 0 ? strlen(s->resources) : 0;
    char *out = calloc(base + strlen(t) + 1, 1);
    if (!out) { fail(r); return NULL; }
    if (base) {
        strcpy(out, s->resources);
        t += sizeof prefix - 1;
    }
    size_t k = base;
    for (; *t; t++) {
        if (*t == '%' && hex(t[1]) >= 0 && hex(t[2]) >= 0) {
            out[k++] = (char)(16 * hex(t[1]) + hex(t[2]));
            t += 2;
        } else {
            out[k++] = *t;
        }
    }
    out[k] = '\0';
    return out;
}

static void *allocate(Reader *r, size_t n, size_t size) {
    void *p = calloc(n ? n : 1, size);
    if (!p) fail(r);
    return p;
}

static int *ints(Reader *r, int n) {
    int *out = allocate(r, (size_t)n, sizeof(int));
    for (int i = 0; out && i < n; i++) out[i] = (int)integer(r);
    return out;
}

char *read_file(const char *path) {
    FILE *file = fopen(path, "rb");
    if (!file) return NULL;
    char *content = NULL;
    if (fseek(file, 0, SEEK_END) == 0) {
        const long size = ftell(file);
        if (size >= 0 && fseek(file, 0, SEEK_SET) == 0 && (content = calloc((size_t)size + 1, 1)) &&
            fread(content, 1, (size_t)size, file) != (size_t)size) {
            free(content);
            content = NULL;
        }
    }
    fclose(file);
    return content;
}

/* ---- the nested FMUs ---- */

static void *library_open(const char *path) {
#ifdef _WIN32
    return (void *)LoadLibraryA(path);
#else
#if defined(RTLD_DEEPBIND) && !defined(SYSTEM_WITHOUT_DEEPBIND) /* the nested FMU's own fmi2 functions, never those
    of the FMU nesting it (the fuzz harness, which exports none, goes without: the sanitizers refuse it) */
    return dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
#else
    return dlopen(path, RTLD_NOW | RTLD_LOCAL);
#endif
#endif
}

static void *library_symbol(void *library, const char *name) {
#ifdef _WIN32
    FARPROC p = GetProcAddress((HMODULE)library, name);
    void *out;
    memcpy(&out, &p, sizeof out);
    return out;
#else
    return dlsym(library, name);
#endif
}

void library_close(void *library) {
#ifdef _WIN32
    FreeLibrary((HMODULE)library);
#else
    dlclose(library);
#endif
}

#ifdef _WIN32
#define PLATFORM "win64"
#define SUFFIX ".dll"
#else
#define PLATFORM "linux64"
#define SUFFIX ".so"
#endif

/* A function of a nested FMU into a function pointer of any type (no object-to-function cast). */
#define BIND(s, nested, field, name)                                                               \
    do {                                                                                           \
        void *found_ = library_symbol((nested)->library, name);                                   \
        if (!found_) {                                                                             \
            say(s, fmi2Error, "logStatusError", "a nested FMU's binary has no %s", name);         \
            return 0;                                                                              \
        }                                                                                          \
        memcpy(&(nested)->field, &found_, sizeof found_);                                          \
    } while (0)

static int load_nested(System *s, Nested *n, const char *folder, const char *identifier) {
    char path[4096];
    snprintf(path, sizeof path, "%sfmus/%s/binaries/" PLATFORM "/%s" SUFFIX, s->resources, folder, identifier);
    n->library = library_open(path);
    if (!n->library) {
        say(s, fmi2Error, "logStatusError", "cannot load the nested FMU's binary %s", path);
        return 0;
    }
    snprintf(path, sizeof path, "%sfmus/%s/resources/", s->resources, folder);
    const size_t size = 3 * strlen(path) + 16;
    n->resources_uri = calloc(size, 1);
    if (!n->resources_uri) return 0;
    char *out = n->resources_uri + sprintf(n->resources_uri, "file://%s", path[0] == '/' ? "" : "/");
    for (const char *c = path; *c; c++) { /* a URI: the bytes outside the unreserved ones percent-encoded */
        const unsigned char b = (unsigned char)(*c == '\\' ? '/' : *c);
        if ((b >= 'a' && b <= 'z') || (b >= 'A' && b <= 'Z') || (b >= '0' && b <= '9') || strchr("-._~/:", b))
            *out++ = (char)b;
        else
            out += sprintf(out, "%%%02X", b);
    }
    BIND(s, n, instantiate, "fmi2Instantiate");
    BIND(s, n, free_instance, "fmi2FreeInstance");
    BIND(s, n, setup_experiment, "fmi2SetupExperiment");
    BIND(s, n, enter_initialization, "fmi2EnterInitializationMode");
    BIND(s, n, exit_initialization, "fmi2ExitInitializationMode");
    BIND(s, n, terminate, "fmi2Terminate");
    BIND(s, n, reset, "fmi2Reset");
    BIND(s, n, set_real, "fmi2SetReal");
    BIND(s, n, set_integer, "fmi2SetInteger");
    BIND(s, n, set_boolean, "fmi2SetBoolean");
    BIND(s, n, set_string, "fmi2SetString");
    BIND(s, n, get_real, "fmi2GetReal");
    BIND(s, n, get_integer, "fmi2GetInteger");
    BIND(s, n, get_boolean, "fmi2GetBoolean");
    BIND(s, n, get_string, "fmi2GetString");
    BIND(s, n, set_input_derivatives, "fmi2SetRealInputDerivatives");
    BIND(s, n, get_output_derivatives, "fmi2GetRealOutputDerivatives");
    BIND(s, n, do_step, "fmi2DoStep");
    BIND(s, n, get_state, "fmi2GetFMUstate");
    BIND(s, n, set_state, "fmi2SetFMUstate");
    BIND(s, n, free_state, "fmi2FreeFMUstate");
    if (!s->offers_model_exchange) return 1;
    BIND(s, n, set_time, "fmi2SetTime");
    BIND(s, n, set_states, "fmi2SetContinuousStates");
    BIND(s, n, get_states, "fmi2GetContinuousStates");
    BIND(s, n, get_nominals, "fmi2GetNominalsOfContinuousStates");
    BIND(s, n, get_derivatives, "fmi2GetDerivatives");
    BIND(s, n, enter_event_mode, "fmi2EnterEventMode");
    BIND(s, n, new_discrete_states, "fmi2NewDiscreteStates");
    BIND(s, n, enter_continuous_time_mode, "fmi2EnterContinuousTimeMode");
    BIND(s, n, completed_integrator_step, "fmi2CompletedIntegratorStep");
    return 1;
}

/* Sets an instance's values, each by the call of its kind; 0 (the instance logged why) on refusal. */
/* ---- reading the system ---- */

/* An instance's values: per value its kind (r, i, b, s), value reference and value. */
static void read_values(System *s, Reader *r, Inner *inner) {
    expect(r, "values");
    inner->n_values = (int)integer(r);
    inner->values = allocate(r, (size_t)inner->n_values, sizeof(Value));
    for (int v = 0; !r->failed && v < inner->n_values; v++) {
        Value *value = &inner->values[v];
        value->kind = token(r)[0];
        value->vr = (unsigned)integer(r);
        if (value->kind == 'r') value->real = real(r);
        else if (value->kind == 'i' || value->kind == 'b') value->integer = (int)integer(r);
        else if (value->kind == 's') value->text = text(s, r);
        else fail(r);
    }
}

static int read_instances(System *s, Reader *r) {
    expect(r, "fmus");
    s->n_fmus = (int)integer(r);
    s->fmus = allocate(r, (size_t)s->n_fmus, sizeof(Nested));
    for (int f = 0; !r->failed && f < s->n_fmus; f++) {
        const char *folder = token(r);
        const char *identifier = token(r);
        s->fmus[f].guid = text(s, r);
        if (r->failed) return 0;
        if (!load_nested(s, &s->fmus[f], folder, identifier)) return 0; /* r->failed unset: a nested FMU */
    }
    expect(r, "instances");
    const int n = s->n_instances = (int)integer(r);
    s->inners = allocate(r, (size_t)n, sizeof(Inner));
    s->kernel_instances = allocate(r, (size_t)n, sizeof(KernelInstance));
    int n_outputs = 0, n_inputs = 0;
    unsigned *outputs = NULL, *inputs = NULL;
    int *sources = NULL, *indices = NULL;
    for (int k = 0; !r->failed && k < n; k++) {
        Inner *inner = &s->inners[k];
        KernelInstance *in = &s->kernel_instances[k];
        expect(r, "instance");
        inner->system = s;
        inner->name = text(s, r);
        inner->fmu = (int)integer(r);
        if (inner->fmu < 0 || inner->fmu >= s->n_fmus) fail(r);
        expect(r, "outputs");
        in->n_outputs = (int)integer(r);
        in->output_offset = n_outputs;
        outputs = realloc(outputs, ((size_t)(n_outputs + in->n_outputs) + 1) * sizeof(unsigned));
        if (!outputs) { fail(r); return 0; }
        for (int i = 0; i < in->n_outputs; i++) outputs[n_outputs + i] = (unsigned)integer(r);
        n_outputs += in->n_outputs;
        expect(r, "inputs");
        in->n_inputs = (int)integer(r);
        in->input_offset = n_inputs;
        const size_t m = (size_t)(n_inputs + in->n_inputs) + 1;
        inputs = realloc(inputs, m * sizeof(unsigned));
        sources = realloc(sources, m * sizeof(int));
        indices = realloc(indices, m * sizeof(int));
        if (!inputs || !sources || !indices) { fail(r); return 0; }
        for (int i = 0; i < in->n_inputs; i++) {
            inputs[n_inputs + i] = (unsigned)integer(r);
            sources[n_inputs + i] = (int)integer(r);
            indices[n_inputs + i] = (int)integer(r);
            if (sources[n_inputs + i] < 0 || sources[n_inputs + i] >= n) fail(r);
        }
        n_inputs += in->n_inputs;
        expect(r, "flags");
        in->rate_order = (int)integer(r);
        in->interpolating = (int)integer(r);
        in->extrapolating = (int)integer(r);
        expect(r, "states"); /* its continuous states as Model Exchange */
        inner->n_states = (int)integer(r);
        inner->first_state = s->n_states;
        if (inner->n_states < 0) fail(r);
        s->n_states += inner->n_states;
        read_values(s, r, inner);
    }
    if (r->failed) return 0;
    s->vrs[0] = outputs, s->vrs[1] = inputs, s->ints[6] = sources, s->ints[7] = indices;
    for (int k = 0; k < n; k++) { /* the arrays are whole now: each instance's places in them */
        KernelInstance *in = &s->kernel_instances[k];
        in->output_vrs = outputs + in->output_offset;
        in->input_vrs = inputs + in->input_offset;
        in->feed_source = sources + in->input_offset;
        in->feed_index = indices + in->input_offset;
        for (int i = 0; i < in->n_inputs; i++)
            if (in->feed_index[i] < 0 || in->feed_index[i] >= s->kernel_instances[in->feed_source[i]].n_outputs) {
                fail(r);
                return 0;
            }
    }
    s->kernel.n_sample_values = n_outputs;
    s->kernel.n_inputs_total = n_inputs;
    return 1;
}

static int read_coupling(System *s, Reader *r) {
    Kernel *k = &s->kernel;
    const int n = s->n_instances;
    expect(r, "sequence");
    if (integer(r) != n) fail(r);
    s->ints[0] = ints(r, n);
    expect(r, "stages");
    if (integer(r) != n) fail(r);
    s->ints[1] = ints(r, n);
    expect(r, "bonds");
    k->n_bonds = (int)integer(r);
    s->bonds = allocate(r, (size_t)k->n_bonds, sizeof(KernelBond));
    for (int b = 0; !r->failed && b < k->n_bonds; b++) {
        KernelPort *ports[] = {&s->bonds[b].effort_out, &s->bonds[b].effort_in, &s->bonds[b].flow_out,
                               &s->bonds[b].flow_in, &s->bonds[b].slope_in};
        for (int p = 0; p < 5; p++) {
            ports[p]->instance = (int)integer(r);
            ports[p]->index = (int)integer(r);
        }
    }
    expect(r, "feeds");
    k->n_feeds = (int)integer(r);
    s->feeds = allocate(r, (size_t)k->n_feeds, sizeof(KernelFeed));
    int longest = 1, total = 0;
    for (int f = 0; !r->failed && f < k->n_feeds; f++) {
        KernelFeed *feed = &s->feeds[f];
        feed->instance = (int)integer(r);
        feed->first = (int)integer(r);
        feed->n_inputs = (int)integer(r);
        feed->n_outputs = (int)integer(r);
        longest = feed->n_inputs > longest ? feed->n_inputs : longest;
        longest = feed->n_outputs > longest ? feed->n_outputs : longest;
        total = feed->first + feed->n_inputs + feed->n_outputs;
    }
    expect(r, "feed_indices");
    const int n_indices = (int)integer(r);
    if (n_indices < total) fail(r);
    s->ints[2] = ints(r, n_indices);
    s->feed_vrs = allocate(r, (size_t)longest, sizeof(unsigned));
    k->feed_vrs = s->feed_vrs;
    k->feed_values = allocate(r, (size_t)longest, sizeof(double));
    k->feed_rates = allocate(r, 2 * (size_t)longest, sizeof(double));
    for (int j = 0; !r->failed && j < n; j++)
        if (s->ints[0][j] < 0 || s->ints[0][j] >= n || s->ints[1][j] <= j || s->ints[1][j] > n) fail(r);
    return !r->failed;
}

static int read_variables(System *s, Reader *r) {
    expect(r, "variables");
    s->n_variables = (int)integer(r);
    s->variables = allocate(r, (size_t)s->n_variables, sizeof(Variable));
    for (int v = 0; !r->failed && v < s->n_variables; v++) {
        s->variables[v].instance = (int)integer(r);
        s->variables[v].kind = token(r)[0];
        s->variables[v].vr = (unsigned)integer(r);
        const char settable = token(r)[0];
        s->variables[v].settable = settable == 's';
        if (s->variables[v].instance < 0 || s->variables[v].instance >= s->n_instances ||
            !strchr("ribs", s->variables[v].kind) || !strchr("sn", settable))
            fail(r);
    }
    expect(r, "end");
    return !r->failed;
}

static int read_parts(System *s, Reader *r, const char *guid);

int read_system(System *s, char *description, const char *guid, long *line) {
    Reader reader = {description, description, 0, 1, 0, 0}, *r = &reader;
    const int read = read_parts(s, r, guid);
    *line = r->failed ? r->failed_line : r->line;
    return read;
}

static int read_parts(System *s, Reader *r, const char *guid) {
    expect(r, "cosim-system");
    if (integer(r) != 1 || r->failed) return READ_FAILED;
    expect(r, "guid");
    const char *own = token(r);
    if (r->failed) return READ_FAILED;
    if (guid && strcmp(own, guid) != 0) return READ_FOREIGN;
    expect(r, "interfaces"); /* what its modelDescription.xml declares: cs, me or both */
    const long n_interfaces = integer(r);
    for (long i = 0; !r->failed && i < n_interfaces && i < 2; i++) {
        const char *offered = token(r);
        if (strcmp(offered, "cs") == 0) s->offers_co_simulation = 1;
        else if (strcmp(offered, "me") == 0) s->offers_model_exchange = 1;
        else fail(r);
    }
    if (n_interfaces < 1 || n_interfaces > 2) fail(r);
    expect(r, "start");
    s->start = real(r);
    expect(r, "algorithm");
    s->kernel.gauss_seidel = (int)integer(r);
    s->kernel.order = (int)integer(r);
    s->sweeps = (int)integer(r);
    s->zero_start = (int)integer(r);
    expect(r, "clock");
    s->clock = (int)integer(r);
    expect(r, "plan");
    s->n_runs = (int)integer(r);
    s->run_step = allocate(r, (size_t)s->n_runs, sizeof(double));
    s->run_count = allocate(r, (size_t)s->n_runs, sizeof(int));
    for (int i = 0; !r->failed && i < s->n_runs; i++) {
        s->run_step[i] = real(r);
        s->run_count[i] = (int)integer(r);
        if (!(s->run_step[i] > 0.0) || s->run_count[i] < 0) fail(r);
    }
    expect(r, "step");
    s->regular_step = real(r);
    if (r->failed || !(s->regular_step > 0.0) || s->kernel.order < 0 || s->kernel.order > 2) return READ_FAILED;
    if (!read_instances(s, r)) return r->failed ? READ_FAILED : READ_NESTED;
    if (s->clock < 0 || s->clock >= s->n_instances) return READ_FAILED;
    return read_coupling(s, r) && read_variables(s, r) ? READ_OK : READ_FAILED;
}

/* The kernel's struct over arrays of its own (what cosim/engine/kernel.py allocates in numpy). */
int build_kernel(System *s) {
    Kernel *k = &s->kernel;
    const size_t n = (size_t)(k->n_sample_values > 0 ? k->n_sample_values : 1);
    const size_t m = (size_t)(k->n_inputs_total > 0 ? k->n_inputs_total : 1);
    const size_t count = (size_t)s->n_instances, longest = n > m ? n : m;
    /* sample_time 3, samples 3n, exact_rates 2n, new_values n, guess n, inputs 3m, record 1,
     * instance_time, fmi_seconds, saved_time per instance */
    double *d = s->doubles = calloc(3 + 3 * n + 2 * n + n + n + 3 * m + 1 + 3 * count, sizeof(double));
    s->ints[3] = calloc(count, sizeof(int));
    s->ints[4] = calloc(longest, sizeof(int));
    s->ints[5] = calloc(longest, sizeof(int));
    s->states = calloc(2 * count, sizeof(void *));
    if (!d || !s->ints[3] || !s->ints[4] || !s->ints[5] || !s->states) return 0;
    for (size_t i = 0; i < longest; i++) s->ints[4][i] = 1, s->ints[5][i] = 2;
    k->n_instances = s->n_instances;
    k->instances = s->kernel_instances;
    k->sequence = s->ints[0];
    k->stage_end = s->ints[1];
    k->threads = 1; /* an importer's FMU runs on the importer's thread: no second one of its own */
    k->keep = k->order + 1 > 2 ? k->order + 1 : 2;
    k->sample_time = d, d += 3;
    k->samples = d, d += 3 * n;
    k->exact_rates = d, d += 2 * n;
    k->new_values = d, d += n;
    k->guess = d, d += n;
    k->input_values = d, d += m;
    k->input_rates = d, d += m;
    k->input_curvatures = d, d += m;
    k->record_scratch = d, d += 1;
    k->instance_time = d, d += count;
    k->fmi_seconds = d, d += count;
    k->saved_time = d;
    k->stepped = s->ints[3];
    k->order_one = s->ints[4];
    k->order_two = s->ints[5];
    k->states = s->states;
    k->startup_states = s->states + count;
    k->bonds = s->bonds;
    k->feeds = s->feeds;
    k->feed_indices = s->ints[2];
    k->n_columns = 0;
    k->column_of = s->ints[3];
    for (int j = 0; j < s->n_instances; j++) {
        KernelInstance *in = &s->kernel_instances[j];
        const Nested *nested = &s->fmus[s->inners[j].fmu];
        in->component = s->inners[j].component;
        memcpy(&in->set_real, &nested->set_real, sizeof in->set_real);
        memcpy(&in->get_real, &nested->get_real, sizeof in->get_real);
        memcpy(&in->set_input_derivatives, &nested->set_input_derivatives, sizeof in->set_input_derivatives);
        memcpy(&in->get_output_derivatives, &nested->get_output_derivatives, sizeof in->get_output_derivatives);
        memcpy(&in->do_step, &nested->do_step, sizeof in->do_step);
        memcpy(&in->get_state, &nested->get_state, sizeof in->get_state);
        memcpy(&in->set_state, &nested->set_state, sizeof in->set_state);
        memcpy(&in->free_state, &nested->free_state, sizeof in->free_state);
        in->n_record = 0;
        in->record_vrs = s->vrs[0];
    }
    return 1;
}
