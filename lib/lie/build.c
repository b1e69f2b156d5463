/* SPDX-License-Identifier: Apache-2.0 */
/* Building local illumination environments (§4.1, §4.1.1, §4.3.2).
 *
 * One unit = (triangle, emitter).  A unit is built by a depth-first walk of
 * its patch tree: classify the patch–emitter pair, and split a partial patch
 * whose list is longer than max_blockers while the patch is larger than
 * min_patch.  Units are built in parallel into per-triangle buffers and
 * concatenated in unit order, so the result never depends on the schedule.
 *
 * This file runs a build or an update and assembles its result; the parts
 * are pair geometry (pair.c), sampling (sample.c), shaft culling (cull.c),
 * the patch tree (subdiv.c), the update memo (memo.c), and parameters and
 * statistics (params.c).  lib/lie/internal.h holds their shared state.
 * Size: just past the size CONTRIBUTING.md asks: running a build and an
 * update share the worker setup and the assembly. */
#include "lie/internal.h"
#include "lie/memo.h"
#include "lie/sample.h"
#include "lie/subdiv.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static lie_status assemble(lie_env *env, const lie_env *old, unit_buf *bufs, uint32_t tri_lo, uint32_t n_tris,
                           int n_clusters, const int32_t *old_unit, uint64_t unit_lo, uint64_t unit_hi, int threads);
static lie_status build_range(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                              const uint8_t *tri_mask, const lie_pixels *px, uint64_t first_unit, uint64_t n_units,
                              const lie_units_old *from, const volatile sig_atomic_t *stop, lie_env_part *out,
                              lie_build_stats *stats, lie_error *err);

static void workers_free(worker *ws, int n)
{
    for (int i = 0; ws && i < n; i++) {
        free(ws[i].hits);
        free(ws[i].stamp);
        free(ws[i].cand);
        free(ws[i].hull);
        free(ws[i].share);
    }
    free(ws);
}

/* Each triangle's expected share of the build: the progress bar's weight,
 * and the order workers take triangles in (the costliest first, so that no
 * long one starts last while the other workers idle).  Its pairs to build
 * times the leaves along a shadow boundary its subdivision can reach (§3.2:
 * a patch splits in four until min_patch, so a boundary crosses about
 * sqrt(area / min_area) of the smallest patches).  Pairs outside the views'
 * mask, or copied from an old env, cost next to nothing. */
/* A pair of triangle tri's expected cost: the leaves along a shadow
 * boundary its subdivision can reach; a triangle the views do not see
 * costs next to nothing. */
static double pair_weight(const build_ctx *c, uint32_t tri)
{
    if (!lie_subdiv_seen(c, tri))
        return 0.05;
    double ratio = c->min_area > 0.0f ? (double)c->s->tri_area[tri] / (double)c->min_area : 1.0;
    return 1.0 + (ratio > 1.0 ? pow(ratio, 0.75) : 0.0);
}

static uint32_t *build_weights(const build_ctx *c, uint32_t n_items, size_t ne)
{
    uint32_t *w = malloc(sizeof *w * ((size_t)n_items + 1));
    if (!w)
        return NULL; /* the bar then counts triangles, in order */
    for (uint32_t i = 0; i < n_items; i++) {
        uint32_t tri = c->tri_lo + i;
        size_t u0 = (size_t)tri * ne, u1 = u0 + ne;
        if (u0 < c->unit_lo)
            u0 = (size_t)c->unit_lo;
        if (u1 > c->unit_hi)
            u1 = (size_t)c->unit_hi;
        size_t pairs = c->s->n_clusters == 0 ? 1 : u1 > u0 ? u1 - u0 : 0;
        if (c->old_unit && !c->node_flags)
            for (size_t u = u0; u < u1; u++)
                pairs -= lie_ctx_old_unit(c, u) >= 0; /* copied */
        double v = (double)(pairs ? pairs : 1) * (pairs ? pair_weight(c, tri) : 0.05) * 4.0;
        w[i] = v < 1.0 ? 1u : v > 1e9 ? 1000000000u : (uint32_t)v;
    }
    return w;
}

/* The items by decreasing weight, ties in item order (a permutation). */
static uint32_t *heaviest_first(const uint32_t *w, uint32_t n)
{
    uint64_t *key = malloc(sizeof *key * ((size_t)n + 1));
    uint32_t *order = malloc(sizeof *order * ((size_t)n + 1));
    if (!key || !order) {
        free(key);
        free(order);
        return NULL; /* in item order: only slower */
    }
    for (uint32_t i = 0; i < n; i++)
        key[i] = ((uint64_t)(UINT32_MAX - w[i]) << 32) | i;
    lie_sort_u64(key, n);
    for (uint32_t i = 0; i < n; i++)
        order[i] = (uint32_t)key[i];
    free(key);
    return order;
}

/* lie_build_control.sink: triangle `item` of c->out (its units, or with
 * `copied` the old env's) handed to the sink, in unit order. */
