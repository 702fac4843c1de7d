/* Minimal reader of firmware/protocol_vectors.json for the C tests: every innermost JSON
 * object (one without nested objects) becomes a vector of key -> raw value text. */
#ifndef VECTORS_H
#define VECTORS_H
#include <stddef.h>
#include <stdint.h>

#define VEC_MAX_KEYS 24

typedef struct {
    int n;
    char *key[VEC_MAX_KEYS];
    char *val[VEC_MAX_KEYS]; /* strings without quotes, numbers as text */
} vec_t;

/* Parse the file; returns the number of vectors (allocated in *out), -1 on error. */
int vec_load(const char *path, vec_t **out);
const char *vec_get(const vec_t *v, const char *key);
long vec_num(const vec_t *v, const char *key);
/* Hex string to bytes; returns length or -1. */
int vec_hex(const char *hex, uint8_t *out, size_t cap);

#endif
