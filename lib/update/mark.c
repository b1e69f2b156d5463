/* SPDX-License-Identifier: Apache-2.0 */
/* Phase 1 of an update (§5.3): which units continue, which nodes the
 * edits' boxes reach, and the work env those answers shape. */
#include "update/internal.h"

#include <stdlib.h>
#include <string.h>

lie_box3 *lie_update_node_boxes(const lie_scene *s)
{
    lie_box3 *b = malloc(sizeof *b * ((size_t)s->n_nodes + 1));
    if (!b)
        return NULL;
    for (int i = 0; i < s->n_nodes; i++)
        b[i] = lie_box3_empty();
    for (int i = 0; i < s->n_instances; i++) {
        const lie_instance *in = &s->instances[i];
        for (uint32_t t = in->first_tri; t < in->first_tri + in->n_tris; t++)
            if (!s->tri_removed[t])
                for (int k = 0; k < 3; k++)
                    lie_box3_grow(&b[in->node], s->tri_p[3 * (size_t)t + k]);
    }
    return b;
}

int lie_update_same_subtree(const lie_env *A, uint32_t a, const lie_env *B, uint32_t b)
{
    const lie_pnode *x = &A->nodes[a], *y = &B->nodes[b];
    if (x->cls != y->cls || x->count != y->count || x->quality != y->quality || !x->child != !y->child)
        return 0;
    if (x->cls == LIE_CLASS_PARTIAL && memcmp(A->pool + x->list, B->pool + y->list, sizeof(uint32_t) * x->count))
        return 0;
    if (x->child)
        for (uint32_t k = 0; k < 4; k++)
            if (!lie_update_same_subtree(A, x->child + k, B, y->child + k))
                return 0;
    return 1;
}

/* An emitter continues when the same, unmoved instance emits before and
 * after, split into the same clusters: its committed index, or -1.  Its
 * index may differ (another emitter appeared or went before it): nothing a
 * unit computes reads the index (lib/lie/sample.c). */
static int32_t emitter_before(const lie_cache *c, const lie_scene *s, int e, const uint8_t *moved)
{
    const lie_emitter *em = &s->emitters[e];
    int32_t o = -1;
    if (moved[em->node])
        return -1;
    uint32_t dig = lie_scene_cluster_digest(s, e);
    for (int k = 0; k < c->n_emitters; k++)
        if (c->emitters[k].type == (uint32_t)em->type && c->emitters[k].node == em->node &&
            c->emitters[k].first_tri == em->first_tri && c->emitters[k].n_tris == em->n_tris &&
            c->emitters[k].n_clusters == (uint32_t)em->n_clusters && c->emitters[k].partition == dig)
            o = k;
    return o;
}

/* Do the views hit triangle t at the same points before and after? */
static int same_pixels(const lie_pixels *a, const lie_pixels *b, uint32_t t)
{
    uint64_t n = a->first[t + 1] - a->first[t];
    return n == b->first[t + 1] - b->first[t] &&
           (n == 0 || memcmp(a->key + a->first[t], b->key + b->first[t], sizeof *a->key * (size_t)n) == 0);
}

/* old_unit: units whose patch or emitter moved, new units, and all units
 * when the smallest patch size changed, are built afresh (-1). */
