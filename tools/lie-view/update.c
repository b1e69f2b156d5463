/* Edits in the viewer (§5) and the asynchronous constructor (§4.3.1).
 *
 * An edit is applied to the scene at once: the ray segment trees, built
 * over the units' roots before the edit, are queried with every changed
 * node's world bounds before and after, the answer is tightened with the
 * roots' exact hulls (lib/rst), and every unit so flagged, every unit of a
 * changed receiver and every unit of a changed emitter becomes pending.
 * The constructor thread then rebuilds pending units a step at a time on a
 * copy of the env and swaps the copy in; rebuilding whole units gives
 * exactly what lie-build gives for the edited scene (lib/lie), so once
 * nothing is pending the env is the one rst-update writes. */
#include "world_internal.h"

#include <stdlib.h>
#include <string.h>

/* ---- pending units ----------------------------------------------------- */

static int same_emitters(const lie_cache_emitter *a, int na, const lie_scene *s)
{
    if (na != s->n_emitters)
        return 0;
    for (int e = 0; e < na; e++)
        if (a[e].type != (uint32_t)s->emitters[e].type || a[e].node != s->emitters[e].node ||
            a[e].first_tri != s->emitters[e].first_tri || a[e].n_tris != s->emitters[e].n_tris)
            return 0;
    return 1;
}

static lie_cache_emitter *emitter_summary(const lie_scene *s)
{
    lie_cache_emitter *em = malloc(sizeof *em * ((size_t)s->n_emitters + 1));
    for (int e = 0; em && e < s->n_emitters; e++) {
        em[e].type = (uint32_t)s->emitters[e].type;
        em[e].node = s->emitters[e].node;
        em[e].first_tri = s->emitters[e].first_tri;
        em[e].n_tris = s->emitters[e].n_tris;
    }
    return em;
}

/* The state before a change, taken while the scene is still the old one. */
typedef struct before {
    lie_box3 *boxes;
    int n_nodes;
    uint32_t n_tris;
    float max_tri_area;
    lie_cache_emitter *emitters;
    int n_emitters;
    lie_rst *rst;          /* over the env as it was (env_gen) */
    uint64_t env_gen;
} before;

static void before_free(before *b)
{
    free(b->boxes);
    free(b->emitters);
    lie_rst_destroy(b->rst);
    memset(b, 0, sizeof *b);
}

static lie_status before_take(view_world *w, before *b, lie_error *err)
{
    memset(b, 0, sizeof *b);
    const lie_scene *s = w->scene;
    b->boxes = world_own_boxes(s);
    b->n_nodes = s->n_nodes;
    b->n_tris = s->n_tris;
    b->max_tri_area = s->max_tri_area;
    b->emitters = emitter_summary(s);
    b->n_emitters = s->n_emitters;
    if (!b->boxes || !b->emitters) {
        before_free(b);
        return lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
    }
    if (!w->cache)
        return LIE_OK;
    /* the trees read the env, which the constructor may swap: read lock */
    pthread_rwlock_rdlock(&w->lock);
    b->env_gen = w->env_gen;
    lie_status st = lie_rst_build(s, w->cache->env, 1, &b->rst, NULL, err);
    pthread_rwlock_unlock(&w->lock);
    if (st != LIE_OK)
        before_free(b);
    return st;
}

/* Mark what the change from `b` to the current scene makes pending; called
 * with the write lock held, the scene already changed.  moved[n] marks nodes
 * whose geometry changed. */
