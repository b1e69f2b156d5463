/* SPDX-License-Identifier: Apache-2.0 */
/* Updating local illumination environments after edits (§5): the update's
 * life — create, edits (phase 1, mark.c), steps (phase 2), commit. */
#include "update/internal.h"
#include "shade/shade.h"

#include <stdlib.h>
#include <string.h>

lie_update_options lie_update_options_default(void)
{
    lie_update_options o;
    memset(&o, 0, sizeof o);
    o.scene = lie_scene_options_default();
    return o;
}

static lie_status unusable(const lie_update *u, lie_error *err)
{
    return lie_error_set(err, LIE_ERR_ARG, u->scene->path, "this update failed earlier and cannot go on");
}

static lie_status nomem(lie_update *u, lie_error *err)
{
    u->failed = 1;
    return lie_error_set(err, LIE_ERR_NOMEM, u->scene->path, "out of memory");
}

static lie_status build_trees(lie_update *u, lie_error *err)
{
    double t0 = lie_time_now();
    lie_rst_destroy(u->rst);
    u->rst = NULL;
    memset(&u->rst_stats, 0, sizeof u->rst_stats);
    lie_status st = lie_rst_build(u->scene, u->cache->env, u->opt.threads, &u->rst, &u->rst_stats, err);
    u->rst_stale = 0;
    u->rst_seconds = lie_time_now() - t0;
    return st;
}

lie_status lie_update_create(lie_cache *cache, lie_scene *scene, const lie_update_options *opt, lie_update **out,
                             lie_error *err)
{
    *out = NULL;
    if (!cache->env || cache->env->n_tris != scene->n_tris || cache->env->n_clusters != scene->n_clusters ||
        cache->n_emitters != scene->n_emitters || cache->state_hash != scene->hash)
        return lie_error_set(err, LIE_ERR_ARG, scene->path, "the scene is not the state the cache was built for");
    lie_update *u = calloc(1, sizeof *u);
    if (!u)
        return lie_error_set(err, LIE_ERR_NOMEM, scene->path, "out of memory");
    u->cache = cache;
    u->scene = scene;
    u->opt = opt ? *opt : lie_update_options_default();
    u->base_tris = scene->n_tris;
    u->base_max_area = scene->max_tri_area;
    u->base_area = lie_whole_area(scene);
    u->base_far = lie_pair_ray_far(scene);
    u->base_light = lie_scene_light_digest(scene);
    if (!u->opt.full && build_trees(u, err) != LIE_OK) {
        lie_update_destroy(u);
        return err->status;
    }
    *out = u;
    return LIE_OK;
}

/* Forget the edits since the commit and their answers. */
static void drop_edits(lie_update *u)
{
    for (int i = 0; i < u->n_log; i++) {
        free(u->log[i].name);
        free(u->log[i].text);
    }
    free(u->log);
    free(u->boxes);
    free(u->moved);
    free(u->tree_flags);
    lie_update_drop_answers(u);
    u->log = NULL;
    u->boxes = NULL;
    u->moved = NULL;
    u->tree_flags = NULL;
    u->n_log = u->n_boxes = u->n_moved = 0;
    u->cap_boxes = u->cap_moved = 0;
    u->dirty = 0;
}

void lie_update_destroy(lie_update *u)
{
    if (!u)
        return;
    drop_edits(u);
    lie_rst_destroy(u->rst);
    lie_rt_destroy(u->rt);
    lie_pixels_destroy(u->base_px);
    lie_pixels_destroy(u->px);
    free(u);
}

static int push_box(lie_update *u, lie_box3 b)
{
    if (!LIE_GROW(u->boxes, u->cap_boxes, (size_t)u->n_boxes + 1))
        return 0;
    u->boxes[u->n_boxes++] = b;
    return 1;
}

static int push_moved(lie_update *u, int node)
{
    if (!LIE_GROW(u->moved, u->cap_moved, (size_t)u->n_moved + 1))
        return 0;
    u->moved[u->n_moved++] = node;
    return 1;
}

/* The edit log's entry: the file's text as it was, or a built edit's
 * written form (lie_edit_text). */
