/* SPDX-License-Identifier: Apache-2.0 */
/* The viewer's world: the scene, its cache, the ray tracer, and the edits
 * made in the session, with the asynchronous constructor of §4.3.1.
 *
 * An edit goes through lib/update at once (§5, phase 1): the scene
 * changes and the units the ray segment trees flag become pending.  The
 * renderer draws from the update's snapshot, in which pending pairs are
 * LIE_CLASS_NONE and so answered by Embree over the whole scene: no frame
 * is ever stale.  The constructor thread recomputes pending units a step at
 * a time (phase 2) and publishes a new snapshot after each step, after
 * which those units are fast again (update.c). */
#include "world_internal.h"

#include <stdlib.h>
#include <string.h>

/* ---- the oracle ------------------------------------------------------ */

lie_status world_make_oracle(view_world *w, lie_error *err)
{
    lie_env_shadows_destroy(w->vis);
    w->vis = NULL;
    if (w->ctor) { /* the live env: landings change it in place (lie_ctor_read_lock) */
        lie_status st = lie_env_shadows_create(w->scene, lie_ctor_env(w->ctor), &w->vis, err);
        if (st == LIE_OK)
            lie_env_shadows_grow(w->vis, lie_ctor_longest(w->ctor));
        return st;
    }
    if (!w->render_env)
        return LIE_OK;
    return lie_env_shadows_create(w->scene, w->render_env, &w->vis, err);
}

/* ---- reading ---------------------------------------------------------- */

void view_world_read_lock(view_world *w)
{
    pthread_rwlock_rdlock(&w->lock);
    if (w->ctor)
        lie_ctor_read_lock(w->ctor);
}
void view_world_read_unlock(view_world *w)
{
    if (w->ctor)
        lie_ctor_read_unlock(w->ctor);
    pthread_rwlock_unlock(&w->lock);
}
void view_world_sync_oracle(view_world *w)
{
    if (w->ctor && w->vis)
        lie_env_shadows_grow(w->vis, lie_ctor_longest(w->ctor));
}
uint64_t view_world_units_version(const view_world *w) { return w->ctor ? lie_ctor_version(w->ctor) : 0; }
void view_world_hold(view_world *w)
{
    if (w->ctor) {
        lie_ctor_hold(w->ctor);
        return;
    }
    /* lib/update's steps: the one running ends (it publishes), no other starts */
    pthread_mutex_lock(&w->cm);
    w->held++;
    while (w->stepping)
        pthread_cond_wait(&w->ccv, &w->cm);
    pthread_mutex_unlock(&w->cm);
}
void view_world_release(view_world *w)
{
    if (w->ctor) {
        lie_ctor_release(w->ctor);
        return;
    }
    pthread_mutex_lock(&w->cm);
    if (w->held > 0)
        w->held--;
    pthread_cond_broadcast(&w->ccv);
    pthread_mutex_unlock(&w->cm);
}
void view_world_look(view_world *w, const lie_camera *cam)
{
    if (w->ctor)
        lie_ctor_view(w->ctor, cam);
}
lie_ctor *view_world_ctor(const view_world *w) { return w->ctor; }
const lie_scene *view_world_scene(const view_world *w) { return w->scene; }
const lie_rt *view_world_rt(const view_world *w) { return w->rt; }
const lie_vis_oracle *view_world_oracle(const view_world *w) { return w->vis ? lie_env_shadows_oracle(w->vis) : NULL; }
uint64_t view_world_version(const view_world *w) { return atomic_load(&((view_world *)w)->version); }
int64_t view_world_pending(const view_world *w)
{
    if (w->ctor) {
        lie_ctor_stats cs;
        lie_ctor_get_stats(w->ctor, &cs);
        return (int64_t)cs.units_pending + cs.sampling;
    }
    return atomic_load(&((view_world *)w)->n_pending);
}
uint64_t view_world_units_built(const view_world *w)
{
    if (!w->ctor)
        return 0;
    lie_ctor_stats cs;
    lie_ctor_get_stats(w->ctor, &cs);
    return cs.units_built;
}
int view_world_busy(const view_world *w)
{
    view_world *m = (view_world *)w;
    if (m->ctor)
        return !m->failed && lie_ctor_wait(m->ctor, 0.0, NULL) == 0;
    return !m->failed && (atomic_load(&m->n_pending) > 0 || atomic_load(&m->dirty));
}
int64_t view_world_pending_max(const view_world *w) { return w->pending_max; }
double view_world_last_update_ms(const view_world *w) { return w->last_ms; }
int view_world_has_cache(const view_world *w) { return w->cache != NULL; }