static lie_status mark_pending(view_world *w, before *b, const uint8_t *moved, lie_error *err)
{
    lie_scene *s = w->scene;
    lie_env *env = w->cache->env;
    size_t n_units = (size_t)s->n_tris * (size_t)s->n_emitters;
    if (s->n_tris != b->n_tris || !same_emitters(b->emitters, b->n_emitters, s)) {
        /* Triangles or emitters changed in number or identity: units no longer
         * line up with the env's, so rebuild everything now (rst-update keeps
         * the units of unchanged emitters; the viewer does not, yet). */
        lie_status st = world_rebuild_all(w, err);
        if (st != LIE_OK)
            return st;
        memset(w->pending, 0, n_units + 1);
        atomic_store(&w->n_pending, 0);
        return LIE_OK;
    }
    int64_t added = 0;
    if (s->max_tri_area != b->max_tri_area) {
        /* the smallest patch size follows the largest triangle: everything */
        for (size_t u = 0; u < n_units; u++)
            if (!w->pending[u]) {
                w->pending[u] = 1;
                added++;
            }
    } else {
        lie_box3 *after = world_own_boxes(s);
        lie_box3 *boxes = malloc(sizeof *boxes * (2 * (size_t)s->n_nodes + 1));
        uint8_t *flags = calloc((size_t)env->n_nodes + 1, 1);
        if (!after || !boxes || !flags) {
            free(after);
            free(boxes);
            free(flags);
            return lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
        }
        int nb = 0;
        for (int n = 0; n < s->n_nodes; n++) {
            if (!moved[n])
                continue;
            if (!lie_box3_is_empty(&after[n]))
                boxes[nb++] = after[n];
            if (n < b->n_nodes && !lie_box3_is_empty(&b->boxes[n]))
                boxes[nb++] = b->boxes[n];
        }
        if (nb > 0) {
            lie_rst *rst = b->rst, *own = NULL;
            if (w->env_gen != b->env_gen) {
                /* the constructor swapped units in since: trees over the env as it is */
                lie_status st = lie_rst_build(s, env, 1, &own, NULL, err);
                if (st != LIE_OK) {
                    free(after);
                    free(boxes);
                    free(flags);
                    return st;
                }
                rst = own;
            }
            for (int i = 0; i < nb; i++)
                lie_rst_query(rst, boxes[i], flags);
            /* hulls on the edited scene: right for every patch and emitter that
             * did not move (the others are rebuilt whole below) */
            lie_rst_refine(s, env, boxes, nb, flags);
            lie_rst_destroy(own);
        }
        int ne = s->n_emitters;
        for (uint32_t t = 0; t < s->n_tris; t++) {
            int receiver = moved[s->instances[s->tri_instance[t]].node];
            for (int e = 0; e < ne; e++) {
                size_t u = (size_t)t * (size_t)ne + (size_t)e;
                if (!w->pending[u] && (receiver || moved[s->emitters[e].node] || flags[env->root[u]])) {
                    w->pending[u] = 1;
                    added++;
                }
            }
        }
        free(after);
        free(boxes);
        free(flags);
    }
    int64_t now = atomic_fetch_add(&w->n_pending, added) + added;
    if (now > w->pending_max)
        w->pending_max = now;
    return LIE_OK;
}

/* Swap in the new world after a change: ray tracer, oracle, pending units. */
static lie_status commit(view_world *w, before *b, const uint8_t *moved, lie_error *err)
{
    lie_rt *rt = NULL;
    lie_status st = lie_rt_create(w->scene, &rt, err);
    if (st != LIE_OK)
        return st;
    lie_rt_destroy(w->rt);
    w->rt = rt;
    if (w->cache) {
        st = mark_pending(w, b, moved, err);
        if (st == LIE_OK)
            st = world_make_oracle(w, err);
    }
    w->epoch++;
    atomic_fetch_add(&w->version, 1);
    if (atomic_load(&w->n_pending) > 0) {
        pthread_mutex_lock(&w->cm);
        pthread_cond_broadcast(&w->ccv);
        pthread_mutex_unlock(&w->cm);
    }
    return st;
}

/* ---- the session's edits -------------------------------------------------- */

static const char *edit_name(const view_world *w) { return w->opt.record ? w->opt.record : "lie-view.yaml"; }

/* All live groups as one edit file's text (caller frees). */
static char *live_text(const view_world *w, int n_groups)
{
    size_t len = 1;
    for (int i = 0; i < n_groups; i++)
        len += strlen(w->live[i]);
    char *t = malloc(len);
    if (!t)
        return NULL;
    t[0] = 0;
    for (int i = 0, at = 0; i < n_groups; i++) {
        size_t k = strlen(w->live[i]);
        memcpy(t + at, w->live[i], k + 1);
        at += (int)k;
    }
    return t;
}

/* The session's starting scene with the first n_groups live groups applied. */
static lie_status replay(view_world *w, int n_groups, lie_scene **out, lie_error *err)
{
    lie_status st = world_load_base(w, out, err);
    char *text = st == LIE_OK ? live_text(w, n_groups) : NULL;
    if (st == LIE_OK && !text)
        st = lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
    lie_edit *e = NULL;
    if (st == LIE_OK && *text)
        st = lie_edit_parse((const unsigned char *)text, strlen(text), edit_name(w), &e, err);
    if (st == LIE_OK && e)
        st = lie_edit_apply(*out, e, &w->opt.so, NULL, err);
    lie_edit_destroy(e);
    free(text);
    if (st != LIE_OK) {
        lie_scene_destroy(*out);
        *out = NULL;
    }
    return st;
}

