/* A resource location as a folder on this machine (location.c): FMI 2.0's URI or FMI 3.0's path. */
#ifndef FMU_LOCATION_H
#define FMU_LOCATION_H

#include <stddef.h>

/* The folder `location` names, as a native path ending in '/' (allocated by `allocate`, as calloc),
 * from FMI 2.0's URI (file:///path/, file://localhost/path/, file:/path/, percent-encoded) or
 * FMI 3.0's native path; NULL for anything else (another scheme, another host, none given). */
char *location_folder(const char *location, void *(*allocate)(size_t, size_t));

#endif
