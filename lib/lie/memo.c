/* SPDX-License-Identifier: Apache-2.0 */
/* The update memo (§5): the nodes an update recomputes, computed in
 * parallel before the build proper takes them (lib/lie/memo.h). */
#include "lie/memo.h"
#include "lie/pair.h"
#include "lie/sample.h"
#include "lie/subdiv.h"

#include <stdlib.h>
#include <string.h>

static uint64_t memo_key(uint32_t tri, lie_patch_path path, int e)
{
    return lie_hash_u64x4(tri, path.digits, (uint64_t)path.depth, (uint64_t)e);
}

/* The memo entry of a node new in this update (no old node), or -1. */
int32_t lie_memo_find_new(const build_ctx *c, uint32_t tri, lie_patch_path path, int e)
{
    if (!c->memo_new)
        return -1;
    for (size_t h = memo_key(tri, path, e) & c->memo_new_mask;; h = (h + 1) & c->memo_new_mask) {
        int32_t i = c->memo_new[h];
        if (i < 0)
            return -1;
        const memo_entry *m = &c->memo[i];
        if (m->tri == tri && m->e == e && m->path.digits == path.digits && m->path.depth == path.depth)
            return i;
    }
}

/* ---- update: flagged nodes recomputed in parallel ------------------------ */

/* An update's work sits in few units (a floor triangle's patch tree under a
 * moved object holds most of it), so parallelism over triangles leaves the
 * cores idle.  Before the build proper, the nodes build_node will compute
 * are computed in parallel, in waves by depth: wave 0 the flagged roots and
 * the roots of units built afresh, wave d+1 the children of wave d's nodes
 * that split (their flagged old children, or all four where there were
 * none).  These are exactly the nodes build_node computes (a sampled pair
 * depends only on its patch and emitter), so the result and the statistics
 * do not change; build_node takes each from the memo. */
typedef struct memo_state {
    build_ctx *c;
    size_t first, n;      /* this wave: memo[first, first + n) */
} memo_state;

static void memo_compute(void *ctx, size_t item, int worker_id)
{
    memo_state *ms = ctx;
    const build_ctx *c = ms->c;
    worker *w = &c->workers[worker_id];
    memo_entry *m = &c->memo[ms->first + item];
    const lie_scene *s = c->s;
    lie_vec3 V[3];
    lie_patch_world(m->path, &s->tri_p[3 * (size_t)m->tri], V);
    int two_sided = lie_pair_two_sided(s, m->tri);
    size_t n_list = 0;
    m->quality = 0;
    if (lie_pair_unlit(c->s, m->tri, V, two_sided, m->e))
        m->cls = LIE_CLASS_UNLIT;
    else
        m->cls = lie_sample_pair(c, w, m->tri, m->path, V, two_sided, m->e, &m->quality, &n_list);
    m->n_list = (uint32_t)n_list;
    m->list = NULL;
    if (n_list && !w->nomem) {
        m->list = malloc(n_list * sizeof *m->list);
        if (!m->list)
            w->nomem = 1;
        else
            memcpy(m->list, w->hits, n_list * sizeof *m->list);
    }
}

static int memo_push(build_ctx *c, size_t *n, size_t *cap, uint32_t old, uint32_t tri, lie_patch_path path, int e)
{
    if (!LIE_GROW(c->memo, *cap, *n + 1))
        return 0;
    memo_entry *m = &c->memo[(*n)++];
    memset(m, 0, sizeof *m);
    m->old = old;
    m->tri = tri;
    m->path = path;
    m->e = e;
    if (old != MEMO_NO_OLD)
        c->memo_of[old] = (int32_t)(*n - 1);
    return 1;
}

/* Index the entries of new nodes for lie_memo_find_new. */
static int memo_index_new(build_ctx *c, size_t n)
{
    size_t cap = 16;
    while (cap < 2 * n)
        cap *= 2;
    c->memo_new = malloc(sizeof *c->memo_new * cap);
    if (!c->memo_new)
        return 0;
    for (size_t i = 0; i < cap; i++)
        c->memo_new[i] = -1;
    c->memo_new_mask = cap - 1;
    for (size_t i = 0; i < n; i++) {
        const memo_entry *m = &c->memo[i];
        if (m->old != MEMO_NO_OLD)
            continue;
        size_t h = memo_key(m->tri, m->path, m->e) & c->memo_new_mask;
        while (c->memo_new[h] >= 0)
            h = (h + 1) & c->memo_new_mask;
        c->memo_new[h] = (int32_t)i;
    }
    return 1;
}