static int push(char ***arr, int *n, char *s)
{
    char **a = realloc(*arr, sizeof *a * ((size_t)*n + 1));
    if (!a)
        return 0;
    a[(*n)++] = s;
    *arr = a;
    return 1;
}

static void note_ms(view_world *w, double t0)
{
    w->last_ms = 1e3 * (lie_time_now() - t0);
    double *m = realloc(w->update_ms, sizeof *m * ((size_t)w->n_update_ms + 1));
    if (m) {
        m[w->n_update_ms++] = w->last_ms;
        w->update_ms = m;
    }
}

/* Apply one group in place. */
static lie_status apply_group(view_world *w, const char *yaml, lie_error *err)
{
    double t0 = lie_time_now();
    lie_edit *e = NULL;
    lie_status st = lie_edit_parse((const unsigned char *)yaml, strlen(yaml), edit_name(w), &e, err);
    if (st != LIE_OK)
        return st;
    /* names first, so that a bad edit changes nothing */
    for (int i = 0; st == LIE_OK && i < e->n_ops; i++) {
        int node;
        if (e->ops[i].kind == LIE_EDIT_ADD)
            continue;
        st = lie_edit_find_node(w->scene, e->ops[i].node, &node, e->name, e->ops[i].line, e->ops[i].col, err);
        if (st == LIE_OK && w->scene->nodes[node].removed)
            st = lie_error_set_at(err, LIE_ERR_ARG, e->name, e->ops[i].line, e->ops[i].col,
                                  "node '%s' was removed", e->ops[i].node);
    }
    before b;
    if (st == LIE_OK)
        st = before_take(w, &b, err);
    if (st != LIE_OK) {
        lie_edit_destroy(e);
        return st;
    }
    lie_edit_effect fx;
    memset(&fx, 0, sizeof fx);
    uint8_t *moved = calloc((size_t)w->scene->n_nodes + 64, 1);
    pthread_rwlock_wrlock(&w->lock);
    st = moved ? lie_edit_apply(w->scene, e, &w->opt.so, &fx, err)
               : lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
    if (st != LIE_OK && moved) {
        /* the scene may be half edited: back to the last good state */
        lie_scene *good = NULL;
        lie_error ignore;
        if (replay(w, w->n_live, &good, &ignore) == LIE_OK) {
            lie_scene_destroy(w->scene);
            w->scene = good;
            lie_rt *rt = NULL;
            if (lie_rt_create(w->scene, &rt, &ignore) == LIE_OK) {
                lie_rt_destroy(w->rt);
                w->rt = rt;
            }
            world_make_oracle(w, &ignore);
        }
    }
    if (st == LIE_OK) {
        uint8_t *m2 = realloc(moved, (size_t)w->scene->n_nodes + 1);
        if (m2) {
            moved = m2;
            for (int k = 0; k < fx.n_nodes; k++)
                if (fx.nodes[k] >= 0 && fx.nodes[k] < w->scene->n_nodes)
                    moved[fx.nodes[k]] = 1;
            st = commit(w, &b, moved, err);
        } else {
            st = lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
        }
    }
    pthread_rwlock_unlock(&w->lock);
    lie_edit_effect_free(&fx);
    free(moved);
    before_free(&b);
    lie_edit_destroy(e);
    if (st == LIE_OK)
        note_ms(w, t0);
    return st;
}

lie_status view_world_edit(view_world *w, const char *yaml, int join, lie_error *err)
{
    char *copy = strdup(yaml);
    if (!copy)
        return lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
    lie_status st = apply_group(w, copy, err);
    if (st == LIE_OK && join && w->n_live > 0) {
        size_t a = strlen(w->live[w->n_live - 1]), b = strlen(copy);
        char *g = realloc(w->live[w->n_live - 1], a + b + 1);
        if (g) {
            memcpy(g + a, copy, b + 1);
            w->live[w->n_live - 1] = g;
            free(copy);
            copy = NULL;
        } else {
            st = lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
        }
    } else if (st == LIE_OK && !push(&w->live, &w->n_live, copy)) {
        st = lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
    }
    if (st != LIE_OK) {
        free(copy);
        return st;
    }
    for (int i = 0; i < w->n_undone; i++)
        free(w->undone[i]);
    w->n_undone = 0;
    return LIE_OK;
}

