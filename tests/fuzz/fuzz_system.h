/* What the system FMU's harnesses (fuzz_fmi.c: FMI 2.0, fuzz_fmi3.c: FMI 3.0, each built with
 * FUZZ_SYSTEM) know of the FMU under test, read from its modelDescription.xml where a model's
 * harness has its variable table: each variable's type, where setting it may succeed (by causality
 * and variability), its start; the number of continuous states; the interface it offers; its token
 * and resources. Included by fuzz_common.h, after the oracle's states. */
#ifndef FUZZ_SYSTEM_H
#define FUZZ_SYSTEM_H

enum { MAX_VARIABLES = 8192, MAX_STATES = 512 };

typedef struct {
    int type;    /* 'r' Real (FMI 3.0: Float64), 'i' Integer (Int32), 'b' Boolean, 's' String; 0 none */
    int allowed; /* the states in which setting it may succeed (0: never) */
    double start;
} SystemVariable;

static SystemVariable variables[MAX_VARIABLES]; /* by value reference */
static int n_variables = 0, n_states = 0, offers_model_exchange = 0, has_fmu_state = 0;
static char guid[128], resources[4200], name[64] = "system";

/* The attribute `key="..."` of the element that starts at `from` (before `end`) into out. */
static int attribute(const char *from, const char *end, const char *key, char *out, size_t size) {
    char pattern[64];
    snprintf(pattern, sizeof pattern, " %s=\"", key);
    const char *at = strstr(from, pattern);
    if (!at || at > end) return 0;
    at += strlen(pattern);
    const char *close = strchr(at, '"');
    if (!close || (size_t)(close - at) >= size) return 0;
    memcpy(out, at, (size_t)(close - at));
    out[close - at] = '\0';
    return 1;
}

static char *read_text(const char *path) {
    FILE *file = fopen(path, "rb");
    if (!file) return NULL;
    fseek(file, 0, SEEK_END);
    const long size = ftell(file);
    fseek(file, 0, SEEK_SET);
    char *text = size > 0 ? malloc((size_t)size + 1) : NULL;
    if (text && fread(text, 1, (size_t)size, file) == (size_t)size) text[size] = '\0';
    else free(text), text = NULL;
    fclose(file);
    return text;
}

/* One variable: its element's attributes from `v` to `tag_end` (the opening tag's '>'), its type. */
static void add_variable(const char *v, const char *tag_end, int type) {
    char value[256], causality[32] = "local", variability[32] = "continuous";
    if (!attribute(v, tag_end, "valueReference", value, sizeof value)) return;
    const long vr = strtol(value, NULL, 10);
    if (vr < 0 || vr >= MAX_VARIABLES) return;
    SystemVariable *var = &variables[vr];
    attribute(v, tag_end, "causality", causality, sizeof causality);
    attribute(v, tag_end, "variability", variability, sizeof variability);
    var->type = type;
    var->start = attribute(v, tag_end, "start", value, sizeof value) ? strtod(value, NULL) : 0.0;
    if (!strcmp(causality, "parameter"))
        var->allowed = S_INSTANTIATED | S_INIT | (!strcmp(variability, "tunable") ? S_STEP_COMPLETE | S_EVENT : 0);
    else if (!strcmp(causality, "input"))
        var->allowed = S_SET & (!strcmp(variability, "continuous") ? S_SET : ~S_CONTINUOUS);
    if (vr + 1 > n_variables) n_variables = (int)vr + 1;
}

/* The number of elements `<tag` between from and end. */
static int count(const char *from, const char *end, const char *tag) {
    int n = 0;
    for (const char *u = from; u && end && (u = strstr(u + 1, tag)) && u < end;) n++;
    return n;
}

/* What the harness needs of the FMU's description (FMI 2.0 or 3.0, as its fmiVersion says); 0 if it
 * cannot be had. */