static lie_status deliver(build_ctx *c, size_t item)
{
    const unit_buf *u = &c->out[item];
    size_t ne = (size_t)c->s->n_clusters;
    for (size_t e = 0; e < ne; e++) {
        size_t unit = ((size_t)c->tri_lo + item) * ne + e;
        if (unit < c->unit_lo || unit >= c->unit_hi)
            continue;
        lie_status st;
        if (u->copied)
            st = c->sink(c->sink_ctx, c->old->nodes, c->old->pool, c->old->root[lie_ctx_old_unit(c, unit)]);
        else if (!u->roots)
            st = LIE_ERR_NOMEM; /* its worker ran out (and fails the build) */
        else
            st = c->sink(c->sink_ctx, u->nodes, u->pool, u->roots[e]);
        if (st != LIE_OK)
            return st;
    }
    return LIE_OK;
}

/* lie_parallel_for body with a sink: build triangle `item`, then hand
 * over every triangle done from the first not handed over yet, and free
 * them: what is held is the triangles done beyond one still building. */
static void sink_triangle(void *ctx, size_t item, int worker_id)
{
    build_ctx *c = ctx;
    lie_subdiv_triangle(ctx, item, worker_id);
    pthread_mutex_lock(&c->sink_m);
    /* a worker out of memory or past the node budget left this triangle
     * unfinished: the build fails, and nothing more is handed over */
    if (c->workers[worker_id].nomem && c->sink_st == LIE_OK)
        c->sink_st = LIE_ERR_NOMEM;
    c->sink_done[item] = 1;
    while (c->sink_next < c->sink_n && c->sink_done[c->sink_next]) {
        unit_buf *u = &c->out[c->sink_next];
        if (c->sink_st == LIE_OK)
            c->sink_st = deliver(c, c->sink_next);
        free(u->roots);
        free(u->nodes);
        free(u->pool);
        memset(u, 0, sizeof *u);
        c->sink_next++;
    }
    pthread_mutex_unlock(&c->sink_m);
}

/* Build (or, with a mask, rebuild some units of) every triangle, then
 * concatenate the per-triangle buffers in unit order (or, with a sink,
 * hand them over in that order as they are done: lie_build_control.sink).  `stop` (may be
 * NULL) interrupts it: env->partial says whether a unit was left out.
 * An update continues the units of `old` (NULL: env itself, updated in
 * place): old_unit[unit - unit_lo] is the unit of old that unit continues,
 * or -1, and node_flags marks old's nodes to recompute. */