static int push_log(lie_update *u, const lie_edit *edit)
{
    lie_cache_edit *nl = realloc(u->log, sizeof *nl * ((size_t)u->n_log + 1));
    if (!nl)
        return 0;
    u->log = nl;
    lie_cache_edit *le = &u->log[u->n_log];
    lie_error e;
    le->name = strdup(edit->name);
    if (!le->name || lie_edit_text(edit, &le->text, &le->size, &e) != LIE_OK) {
        free(le->name);
        return 0;
    }
    u->n_log++;
    return 1;
}

/* Apply the edit, keeping every edited node's bounds before and after. */
static lie_status apply_edit(lie_update *u, const lie_edit *edit, lie_error *err)
{
    lie_scene *s = u->scene;
    lie_box3 *before = lie_update_node_boxes(s), *after = NULL;
    int n_before = s->n_nodes;
    lie_edit_effect fx;
    memset(&fx, 0, sizeof fx);
    lie_status st = before ? lie_edit_apply(s, edit, &u->opt.scene, &fx, err) : LIE_ERR_NOMEM;
    if (st == LIE_OK && !(after = lie_update_node_boxes(s)))
        st = LIE_ERR_NOMEM;
    for (int k = 0; st == LIE_OK && k < fx.n_nodes; k++) {
        int nd = fx.nodes[k];
        if (nd < s->n_nodes && !lie_box3_is_empty(&after[nd]) && !push_box(u, after[nd]))
            st = LIE_ERR_NOMEM;
        if (nd < n_before && !lie_box3_is_empty(&before[nd]) && !push_box(u, before[nd]))
            st = LIE_ERR_NOMEM;
    }
    for (int k = 0; st == LIE_OK && k < fx.n_nodes; k++)
        if (!push_moved(u, fx.nodes[k]))
            st = LIE_ERR_NOMEM;
    lie_edit_effect_free(&fx);
    free(before);
    free(after);
    if (st == LIE_ERR_NOMEM)
        lie_error_set(err, st, edit->name, "out of memory");
    return st;
}

lie_status lie_update_edit(lie_update *u, const lie_edit *edit, lie_error *err)
{
    if (u->failed)
        return unusable(u, err);
    if (!u->dirty) {
        /* the first edit after a commit: answers refer to the new state */
        memset(&u->st, 0, sizeof u->st);
        if (!u->opt.full && (u->rst_stale || !u->rst) && build_trees(u, err) != LIE_OK) {
            u->failed = 1;
            return err->status;
        }
        u->st.rst = u->rst_stats;
        u->st.seconds_rst = u->rst_seconds;
        u->tree_flags = u->rst ? calloc((size_t)u->cache->env->n_nodes + 1, 1) : NULL;
        if (u->rst && !u->tree_flags)
            return nomem(u, err);
        /* a cache built for views: where their pixels fall before the edits */
        lie_pixels_destroy(u->base_px);
        u->base_px = NULL;
        if (u->cache->views.n_cams && lie_update_view_pixels(u, &u->base_px, err) != LIE_OK) {
            u->failed = 1;
            return err->status;
        }
    }
    u->dirty = 1;
    lie_rt_destroy(u->rt); /* Embree's view of the scene is about to go stale */
    u->rt = NULL;
    double t0 = lie_time_now();
    int first_box = u->n_boxes;
    if (apply_edit(u, edit, err) != LIE_OK || !push_log(u, edit)) {
        u->failed = 1;
        if (!err->status)
            lie_error_set(err, LIE_ERR_NOMEM, edit->name, "out of memory");
        return err->status;
    }
    u->st.edits++;
    u->st.seconds_edit += lie_time_now() - t0;
    t0 = lie_time_now();
    for (int i = first_box; u->rst && i < u->n_boxes; i++)
        lie_rst_query(u->rst, u->boxes[i], u->tree_flags);
    u->st.seconds_query += lie_time_now() - t0;
    if (lie_update_mark(u, err) != LIE_OK) {
        u->failed = 1;
        return err->status;
    }
    return LIE_OK;
}

size_t lie_update_pending(const lie_update *u) { return u->n_pending; }

lie_status lie_update_view_pixels(lie_update *u, lie_pixels **out, lie_error *err)
{
    const lie_cache_views *v = &u->cache->views;
    double t0 = lie_time_now();
    if (!u->rt && lie_rt_create(u->scene, &u->rt, err) != LIE_OK)
        return err->status;
    u->st.seconds_bvh += lie_time_now() - t0;
    t0 = lie_time_now();
    lie_status st = lie_camera_pixels(u->scene, u->rt, v->cams, v->n_cams, v->width, v->height, v->max_depth, out, err);
    u->st.seconds_views += lie_time_now() - t0;
    return st;
}

