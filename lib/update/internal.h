/* SPDX-License-Identifier: Apache-2.0 */
/* lib/update's private state, shared by its files (see update.h). */
#ifndef LIE_UPDATE_INTERNAL_H
#define LIE_UPDATE_INTERNAL_H

#include "update/update.h"

struct lie_update {
    lie_cache *cache;         /* borrowed: cache->env is the committed state */
    lie_scene *scene;         /* borrowed: edited by lie_update_edit */
    lie_update_options opt;
    int failed;

    /* The committed state, which the trees and the flags refer to. */
    lie_rst *rst;             /* NULL with opt.full */
    int rst_stale;            /* committed since the trees were built */
    lie_rst_stats rst_stats;  /* of the trees' build */
    double rst_seconds;
    uint32_t base_tris;
    float base_max_area;
    double base_area;         /* lie_whole_area of the committed scene */
    float base_far;           /* lie_pair_ray_far of the committed scene */
    uint64_t base_light;      /* lie_scene_light_digest of the committed scene */
    lie_pixels *base_px;      /* a cache built for views: their pixels on the committed scene */

    /* Edits since the last commit. */
    int dirty;
    lie_box3 *boxes;          /* every edited node's bounds, before and after */
    int n_boxes;
    size_t cap_boxes;
    int *moved;               /* nodes whose transform, geometry or presence changed */
    int n_moved;
    size_t cap_moved;
    lie_cache_edit *log;      /* the edit files, for the cache's edit log */
    int n_log;
    uint8_t *tree_flags;      /* per committed node: flagged by the trees (queries accumulate) */

    /* Phase 1's answer for all of them. */
    int32_t *old_unit;        /* per unit of the edited scene: the committed unit it continues, or -1 */
    uint8_t *flags;           /* per committed node: recompute (tree flags tightened by exact hulls) */

    /* Phase 2. */
    lie_env *work;            /* shaped for the edited scene: committed content, steps' results */
    uint8_t *work_flags;      /* per work node: still to recompute */
    uint8_t *pending;         /* per unit: 1 = recompute flagged nodes, 2 = build afresh, 0 = done */
    size_t n_pending;
    lie_rt *rt;               /* Embree over the edited scene, made by the first step (or by
                                 phase 1, for the views' pixels) */
    lie_pixels *px;           /* a cache built for views: their pixels on the edited scene */

    lie_update_stats st;
};

/* Phase 1 (mark.c): after the edits since the commit, compute old_unit,
 * flags, work, work_flags and pending. */
lie_status lie_update_mark(lie_update *u, lie_error *err);
/* The cache's views' pixels on the scene as it is now (making u->rt for
 * it when there is none). */
lie_status lie_update_view_pixels(lie_update *u, lie_pixels **out, lie_error *err);
/* Free phase 1's answers and the work env (pending work is dropped). */
void lie_update_drop_answers(lie_update *u);

/* World bounds of every glTF node's own triangles (empty boxes for none);
 * the caller frees. */
lie_box3 *lie_update_node_boxes(const lie_scene *s);

/* The nodes and pool entries of node n of env and its subtree. */
void lie_update_subtree_size(const lie_env *env, uint32_t n, uint32_t *nodes, uint32_t *pool);
/* Copy node `from` of env and its subtree to node idx of w (w->n_nodes and
 * w->n_pool are where its children and lists go, w's arrays large enough:
 * lie_update_subtree_size), in the order lib/lie's assembly lays a unit out
 * (children appended as their parent is visited, depth first), and each
 * node's flag from flags to wf. */
void lie_update_copy_subtree(const lie_env *env, const uint8_t *flags, uint32_t from, lie_env *w, uint8_t *wf,
                             uint32_t idx);

/* Are the subtrees at node a of A and node b of B identical? */
int lie_update_same_subtree(const lie_env *A, uint32_t a, const lie_env *B, uint32_t b);

#endif