static lie_status run_build(lie_env *env, const lie_env *old, const lie_scene *s, const lie_rt *rt,
                           const int32_t *old_unit, const uint8_t *node_flags, const uint8_t *tri_mask, const lie_pixels *px,
                           uint64_t unit_lo, uint64_t unit_hi, int threads, int memo, lie_progress *progress,
                           const volatile sig_atomic_t *stop, int audit, const lie_build_control *sink,
                           lie_build_stats *stats)
{
    build_ctx c;
    memset(&c, 0, sizeof c);
    if (sink && sink->sink) {
        c.sink = sink->sink;
        c.sink_ctx = sink->sink_ctx;
    }
    c.s = s;
    c.rt = rt;
    c.p = &env->params;
    c.min_area = env->params.min_patch * s->max_tri_area;
    c.ray_far = lie_pair_ray_far(s);
    c.old = old ? old : env;
    c.old_unit = old_unit;
    c.node_flags = node_flags;
    c.tri_mask = tri_mask;
    c.pix = px;
    /* a whole build's model: pixels estimated by area (lie_whole_pixels) */
    if (!px && env->params.frames && env->params.whole_pixels)
        c.whole_area = lie_whole_area(s);
    c.stop = stop;
    c.audit_complex = audit;
    /* the triangles holding units [unit_lo, unit_hi) */
    size_t ne = s->n_clusters > 0 ? (size_t)s->n_clusters : 1;
    c.unit_lo = unit_lo;
    c.unit_hi = unit_hi;
    c.tri_lo = (uint32_t)(unit_lo / ne);
    uint32_t n_items = unit_hi > unit_lo ? (uint32_t)((unit_hi - 1) / ne + 1 - c.tri_lo) : 0;
    if (s->n_clusters == 0) {
        c.tri_lo = 0;
        n_items = s->n_tris;
    }
    if (threads <= 0)
        threads = lie_cpu_count();
    c.workers = calloc((size_t)threads, sizeof *c.workers);
    c.out = calloc((size_t)n_items + 1, sizeof *c.out);
    atomic_uint_least64_t nodes_made = 0;
    for (int i = 0; c.workers && i < threads; i++) {
        c.workers[i].nodes_made = &nodes_made;
        c.workers[i].max_nodes = c.p->max_nodes ? c.p->max_nodes : LIE_MAX_NODES_DEFAULT;
    }
    lie_status st = c.workers && c.out ? lie_sample_tables(&c) : LIE_ERR_NOMEM;
    size_t n_memo = 0;
    if (st == LIE_OK && memo && node_flags && old_unit && c.p->mode == LIE_BLOCKERS_SAMPLED)
        st = lie_memo_precompute(&c, threads, &n_memo);
    uint32_t *weight = st == LIE_OK ? build_weights(&c, n_items, ne) : NULL;
    /* the costliest first, unless units go to a sink, which takes them in
     * order: then in order, so that few wait for one still building */
    uint32_t *order = weight && threads > 1 && !c.sink ? heaviest_first(weight, n_items) : NULL;
    if (c.sink) {
        c.sink_n = n_items;
        c.sink_done = calloc((size_t)n_items + 1, 1);
        if (!c.sink_done)
            st = LIE_ERR_NOMEM;
        pthread_mutex_init(&c.sink_m, NULL);
    }
    lie_parallel_report rep;
    memset(&rep, 0, sizeof rep);
    if (st == LIE_OK)
        st = lie_parallel_for_ordered(n_items, threads, c.sink ? sink_triangle : lie_subdiv_triangle, &c, order,
                                      progress && progress->active ? weight : NULL,
                                      progress ? lie_progress_cb : NULL, progress, &rep);
    if (c.sink) {
        pthread_mutex_destroy(&c.sink_m);
        free(c.sink_done);
        if (st == LIE_OK && c.sink_next != c.sink_n)
            st = LIE_ERR_NOMEM; /* a triangle was not done: only when a worker failed */
    }
    free(order);
    free(weight);
    lie_memo_free(&c, n_memo);
    uint64_t interrupted = 0;
    for (int i = 0; c.workers && i < threads; i++) {
        if (c.workers[i].nomem && st != LIE_ERR_LIMIT)
            st = c.workers[i].over ? LIE_ERR_LIMIT : LIE_ERR_NOMEM;
        interrupted += c.workers[i].st.units_interrupted;
        if (stats)
            lie_stats_merge(stats, &c.workers[i].st);
    }
    if (stats) {
        stats->workers = rep.workers;
        stats->seconds_cpu_sum += c.par_cpu_sum + rep.cpu_sum;
        stats->seconds_cpu_max += c.par_cpu_max + rep.cpu_max;
        stats->seconds_tail += c.par_tail + rep.tail;
    }
    if (st == LIE_OK && c.sink)
        st = c.sink_st;
    else if (st == LIE_OK)
        st = assemble(env, c.old, c.out, c.tri_lo, n_items, s->n_clusters, old_unit, unit_lo, unit_hi, threads);
    if (st == LIE_OK && interrupted)
        env->partial = 1;
    for (uint32_t t = 0; c.out && t < n_items; t++) {
        free(c.out[t].roots);
        free(c.out[t].nodes);
        free(c.out[t].pool);
    }
    free(c.out);
    free(c.halton);
    workers_free(c.workers, threads);
    return st;
}

void lie_env_describe(lie_env *env, const lie_scene *s, const lie_build_params *p)
{
    env->n_tris = s->n_tris;
    env->n_clusters = s->n_clusters;
    env->params = *p;
    env->params.threads = 0; /* not part of what was built: any count builds the same */
    env->scene_hash = s->hash;
}

void lie_env_destroy(lie_env *env)
{
    if (!env)
        return;
    lie_forest_free(env->root, env->nodes, env->pool);
    free(env);
}

/* Copy old node `from` and its subtree to node idx of the new arrays, in
 * the order copy_node gives (children appended at next_node, lists at
 * next_pool, as their nodes are visited). */
static void copy_direct(const lie_env *old, uint32_t from, lie_pnode *nd, uint32_t *pl, uint32_t idx,
                        uint32_t *next_node, uint32_t *next_pool)
{
    lie_pnode x = old->nodes[from];
    if (x.child) {
        uint32_t first = *next_node, oc = x.child;
        *next_node += 4;
        x.child = first;
        nd[idx] = x;
        for (uint32_t k = 0; k < 4; k++)
            copy_direct(old, oc + k, nd, pl, first + k, next_node, next_pool);
        return;
    }
    if (x.cls == LIE_CLASS_PARTIAL) {
        memcpy(pl + *next_pool, old->pool + x.list, sizeof *pl * x.count);
        x.list = *next_pool;
        *next_pool += x.count;
    }
    nd[idx] = x;
}

/* Whether node idx or a node below it is unbuilt. */
static int holds_unbuilt(const lie_env *env, uint32_t idx)
{
    const lie_pnode *x = &env->nodes[idx];
    if (!x->child)
        return x->cls == LIE_CLASS_NONE;
    for (uint32_t k = 0; k < 4; k++)
        if (holds_unbuilt(env, x->child + k))
            return 1;
    return 0;
}

/* The shared leaves of an env whose units own `own` nodes: unlit first,
 * then none, each only if used; *n_nodes the total. */
typedef struct shared_leaves {
    uint32_t unlit, none, n_nodes;
} shared_leaves;

static shared_leaves shared_place(uint32_t own, int used_unlit, int used_none)
{
    shared_leaves sh = {own, own + (uint32_t)(used_unlit != 0), own};
    sh.n_nodes = own + (uint32_t)(used_unlit != 0) + (uint32_t)(used_none != 0);
    return sh;
}