/* The edits are done: the cache takes the new environments and state. */
static lie_status commit(lie_update *u, lie_error *err)
{
    const lie_scene *s = u->scene;
    lie_cache *c = u->cache;
    lie_env *w = u->work;
    size_t n_units = (size_t)s->n_tris * (size_t)s->n_clusters;
    u->st.units_changed = 0;
    for (size_t k = 0; k < n_units; k++) {
        if (u->old_unit[k] < 0)
            continue;
        uint32_t r = c->env->root[u->old_unit[k]];
        if (u->flags[r])
            u->st.units_changed += !lie_update_same_subtree(c->env, r, w, w->root[k]);
    }
    lie_cache_edit *log = realloc(c->edits, sizeof *log * ((size_t)c->n_edits + (size_t)u->n_log + 1));
    if (!log)
        return nomem(u, err);
    c->edits = log;
    if (lie_cache_set_state(c, s, err) != LIE_OK) {
        u->failed = 1;
        return err->status;
    }
    memcpy(c->edits + c->n_edits, u->log, sizeof *log * (size_t)u->n_log);
    c->n_edits += u->n_log;
    u->n_log = 0;
    w->scene_hash = s->hash;
    c->version = 0; /* every unit now follows this library's rules */
    lie_env_destroy(c->env);
    c->env = w;
    u->work = NULL;
    drop_edits(u);
    u->base_tris = s->n_tris;
    u->base_max_area = s->max_tri_area;
    u->base_area = lie_whole_area(s);
    u->base_far = lie_pair_ray_far(s);
    u->base_light = lie_scene_light_digest(s);
    u->rst_stale = 1;
    if (u->opt.keep_trees && !u->opt.full)
        return build_trees(u, err) == LIE_OK ? LIE_OK : (u->failed = 1, err->status);
    return LIE_OK;
}

/* The nodes of a unit's tree from root r: contiguous from r in an env
 * lib/lie lays out (a lone leaf, shared, is never pending). */
static uint32_t tree_nodes(const lie_env *env, uint32_t r)
{
    uint32_t n = 1;
    for (uint32_t k = 0; env->nodes[r].child && k < 4; k++)
        n += tree_nodes(env, env->nodes[r].child + k);
    return n;
}

/* Recompute the chosen pending units of the work env in place (the others
 * are copied as they are), then carry the flags of the units still
 * pending over to the new layout. */
static lie_status recompute(lie_update *u, const uint8_t *chosen, lie_error *err)
{
    lie_env *w = u->work;
    const lie_scene *s = u->scene;
    size_t n_units = (size_t)s->n_tris * (size_t)s->n_clusters;
    int32_t *old_unit = malloc(sizeof *old_unit * (n_units + 1));
    uint8_t *flags = malloc((size_t)w->n_nodes + 1);
    uint32_t *root = malloc(sizeof *root * (n_units + 1));
    if (!old_unit || !flags || !root) {
        free(old_unit);
        free(flags);
        free(root);
        return nomem(u, err);
    }
    memcpy(root, w->root, sizeof *root * n_units);
    memcpy(flags, u->work_flags, w->n_nodes);
    for (size_t k = 0; k < n_units; k++) {
        old_unit[k] = chosen[k] && u->pending[k] == 2 ? -1 : (int32_t)k;
        if (!chosen[k] && u->pending[k] == 1)
            memset(flags + root[k], 0, tree_nodes(w, root[k]));
    }
    lie_build_stats bst;
    lie_status st = lie_env_update_views(w, s, u->rt, u->px, old_unit, flags, u->opt.threads, &bst, err);
    free(old_unit);
    free(flags);
    if (st != LIE_OK) {
        free(root);
        u->failed = 1;
        return st;
    }
    for (int d = 0; d <= LIE_PATCH_MAX_DEPTH; d++)
        u->st.nodes_recomputed += bst.patches_per_depth[d];
    u->st.seconds_cpu_workers += bst.seconds_cpu_sum;
    u->st.seconds_cpu_worker_max += bst.seconds_cpu_max;
    u->st.seconds_tail += bst.seconds_tail;
    /* units are contiguous in unit order, in the work env as in any env
     * lib/lie assembles; an unchosen unit keeps its layout */
    uint8_t *nf = calloc((size_t)w->n_nodes + 1, 1);
    if (!nf) {
        free(root);
        return nomem(u, err);
    }
    for (size_t k = 0; k < n_units; k++) {
        if (chosen[k]) {
            u->pending[k] = 0;
            continue;
        }
        if (u->pending[k] == 1) /* copied as it was: the same tree */
            memcpy(nf + w->root[k], u->work_flags + root[k], tree_nodes(w, w->root[k]));
    }
    free(root);
    free(u->work_flags);
    u->work_flags = nf;
    return LIE_OK;
}