void lie_memo_free(build_ctx *c, size_t n)
{
    for (size_t i = 0; c->memo && i < n; i++)
        free(c->memo[i].list);
    LIE_FREE(c->memo);
    LIE_FREE(c->memo_of);
    LIE_FREE(c->memo_new);
}

/* Entries [first, n) by decreasing patch area, ties in entry order, as
 * offsets from first; NULL (entry order) when out of memory. */
static uint32_t *largest_first(const build_ctx *c, size_t first, size_t n)
{
    size_t m = n - first;
    uint64_t *key = malloc(sizeof *key * (m + 1));
    uint32_t *order = malloc(sizeof *order * (m + 1));
    if (!key || !order || m > UINT32_MAX) {
        free(key);
        free(order);
        return NULL;
    }
    for (size_t i = 0; i < m; i++) {
        const memo_entry *e = &c->memo[first + i];
        int d = e->path.depth < 15 ? e->path.depth : 15;
        float area = c->s->tri_area[e->tri] / (float)(1u << (2 * d));
        uint32_t bits;
        memcpy(&bits, &area, sizeof bits); /* a non-negative float's bits order as the float */
        key[i] = ((uint64_t)(~bits) << 32) | (uint32_t)i;
    }
    lie_sort_u64(key, m);
    for (size_t i = 0; i < m; i++)
        order[i] = (uint32_t)key[i];
    free(key);
    return order;
}

lie_status lie_memo_precompute(build_ctx *c, int threads, size_t *n_memo)
{
    const lie_env *old = c->old;
    const lie_scene *s = c->s;
    *n_memo = 0;
    c->memo_of = malloc(sizeof *c->memo_of * ((size_t)old->n_nodes + 1));
    if (!c->memo_of)
        return LIE_ERR_NOMEM;
    for (uint32_t i = 0; i < old->n_nodes; i++)
        c->memo_of[i] = -1;
    size_t n = 0, cap = 0;
    size_t ne = (size_t)s->n_clusters;
    for (uint32_t t = 0; t < s->n_tris; t++)
        for (size_t e = 0; e < ne; e++) {
            int32_t ou = lie_ctx_old_unit(c, (uint64_t)t * ne + e);
            uint32_t r = ou < 0 ? MEMO_NO_OLD : old->root[ou];
            if (r == MEMO_NO_OLD && !lie_subdiv_seen(c, t))
                continue; /* outside the views: one none node, nothing to sample */
            if ((r == MEMO_NO_OLD || c->node_flags[r]) && !memo_push(c, &n, &cap, r, t, lie_patch_root(), (int)e)) {
                *n_memo = n;
                return LIE_ERR_NOMEM;
            }
        }
    size_t first = 0;
    lie_status st = LIE_OK;
    while (st == LIE_OK && first < n) {
        memo_state ms = {c, first, n - first};
        /* a level ends when its last node is done: the largest patches
         * (most segments and candidates) first, so none starts last */
        uint32_t *order = threads != 1 ? largest_first(c, first, n) : NULL;
        lie_parallel_report rep;
        st = lie_parallel_for_ordered(ms.n, threads, memo_compute, &ms, order, NULL, NULL, NULL, &rep);
        free(order);
        c->par_cpu_sum += rep.cpu_sum;
        c->par_cpu_max += rep.cpu_max;
        c->par_tail += rep.tail;
        for (int i = 0; i < threads; i++)
            if (c->workers[i].nomem)
                st = LIE_ERR_NOMEM;
        size_t end = n;
        for (size_t i = first; st == LIE_OK && i < end; i++) {
            const memo_entry m = c->memo[i];
            uint32_t child = m.old == MEMO_NO_OLD ? 0 : old->nodes[m.old].child;
            if (!lie_subdiv_splits(c, m.tri, m.path, m.e, m.cls, m.list, m.n_list) ||
                (lie_subdiv_modelled(c) && !lie_subdiv_pixels_pay(c, m.tri, m.path, m.cls, m.n_list, m.quality)))
                continue;
            /* the children build_node will compute: flagged old ones, or
             * all four when the node had none (unflagged ones are copied) */
            for (uint32_t k = 0; k < 4; k++)
                if ((!child || c->node_flags[child + k]) &&
                    !memo_push(c, &n, &cap, child ? child + k : MEMO_NO_OLD, m.tri,
                               lie_patch_child(m.path, (int)k), m.e))
                    st = LIE_ERR_NOMEM;
        }
        first = end;
    }
    *n_memo = n;
    if (st == LIE_OK && !memo_index_new(c, n))
        st = LIE_ERR_NOMEM;
    return st;
}
