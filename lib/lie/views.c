/* SPDX-License-Identifier: Apache-2.0 */
/* Adding views to an env built for views (lie-build --into): the units the
 * new pixels need are built or refined, every other unit is kept as it is,
 * and the result is the env one build for all the views gives
 * (lib/lie/lie.h, lie_env_add_views). */
#include "lie/internal.h"
#include "lie/subdiv.h"

#include <stdlib.h>
#include <string.h>

/* Every old hit is a new hit: the new views include the old ones. */
static int includes(const lie_pixels *old_px, const lie_pixels *new_px, uint32_t tri)
{
    uint64_t i = old_px->first[tri], j = new_px->first[tri];
    for (; i < old_px->first[tri + 1]; i++, j++) {
        while (j < new_px->first[tri + 1] && new_px->key[j] < old_px->key[i])
            j++;
        if (j == new_px->first[tri + 1] || new_px->key[j] != old_px->key[i])
            return 0;
    }
    return 1;
}

/* Flag the leaves of node idx (patch path of unit (tri, e)) whose
 * decision more pixels may change, and their ancestors; returns whether
 * any node below idx is flagged.  Only the pixel test of a split depends
 * on pixels (lib/lie/subdiv.c, lie_subdiv_pixels_pay), and it only turns from "no"
 * to "yes" as pixels grow: so only a leaf that test kept from splitting
 * can change.  Such a leaf was a partial pair with a list longer than
 * max_blockers, large enough to split; it was stored as partial with its
 * exact list (longer than max_blockers), or as complex.  Its pixels must
 * have grown, too. */
static int flag_node(const lie_env *env, const lie_scene *s, const lie_pixels *old_px, const lie_pixels *new_px,
                     uint32_t idx, uint32_t tri, lie_patch_path path, uint8_t *flags)
{
    const lie_pnode *x = &env->nodes[idx];
    if (lie_pixels_hits(old_px, tri, path) == lie_pixels_hits(new_px, tri, path))
        return 0;
    int any = 0;
    if (x->child) {
        for (int k = 0; k < 4; k++)
            any |= flag_node(env, s, old_px, new_px, x->child + (uint32_t)k, tri, lie_patch_child(path, k), flags);
    } else {
        const lie_build_params *p = &env->params;
        float area = s->tri_area[tri] / (float)(1u << (2 * (path.depth < 15 ? path.depth : 15)));
        int may_split = area > p->min_patch * s->max_tri_area && path.depth < LIE_PATCH_MAX_DEPTH;
        any = may_split && (x->cls == LIE_CLASS_COMPLEX || (x->cls == LIE_CLASS_PARTIAL && x->count > p->max_blockers));
    }
    if (any && flags)
        flags[idx] = 1;
    return any;
}

int lie_env_tri_stale(const lie_env *env, const lie_scene *s, const lie_pixels *old_px, const lie_pixels *new_px,
                      uint32_t tri)
{
    if (lie_pixels_tri_hash(old_px, tri) == lie_pixels_tri_hash(new_px, tri))
        return 0;
    if (old_px->first[tri + 1] == old_px->first[tri])
        return 1; /* not seen before: built now */
    double *share = malloc(sizeof *share * ((size_t)env->n_clusters + 1));
    if (!share)
        return 1; /* decided anew: the rebuild gives the same units */
    lie_unit_shares(s, tri, lie_pair_ray_far(s), share);
    for (int e = 0; e < env->n_clusters; e++) {
        uint32_t root = env->root[(size_t)tri * (size_t)env->n_clusters + (size_t)e];
        if (env->nodes[root].cls == LIE_CLASS_NONE) {
            if (lie_unit_pays(&env->params, new_px, tri, share[e])) {
                free(share);
                return 1;
            }
        } else if (env->params.frames && flag_node(env, s, old_px, new_px, root, tri, lie_patch_root(), NULL)) {
            free(share);
            return 1;
        }
    }
    free(share);
    return 0;
}

lie_status lie_env_add_views(lie_env *env, const lie_scene *s, const lie_rt *rt, const lie_pixels *old_px,
                             const lie_pixels *new_px, int threads, lie_build_stats *stats, lie_add_stats *as,
                             lie_error *err)
{
    memset(as, 0, sizeof *as);
    if (env->n_tris != s->n_tris || env->n_clusters != s->n_clusters || old_px->n_tris != s->n_tris ||
        new_px->n_tris != s->n_tris || env->scene_hash != s->hash)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "the env, the pixels and the scene do not match");
    size_t ne = (size_t)s->n_clusters, n_units = (size_t)s->n_tris * ne;
    int32_t *old_unit = malloc(sizeof *old_unit * (n_units + 1));
    uint8_t *flags = calloc((size_t)env->n_nodes + 1, 1);
    double *share = malloc(sizeof *share * (ne + 1));
    float far = lie_pair_ray_far(s);
    if (!old_unit || !flags || !share) {
        free(old_unit);
        free(flags);
        free(share);
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    }
    lie_status st = LIE_OK;
    for (uint32_t t = 0; t < s->n_tris && st == LIE_OK; t++) {
        int seen_before = old_px->first[t + 1] > old_px->first[t];
        if (seen_before)
            lie_unit_shares(s, t, far, share);
        if (!includes(old_px, new_px, t))
            st = lie_error_set(err, LIE_ERR_ARG, s->path, "triangle %u: the new views lose pixels of the old", t);
        for (size_t e = 0; e < ne; e++) {
            size_t u = (size_t)t * ne + e;
            old_unit[u] = (int32_t)u;
            int unpaid = seen_before && env->nodes[env->root[u]].cls == LIE_CLASS_NONE &&
                         lie_unit_pays(&env->params, new_px, t, share[e]);
            if ((!seen_before && new_px->first[t + 1] > new_px->first[t]) || unpaid) {
                old_unit[u] = -1; /* not built before (not seen, or too few pixels to pay): built now */
                as->units_new++;
            } else if (seen_before && env->params.frames &&
                       flag_node(env, s, old_px, new_px, env->root[u], t, lie_patch_root(), flags)) {
                as->units_refined++;
            } else {
                as->units_kept++;
            }
        }
    }
    for (uint32_t i = 0; i < env->n_nodes; i++)
        as->nodes_flagged += flags[i];
    if (st == LIE_OK)
        st = lie_build_update(env, s, rt, new_px, old_unit, flags, threads, 0, stats, err);
    /* an interrupted env's unbuilt units were among those built (the seen
     * ones that pay): the result is whole */
    if (st == LIE_OK)
        env->partial = 0;
    free(old_unit);
    free(flags);
    free(share);
    return st;
}