static void shared_write(lie_pnode *nd, const shared_leaves *sh, int used_unlit, int used_none)
{
    if (used_unlit) {
        memset(&nd[sh->unlit], 0, sizeof *nd);
        nd[sh->unlit].cls = LIE_CLASS_UNLIT;
    }
    if (used_none) {
        memset(&nd[sh->none], 0, sizeof *nd);
        nd[sh->none].cls = LIE_CLASS_NONE;
    }
}

/* The lone class of a unit with root r in env (LIE_ROOT_LONE_*), or 0. */
static uint32_t lone_of(const lie_env *env, uint32_t r)
{
    const lie_pnode *x = &env->nodes[r];
    if (!lie_pnode_lone(x))
        return 0;
    return x->cls == LIE_CLASS_UNLIT ? LIE_ROOT_LONE_UNLIT : LIE_ROOT_LONE_NONE;
}

lie_status lie_env_lay_out(const lie_env *const *src, const uint64_t *n_units, size_t n_src, const uint8_t *drop,
                           lie_env *dst, uint64_t *own)
{
    /* the sizes first: a unit's tree, reachable from its root */
    uint64_t nodes = 0, pool = 0, all = 0;
    int used[2] = {0, 0}; /* unlit, none */
    for (size_t i = 0; i < n_src; i++)
        for (uint64_t u = 0; u < n_units[i]; u++, all++) {
            uint32_t r = src[i]->root[u], lone = drop && drop[all] ? LIE_ROOT_LONE_NONE : lone_of(src[i], r);
            if (lone) {
                used[lone == LIE_ROOT_LONE_NONE] = 1;
                continue;
            }
            uint32_t nn = 0, np = 0;
            lie_subtree_size(src[i], r, &nn, &np);
            nodes += nn;
            pool += np;
        }
    if (own)
        *own = nodes;
    if (nodes >= 0xFFFFFFF0u || pool >= 0xFFFFFFF0u)
        return LIE_ERR_LIMIT;
    shared_leaves sh = shared_place((uint32_t)nodes, used[0], used[1]);
    uint32_t *root = malloc(sizeof *root * ((size_t)all + 1));
    lie_pnode *nd = malloc(sizeof *nd * ((size_t)sh.n_nodes + 1));
    uint32_t *pl = malloc(sizeof *pl * ((size_t)pool + 1));
    if (!root || !nd || !pl) {
        lie_forest_free(root, nd, pl);
        return LIE_ERR_NOMEM;
    }
    /* unit by unit, each tree as copy_node lays it out: a build's layout */
    uint32_t next_node = 0, next_pool = 0;
    all = 0;
    for (size_t i = 0; i < n_src; i++)
        for (uint64_t u = 0; u < n_units[i]; u++, all++) {
            uint32_t r = src[i]->root[u], lone = drop && drop[all] ? LIE_ROOT_LONE_NONE : lone_of(src[i], r);
            if (lone) {
                root[all] = lone == LIE_ROOT_LONE_UNLIT ? sh.unlit : sh.none;
                dst->partial |= drop && drop[all];
                continue;
            }
            uint32_t idx = next_node++;
            root[all] = idx;
            copy_direct(src[i], r, nd, pl, idx, &next_node, &next_pool);
        }
    shared_write(nd, &sh, used[0], used[1]);
    dst->root = root;
    dst->nodes = nd;
    dst->pool = pl;
    dst->n_nodes = sh.n_nodes;
    dst->n_pool = next_pool;
    return LIE_OK;
}

/* lie_env_compact; with `whole_units`, a unit holding an unbuilt leaf
 * below its root (an update's pending leaves) is left unbuilt whole. */
static lie_status compact(const lie_env *src, int whole_units, lie_env **out, lie_error *err)
{
    *out = NULL;
    size_t n_units = (size_t)src->n_tris * (size_t)src->n_clusters;
    uint8_t *drop = whole_units ? calloc(n_units + 1, 1) : NULL;
    if (whole_units && !drop)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    for (size_t u = 0; drop && u < n_units; u++)
        drop[u] = src->nodes[src->root[u]].child && holds_unbuilt(src, src->root[u]);
    lie_env *env = calloc(1, sizeof *env);
    lie_status st = env ? LIE_OK : LIE_ERR_NOMEM;
    if (env) {
        *env = *src;
        env->root = NULL;
        env->nodes = NULL;
        env->pool = NULL;
        uint64_t nu = n_units;
        st = lie_env_lay_out(&src, &nu, 1, drop, env, NULL);
    }
    free(drop);
    if (st != LIE_OK) {
        free(env);
        return st == LIE_ERR_LIMIT
                   ? lie_error_set(err, LIE_ERR_LIMIT, NULL, "the patch trees hold too many nodes for one env")
                   : lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    }
    *out = env;
    return LIE_OK;
}

lie_status lie_env_compact(const lie_env *src, lie_env **out, lie_error *err) { return compact(src, 0, out, err); }

