#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "vectors.h"

static char *read_all(const char *path)
{
    FILE *f = fopen(path, "rb");
    long n;
    char *buf;
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    buf = (char *)malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    if (buf) buf[n] = 0;
    fclose(f);
    return buf;
}

static char *parse_string(char *p, char **start)
{
    /* p at the opening quote; the vectors contain no escapes */
    *start = ++p;
    while (*p && *p != '"') p++;
    if (*p) *p++ = 0;
    return p;
}

static int parse_object(char *p, char *end, vec_t *v)
{
    v->n = 0;
    while (p < end) {
        char *k, *val;
        while (p < end && *p != '"') p++;
        if (p >= end) break;
        p = parse_string(p, &k);
        while (p < end && (*p == ' ' || *p == ':' || *p == '\n')) p++;
        if (*p == '"') {
            p = parse_string(p, &val);
        } else {
            val = p;
            while (p < end && *p != ',' && *p != '\n' && *p != '}') p++;
            if (p < end) *p++ = 0;
        }
        if (v->n < VEC_MAX_KEYS) {
            v->key[v->n] = k;
            v->val[v->n] = val;
            v->n++;
        }
    }
    return v->n;
}

int vec_load(const char *path, vec_t **out)
{
    char *text = read_all(path), *p, *open = NULL;
    int count = 0, cap = 64, depth_ok = 0;
    vec_t *vs;
    if (!text) return -1;
    vs = (vec_t *)calloc((size_t)cap, sizeof *vs);
    for (p = text; *p; p++) {
        if (*p == '"') { /* skip strings (they hold no braces, but be safe) */
            p++;
            while (*p && *p != '"') p++;
            if (!*p) break;
            continue;
        }
        if (*p == '{') {
            open = p;
            depth_ok = 1;
        } else if (*p == '}' && depth_ok && open) {
            if (count == cap) {
                cap *= 2;
                vs = (vec_t *)realloc(vs, (size_t)cap * sizeof *vs);
            }
            *p = 0;
            parse_object(open + 1, p, &vs[count++]);
            depth_ok = 0;
        }
    }
    *out = vs;
    return count;
}

const char *vec_get(const vec_t *v, const char *key)
{
    int i;
    for (i = 0; i < v->n; i++) {
        if (strcmp(v->key[i], key) == 0) return v->val[i];
    }
    return NULL;
}

long vec_num(const vec_t *v, const char *key)
{
    const char *s = vec_get(v, key);
    return s ? strtol(s, NULL, 10) : -999999;
}

int vec_hex(const char *hex, uint8_t *out, size_t cap)
{
    size_t n = strlen(hex), i;
    if (n % 2 || n / 2 > cap) return -1;
    for (i = 0; i < n / 2; i++) {
        unsigned int b;
        if (sscanf(hex + 2 * i, "%2x", &b) != 1) return -1;
        out[i] = (uint8_t)b;
    }
    return (int)(n / 2);
}
