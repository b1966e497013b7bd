/* A resource location as a folder on this machine: what an FMU (fmu/common/runtime.c) and the
 * system FMU that nests FMUs (cosim/engine/kernel/system_fmu.c) are given at instantiation. */
#include "location.h"

#include <string.h>

static int hex_digit(char c) {
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
}

char *location_folder(const char *location, void *(*allocate)(size_t, size_t)) {
    if (!location || !location[0]) return NULL;
    const char *path = location;
    if (strncmp(location, "file:", 5) == 0) {
        path = location + 5;
        if (strncmp(path, "///", 3) == 0) path += 2;
        else if (strncmp(path, "//localhost/", 12) == 0) path += 11;
        else if (strncmp(path, "//", 2) == 0) return NULL; /* another host's */
#ifdef _WIN32
        if (path[0] == '/' && path[1] && path[2] == ':') path++; /* /C:/... */
#endif
    } else if (strstr(location, "://")) {
        return NULL;
    }
    const size_t n = strlen(path);
    char *out = (char *)allocate(n + 2, 1);
    if (!out) return NULL;
    size_t k = 0;
    for (size_t i = 0; i < n; i++) { /* percent-decoded where it was a URI */
        const int high = i + 2 < n ? hex_digit(path[i + 1]) : -1, low = i + 2 < n ? hex_digit(path[i + 2]) : -1;
        if (path != location && path[i] == '%' && high >= 0 && low >= 0) {
            out[k++] = (char)(16 * high + low);
            i += 2;
        } else {
            out[k++] = path[i];
        }
    }
    if (k == 0 || (out[k - 1] != '/' && out[k - 1] != '\\')) out[k++] = '/';
    out[k] = '\0';
    return out;
}