static lie_status map_units(lie_update *u)
{
    const lie_scene *s = u->scene;
    const lie_cache *c = u->cache;
    size_t n_units = (size_t)s->n_tris * (size_t)s->n_clusters;
    uint8_t *moved = calloc((size_t)s->n_nodes + 1, 1);
    int32_t *emap = malloc(sizeof *emap * ((size_t)s->n_emitters + 1));
    int32_t *cmap = malloc(sizeof *cmap * ((size_t)s->n_clusters + 1));  /* committed cluster, or -1 */
    int32_t *ofirst = malloc(sizeof *ofirst * ((size_t)c->n_emitters + 1)); /* committed first clusters */
    u->old_unit = malloc(sizeof *u->old_unit * (n_units + 1));
    if (!moved || !emap || !cmap || !ofirst || !u->old_unit) {
        free(moved);
        free(emap);
        free(cmap);
        free(ofirst);
        return LIE_ERR_NOMEM;
    }
    for (int k = 0, f = 0; k < c->n_emitters; k++) {
        ofirst[k] = f;
        f += (int)c->emitters[k].n_clusters;
    }
    for (int k = 0; k < u->n_moved; k++)
        if (u->moved[k] >= 0 && u->moved[k] < s->n_nodes)
            moved[u->moved[k]] = 1;
    for (int e = 0; e < s->n_emitters; e++)
        emap[e] = emitter_before(c, s, e, moved);
    /* Scene-wide quantities a unit reads.  The shafts of a light at
     * infinity (no points hold it) reach lie_pair_ray_far, which the bounds
     * set: when it changes, so may all of that light's units.  The smallest
     * patch is a share of the largest triangle's area (--min-patch): when
     * that changes (or stops being a number), every unit may.  A cache
     * whose units were built by older rules (formats/lie-cache.md,
     * Versions) is rebuilt whole, as a rebuild would give other bytes. */
    const int far_changed = lie_pair_ray_far(s) != u->base_far;
    for (int k = 0; k < s->n_clusters; k++) {
        int e = s->clusters[k].emitter;
        const lie_vec3 *pts;
        int at_infinity = lie_emitter_extent(s, e, &pts) == 0;
        cmap[k] = emap[e] < 0 || (far_changed && at_infinity) ? -1 : ofirst[emap[e]] + (k - s->emitters[e].first_cluster);
    }
    const size_t old_nc = (size_t)u->cache->env->n_clusters;
    const lie_env *old_env = u->cache->env;
    /* A whole build's model (no views) reads the scene's surface, rounded to
     * a power of two (lie_whole_pixels): when that changes, every unit may */
    const int whole_model = !u->px && old_env->params.frames && old_env->params.whole_pixels;
    int everything = u->opt.full || !(s->max_tri_area == u->base_max_area) || lie_cache_rules_old(c) ||
                     (whole_model && lie_whole_area(s) != u->base_area);
    /* The cost model's decision to build a unit of a view-built cache (or
     * of a whole build's) reads every emitter's light at the triangle
     * (lie_unit_shares): when the light changed, a unit whose decision it
     * turned is built afresh (or left unbuilt), the others kept. */
    const double area = whole_model ? lie_whole_area(s) : 0.0;
    double *share = NULL;
    if ((u->px || whole_model) && !everything && old_env->params.frames &&
        lie_scene_light_digest(s) != u->base_light && !(share = malloc(sizeof *share * ((size_t)s->n_clusters + 1)))) {
        free(moved);
        free(emap);
        free(cmap);
        free(ofirst);
        return LIE_ERR_NOMEM;
    }
    const float far = lie_pair_ray_far(s);
    u->st.units_views = 0;
    for (uint32_t t = 0; t < s->n_tris; t++) {
        int patch_moved = t >= u->base_tris || moved[s->instances[s->tri_instance[t]].node];
        /* a view-built cache: a triangle whose pixels changed is decided anew */
        if (u->px && !patch_moved && !everything && !same_pixels(u->base_px, u->px, t)) {
            patch_moved = 1;
            u->st.units_views += (uint64_t)s->n_clusters;
        }
        int decide = share && !patch_moved && (!u->px || u->px->first[t + 1] > u->px->first[t]);
        double pixels = 0.0;
        if (decide) {
            pixels = u->px ? (double)lie_pixels_hits(u->px, t, lie_patch_root()) / (double)u->px->rays_per_pixel
                           : lie_whole_pixels(s, &old_env->params, area, t);
            lie_unit_shares(s, t, far, share);
        }
        for (int k = 0; k < s->n_clusters; k++) {
            size_t unit = (size_t)t * (size_t)s->n_clusters + (size_t)k;
            u->old_unit[unit] = everything || patch_moved || cmap[k] < 0
                                    ? -1
                                    : (int32_t)((size_t)t * old_nc + (size_t)cmap[k]);
            if (decide && u->old_unit[unit] >= 0) {
                int built = old_env->nodes[old_env->root[u->old_unit[unit]]].cls != LIE_CLASS_NONE;
                if (built != lie_unit_pays_pixels(&old_env->params, pixels, share[k])) {
                    u->old_unit[unit] = -1;
                    u->st.units_views++;
                }
            }
        }
    }
    free(share);
    free(moved);
    free(emap);
    free(cmap);
    free(ofirst);
    return LIE_OK;
}