const double *view_world_update_ms(const view_world *w, int *n)
{
    *n = w->n_update_ms;
    return w->update_ms;
}

/* ---- nodes ------------------------------------------------------------ */

void view_node_subtree(const lie_scene *s, int node, uint8_t *in)
{
    memset(in, 0, (size_t)s->n_nodes);
    if (node < 0 || node >= s->n_nodes)
        return;
    /* a node is in the subtree when one of its ancestors is `node` */
    for (int i = 0; i < s->n_nodes; i++)
        for (int a = i, guard = 0; a >= 0 && guard <= s->n_nodes; a = s->nodes[a].parent, guard++)
            if (a == node) {
                in[i] = 1;
                break;
            }
}

lie_box3 view_node_bounds(const lie_scene *s, int node)
{
    lie_box3 b = lie_box3_empty();
    uint8_t *in = calloc((size_t)s->n_nodes + 1, 1);
    if (!in)
        return b;
    view_node_subtree(s, node, in);
    for (int i = 0; i < s->n_instances; i++) {
        const lie_instance *ins = &s->instances[i];
        if (!in[ins->node])
            continue;
        for (uint32_t t = ins->first_tri; t < ins->first_tri + ins->n_tris; t++)
            if (!s->tri_removed[t])
                for (int k = 0; k < 3; k++)
                    lie_box3_grow(&b, s->tri_p[3 * (size_t)t + k]);
    }
    free(in);
    return b;
}

const char *view_node_name(const lie_scene *s, int node, char *buf, size_t size)
{
    if (node < 0 || node >= s->n_nodes)
        snprintf(buf, size, "-");
    else if (s->nodes[node].name && *s->nodes[node].name)
        lie_escape_controls(buf, size, s->nodes[node].name); /* from the file: shown on the overlay */
    else
        snprintf(buf, size, "#%d", node);
    return buf;
}

int view_node_under(const lie_scene *s, const lie_rt *rt, const lie_camera *cam, int width, int height, float x,
                    float y, lie_vec3 *hit_point)
{
    lie_view v = lie_view_make(cam, width, height);
    lie_vec3 org, dir;
    lie_view_ray(&v, x, y, width, height, &org, &dir);
    lie_hit hit;
    if (!lie_rt_intersect(rt, org, dir, 0.0f, INFINITY, 1, &hit) || hit.tri >= s->n_tris)
        return -1;
    if (hit_point)
        *hit_point = lie_v3_add(org, lie_v3_scale(dir, hit.t));
    return s->instances[s->tri_instance[hit.tri]].node;
}

/* ---- opening ---------------------------------------------------------- */

static int looks_like_gltf(const unsigned char *d, size_t n)
{
    size_t i = 0;
    if (n >= 4 && memcmp(d, "glTF", 4) == 0)
        return 1;
    if (n >= 3 && d[0] == 0xEF && d[1] == 0xBB && d[2] == 0xBF)
        i = 3;
    while (i < n && (d[i] == ' ' || d[i] == '\t' || d[i] == '\r' || d[i] == '\n'))
        i++;
    return i < n && d[i] == '{';
}

/* The scene as the session started: the glTF file, with the cache's log. */
static lie_status load_base(view_world *w, lie_scene **out, lie_error *err)
{
    if (w->cache)
        return lie_cache_load_scene(w->cache, w->input, NULL, &w->opt.so, out, err);
    return lie_scene_load(w->input, &w->opt.so, out, err);
}

