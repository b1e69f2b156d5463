/* SPDX-License-Identifier: Apache-2.0 */
/* File sets: inputs held in memory by the path they were read from, and
 * the identities of a run's inputs and outputs (core.h).  A handful of files
 * per load, so lookups are linear. */
#include "core/core.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

enum { HELD, INPUT, OUTPUT }; /* bytes held (an input); an input's identity only; an output */

typedef struct held_file {
    char *path;
    unsigned char *data;
    size_t size;
    int role, has_id; /* has_id: dev and ino are the file's (it existed) */
    dev_t dev;
    ino_t ino;
    char *real; /* an output: its resolved path (it may not exist yet) */
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
        free(set->files[i].real);
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
        if (set->files[i].role == HELD && strcmp(set->files[i].path, path) == 0) {
            *size = set->files[i].size;
            return set->files[i].data;
        }
    return NULL;
}

/* Take ownership of path and data (freed on failure); the entry's identity
 * is the file's at path now, if it is there. */
static lie_status adopt_as(lie_file_set *set, char *path, unsigned char *data, size_t size, int role,
                           lie_error *err)
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
    held_file f = {path, data, size, role, 0, 0, 0, NULL};
    struct stat st;
    if (strcmp(path, "-") != 0 && stat(path, &st) == 0) {
        f.has_id = 1;
        f.dev = st.st_dev;
        f.ino = st.st_ino;
    }
    set->files[set->n++] = f;
    set->bytes += size;
    return LIE_OK;
}

static lie_status adopt(lie_file_set *set, char *path, unsigned char *data, size_t size, lie_error *err)
{
    return adopt_as(set, path, data, size, HELD, err);
}

lie_status lie_file_set_add(lie_file_set *set, const char *path, const void *data, size_t size, lie_error *err)
{
    if (set->mode == LIE_FILES_NAMES)
        return lie_file_set_note(set, path, err);
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
    size_t total = 16, count = 0;
    for (size_t i = 0; i < set->n; i++)
        if (set->files[i].role == HELD) {
            total += 16 + strlen(set->files[i].path) + set->files[i].size;
            count++;
        }
    unsigned char *d = malloc(total), *p = d;
    if (!d)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory for %zu bytes", total);
    memcpy(p, MAGIC, 8);
    put64(p + 8, count);
    p += 16;
    for (size_t i = 0; i < set->n; i++) {
        const held_file *f = &set->files[i];
        if (f->role != HELD)
            continue;
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

/* ---- a run's inputs and outputs -------------------------------------------
 * An output must not be an input, nor another output of the same run: the
 * same file by device and inode when it exists (a symlink or a hard link to
 * it too), or the same resolved path when it does not yet.  Devices, FIFOs
 * and "-" are written in place and are never the same file in this sense
 * (two writes to /dev/null are fine). */

lie_status lie_file_set_note(lie_file_set *set, const char *path, lie_error *err)
{
    if (!set || strcmp(path, "-") == 0)
        return LIE_OK;
    for (size_t i = 0; i < set->n; i++)
        if (set->files[i].role != OUTPUT && strcmp(set->files[i].path, path) == 0)
            return LIE_OK;
    char *p = strdup(path);
    if (!p)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    return adopt_as(set, p, NULL, 0, INPUT, err);
}

lie_status lie_file_set_note_all(lie_file_set *set, const lie_file_set *from, lie_error *err)
{
    for (size_t i = 0; set && from && i < from->n; i++)
        if (from->files[i].role != OUTPUT) {
            lie_status st = lie_file_set_note(set, from->files[i].path, err);
            if (st != LIE_OK)
                return st;
        }
    return LIE_OK;
}

/* The path with its folder resolved (symlinks, "..") and, when the file
 * itself is a symlink, followed as lie_atomic_open follows it; malloc'd, or
 * NULL when the folder does not exist (the write will fail anyway). */
static char *resolved(const char *path)
{
    char *whole = realpath(path, NULL);
    if (whole)
        return whole;
    const char *slash = strrchr(path, '/');
    char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - path) + (slash == path) : 1, slash ? path : ".");
    char *rdir = realpath(dir, NULL);
    if (!rdir)
        return NULL;
    const char *base = slash ? slash + 1 : path;
    size_t n = strlen(rdir) + 1 + strlen(base) + 1;
    char *out = malloc(n);
    if (out)
        snprintf(out, n, "%s/%s", strcmp(rdir, "/") == 0 ? "" : rdir, base);
    free(rdir);
    return out;
}

/* The check of lie_file_set_claim; claim: record it as an output too. */
static lie_status check(lie_file_set *set, const char *path, const char *replaces, int claim, lie_error *err)
{
    if (!set || strcmp(path, "-") == 0)
        return LIE_OK;
    struct stat st;
    int exists = stat(path, &st) == 0;
    if (exists && !S_ISREG(st.st_mode))
        return LIE_OK; /* a device or FIFO: written in place, never replaced */
    char *real = resolved(path);
    for (size_t i = 0; i < set->n; i++) {
        const held_file *f = &set->files[i];
        int same = (exists && f->has_id && f->dev == st.st_dev && f->ino == st.st_ino) ||
                   (real && f->real && strcmp(real, f->real) == 0);
        if (same && f->role != OUTPUT && replaces && strcmp(f->path, replaces) == 0)
            continue; /* the input this output is the new version of */
        if (same) {
            free(real);
            return lie_error_set(err, LIE_ERR_ARG, path, "is also %s %s: refusing to write over it",
                                 f->role == OUTPUT ? "the output" : "the input", f->path);
        }
    }
    if (!claim) {
        free(real);
        return LIE_OK;
    }
    char *p = strdup(path);
    if (!p) {
        free(real);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    lie_status s = adopt_as(set, p, NULL, 0, OUTPUT, err);
    if (s != LIE_OK) {
        free(real);
        return s;
    }
    set->files[set->n - 1].real = real;
    return LIE_OK;
}

lie_status lie_file_set_claim(lie_file_set *set, const char *path, const char *replaces, lie_error *err)
{
    return check(set, path, replaces, 1, err);
}

lie_status lie_file_set_check(lie_file_set *set, const char *path, lie_error *err)
{
    return check(set, path, NULL, 0, err);
}