/* flags: the trees' answers, tightened by each flagged root's exact hull
 * and carried down the patch trees while the hulls meet a box.  The hulls
 * are computed on the edited scene, which is right for every patch and
 * emitter that did not move (the others are rebuilt anyway) as long as
 * emitters kept their indices; otherwise a flagged root's whole subtree
 * goes along. */
static lie_status flag_nodes(lie_update *u)
{
    const lie_env *env = u->cache->env;
    const lie_scene *s = u->scene;
    const lie_cache *c = u->cache;
    u->flags = malloc((size_t)env->n_nodes + 1);
    if (!u->flags)
        return LIE_ERR_NOMEM;
    if (u->tree_flags)
        memcpy(u->flags, u->tree_flags, env->n_nodes);
    else
        memset(u->flags, 0, env->n_nodes);
    u->st.nodes_flagged_5d = 0;
    for (uint32_t i = 0; i < env->n_nodes; i++)
        u->st.nodes_flagged_5d += u->flags[i];
    int same_emitters = s->n_emitters == c->n_emitters;
    for (int e = 0; same_emitters && e < s->n_emitters; e++)
        same_emitters = c->emitters[e].node == s->emitters[e].node && c->emitters[e].first_tri == s->emitters[e].first_tri &&
                        c->emitters[e].n_clusters == (uint32_t)s->emitters[e].n_clusters &&
                        c->emitters[e].partition == lie_scene_cluster_digest(s, e);
    if (u->rst && same_emitters)
        lie_rst_refine(s, env, u->boxes, u->n_boxes, u->flags, u->opt.threads);
    else if (u->rst)
        lie_rst_spread(env, u->flags);
    u->st.nodes_flagged = 0;
    for (uint32_t i = 0; i < env->n_nodes; i++)
        u->st.nodes_flagged += u->flags[i];
    return LIE_OK;
}

void lie_update_subtree_size(const lie_env *env, uint32_t n, uint32_t *nodes, uint32_t *pool)
{
    const lie_pnode *x = &env->nodes[n];
    ++*nodes;
    if (x->cls == LIE_CLASS_PARTIAL && !x->child)
        *pool += x->count;
    for (uint32_t k = 0; x->child && k < 4; k++)
        lie_update_subtree_size(env, x->child + k, nodes, pool);
}

void lie_update_copy_subtree(const lie_env *env, const uint8_t *flags, uint32_t from, lie_env *w, uint8_t *wf,
                             uint32_t idx)
{
    lie_pnode x = env->nodes[from];
    wf[idx] = flags[from];
    if (x.child) {
        uint32_t first = w->n_nodes, oc = x.child;
        w->n_nodes += 4;
        x.child = first;
        w->nodes[idx] = x;
        for (uint32_t k = 0; k < 4; k++)
            lie_update_copy_subtree(env, flags, oc + k, w, wf, first + k);
        return;
    }
    if (x.cls == LIE_CLASS_PARTIAL) {
        memcpy(w->pool + w->n_pool, env->pool + x.list, sizeof *w->pool * x.count);
        x.list = w->n_pool;
        w->n_pool += x.count;
    }
    w->nodes[idx] = x;
}

/* The work env: per unit of the edited scene, in unit order and each
 * contiguous, the committed unit it continues or, for a unit to build
 * afresh, a none leaf; laid out as lib/lie lays out a build (lone leaves
 * shared after the other units' nodes: lib/lie/lie.h, lie_pnode_lone), so
 * that an update that recomputes nothing still gives a build's env. */
