/* SPDX-License-Identifier: Apache-2.0 */
/* File sets: inputs held in memory by the path they were read from
 * (core.h).  A handful of files per load, so lookups are linear. */
#include "core/core.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct held_file {
    char *path;
    unsigned char *data;
    size_t size;
} held_file;

struct lie_file_set {
    lie_file_set_mode mode;
    held_file *files;
    size_t n, cap;
    uint64_t bytes;
};

lie_file_set *lie_file_set_create(lie_file_set_mode mode)
{
    lie_file_set *set = calloc(1, sizeof *set);
    if (set)
        set->mode = mode;
    return set;
}

void lie_file_set_destroy(lie_file_set *set)
{
    if (!set)
        return;
    for (size_t i = 0; i < set->n; i++) {
        free(set->files[i].path);
        free(set->files[i].data);
    }
    free(set->files);
    free(set);
}

lie_file_set_mode lie_file_set_get_mode(const lie_file_set *set) { return set->mode; }
size_t lie_file_set_count(const lie_file_set *set) { return set ? set->n : 0; }
uint64_t lie_file_set_bytes(const lie_file_set *set) { return set ? set->bytes : 0; }

const unsigned char *lie_file_set_find(const lie_file_set *set, const char *path, size_t *size)
{
    for (size_t i = 0; set && i < set->n; i++)
        if (strcmp(set->files[i].path, path) == 0) {
            *size = set->files[i].size;
            return set->files[i].data;
        }
    return NULL;
}

/* Take ownership of path and data (freed on failure). */
static lie_status adopt(lie_file_set *set, char *path, unsigned char *data, size_t size, lie_error *err)
{
    if (set->n == set->cap) {
        size_t cap = set->cap ? 2 * set->cap : 8;
        held_file *f = realloc(set->files, cap * sizeof *f);
        if (!f) {
            free(path);
            free(data);
            return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
        }
        set->files = f;
        set->cap = cap;
    }
    set->files[set->n++] = (held_file){path, data, size};
    set->bytes += size;
    return LIE_OK;
}

lie_status lie_file_set_add(lie_file_set *set, const char *path, const void *data, size_t size, lie_error *err)
{
    size_t old;
    if (lie_file_set_find(set, path, &old))
        return LIE_OK; /* the first bytes read stay: a load sees one version of a file */
    char *p = strdup(path);
    unsigned char *d = malloc(size + 1);
    if (!p || !d) {
        free(p);
        free(d);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    if (size)
        memcpy(d, data, size);
    return adopt(set, p, d, size, err);
}

lie_status lie_file_set_read(lie_file_set *set, const char *path, uint64_t max, unsigned char **data, size_t *size,
                             lie_error *err)
{
    *data = NULL;
    *size = 0;
    size_t n;
    const unsigned char *held = lie_file_set_find(set, path, &n);
    if (held) {
        if ((uint64_t)n > max)
            return lie_error_set(err, LIE_ERR_LIMIT, path, "%zu bytes, beyond the limit of %llu", n,
                                 (unsigned long long)max);
        if (!(*data = malloc(n + 1)))
            return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
        if (n)
            memcpy(*data, held, n);
        *size = n;
        return LIE_OK;
    }
    if (set && set->mode == LIE_FILES_ONLY)
        return lie_error_set(err, LIE_ERR_IO, path, "cannot open: %s", LIE_FILE_SET_MISSING);
    lie_status st = lie_read_file_max(path, max, data, size, err);
    if (st == LIE_OK && set && (st = lie_file_set_add(set, path, *data, *size, err)) != LIE_OK) {
        free(*data);
        *data = NULL;
        *size = 0;
    }
    return st;
}

int lie_file_set_exists(const lie_file_set *set, const char *path)
{
    size_t n;
    if (lie_file_set_find(set, path, &n))
        return 1;
    if (set && set->mode == LIE_FILES_ONLY)
        return 0;
    return access(path, F_OK) == 0;
}

/* ---- one buffer ------------------------------------------------------------
 * "LIEFILES", u64 count, then per file u64 path length, u64 size, the path
 * (no NUL), the bytes; integers little-endian.  Only processes of one job
 * exchange it (lib/dist), yet unpack checks every length. */

static const char MAGIC[8] = {'L', 'I', 'E', 'F', 'I', 'L', 'E', 'S'};

static void put64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static uint64_t get64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 0; i < 8; i++)
        v |= (uint64_t)p[i] << (8 * i);
    return v;
}

lie_status lie_file_set_pack(const lie_file_set *set, unsigned char **data, size_t *size, lie_error *err)
{
    size_t total = 16;
    for (size_t i = 0; i < set->n; i++)
        total += 16 + strlen(set->files[i].path) + set->files[i].size;
    unsigned char *d = malloc(total), *p = d;
    if (!d)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory for %zu bytes", total);
    memcpy(p, MAGIC, 8);
    put64(p + 8, set->n);
    p += 16;
    for (size_t i = 0; i < set->n; i++) {
        const held_file *f = &set->files[i];
        size_t len = strlen(f->path);
        put64(p, len);
        put64(p + 8, f->size);
        memcpy(p + 16, f->path, len);
        if (f->size)
            memcpy(p + 16 + len, f->data, f->size);
        p += 16 + len + f->size;
    }
    *data = d;
    *size = total;
    return LIE_OK;
}

lie_status lie_file_set_unpack(const unsigned char *data, size_t size, lie_file_set **out, lie_error *err)
{
    *out = NULL;
    if (size < 16 || memcmp(data, MAGIC, 8) != 0)
        return lie_error_set(err, LIE_ERR_FORMAT, NULL, "not a packed file set");
    lie_file_set *set = lie_file_set_create(LIE_FILES_ONLY);
    if (!set)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    uint64_t count = get64(data + 8);
    size_t at = 16;
    lie_status st = LIE_OK;
    for (uint64_t i = 0; st == LIE_OK && i < count; i++) {
        if (size - at < 16) {
            st = lie_error_set(err, LIE_ERR_FORMAT, NULL, "packed file set: file %llu is truncated",
                               (unsigned long long)i);
            break;
        }
        uint64_t len = get64(data + at), n = get64(data + at + 8);
        at += 16;
        if (len == 0 || len > size - at || n > size - at - len) {
            st = lie_error_set(err, LIE_ERR_FORMAT, NULL, "packed file set: file %llu runs past the end",
                               (unsigned long long)i);
            break;
        }
        if (memchr(data + at, 0, len)) { /* a path is a C string: it would be cut short */
            st = lie_error_set(err, LIE_ERR_FORMAT, NULL, "packed file set: the path of file %llu holds a NUL byte",
                               (unsigned long long)i);
            break;
        }
        char *path = malloc(len + 1);
        unsigned char *d = malloc(n + 1);
        if (!path || !d) {
            free(path);
            free(d);
            st = lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
            break;
        }
        memcpy(path, data + at, len);
        path[len] = 0;
        if (n)
            memcpy(d, data + at + len, n);
        at += len + n;
        st = adopt(set, path, d, n, err);
    }
    if (st == LIE_OK && at != size)
        st = lie_error_set(err, LIE_ERR_FORMAT, NULL, "packed file set: %zu bytes after the last file", size - at);
    if (st != LIE_OK) {
        lie_file_set_destroy(set);
        return st;
    }
    *out = set;
    return LIE_OK;
}