lie_status lie_env_compact_units(const lie_env *src, lie_env **out, lie_error *err)
{
    return compact(src, 1, out, err);
}

/* Concatenate per-triangle unit buffers (of triangles tri_lo + t) into
 * env's flat arrays (copied triangles straight from env's old arrays, which
 * are freed last); env->root[unit - unit_lo] for the units in
 * [unit_lo, unit_hi).  Each triangle's place follows from the sizes before
 * it, so triangles are copied in parallel, in chunks, into disjoint parts
 * of the arrays: the same bytes for any thread count.  (Serial, it was
 * about a tenth of an update's serial time on museum3.) */
typedef struct assembly {
    const lie_env *old;
    const unit_buf *bufs;
    uint32_t tri_lo, n_tris;
    int n_clusters;
    const int32_t *old_unit;
    uint64_t unit_lo, unit_hi;
    const uint32_t *nb, *pb; /* per triangle: its first node and pool entry */
    shared_leaves sh;
    uint32_t *root;
    lie_pnode *nd;
    uint32_t *pl;
} assembly;

#define ASSEMBLE_CHUNK 512u /* triangles per parallel item */

static void assemble_tri(const assembly *a, uint32_t t)
{
    const unit_buf *u = &a->bufs[t];
    uint32_t nb = a->nb[t], pb = a->pb[t];
    if (u->copied) {
        uint32_t next_node = nb, next_pool = pb;
        for (int e = 0; e < a->n_clusters; e++) {
            size_t unit = (size_t)(a->tri_lo + t) * (size_t)a->n_clusters + (size_t)e;
            uint32_t r = a->old->root[a->old_unit[unit - a->unit_lo]], lone = lone_of(a->old, r);
            if (lone) {
                a->root[unit - a->unit_lo] = lone == LIE_ROOT_LONE_UNLIT ? a->sh.unlit : a->sh.none;
                continue;
            }
            uint32_t idx = next_node++;
            a->root[unit - a->unit_lo] = idx;
            copy_direct(a->old, r, a->nd, a->pl, idx, &next_node, &next_pool);
        }
        return;
    }
    for (int e = 0; e < a->n_clusters; e++) {
        uint64_t unit = (uint64_t)(a->tri_lo + t) * (uint64_t)a->n_clusters + (uint64_t)e;
        if (unit < a->unit_lo || unit >= a->unit_hi)
            continue;
        uint32_t r = u->roots[e];
        a->root[unit - a->unit_lo] = r == LIE_ROOT_LONE_UNLIT ? a->sh.unlit : r == LIE_ROOT_LONE_NONE ? a->sh.none : nb + r;
    }
    for (uint32_t i = 0; i < u->n_nodes; i++) {
        lie_pnode x = u->nodes[i];
        if (x.child)
            x.child += nb;
        if (x.cls == LIE_CLASS_PARTIAL)
            x.list += pb;
        a->nd[nb + i] = x;
    }
    if (u->n_pool)
        memcpy(a->pl + pb, u->pool, sizeof *a->pl * u->n_pool);
}

static void assemble_chunk(void *ctx, size_t item, int worker_id)
{
    (void)worker_id;
    const assembly *a = ctx;
    uint32_t t0 = (uint32_t)item * ASSEMBLE_CHUNK;
    uint32_t t1 = a->n_tris - t0 < ASSEMBLE_CHUNK ? a->n_tris : t0 + ASSEMBLE_CHUNK;
    for (uint32_t t = t0; t < t1; t++)
        assemble_tri(a, t);
}

