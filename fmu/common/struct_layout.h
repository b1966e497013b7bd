/* A C struct's layout as data, so that a binding in another language (Python's ctypes) can check
 * its own copy of the struct against the build it loads and refuse a mismatch, instead of reading
 * fields at the wrong offsets. One entry per field, "Struct.field" with its offset and size, and
 * one per struct, "Struct" with offset 0 and its size; the table ends with a NULL name. */
#ifndef STRUCT_LAYOUT_H
#define STRUCT_LAYOUT_H

#include <stddef.h>

typedef struct {
    const char *name;
    size_t offset, size;
} StructLayout;

#define STRUCT_LAYOUT(type) {#type, 0, sizeof(type)}
#define STRUCT_LAYOUT_FIELD(type, field) {#type "." #field, offsetof(type, field), sizeof(((type *)0)->field)}
#define STRUCT_LAYOUT_END {NULL, 0, 0}

#endif