lie_status view_world_undo(view_world *w, int *done, lie_error *err)
{
    *done = 0;
    if (w->n_live == 0)
        return LIE_OK;
    double t0 = lie_time_now();
    /* The state without the last group, replayed from the start (an edit
     * has no exact inverse: a removal cannot be undone by another edit). */
    lie_scene *s1 = NULL;
    lie_status st = replay(w, w->n_live - 1, &s1, err);
    before b;
    if (st == LIE_OK)
        st = before_take(w, &b, err);
    if (st != LIE_OK) {
        lie_scene_destroy(s1);
        return st;
    }
    lie_scene *s0 = w->scene;
    /* what changed: nodes whose triangles differ (slots never move) */
    uint8_t *moved = calloc((size_t)s1->n_nodes + (size_t)s0->n_nodes + 1, 1);
    if (!moved) {
        before_free(&b);
        lie_scene_destroy(s1);
        return lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
    }
    uint32_t nt = s0->n_tris < s1->n_tris ? s0->n_tris : s1->n_tris;
    for (uint32_t t = 0; t < nt; t++)
        if (s0->tri_removed[t] != s1->tri_removed[t] ||
            memcmp(&s0->tri_p[3 * (size_t)t], &s1->tri_p[3 * (size_t)t], 3 * sizeof(lie_vec3)) != 0) {
            moved[s0->instances[s0->tri_instance[t]].node] = 1;
            moved[s1->instances[s1->tri_instance[t]].node] = 1;
        }
    pthread_rwlock_wrlock(&w->lock);
    w->scene = s1;
    st = commit(w, &b, moved, err);
    pthread_rwlock_unlock(&w->lock);
    lie_scene_destroy(s0);
    free(moved);
    before_free(&b);
    if (st != LIE_OK)
        return st;
    if (!push(&w->undone, &w->n_undone, w->live[w->n_live - 1]))
        free(w->live[w->n_live - 1]);
    w->n_live--;
    note_ms(w, t0);
    *done = 1;
    return LIE_OK;
}

lie_status view_world_redo(view_world *w, int *done, lie_error *err)
{
    *done = 0;
    if (w->n_undone == 0)
        return LIE_OK;
    char *g = w->undone[w->n_undone - 1];
    lie_status st = apply_group(w, g, err);
    if (st != LIE_OK)
        return st;
    w->n_undone--;
    if (!push(&w->live, &w->n_live, g)) {
        free(g);
        return lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
    }
    *done = 1;
    return LIE_OK;
}

/* ---- the constructor ----------------------------------------------------- */

static lie_env *env_copy(const lie_env *e)
{
    lie_env *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    *c = *e;
    size_t units = (size_t)e->n_tris * (size_t)e->n_emitters;
    c->root = malloc(sizeof *c->root * (units + 1));
    c->nodes = malloc(sizeof *c->nodes * ((size_t)e->n_nodes + 1));
    c->pool = malloc(sizeof *c->pool * ((size_t)e->n_pool + 1));
    if (!c->root || !c->nodes || !c->pool) {
        lie_env_destroy(c);
        return NULL;
    }
    memcpy(c->root, e->root, sizeof *c->root * units);
    memcpy(c->nodes, e->nodes, sizeof *c->nodes * e->n_nodes);
    memcpy(c->pool, e->pool, sizeof *c->pool * e->n_pool);
    return c;
}

