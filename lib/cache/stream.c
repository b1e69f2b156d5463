/* SPDX-License-Identifier: Apache-2.0 */
/* Writing a cache unit by unit as a build makes them (lib/cache/cache.h,
 * lie_cache_stream). */
#include "cache/internal.h"

#include <errno.h>
#include <stdlib.h>
#include <xxhash.h>

/*
 * A build that writes its units in unit order holds only the ROOTS entries
 * (4 bytes a unit) and one unit at a time: each unit's tree is laid out
 * canonically (write_tree, as encode does) and appended to two spill files
 * (NODES and POOL), their checksums kept running.  Closing writes the file
 * in order through the atomic writer, the spills copied in, the file
 * checksum running over every byte: the bytes lie_cache_write gives the
 * same cache. */
struct lie_cache_stream {
    lie_cache head;            /* the cache's fields; head.env holds no trees */
    lie_env env;               /* its parameters and counts */
    char *name;                /* the output, for messages */
    unsigned char *roots;      /* ROOTS, as written */
    uint64_t n_units, next_unit;
    uint32_t next_node, next_pool;
    FILE *nodes, *pool;        /* the spills */
    XXH3_state_t *h_nodes, *h_pool;
    unsigned char *scratch;    /* one unit's nodes, then its lists */
    size_t cap_scratch;
    lie_status failed;
};

void lie_cache_stream_abort(lie_cache_stream *s)
{
    if (!s)
        return;
    if (s->nodes)
        fclose(s->nodes);
    if (s->pool)
        fclose(s->pool);
    XXH3_freeState(s->h_nodes);
    XXH3_freeState(s->h_pool);
    free(s->roots);
    free(s->scratch);
    free(s->name);
    free(s);
}