static lie_status assemble(lie_env *env, const lie_env *old, unit_buf *bufs, uint32_t tri_lo, uint32_t n_tris,
                           int n_clusters, const int32_t *old_unit, uint64_t unit_lo, uint64_t unit_hi, int threads)
{
    uint64_t nodes = 0, pool = 0;
    int used[2] = {0, 0}; /* the shared leaves: unlit, none */
    for (uint32_t t = 0; t < n_tris; t++) {
        nodes += bufs[t].n_nodes;
        pool += bufs[t].n_pool;
        for (int e = 0; e < n_clusters; e++) {
            uint64_t unit = (uint64_t)(tri_lo + t) * (uint64_t)n_clusters + (uint64_t)e;
            if (unit < unit_lo || unit >= unit_hi)
                continue;
            uint32_t r = bufs[t].copied ? lone_of(old, old->root[old_unit[unit - unit_lo]]) : bufs[t].roots[e];
            used[0] |= r == LIE_ROOT_LONE_UNLIT;
            used[1] |= r == LIE_ROOT_LONE_NONE;
        }
    }
    if (nodes >= 0xFFFFFFF0u || pool >= 0xFFFFFFF0u)
        return LIE_ERR_LIMIT;
    shared_leaves sh = shared_place((uint32_t)nodes, used[0], used[1]);
    uint32_t *root = malloc(sizeof *root * ((size_t)(unit_hi - unit_lo) + 1));
    lie_pnode *nd = malloc(sizeof *nd * (size_t)(sh.n_nodes + 1));
    uint32_t *pl = malloc(sizeof *pl * (size_t)(pool + 1));
    uint32_t *nb = malloc(sizeof *nb * ((size_t)n_tris + 1));
    uint32_t *pb = malloc(sizeof *pb * ((size_t)n_tris + 1));
    lie_status st = root && nd && pl && nb && pb ? LIE_OK : LIE_ERR_NOMEM;
    if (st == LIE_OK) {
        nb[0] = pb[0] = 0;
        for (uint32_t t = 0; t < n_tris; t++) {
            nb[t + 1] = nb[t] + bufs[t].n_nodes;
            pb[t + 1] = pb[t] + bufs[t].n_pool;
        }
        assembly a = {old, bufs, tri_lo, n_tris, n_clusters, old_unit, unit_lo, unit_hi, nb, pb, sh, root, nd, pl};
        st = lie_parallel_for((n_tris + ASSEMBLE_CHUNK - 1) / ASSEMBLE_CHUNK, threads, assemble_chunk, &a, NULL,
                              NULL);
        shared_write(nd, &sh, used[0], used[1]);
    }
    if (st != LIE_OK) {
        free(root);
        free(nd);
        free(pl);
        free(nb);
        free(pb);
        return st;
    }
    lie_forest_free(env->root, env->nodes, env->pool);
    env->root = root;
    env->nodes = nd;
    env->pool = pl;
    env->n_nodes = sh.n_nodes;
    env->n_pool = pb[n_tris];
    free(nb);
    free(pb);
    return LIE_OK;
}

lie_status lie_budget_error(lie_error *err, const lie_scene *s, const lie_build_params *p)
{
    return lie_error_set(err, LIE_ERR_LIMIT, s->path,
                         "the patch trees need more than %llu nodes (max-nodes): raise min-patch or max-nodes",
                         (unsigned long long)(p->max_nodes ? p->max_nodes : LIE_MAX_NODES_DEFAULT));
}

lie_status lie_env_build(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                         lie_progress *progress, lie_env **out, lie_build_stats *stats, lie_error *err)
{
    return lie_env_build_masked(s, rt, p, NULL, progress, out, stats, err);
}

/* A build with no control but a triangle mask or views, and progress. */
static lie_status build_simple(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                               const uint8_t *tri_mask, const lie_pixels *px, lie_progress *progress,
                               lie_env **out, lie_build_stats *stats, lie_error *err)
{
    lie_build_control ctl;
    memset(&ctl, 0, sizeof ctl);
    ctl.tri_mask = tri_mask;
    ctl.pixels = px;
    ctl.progress = progress;
    return lie_env_build_with(s, rt, p, &ctl, out, stats, err);
}

lie_status lie_env_build_masked(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                                const uint8_t *tri_mask, lie_progress *progress, lie_env **out,
                                lie_build_stats *stats, lie_error *err)
{
    return build_simple(s, rt, p, tri_mask, NULL, progress, out, stats, err);
}

lie_status lie_env_build_views(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                               const lie_pixels *px, lie_progress *progress, lie_env **out,
                               lie_build_stats *stats, lie_error *err)
{
    return build_simple(s, rt, p, NULL, px, progress, out, stats, err);
}

/* A resumed env must be the interrupted build of this very build: the same
 * scene and every parameter a cache stores. */
static lie_status resume_check(const lie_env *r, const lie_scene *s, const lie_build_params *p, lie_error *err)
{
    if (r->n_tris != s->n_tris || r->n_clusters != s->n_clusters || r->scene_hash != s->hash)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "the partial build to resume was made for another scene");
    const lie_build_params *q = &r->params;
    if (q->samples != p->samples || q->max_samples != p->max_samples || q->max_blockers != p->max_blockers ||
        q->complex_cap != p->complex_cap || q->min_patch != p->min_patch || q->split_gain != p->split_gain ||
        q->mode != p->mode || q->complex_predict != p->complex_predict || q->whole_pixels != p->whole_pixels)
        return lie_error_set(err, LIE_ERR_ARG, s->path,
                             "the partial build to resume was made with other build parameters");
    return LIE_OK;
}

