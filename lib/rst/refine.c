/* SPDX-License-Identifier: Apache-2.0 */
/* Exact refinement of ray-segment-tree answers: the hull of a flagged
 * unit root's patch and emitter against the edit's boxes, then down its
 * patch tree while the hulls meet them. */
#include "rst/rst.h"

#include <stdlib.h>

typedef struct refine_ctx {
    const lie_scene *s;
    const lie_env *env;
    const lie_box3 *boxes;
    int n_boxes;
    uint8_t *flags;
    lie_vec3 *hull;     /* per worker: hull_cap points */
    size_t hull_cap;
    uint64_t *cleared;  /* per worker */
} refine_ctx;

static void refine_node(const refine_ctx *c, int wid, uint32_t node, uint32_t tri, lie_patch_path path, int e)
{
    if (!c->flags[node])
        return;
    lie_vec3 V[3];
    lie_vec3 *hull = c->hull + (size_t)wid * c->hull_cap;
    lie_patch_world(path, &c->s->tri_p[3 * (size_t)tri], V);
    int n = lie_pair_hull_points(c->s, tri, V, e, hull);
    int meets = 0;
    /* never below the build's shaft tolerance (lie_pair_hull_scale, lib/lie/cull.c) */
    float tol = 1e-5f * fmaxf(lie_pair_hull_scale(hull, n), lie_v3_len(lie_v3_sub(c->s->bounds.hi, c->s->bounds.lo)));
    for (int b = 0; b < c->n_boxes && !meets; b++)
        meets = lie_pair_hull_meets_box(hull, n, c->boxes[b], tol);
    if (!meets) {
        c->flags[node] = 0; /* nor can its children's segments, all among its own */
        c->cleared[wid]++;
        return;
    }
    const lie_pnode *x = &c->env->nodes[node];
    if (x->child)
        for (uint32_t k = 0; k < 4; k++) {
            c->flags[x->child + k] = 1; /* a candidate, as its parent is */
            refine_node(c, wid, x->child + k, tri, lie_patch_child(path, (int)k), e);
        }
}

#define REFINE_CHUNK 256u /* triangles per parallel item */

/* A chunk of triangles: their units' trees touch disjoint flags. */
static void refine_chunk(void *ctx, size_t item, int wid)
{
    const refine_ctx *c = ctx;
    uint32_t t0 = (uint32_t)item * REFINE_CHUNK;
    uint32_t t1 = c->env->n_tris - t0 < REFINE_CHUNK ? c->env->n_tris : t0 + REFINE_CHUNK;
    for (uint32_t t = t0; t < t1; t++)
        for (int e = 0; e < c->env->n_clusters; e++)
            refine_node(c, wid, c->env->root[(size_t)t * (size_t)c->env->n_clusters + (size_t)e], t,
                        lie_patch_root(), e);
}

uint64_t lie_rst_refine(const lie_scene *s, const lie_env *env, const lie_box3 *boxes, int n_boxes, uint8_t *flags,
                        int threads)
{
    int cap = 0;
    for (int e = 0; e < s->n_clusters; e++)
        cap = cap > lie_pair_hull_cap(s, e) ? cap : lie_pair_hull_cap(s, e);
    if (threads <= 0)
        threads = lie_cpu_count();
    refine_ctx c = {s, env, boxes, n_boxes, flags, NULL, (size_t)cap + 1, NULL};
    c.hull = malloc(sizeof *c.hull * c.hull_cap * (size_t)threads);
    c.cleared = calloc((size_t)threads, sizeof *c.cleared);
    lie_status st = c.hull && c.cleared ? LIE_OK : LIE_ERR_NOMEM;
    if (st == LIE_OK)
        st = lie_parallel_for((env->n_tris + REFINE_CHUNK - 1) / REFINE_CHUNK, threads, refine_chunk, &c, NULL,
                              NULL);
    uint64_t cleared = 0;
    for (int i = 0; st == LIE_OK && i < threads; i++)
        cleared += c.cleared[i];
    free(c.hull);
    free(c.cleared);
    if (st != LIE_OK) {
        lie_rst_spread(env, flags); /* out of memory: flag whole subtrees (still correct) */
        return 0;
    }
    return cleared;
}

static void spread_node(const lie_env *env, uint32_t node, uint8_t *flags)
{
    const lie_pnode *x = &env->nodes[node];
    if (!flags[node] || !x->child)
        return;
    for (uint32_t k = 0; k < 4; k++) {
        flags[x->child + k] = 1;
        spread_node(env, x->child + k, flags);
    }
}

void lie_rst_spread(const lie_env *env, uint8_t *flags)
{
    for (size_t u = 0; u < (size_t)env->n_tris * (size_t)env->n_clusters; u++)
        spread_node(env, env->root[u], flags);
}