lie_status lie_cache_stream_open(const char *path, const lie_cache *c, lie_cache_stream **out, lie_error *err)
{
    *out = NULL;
    lie_status st = c && c->env ? lie_cache_check_head(c, path, err)
                                : lie_error_set(err, LIE_ERR_ARG, path, "refusing to write a cache without an env");
    if (st != LIE_OK)
        return st;
    const uint64_t n_units = (uint64_t)c->env->n_tris * (uint64_t)c->env->n_clusters;
    if (n_units > SIZE_MAX / 8)
        return lie_error_set(err, LIE_ERR_LIMIT, path, "%llu units are beyond this machine",
                             (unsigned long long)n_units);
    lie_cache_stream *s = calloc(1, sizeof *s);
    if (s) {
        s->head = *c;
        s->env = *c->env;
        s->env.root = NULL;
        s->env.nodes = NULL;
        s->env.pool = NULL;
        s->head.env = &s->env;
        s->n_units = n_units;
        s->name = strdup(path ? path : "-");
        s->roots = malloc((size_t)(4 * n_units) + 1);
        s->h_nodes = XXH3_createState();
        s->h_pool = XXH3_createState();
    }
    if (!s || !s->name || !s->roots || !s->h_nodes || !s->h_pool) {
        lie_cache_stream_abort(s);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    XXH3_64bits_reset(s->h_nodes);
    XXH3_64bits_reset(s->h_pool);
    /* unlinked temporaries: nothing is left behind, whatever happens */
    s->nodes = tmpfile();
    s->pool = tmpfile();
    if (!s->nodes || !s->pool) {
        int e = errno;
        lie_cache_stream_abort(s);
        return lie_error_set(err, LIE_ERR_IO, path, "cannot create a temporary file: %s", strerror(e ? e : EIO));
    }
    *out = s;
    return LIE_OK;
}

lie_status lie_cache_stream_unit(lie_cache_stream *s, const lie_pnode *nodes, const uint32_t *pool, uint32_t root,
                                 lie_error *err)
{
    if (s->failed)
        return s->failed;
    if (s->next_unit >= s->n_units)
        return s->failed = lie_error_set(err, LIE_ERR_ARG, s->name, "more units than the scene has");
    unsigned char *r = s->roots + 4 * s->next_unit++;
    uint32_t tag = root >= LIE_CACHE_ROOT_LONE_NONE ? root : lie_cache_lone_tag(nodes, root);
    if (tag) {
        lie_cache_put_u32(r, tag);
        return LIE_OK;
    }
    uint64_t n = 0, np = 0;
    lie_cache_tree_size(nodes, root, &n, &np);
    if ((uint64_t)s->next_node + n >= 0xFFFFFFF0u || (uint64_t)s->next_pool + np >= 0xFFFFFFF0u)
        return s->failed = lie_error_set(err, LIE_ERR_LIMIT, s->name, "the patch trees hold too many nodes for one cache");
    size_t need = (size_t)(LIE_CACHE_NODE_SIZE * n + 4 * np);
    if (!LIE_GROW(s->scratch, s->cap_scratch, need + 1))
        return s->failed = lie_error_set(err, LIE_ERR_NOMEM, s->name, "out of memory");
    unsigned char *nb = s->scratch, *pb = s->scratch + LIE_CACHE_NODE_SIZE * n;
    lie_cache_tree_writer tw = {nodes, pool, nb, pb, s->next_node, s->next_pool, s->next_node, s->next_pool};
    uint32_t idx = tw.next_node++;
    lie_cache_put_u32(r, idx);
    lie_cache_write_tree(&tw, root, idx);
    size_t bn = (size_t)(LIE_CACHE_NODE_SIZE * n), bp = (size_t)(4 * np);
    if (fwrite(nb, 1, bn, s->nodes) != bn || (bp && fwrite(pb, 1, bp, s->pool) != bp)) {
        int e = errno;
        return s->failed = lie_error_set(err, LIE_ERR_IO, s->name, "write failed: %s", strerror(e ? e : EIO));
    }
    XXH3_64bits_update(s->h_nodes, nb, bn);
    XXH3_64bits_update(s->h_pool, pb, bp);
    s->next_node = tw.next_node;
    s->next_pool = tw.next_pool;
    return LIE_OK;
}

uint64_t lie_cache_stream_nodes(const lie_cache_stream *s) { return s->next_node; }
uint64_t lie_cache_stream_pool(const lie_cache_stream *s) { return s->next_pool; }

/* n bytes to the file and to its checksum */
static int put_bytes(FILE *fp, XXH3_state_t *h, const void *p, size_t n)
{
    XXH3_64bits_update(h, p, n);
    return fwrite(p, 1, n, fp) == n;
}

/* Zero bytes from `at` up to `to`. */
static int put_zeros(FILE *fp, XXH3_state_t *h, uint64_t at, uint64_t to)
{
    static const unsigned char zero[8];
    return to <= at || put_bytes(fp, h, zero, (size_t)(to - at));
}

/* A spill, from its start, to the file. */
static int put_spill(FILE *fp, XXH3_state_t *h, FILE *spill, uint64_t n, unsigned char *buf, size_t cap)
{
    if (fflush(spill) != 0 || fseek(spill, 0, SEEK_SET) != 0)
        return 0;
    while (n > 0) {
        size_t k = n < cap ? (size_t)n : cap;
        if (fread(buf, 1, k, spill) != k || !put_bytes(fp, h, buf, k))
            return 0;
        n -= k;
    }
    return 1;
}

lie_status lie_cache_stream_close(lie_cache_stream *s, int partial, size_t *bytes, lie_error *err)
{
    if (bytes)
        *bytes = 0;
    lie_status st = s->failed;
    if (st == LIE_OK && s->next_unit != s->n_units)
        st = lie_error_set(err, LIE_ERR_ARG, s->name, "%llu of %llu units written", (unsigned long long)s->next_unit,
                           (unsigned long long)s->n_units);
    lie_cache_layout L;
    lie_cache_lay_out(&s->head, s->next_node, s->next_pool, &L);
    /* everything before ROOTS, and VIEWS, in memory: a few kilobytes and
     * the edit log */
    unsigned char *small = st == LIE_OK ? calloc(1, (size_t)L.off[S_ROOTS] + 1) : NULL;
    unsigned char *views = st == LIE_OK ? calloc(1, (size_t)L.sz[S_VIEWS] + 1) : NULL;
    const size_t cap = (size_t)1 << 20;
    unsigned char *buf = st == LIE_OK ? malloc(cap) : NULL;
    XXH3_state_t *h = st == LIE_OK ? XXH3_createState() : NULL;
    if (st == LIE_OK && (!small || !views || !buf || !h))
        st = lie_error_set(err, LIE_ERR_NOMEM, s->name, "out of memory");
    lie_atomic_file af;
    if (st == LIE_OK)
        st = lie_atomic_open(&af, s->name, err);
    if (st == LIE_OK) {
        s->env.partial = partial;
        lie_cache_put_small(small, views, &s->head, &L, s->next_node, s->next_pool);
        uint64_t hash[S_COUNT];
        for (int k = 0; k < S_ROOTS; k++)
            hash[k] = lie_hash_bytes(small + L.off[k], (size_t)L.sz[k], 0);
        hash[S_ROOTS] = lie_hash_bytes(s->roots, (size_t)L.sz[S_ROOTS], 0);
        hash[S_NODES] = XXH3_64bits_digest(s->h_nodes);
        hash[S_POOL] = XXH3_64bits_digest(s->h_pool);
        hash[S_VIEWS] = lie_hash_bytes(views, (size_t)L.sz[S_VIEWS], 0);
        lie_cache_put_header(small, &L, partial, hash);
        XXH3_64bits_reset(h);
        FILE *fp = af.fp;
        int ok = put_bytes(fp, h, small, (size_t)L.off[S_ROOTS]) &&
                 put_bytes(fp, h, s->roots, (size_t)L.sz[S_ROOTS]) &&
                 put_zeros(fp, h, L.off[S_ROOTS] + L.sz[S_ROOTS], L.off[S_NODES]) &&
                 put_spill(fp, h, s->nodes, L.sz[S_NODES], buf, cap) &&
                 put_zeros(fp, h, L.off[S_NODES] + L.sz[S_NODES], L.off[S_POOL]) &&
                 put_spill(fp, h, s->pool, L.sz[S_POOL], buf, cap);
        uint64_t end = L.off[S_POOL] + L.sz[S_POOL];
        if (ok && L.n_sections > S_VIEWS) {
            ok = put_zeros(fp, h, end, L.off[S_VIEWS]) && put_bytes(fp, h, views, (size_t)L.sz[S_VIEWS]);
            end = L.off[S_VIEWS] + L.sz[S_VIEWS];
        }
        ok = ok && put_zeros(fp, h, end, L.total - 8);
        unsigned char sum[8];
        lie_cache_put_u64(sum, XXH3_64bits_digest(h));
        ok = ok && fwrite(sum, 1, 8, fp) == 8;
        if (!ok) {
            int e = errno;
            lie_atomic_abort(&af);
            st = lie_error_set(err, LIE_ERR_IO, s->name, "write failed: %s", strerror(e ? e : EIO));
        } else {
            st = lie_atomic_commit(&af, err);
        }
    }
    if (st == LIE_OK && bytes)
        *bytes = (size_t)L.total;
    free(small);
    free(views);
    free(buf);
    XXH3_freeState(h);
    lie_cache_stream_abort(s);
    return st;
}
