/* SPDX-License-Identifier: Apache-2.0 */
/* libFuzzer target for the cache reader (lib/cache).  Each input is decoded
 * twice: as is, and with every section checksum and the file checksum
 * recomputed, so that mutations reach the checks behind the checksums.
 * Any input must either fail with one line, or decode to a cache whose
 * trees can be walked and which encodes, decodes again and re-encodes to
 * the same bytes (an accepted input need not be canonical: sections may
 * come in another order or be unknown).
 *
 * Also built into tests/unit/test_fuzz_regressions.c, which replays
 * tests/fuzz/regressions/cache/ under `make test`: there the entry point
 * is renamed through LIE_FUZZ_ENTRY. */
#include <stdlib.h>
#include <string.h>

#include "cache/cache.h"
#include "fuzz_common.h"

#ifndef LIE_FUZZ_ENTRY
#define LIE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

static uint64_t fc_get64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int k = 7; k >= 0; k--)
        v = (v << 8) | p[k];
    return v;
}

static void fc_put64(unsigned char *p, uint64_t v)
{
    for (int k = 0; k < 8; k++)
        p[k] = (unsigned char)(v >> (8 * k));
}

static void fc_reseal(unsigned char *b, size_t size)
{
    if (size < 40)
        return;
    uint32_t n = (uint32_t)fc_get64(b + 20) & 0xFFFFFFFFu;
    for (uint64_t i = 0; i < n && 32 + 32 * (i + 1) <= size - 8; i++) {
        unsigned char *t = b + 32 + 32 * i;
        uint64_t off = fc_get64(t + 8), sz = fc_get64(t + 16);
        if (off <= size && sz <= size - off)
            fc_put64(t + 24, lie_hash_bytes(b + off, (size_t)sz, 0));
    }
    fc_put64(b + size - 8, lie_hash_bytes(b, size - 8, 0));
}

/* The nodes reachable from the roots, in pre-order, as a reader would,
 * each counted once: only a lone leaf (lie_pnode_lone, formats/lie-cache.md:
 * the reader shares one among the units that are one unlit or unbuilt
 * leaf) may be reached from more than one root. */
static uint64_t fc_walk(const lie_env *env, uint32_t node, int depth, unsigned char *seen)
{
    const lie_pnode *n = &env->nodes[node];
    if (depth > LIE_PATCH_MAX_DEPTH || node >= env->n_nodes)
        abort();
    if (seen[node]) {
        if (depth > 0 || !lie_pnode_lone(n))
            abort();
        return 0;
    }
    seen[node] = 1;
    uint64_t count = 1;
    if (n->cls == LIE_CLASS_PARTIAL && !n->child)
        for (uint32_t k = 0; k < n->count; k++)
            if (env->pool[n->list + k] >= env->n_tris)
                abort();
    if (n->child)
        for (uint32_t c = 0; c < 4; c++)
            count += fc_walk(env, n->child + c, depth + 1, seen);
    return count;
}

static void fc_check(const unsigned char *data, size_t size)
{
    lie_cache *c = NULL;
    lie_error err;
    if (lie_cache_decode(data, size, "fuzz.lie", &c, &err) != LIE_OK) {
        if (c || fuzz_msg_bad(&err) || !err.msg[0])
            abort();
        return;
    }
    lie_cache_section sec[LIE_CACHE_MAX_SECTIONS];
    int n_sec = 0;
    if (lie_cache_sections(data, size, "fuzz.lie", sec, &n_sec, &err) != LIE_OK)
        abort();
    lie_build_stats st;
    lie_env_stats(c->env, &st);
    uint64_t nodes = 0;
    unsigned char *seen = calloc(c->env->n_nodes + 1, 1);
    if (!seen)
        abort();
    for (size_t u = 0; u < (size_t)c->env->n_tris * (size_t)c->env->n_clusters; u++)
        nodes += fc_walk(c->env, c->env->root[u], 0, seen);
    free(seen);
    if (nodes != c->env->n_nodes)
        abort();
    unsigned char *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    lie_cache *d = NULL;
    if (lie_cache_encode(c, &a, &na, &err) != LIE_OK || lie_cache_decode(a, na, "again", &d, &err) != LIE_OK ||
        lie_cache_encode(d, &b, &nb, &err) != LIE_OK || na != nb || memcmp(a, b, na) != 0)
        abort();
    free(a);
    free(b);
    lie_cache_destroy(d);
    lie_cache_destroy(c);
}

int LIE_FUZZ_ENTRY(const unsigned char *data, size_t size);
int LIE_FUZZ_ENTRY(const unsigned char *data, size_t size)
{
    fc_check(data, size);
    if (size >= 40) {
        unsigned char *copy = malloc(size);
        if (!copy)
            return 0;
        memcpy(copy, data, size);
        fc_reseal(copy, size);
        fc_check(copy, size);
        free(copy);
    }
    return 0;
}