lie_status lie_env_build_with(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                              const lie_build_control *ctl, lie_env **out, lie_build_stats *stats, lie_error *err)
{
    *out = NULL;
    if (lie_build_params_check(p, err) != LIE_OK)
        return LIE_ERR_ARG;
    if (ctl->pixels && ctl->pixels->n_tris != s->n_tris)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "pixels for %u triangles, not %u", ctl->pixels->n_tris,
                             s->n_tris);
    if (ctl->resume && resume_check(ctl->resume, s, p, err) != LIE_OK)
        return LIE_ERR_ARG;
    double t0 = lie_time_now();
    lie_env *env = calloc(1, sizeof *env);
    uint64_t n_units = (uint64_t)s->n_tris * (uint64_t)s->n_clusters;
    int32_t *old_unit = NULL;
    if (env && ctl->resume && ctl->sink) {
        /* with a sink, the interrupted build's units are handed over from
         * where they are (run_build's old): no copy of them is made */
        const lie_env *r = ctl->resume;
        old_unit = n_units < INT32_MAX ? malloc(sizeof *old_unit * ((size_t)n_units + 1)) : NULL;
        if (!old_unit) {
            free(env);
            env = NULL;
        }
        for (uint64_t u = 0; old_unit && u < n_units; u++)
            old_unit[u] = r->nodes[r->root[u]].cls == LIE_CLASS_NONE ? -1 : (int32_t)u;
    } else if (env && ctl->resume) {
        /* a resume is an update that copies every unit the interrupted
         * build finished (copy_node lays it out as a build does) and builds
         * the others afresh: lie_env_update's old_unit, without flags */
        const lie_env *r = ctl->resume;
        old_unit = n_units < INT32_MAX ? malloc(sizeof *old_unit * ((size_t)n_units + 1)) : NULL;
        env->root = malloc(sizeof *env->root * ((size_t)n_units + 1));
        env->nodes = malloc(sizeof *env->nodes * ((size_t)r->n_nodes + 1));
        env->pool = malloc(sizeof *env->pool * ((size_t)r->n_pool + 1));
        if (!old_unit || !env->root || !env->nodes || !env->pool) {
            free(old_unit);
            lie_env_destroy(env);
            env = NULL;
        } else {
            memcpy(env->root, r->root, sizeof *env->root * (size_t)n_units);
            memcpy(env->nodes, r->nodes, sizeof *env->nodes * (size_t)r->n_nodes);
            memcpy(env->pool, r->pool, sizeof *env->pool * (size_t)r->n_pool);
            env->n_nodes = r->n_nodes;
            env->n_pool = r->n_pool;
            for (uint64_t u = 0; u < n_units; u++)
                old_unit[u] = r->nodes[r->root[u]].cls == LIE_CLASS_NONE ? -1 : (int32_t)u;
        }
    }
    if (!env)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    lie_env_describe(env, s, p);
    if (stats)
        memset(stats, 0, sizeof *stats);
    lie_status st = run_build(env, ctl->sink ? ctl->resume : NULL, s, rt, old_unit, NULL, ctl->tri_mask, ctl->pixels, 0,
                              n_units, p->threads, 0, ctl->progress, ctl->stop, ctl->audit_complex, ctl, stats);
    free(old_unit);
    if (st != LIE_OK) {
        lie_env_destroy(env);
        if (st == LIE_ERR_LIMIT)
            return lie_budget_error(err, s, p);
        return lie_error_set(err, st, s->path, "building local illumination environments: %s",
                             lie_status_str(st));
    }
    if (stats)
        stats->seconds = lie_time_now() - t0;
    *out = env;
    return LIE_OK;
}

lie_status lie_env_build_range(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                               const uint8_t *tri_mask, uint64_t first_unit, uint64_t n_units, lie_env_part *out,
                               lie_build_stats *stats, lie_error *err)
{
    return build_range(s, rt, p, tri_mask, NULL, first_unit, n_units, NULL, NULL, out, stats, err);
}

lie_status lie_env_build_range_views(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                                     const lie_pixels *px, uint64_t first_unit, uint64_t n_units,
                                     lie_env_part *out, lie_build_stats *stats, lie_error *err)
{
    memset(out, 0, sizeof *out);
    if (px && px->n_tris != s->n_tris)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "pixels for %u triangles, not %u", px->n_tris, s->n_tris);
    return build_range(s, rt, p, NULL, px, first_unit, n_units, NULL, NULL, out, stats, err);
}

lie_status lie_env_build_units(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                               const lie_pixels *px, uint64_t first_unit, uint64_t n_units,
                               const lie_units_old *from, const volatile sig_atomic_t *stop, lie_env_part *out,
                               lie_build_stats *stats, lie_error *err)
{
    memset(out, 0, sizeof *out);
    if (px && px->n_tris != s->n_tris)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "pixels for %u triangles, not %u", px->n_tris, s->n_tris);
    return build_range(s, rt, p, NULL, px, first_unit, n_units, from, stop, out, stats, err);
}

/* Parameters and a unit range a build can take. */
static lie_status check_range(const lie_scene *s, const lie_build_params *p, uint64_t first_unit, uint64_t n_units,
                              lie_error *err)
{
    if (lie_build_params_check(p, err) != LIE_OK)
        return LIE_ERR_ARG;
    uint64_t total = (uint64_t)s->n_tris * (uint64_t)s->n_clusters;
    if (first_unit > total || n_units > total - first_unit)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "units %llu..%llu out of range (%llu)",
                             (unsigned long long)first_unit, (unsigned long long)(first_unit + n_units),
                             (unsigned long long)total);
    return LIE_OK;
}