void *world_constructor_main(void *arg)
{
    view_world *w = arg;
    size_t step = 32, cursor = 0;
    int threads = w->opt.threads > 0 ? w->opt.threads : 1;
    for (;;) {
        pthread_mutex_lock(&w->cm);
        while (!w->quit && atomic_load(&w->n_pending) == 0)
            pthread_cond_wait(&w->ccv, &w->cm);
        int quit = w->quit;
        pthread_mutex_unlock(&w->cm);
        if (quit)
            break;
        double t0 = lie_time_now();
        /* one step: rebuild up to `step` pending units on a copy */
        pthread_rwlock_rdlock(&w->lock);
        uint64_t epoch = w->epoch;
        size_t n_units = (size_t)w->scene->n_tris * (size_t)w->scene->n_emitters;
        uint32_t *chosen = malloc(sizeof *chosen * (step + 1));
        int32_t *old_unit = malloc(sizeof *old_unit * (n_units + 1));
        lie_env *copy = chosen && old_unit ? env_copy(w->cache->env) : NULL;
        size_t k = 0;
        lie_status st = copy ? LIE_OK : LIE_ERR_NOMEM;
        if (st == LIE_OK) {
            for (size_t u = 0; u < n_units; u++)
                old_unit[u] = (int32_t)u;
            for (size_t i = 0; i < n_units && k < step; i++) {
                size_t u = (cursor + i) % n_units;
                if (w->pending[u]) {
                    chosen[k++] = (uint32_t)u;
                    old_unit[u] = -1;
                }
            }
            lie_error err;
            if (k > 0)
                st = lie_env_update(copy, w->scene, w->rt, old_unit, NULL, threads, NULL, &err);
        }
        pthread_rwlock_unlock(&w->lock);
        free(old_unit);
        if (st == LIE_OK && k > 0) {
            pthread_rwlock_wrlock(&w->lock);
            if (epoch == w->epoch) {
                lie_env *env = w->cache->env, tmp = *env;
                *env = *copy; /* the oracle holds env's address: swap contents */
                *copy = tmp;
                for (size_t i = 0; i < k; i++)
                    w->pending[chosen[i]] = 0;
                w->env_gen++;
                lie_error err;
                world_make_oracle(w, &err); /* list lengths may have grown */
                /* the version first: whoever sees nothing pending sees the new version */
                atomic_fetch_add(&w->version, 1);
                atomic_fetch_sub(&w->n_pending, (int64_t)k);
                cursor = (chosen[k - 1] + 1) % n_units;
            }
            pthread_rwlock_unlock(&w->lock);
        }
        lie_env_destroy(copy);
        free(chosen);
        if (st != LIE_OK) {
            /* out of memory: leave the units pending (Embree answers them) */
            struct timespec ts = {0, 50 * 1000 * 1000};
            nanosleep(&ts, NULL);
        }
        /* steps of about 20 ms keep edits waiting little */
        double dt = lie_time_now() - t0;
        if (dt < 0.01 && step < 65536)
            step *= 2;
        else if (dt > 0.04 && step > 8)
            step /= 2;
        pthread_mutex_lock(&w->cm);
        if (atomic_load(&w->n_pending) == 0)
            pthread_cond_broadcast(&w->ccv);
        pthread_mutex_unlock(&w->cm);
    }
    return NULL;
}

void view_world_wait(view_world *w)
{
    pthread_mutex_lock(&w->cm);
    while (atomic_load(&w->n_pending) > 0 && w->ctor_started)
        pthread_cond_wait(&w->ccv, &w->cm);
    pthread_mutex_unlock(&w->cm);
}

/* ---- saving ---------------------------------------------------------------- */

lie_status view_world_write_record(view_world *w, lie_error *err)
{
    if (!w->opt.record)
        return LIE_OK;
    char *text = live_text(w, w->n_live);
    if (!text)
        return lie_error_set(err, LIE_ERR_NOMEM, w->opt.record, "out of memory");
    lie_atomic_file af;
    lie_status st = lie_atomic_open(&af, w->opt.record, err);
    if (st == LIE_OK) {
        if (fwrite(text, 1, strlen(text), af.fp) != strlen(text)) {
            lie_atomic_abort(&af);
            st = lie_error_set(err, LIE_ERR_IO, w->opt.record, "write failed");
        } else {
            st = lie_atomic_commit(&af, err);
        }
    }
    free(text);
    return st;
}

lie_status view_world_save(view_world *w, const char *path, lie_error *err)
{
    if (!w->cache)
        return lie_error_set(err, LIE_ERR_UNSUPPORTED, path, "the viewer was started on a scene, not a cache");
    view_world_wait(w);
    pthread_rwlock_wrlock(&w->lock);
    const lie_scene *s = w->scene;
    lie_cache c = *w->cache;
    w->cache->env->scene_hash = s->hash; /* edits that moved nothing (materials) leave it */
    char *text = live_text(w, w->n_live);
    lie_cache_edit *log = malloc(sizeof *log * ((size_t)c.n_edits + 1));
    lie_cache_emitter *em = emitter_summary(s);
    lie_status st = LIE_OK;
    if (!text || !log || !em) {
        st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    } else {
        /* the session's edits as one log entry, as rst-update CACHE EDITS.yaml writes it */
        memcpy(log, c.edits, sizeof *log * (size_t)c.n_edits);
        if (w->n_live > 0) {
            log[c.n_edits].name = (char *)edit_name(w);
            log[c.n_edits].text = (unsigned char *)text;
            log[c.n_edits].size = strlen(text);
            c.n_edits++;
        }
        c.edits = log;
        c.emitters = em;
        c.n_emitters = s->n_emitters;
        c.n_tris = s->n_tris;
        c.state_hash = s->hash;
        st = lie_cache_write(path, &c, NULL, err);
    }
    pthread_rwlock_unlock(&w->lock);
    free(text);
    free(log);
    free(em);
    return st;
}