static lie_status make_work(lie_update *u)
{
    const lie_env *env = u->cache->env;
    const lie_scene *s = u->scene;
    size_t n_units = (size_t)s->n_tris * (size_t)s->n_clusters;
    uint64_t nodes = 0, pool = 0;
    int used_unlit = 0, used_none = 0;
    for (size_t k = 0; k < n_units; k++) {
        uint32_t a = 0, b = 0;
        const lie_pnode *r = u->old_unit[k] >= 0 ? &env->nodes[env->root[u->old_unit[k]]] : NULL;
        if (!r || lie_pnode_lone(r)) {
            used_unlit |= r && r->cls == LIE_CLASS_UNLIT;
            used_none |= !r || r->cls == LIE_CLASS_NONE;
            continue;
        }
        lie_update_subtree_size(env, env->root[u->old_unit[k]], &a, &b);
        nodes += a;
        pool += b;
    }
    const uint64_t own = nodes;
    nodes += (uint64_t)used_unlit + (uint64_t)used_none;
    if (nodes >= 0xFFFFFFF0u || pool >= 0xFFFFFFF0u)
        return LIE_ERR_LIMIT;
    lie_env *w = calloc(1, sizeof *w);
    u->work = w;
    u->pending = calloc(n_units + 1, 1);
    u->work_flags = calloc((size_t)nodes + 1, 1);
    if (!w || !u->pending || !u->work_flags)
        return LIE_ERR_NOMEM;
    *w = *env;
    w->n_tris = s->n_tris;
    w->n_clusters = s->n_clusters;
    w->root = malloc(sizeof *w->root * (n_units + 1));
    w->nodes = malloc(sizeof *w->nodes * ((size_t)nodes + 1));
    w->pool = malloc(sizeof *w->pool * ((size_t)pool + 1));
    w->n_nodes = w->n_pool = 0;
    if (!w->root || !w->nodes || !w->pool)
        return LIE_ERR_NOMEM;
    const uint32_t shared_unlit = (uint32_t)own, shared_none = (uint32_t)own + (uint32_t)used_unlit;
    u->n_pending = 0;
    for (size_t k = 0; k < n_units; k++) {
        const lie_pnode *r = u->old_unit[k] >= 0 ? &env->nodes[env->root[u->old_unit[k]]] : NULL;
        if (!r) {
            w->root[k] = shared_none;
            u->pending[k] = 2;
        } else if (lie_pnode_lone(r)) {
            /* unlit or unbuilt: shared, and if flagged built afresh (a lone
             * leaf recomputed is the unit built) */
            w->root[k] = r->cls == LIE_CLASS_UNLIT ? shared_unlit : shared_none;
            u->pending[k] = u->flags[env->root[u->old_unit[k]]] ? 2 : 0;
        } else {
            uint32_t idx = w->n_nodes++;
            w->root[k] = idx;
            uint32_t from = env->root[u->old_unit[k]];
            lie_update_copy_subtree(env, u->flags, from, w, u->work_flags, idx);
            u->pending[k] = u->flags[from];
        }
        u->n_pending += u->pending[k] != 0;
    }
    if (used_unlit) {
        memset(&w->nodes[shared_unlit], 0, sizeof w->nodes[shared_unlit]);
        w->nodes[shared_unlit].cls = LIE_CLASS_UNLIT;
    }
    if (used_none) {
        memset(&w->nodes[shared_none], 0, sizeof w->nodes[shared_none]);
        w->nodes[shared_none].cls = LIE_CLASS_NONE;
    }
    w->n_nodes = (uint32_t)nodes;
    return LIE_OK;
}

void lie_update_drop_answers(lie_update *u)
{
    free(u->old_unit);
    free(u->flags);
    free(u->work_flags);
    free(u->pending);
    lie_pixels_destroy(u->px);
    u->px = NULL;
    lie_env_destroy(u->work);
    u->old_unit = NULL;
    u->flags = u->work_flags = u->pending = NULL;
    u->work = NULL;
    u->n_pending = 0;
}

lie_status lie_update_mark(lie_update *u, lie_error *err)
{
    double t0 = lie_time_now();
    lie_update_drop_answers(u);
    lie_status st = LIE_OK;
    if (u->cache->views.n_cams) {
        /* the views' pixels on the edited scene (Embree's, kept for the steps) */
        lie_rt_destroy(u->rt);
        u->rt = NULL;
        if ((st = lie_update_view_pixels(u, &u->px, err)) != LIE_OK)
            return st;
    }
    st = map_units(u);
    if (st == LIE_OK)
        st = flag_nodes(u);
    if (st == LIE_OK)
        st = make_work(u);
    if (st != LIE_OK)
        return lie_error_set(err, st, u->scene->path, "marking the units to update: %s", lie_status_str(st));
    const lie_scene *s = u->scene;
    size_t n_units = (size_t)s->n_tris * (size_t)s->n_clusters;
    u->st.units = n_units;
    u->st.units_rebuilt = u->st.units_flagged = 0;
    for (size_t k = 0; k < n_units; k++) {
        u->st.units_rebuilt += u->pending[k] == 2;
        u->st.units_flagged += u->pending[k] == 1;
    }
    u->st.units_pending = u->n_pending;
    u->st.seconds_query += lie_time_now() - t0;
    return LIE_OK;
}