lie_status lie_env_unit_weights(const lie_scene *s, const lie_build_params *p, const lie_pixels *px,
                                uint64_t first_unit, uint64_t n_units, double *out, lie_error *err)
{
    if (check_range(s, p, first_unit, n_units, err) != LIE_OK)
        return err->status;
    if (px && px->n_tris != s->n_tris)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "pixels for %u triangles, not %u", px->n_tris, s->n_tris);
    build_ctx c;
    memset(&c, 0, sizeof c);
    c.s = s;
    c.p = p;
    c.min_area = p->min_patch * s->max_tri_area;
    c.pix = px;
    for (uint64_t i = 0; i < n_units; i++)
        out[i] = pair_weight(&c, (uint32_t)((first_unit + i) / (uint64_t)s->n_clusters));
    return LIE_OK;
}

static lie_status build_range(const lie_scene *s, const lie_rt *rt, const lie_build_params *p,
                              const uint8_t *tri_mask, const lie_pixels *px, uint64_t first_unit, uint64_t n_units,
                              const lie_units_old *from, const volatile sig_atomic_t *stop, lie_env_part *out,
                              lie_build_stats *stats, lie_error *err)
{
    memset(out, 0, sizeof *out);
    if (check_range(s, p, first_unit, n_units, err) != LIE_OK)
        return err->status;
    double t0 = lie_time_now();
    lie_env part;
    memset(&part, 0, sizeof part);
    part.params = *p;
    if (stats)
        memset(stats, 0, sizeof *stats);
    lie_status st = LIE_OK;
    if (n_units)
        st = run_build(&part, from ? from->env : NULL, s, rt, from ? from->old_unit : NULL,
                       from ? from->node_flags : NULL, tri_mask, px, first_unit, first_unit + n_units, p->threads, 0,
                       NULL, stop, 0, NULL, stats);
    if (st != LIE_OK) {
        free(part.root);
        free(part.nodes);
        free(part.pool);
        if (st == LIE_ERR_LIMIT)
            return lie_budget_error(err, s, p);
        return lie_error_set(err, st, s->path, "building local illumination environments: %s", lie_status_str(st));
    }
    if (stats)
        stats->seconds = lie_time_now() - t0;
    out->first_unit = first_unit;
    out->n_units = n_units;
    out->root = part.root;
    out->nodes = part.nodes;
    out->n_nodes = part.n_nodes;
    out->pool = part.pool;
    out->n_pool = part.n_pool;
    return LIE_OK;
}

lie_status lie_env_rebuild_units(lie_env *env, const lie_scene *s, const lie_rt *rt,
                                 const uint32_t *units, size_t n_units, int threads,
                                 lie_build_stats *stats, lie_error *err)
{
    if (env->n_tris != s->n_tris || env->n_clusters != s->n_clusters)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "the scene's triangles or emitters changed in number");
    size_t n = (size_t)s->n_tris * (size_t)s->n_clusters;
    int32_t *old_unit = malloc(sizeof *old_unit * (n + 1));
    if (!old_unit)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    for (size_t u = 0; u < n; u++)
        old_unit[u] = (int32_t)u;
    for (size_t i = 0; i < n_units; i++)
        if (units[i] < n)
            old_unit[units[i]] = -1;
    lie_status st = lie_env_update(env, s, rt, old_unit, NULL, threads, stats, err);
    free(old_unit);
    return st;
}

lie_status lie_env_update(lie_env *env, const lie_scene *s, const lie_rt *rt, const int32_t *old_unit,
                          const uint8_t *node_flags, int threads, lie_build_stats *stats, lie_error *err)
{
    return lie_env_update_views(env, s, rt, NULL, old_unit, node_flags, threads, stats, err);
}

lie_status lie_env_update_views(lie_env *env, const lie_scene *s, const lie_rt *rt, const lie_pixels *px,
                                const int32_t *old_unit, const uint8_t *node_flags, int threads,
                                lie_build_stats *stats, lie_error *err)
{
    return lie_build_update(env, s, rt, px, old_unit, node_flags, threads, 1, stats, err);
}

lie_status lie_build_update(lie_env *env, const lie_scene *s, const lie_rt *rt, const lie_pixels *px,
                            const int32_t *old_unit, const uint8_t *node_flags, int threads, int memo,
                            lie_build_stats *stats, lie_error *err)
{
    if (px && px->n_tris != s->n_tris)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "pixels for %u triangles, not %u", px->n_tris, s->n_tris);
    double t0 = lie_time_now();
    if (stats)
        memset(stats, 0, sizeof *stats);
    lie_status st = run_build(env, NULL, s, rt, old_unit, node_flags, NULL, px, 0,
                              (uint64_t)s->n_tris * (uint64_t)s->n_clusters, threads, memo, NULL, NULL, 0, NULL, stats);
    if (stats)
        stats->seconds = lie_time_now() - t0;
    if (st == LIE_ERR_LIMIT)
        return lie_budget_error(err, s, &env->params);
    if (st != LIE_OK)
        return lie_error_set(err, st, s->path, "updating local illumination environments: %s",
                             lie_status_str(st));
    env->n_tris = s->n_tris;
    env->n_clusters = s->n_clusters;
    env->scene_hash = s->hash;
    return LIE_OK;
}