lie_status view_world_open(const char *input, const view_world_options *opt, view_world **out, lie_error *err)
{
    *out = NULL;
    view_world *w = calloc(1, sizeof *w);
    if (!w)
        return lie_error_set(err, LIE_ERR_NOMEM, input, "out of memory");
    /* writers first: an edit must not wait behind a stream of render bands */
    pthread_rwlockattr_t attr;
    pthread_rwlockattr_init(&attr);
    pthread_rwlockattr_setkind_np(&attr, PTHREAD_RWLOCK_PREFER_WRITER_NONRECURSIVE_NP);
    pthread_rwlock_init(&w->lock, &attr);
    pthread_rwlockattr_destroy(&attr);
    pthread_mutex_init(&w->cm, NULL);
    pthread_cond_init(&w->ccv, NULL);
    w->opt = *opt;
    w->input = strdup(input);
    w->applied = view_world_new_edit(w);
    unsigned char *data = NULL;
    size_t size = 0;
    lie_status st = w->input && w->applied ? lie_read_file(input, &data, &size, err)
                             : lie_error_set(err, LIE_ERR_NOMEM, input, "out of memory");
    if (st == LIE_OK && !looks_like_gltf(data, size))
        st = lie_cache_decode(data, size, input, &w->cache, err);
    free(data);
    if (st == LIE_OK && strcmp(input, "-") == 0 && !w->cache)
        st = lie_error_set(err, LIE_ERR_UNSUPPORTED, input, "a glTF scene cannot be read from stdin");
    if (st == LIE_OK)
        st = load_base(w, &w->scene, err);
    if (st == LIE_OK && w->cache)
        w->n_edits0 = w->cache->n_edits; /* the log as loaded, which --save keeps */
    if (st == LIE_OK)
        st = lie_rt_create(w->scene, &w->rt, err);
    if (st == LIE_OK)
        w->loaded_hash = w->cache ? w->cache->scene_hash : w->scene->hash;
    /* a scene, or a partial cache: the asynchronous constructor builds (and
     * finishes) it; a whole cache: lib/update keeps it through edits */
    if (st == LIE_OK && (!w->cache || w->cache->env->partial)) {
        lie_ctor_options co = lie_ctor_options_default();
        co.threads = opt->threads;
        co.view_width = opt->view_width;
        co.view_height = opt->view_height;
        co.max_depth = opt->max_depth;
        st = lie_ctor_create(w->scene, w->rt, &co, w->cache, &w->ctor, err);
    } else if (st == LIE_OK && w->cache) {
        lie_update_options uo = lie_update_options_default();
        uo.threads = opt->threads;
        uo.keep_trees = 1; /* the next edit finds the trees ready */
        uo.scene = opt->so;
        st = lie_update_create(w->cache, w->scene, &uo, &w->up, err);
        if (st == LIE_OK)
            st = lie_update_snapshot(w->up, &w->render_env, err);
    }
    if (st == LIE_OK)
        st = world_make_oracle(w, err);
    if (st == LIE_OK && w->up) {
        if (pthread_create(&w->ctor_thread, NULL, world_constructor_main, w) != 0)
            st = lie_error_set(err, LIE_ERR_NOMEM, input, "cannot start the constructor thread");
        else
            w->ctor_started = 1;
    }
    if (st != LIE_OK) {
        view_world_close(w);
        return st;
    }
    atomic_store(&w->version, 1);
    *out = w;
    return LIE_OK;
}

void view_thread_quit(pthread_mutex_t *m, pthread_cond_t *cv, int *quit, pthread_t tid)
{
    pthread_mutex_lock(m);
    *quit = 1;
    pthread_cond_broadcast(cv);
    pthread_mutex_unlock(m);
    pthread_join(tid, NULL);
}

void view_world_close(view_world *w)
{
    if (!w)
        return;
    if (w->ctor_started) {
        view_thread_quit(&w->cm, &w->ccv, &w->quit, w->ctor_thread);
    }
    lie_ctor_destroy(w->ctor);
    world_free_session(w);
    free(w->update_ms);
    lie_update_destroy(w->up);
    lie_env_destroy(w->render_env);
    lie_env_shadows_destroy(w->vis);
    lie_rt_destroy(w->rt);
    lie_scene_destroy(w->scene);
    lie_cache_destroy(w->cache);
    free(w->input);
    pthread_rwlock_destroy(&w->lock);
    pthread_mutex_destroy(&w->cm);
    pthread_cond_destroy(&w->ccv);
    free(w);
}