static int read_description(const char *folder) {
    char path[4096], value[256];
    snprintf(path, sizeof path, "%s/modelDescription.xml", folder);
    char *text = read_text(path);
    if (!text) { fprintf(stderr, "fuzz_system: cannot read %s\n", path); return 0; }
    const char *end = text + strlen(text);
    const int fmi3 = attribute(text, end, "fmiVersion", value, sizeof value) && value[0] == '3';
    if (!attribute(text, end, fmi3 ? "instantiationToken" : "guid", guid, sizeof guid)) { free(text); return 0; }
    const char *me = strstr(text, "<ModelExchange"), *cs = strstr(text, "<CoSimulation");
    offers_model_exchange = me != NULL && cs == NULL;
    const char *interface = me ? me : cs;
    if (interface) attribute(interface, strchr(interface, '>'), "modelIdentifier", name, sizeof name);
    has_fmu_state = interface && attribute(interface, strchr(interface, '>'), fmi3 ? "canGetAndSetFMUState"
                                           : "canGetAndSetFMUstate", value, sizeof value) && !strcmp(value, "true");
    const char *list = strstr(text, "<ModelVariables>"), *list_end = strstr(text, "</ModelVariables>");
    if (!list || !list_end) { free(text); return 0; }
    if (!fmi3) {
        for (const char *v = strstr(list, "<ScalarVariable"); v && v < list_end; v = strstr(v + 1, "<ScalarVariable")) {
            const char *close = strstr(v, "</ScalarVariable>");
            if (!close) break;
            const char *typed = strchr(strchr(v, '>') + 1, '<');
            add_variable(v, strchr(v, '>'), !strncmp(typed, "<Integer", 8) ? 'i' : !strncmp(typed, "<Boolean", 8) ? 'b'
                                            : !strncmp(typed, "<String", 7) ? 's' : 'r');
        }
    } else {
        static const struct { const char *tag; int type; } TYPES[] = {
            {"<Float64 ", 'r'}, {"<Int32 ", 'i'}, {"<Boolean ", 'b'}, {"<String ", 's'}};
        for (size_t k = 0; k < sizeof TYPES / sizeof TYPES[0]; k++)
            for (const char *v = strstr(list, TYPES[k].tag); v && v < list_end; v = strstr(v + 1, TYPES[k].tag))
                add_variable(v, strchr(v, '>'), TYPES[k].type);
    }
    n_states = fmi3 ? count(text, end, "<ContinuousStateDerivative")
                    : count(strstr(text, "<Derivatives>"), strstr(text, "</Derivatives>"), "<Unknown");
    free(text);
    if (n_states > MAX_STATES) { fprintf(stderr, "fuzz_system: %d states, more than %d\n", n_states, MAX_STATES); return 0; }
    if (fmi3) snprintf(resources, sizeof resources, "%s/resources/", folder); /* FMI 3.0: a path */
    else snprintf(resources, sizeof resources, "file://%s/resources", folder);
    return n_variables > 0;
}

static int fuzz_option(const char *flag, const char *value) {
    if (strcmp(flag, "--fmu-dir") != 0) return 0;
    return read_description(value);
}
static const char *fuzz_name(void) { return name; }

static double value_for(int vr) {
    if (pick(3) == 0) return hostile_real();
    const double start = variables[vr].start;
    return start == 0.0 ? uniform() - 0.5 : start * (1.0 + 0.2 * (uniform() - 0.5));
}

static unsigned random_vr(void) {
    return pick(10) == 0 ? (unsigned)(n_variables + pick(100)) : (unsigned)pick(n_variables);
}

/* Where setting these references as `type` may succeed: nowhere if one is not of that type. */
static int settable_states(const unsigned *vrs, size_t nvr, int type) {
    int allowed = S_SET;
    for (size_t i = 0; vrs && i < nvr; i++)
        allowed &= vrs[i] < (unsigned)n_variables && variables[vrs[i]].type == type ? variables[vrs[i]].allowed : 0;
    return allowed;
}

#endif
