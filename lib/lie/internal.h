/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/lie: the shared state of a build (lib/lie/build.c) and
 * the helpers every part of it uses. */
#ifndef LIE_INTERNAL_H
#define LIE_INTERNAL_H

#include "lie/lie.h"

#include <pthread.h>
#include <stdatomic.h>

/* ---- per-unit output and per-worker scratch ----------------------------- */

/* A unit_buf's root for a unit that is one lone leaf (lie_pnode_lone): it
 * holds no node, and assembly points it at the env's shared leaf. */
#define LIE_ROOT_LONE_UNLIT LIE_UNIT_LONE_UNLIT
#define LIE_ROOT_LONE_NONE LIE_UNIT_LONE_NONE

typedef struct unit_buf {
    uint32_t *roots;      /* per emitter: the unit's root, local index, or LIE_ROOT_LONE_* */
    lie_pnode *nodes;
    uint32_t n_nodes;
    size_t cap_nodes;
    uint32_t *pool;
    uint32_t n_pool;
    size_t cap_pool;
    int copied;           /* update: every unit is copied whole from the old env at
                             assembly; nothing is held here but the sizes */
} unit_buf;

typedef struct worker {
    uint32_t *hits;      /* all-hits results of a pair, each triangle once */
    size_t n_hits, cap_hits;
    uint32_t *stamp;     /* per triangle: the pair that last added it to hits */
    uint32_t stamp_id;
    uint32_t *cand;      /* conservative candidates */
    size_t n_cand, cap_cand;
    lie_vec3 *hull;      /* conservative hull points */
    size_t cap_hull;
    lie_build_stats st;
    int nomem;
    int stopped;              /* the build's stop flag was seen inside a unit: drop it */
    int over;                 /* the node budget ran out (nomem is set too, to stop) */
    atomic_uint_least64_t *nodes_made; /* shared by all workers */
    uint64_t max_nodes;
    double *share;            /* lie_unit_shares of the triangle at hand */
    size_t cap_share;
    int root_predicted;       /* the unit at hand was predicted complex (lib/lie/subdiv.c) */
} worker;

typedef struct build_ctx {
    const lie_scene *s;
    const lie_rt *rt;
    const lie_build_params *p;
    float min_area;       /* absolute smallest patch area that may still split */
    float ray_far;        /* towards directional emitters */
    const lie_env *old;   /* rebuild: units not in the mask are copied from here */
    const int32_t *old_unit;  /* update: per unit from unit_lo, the old unit to copy or update,
                                 or -1 to build afresh (NULL: build everything) */
    const uint8_t *node_flags; /* update: per old node, 1 = recompute (NULL: none) */
    const uint8_t *tri_mask;   /* build only these triangles (NULL: all) */
    const lie_pixels *pix;     /* views: build only triangles with hits, as fine as their pixels
                                  need (NULL: all, as fine as the lists need) */
    double whole_area;         /* no views: lie_whole_area when the whole build's model decides
                                  (p->frames and p->whole_pixels), else 0 */
    uint64_t unit_lo, unit_hi; /* build only units [unit_lo, unit_hi) ... */
    uint32_t tri_lo;           /* ... of triangles tri_lo + item (out[item]) */
    unit_buf *out;        /* per triangle: its units, in emitter order, each contiguous */
    worker *workers;
    /* update: flagged old nodes already recomputed in parallel (see
     * lie_memo_precompute); memo_of[old node] indexes memo, or -1 */
    int32_t *memo_of;
    struct memo_entry *memo;
    int32_t *memo_new;    /* open-addressing table of the memo entries of new nodes */
    size_t memo_new_mask;
    const volatile sig_atomic_t *stop; /* lie_build_control.stop, or NULL */
    int audit_complex;         /* lie_build_control.audit_complex */
    /* the parallel loops' CPU seconds so far (lie_parallel_report): summed
     * over workers, the busiest worker's per loop summed, idle tails */
    double par_cpu_sum, par_cpu_max, par_tail;
    /* lie_build_control.sink: triangles done (sink_done), handed over in
     * order from sink_next under sink_m, the first failure in sink_st */
    lie_unit_sink_fn sink;
    void *sink_ctx;
    pthread_mutex_t sink_m;
    uint8_t *sink_done;
    size_t sink_next, sink_n;
    lie_status sink_st;
    double *halton;       /* radical inverses in bases 2, 3, 5, 7 of 0..n_halton-1 */
    uint32_t n_halton;
} build_ctx;

/* The unit of c->old that unit continues in an update, or -1 (built
 * afresh, or no update): old_unit is indexed from the range's first unit. */
static inline int32_t lie_ctx_old_unit(const build_ctx *c, uint64_t unit)
{
    return c->old_unit ? c->old_unit[unit - c->unit_lo] : -1;
}

/* Sort v[0..n) and drop repeats; returns the new length. */
size_t lie_sort_unique(uint32_t *v, size_t n);
/* Sort v[0..n) ascending. */
void lie_sort_u64(uint64_t *v, size_t n);

/* Count a partial list of n blockers in the list-length histogram. */
void lie_stats_hist_add(lie_build_stats *st, uint32_t n);
/* Add src's counts to dst's. */
void lie_stats_merge(lie_build_stats *dst, const lie_build_stats *src);
/* lie_env_update_views, with (memo = 1) or without the parallel
 * recomputation of flagged nodes before the build (lib/lie/memo.c), which
 * pays where the work sits in few units; lie_env_add_views's sits in many. */
lie_status lie_build_update(lie_env *env, const lie_scene *s, const lie_rt *rt, const lie_pixels *px,
                            const int32_t *old_unit, const uint8_t *node_flags, int threads, int memo,
                            lie_build_stats *stats, lie_error *err);
/* The nodes and pool entries of node `from` of env and its subtree (subdiv.c). */
void lie_subtree_size(const lie_env *env, uint32_t from, uint32_t *n_nodes, uint32_t *n_pool);
/* The same for a unit's tree from its root, which holds none when it is a
 * lone leaf (shared). */
void lie_unit_size(const lie_env *env, uint32_t root, uint32_t *n_nodes, uint32_t *n_pool);
/* Lay units out as a build does (lib/lie/lie.h, lie_pnode_lone): the units
 * of src[0] .. src[n_src - 1] in order (src[i] holds n_units[i] units, its
 * root, nodes and pool its own), each unit's tree depth first as built,
 * lists in node order, lone leaves shared; with `drop` (one flag per unit
 * of all the sources), a flagged unit becomes a lone none leaf.  Fills
 * dst's root, nodes, pool and their counts, and sets dst->partial if a
 * unit was dropped; *own (may be NULL) is the nodes the units own (not the
 * shared leaves).  LIE_ERR_LIMIT past 2^32 nodes. */
lie_status lie_env_lay_out(const lie_env *const *src, const uint64_t *n_units, size_t n_src, const uint8_t *drop,
                           lie_env *dst, uint64_t *own);
/* The error of a build that needs more than max-nodes nodes (build.c). */
/* What an env was built from: the scene's counts and hash, the parameters. */
void lie_env_describe(lie_env *env, const lie_scene *s, const lie_build_params *p);
/* The three arrays of an env's or a part's patch forest (root, nodes,
 * pool), released. */
void lie_forest_free(uint32_t *root, lie_pnode *nodes, uint32_t *pool);
lie_status lie_budget_error(lie_error *err, const lie_scene *s, const lie_build_params *p);

#endif