lie_status lie_update_step(lie_update *u, size_t max_units, size_t *remaining, lie_error *err)
{
    if (remaining)
        *remaining = u->n_pending;
    if (u->failed)
        return unusable(u, err);
    if (!u->dirty)
        return LIE_OK;
    double t0 = lie_time_now();
    if (u->n_pending && !u->rt) {
        if (lie_rt_create(u->scene, &u->rt, err) != LIE_OK) {
            u->failed = 1;
            return err->status;
        }
        u->st.seconds_bvh += lie_time_now() - t0;
        t0 = lie_time_now();
    }
    if (u->n_pending) {
        size_t n_units = (size_t)u->scene->n_tris * (size_t)u->scene->n_clusters;
        uint8_t *chosen = calloc(n_units + 1, 1);
        if (!chosen)
            return nomem(u, err);
        size_t n = 0;
        for (size_t k = 0; k < n_units && (max_units == 0 || n < max_units); k++)
            if (u->pending[k]) {
                chosen[k] = 1;
                n++;
            }
        lie_status st = recompute(u, chosen, err);
        free(chosen);
        if (st != LIE_OK)
            return st;
        u->n_pending -= n;
        u->st.units_pending = u->n_pending;
        u->st.seconds_update += lie_time_now() - t0;
    }
    if (remaining)
        *remaining = u->n_pending;
    return u->n_pending ? LIE_OK : commit(u, err);
}

lie_status lie_update_snapshot(const lie_update *u, lie_env **out, lie_error *err)
{
    *out = NULL;
    const lie_env *e = u->work ? u->work : u->cache->env;
    lie_env *c = calloc(1, sizeof *c);
    if (!c)
        return lie_error_set(err, LIE_ERR_NOMEM, u->scene->path, "out of memory");
    *c = *e;
    size_t units = (size_t)e->n_tris * (size_t)e->n_clusters;
    c->root = malloc(sizeof *c->root * (units + 1));
    c->nodes = malloc(sizeof *c->nodes * ((size_t)e->n_nodes + 1));
    c->pool = malloc(sizeof *c->pool * ((size_t)e->n_pool + 1));
    if (!c->root || !c->nodes || !c->pool) {
        lie_env_destroy(c);
        return lie_error_set(err, LIE_ERR_NOMEM, u->scene->path, "out of memory");
    }
    memcpy(c->root, e->root, sizeof *c->root * units);
    memcpy(c->nodes, e->nodes, sizeof *c->nodes * e->n_nodes);
    memcpy(c->pool, e->pool, sizeof *c->pool * e->n_pool);
    if (u->work) {
        /* a flagged leaf is not known yet: the renderer asks Embree */
        for (uint32_t i = 0; i < c->n_nodes; i++)
            if (u->work_flags[i] && !c->nodes[i].child) {
                memset(&c->nodes[i], 0, sizeof c->nodes[i]);
                c->nodes[i].cls = LIE_CLASS_NONE;
            }
        c->scene_hash = u->scene->hash;
    }
    *out = c;
    return LIE_OK;
}

void lie_update_get_stats(const lie_update *u, lie_update_stats *stats) { *stats = u->st; }

lie_status lie_update_apply(lie_cache *cache, lie_scene *scene, const lie_edit *const *edits, int n_edits,
                            const lie_update_options *opt, lie_update_stats *stats, lie_error *err)
{
    lie_update *u = NULL;
    lie_status st = lie_update_create(cache, scene, opt, &u, err);
    for (int i = 0; st == LIE_OK && i < n_edits; i++)
        st = lie_update_edit(u, edits[i], err);
    if (st == LIE_OK)
        st = lie_update_step(u, 0, NULL, err);
    if (u && stats)
        lie_update_get_stats(u, stats);
    lie_update_destroy(u);
    return st;
}
