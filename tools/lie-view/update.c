/* SPDX-License-Identifier: Apache-2.0 */
/* Edits in the viewer, through lib/update (§5), and the asynchronous
 * constructor (§4.3.1).
 *
 * An edit is phase 1 of the update, under the world's write lock: the
 * scene changes, pending units are marked, and the renderer gets a new
 * Embree scene and the update's snapshot (pending pairs answered by
 * Embree).  The constructor thread runs phase 2 a step at a time under the
 * read lock (renders go on meanwhile) and publishes each step's snapshot.
 * When nothing is pending the update has committed: the cache holds what
 * rst-update would write for the session's edits.
 *
 * Edits are lie_edit values the session builds (lib/edit).  Undo applies
 * the edit that restores what a group changed (lie_edit_inverse: a node's
 * local transform as it was, its materials as they were), so the record of
 * the session stays a plain edit file (lie_edit_write) that rst-update
 * replays exactly.  A removal is undone by `restore`; an added object has no
 * such inverse in formats/edit.md and is not undone. */
#include "world_internal.h"

#include <stdlib.h>
#include <string.h>

/* ---- applying ----------------------------------------------------------------- */

static const char *edit_name(const view_world *w) { return w->opt.record ? w->opt.record : "lie-view.yaml"; }

static void note_ms(view_world *w, double t0)
{
    w->last_ms = 1e3 * (lie_time_now() - t0);
    double *m = realloc(w->update_ms, sizeof *m * ((size_t)w->n_update_ms + 1));
    if (m) {
        m[w->n_update_ms++] = w->last_ms;
        w->update_ms = m;
    }
}

lie_edit *view_world_new_edit(const view_world *w) { return lie_edit_create(edit_name(w)); }

/* Check the nodes, and if `inverse` is given work out the restoring edit
 * first (*inverse NULL: e adds an object, which nothing takes out again). */
static lie_status prepare(view_world *w, const lie_edit *e, lie_edit **inverse, lie_error *err)
{
    lie_status st = LIE_OK;
    for (int i = 0; st == LIE_OK && i < e->n_ops; i++) {
        const lie_edit_op *op = &e->ops[i];
        int node;
        if (op->kind == LIE_EDIT_ADD)
            continue;
        st = lie_edit_find_node(w->scene, op->node, &node, e->name, op->line, op->col, err);
        if (st == LIE_OK && w->scene->nodes[node].removed && op->kind != LIE_EDIT_RESTORE)
            st = lie_error_set_at(err, LIE_ERR_ARG, e->name, op->line, op->col, "node '%s' was removed", op->node);
    }
    if (st == LIE_OK && inverse) {
        lie_error sub;
        st = lie_edit_inverse(w->scene, e, inverse, &sub);
        if (st == LIE_ERR_UNSUPPORTED)
            st = LIE_OK;
        else if (st != LIE_OK)
            *err = sub;
    }
    return st;
}

/* Append every operation of `from` to `to`. */
static lie_status append_all(lie_edit *to, const lie_edit *from, lie_error *err)
{
    lie_status st = LIE_OK;
    for (int i = 0; st == LIE_OK && i < from->n_ops; i++)
        st = lie_edit_append(to, &from->ops[i], err);
    return st;
}

/* Whether an edit only moves nodes: the constructor then builds again only
 * what the moved geometry may reach (lie_ctor_edited). */
static int moves_only(const lie_edit *e)
{
    for (int i = 0; i < e->n_ops; i++) {
        lie_edit_kind k = e->ops[i].kind;
        if (k != LIE_EDIT_MOVE_BY && k != LIE_EDIT_MOVE_TO && k != LIE_EDIT_ROTATE && k != LIE_EDIT_SCALE &&
            k != LIE_EDIT_SET_TRANSFORM)
            return 0;
    }
    return 1;
}

/* Phase 1 and a new frame's worth of state, under the write lock. */
static lie_status apply(view_world *w, const lie_edit *e, lie_error *err)
{
    double t0 = lie_time_now();
    lie_status st = LIE_OK;
    pthread_rwlock_wrlock(&w->lock);
    if (w->ctor)
        lie_ctor_hold(w->ctor); /* the unit in progress is dropped: the scene changes under it */
    if (w->up) {
        st = lie_update_edit(w->up, e, err);
    } else {
        st = lie_edit_apply(w->scene, e, &w->opt.so, NULL, err);
    }
    if (st == LIE_OK) {
        lie_rt *rt = NULL;
        st = lie_rt_create(w->scene, &rt, err);
        if (st == LIE_OK && w->ctor)
            st = lie_ctor_edited(w->ctor, rt, moves_only(e), err);
        if (st == LIE_OK) {
            lie_rt_destroy(w->rt);
            w->rt = rt;
        } else {
            lie_rt_destroy(rt);
        }
        /* the oracle holds the blockers' positions: made again for the edited scene */
        if (st == LIE_OK && w->ctor)
            st = world_make_oracle(w, err);
    }
    if (w->ctor)
        lie_ctor_release(w->ctor);
    if (st == LIE_OK && w->up) {
        lie_env *snap = NULL;
        st = lie_update_snapshot(w->up, &snap, err);
        if (st == LIE_OK) {
            lie_env_destroy(w->render_env);
            w->render_env = snap;
            st = world_make_oracle(w, err);
        }
        int64_t p = (int64_t)lie_update_pending(w->up);
        atomic_store(&w->n_pending, p);
        atomic_store(&w->dirty, 1); /* a step commits, even with nothing pending */
        if (p > w->pending_max)
            w->pending_max = p;
    }
    if (st == LIE_OK)
        st = append_all(w->applied, e, err);
    /* a failed phase 1 leaves the update unusable (lib/update): the session ends */
    w->failed |= st != LIE_OK;
    w->epoch++;
    atomic_fetch_add(&w->version, 1);
    pthread_rwlock_unlock(&w->lock);
    if (st != LIE_OK)
        return st;
    note_ms(w, t0);
    pthread_mutex_lock(&w->cm);
    pthread_cond_broadcast(&w->ccv);
    pthread_mutex_unlock(&w->cm);
    return LIE_OK;
}

static int push_group(view_world *w, lie_edit *edit, lie_edit *inverse)
{
    view_group *g = realloc(w->live, sizeof *g * ((size_t)w->n_live + 1));
    if (!g)
        return 0;
    w->live = g;
    g[w->n_live].edit = edit;
    g[w->n_live].inverse = inverse;
    w->n_live++;
    return 1;
}

static lie_status unusable(view_world *w, lie_error *err)
{
    return lie_error_set(err, LIE_ERR_ARG, w->input, "an earlier edit failed: edits are off");
}

/* A copy of e to keep in a group. */
static lie_edit *copy_of(const view_world *w, const lie_edit *e, lie_error *err)
{
    lie_edit *c = view_world_new_edit(w);
    if (!c) {
        lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
        return NULL;
    }
    if (append_all(c, e, err) != LIE_OK) {
        lie_edit_destroy(c);
        return NULL;
    }
    return c;
}

lie_status view_world_edit(view_world *w, const lie_edit *e, int join, lie_error *err)
{
    if (w->failed)
        return unusable(w, err);
    join = join && w->n_live > 0;
    lie_edit *inverse = NULL;
    lie_status st = prepare(w, e, join ? NULL : &inverse, err);
    if (st == LIE_OK)
        st = apply(w, e, err);
    if (st != LIE_OK) {
        lie_edit_destroy(inverse);
        return st;
    }
    /* the group: one drag's steps join; its inverse is from before the first */
    lie_error sub;
    if (join) {
        append_all(w->live[w->n_live - 1].edit, e, &sub); /* out of memory: redo repeats less */
    } else {
        lie_edit *c = copy_of(w, e, &sub);
        if (!c || !push_group(w, c, inverse)) {
            lie_edit_destroy(c);
            lie_edit_destroy(inverse);
        }
    }
    for (int i = 0; i < w->n_undone; i++)
        lie_edit_destroy(w->undone[i]);
    w->n_undone = 0;
    return LIE_OK;
}

lie_status view_world_undo(view_world *w, int *done, lie_error *err)
{
    *done = 0;
    if (w->failed)
        return unusable(w, err);
    if (w->n_live == 0)
        return LIE_OK;
    view_group *g = &w->live[w->n_live - 1];
    if (!g->inverse)
        return lie_error_set(err, LIE_ERR_UNSUPPORTED, w->input,
                             "adding an object cannot be undone (formats/edit.md has no edit that takes it out again)");
    lie_status st = g->inverse->n_ops ? prepare(w, g->inverse, NULL, err) : LIE_OK;
    if (st == LIE_OK && g->inverse->n_ops)
        st = apply(w, g->inverse, err);
    if (st != LIE_OK)
        return st;
    lie_edit **u = realloc(w->undone, sizeof *u * ((size_t)w->n_undone + 1));
    if (u) {
        w->undone = u;
        u[w->n_undone++] = g->edit;
    } else {
        lie_edit_destroy(g->edit);
    }
    lie_edit_destroy(g->inverse);
    w->n_live--;
    *done = 1;
    return LIE_OK;
}

lie_status view_world_redo(view_world *w, int *done, lie_error *err)
{
    *done = 0;
    if (w->failed)
        return unusable(w, err);
    if (w->n_undone == 0)
        return LIE_OK;
    lie_edit *e = w->undone[w->n_undone - 1], *inverse = NULL;
    lie_status st = prepare(w, e, &inverse, err);
    if (st == LIE_OK)
        st = apply(w, e, err);
    if (st != LIE_OK) {
        lie_edit_destroy(inverse);
        return st;
    }
    w->n_undone--;
    if (!push_group(w, e, inverse)) {
        lie_edit_destroy(e);
        lie_edit_destroy(inverse);
    }
    *done = 1;
    return LIE_OK;
}

void world_free_session(view_world *w)
{
    for (int i = 0; i < w->n_live; i++) {
        lie_edit_destroy(w->live[i].edit);
        lie_edit_destroy(w->live[i].inverse);
    }
    for (int i = 0; i < w->n_undone; i++)
        lie_edit_destroy(w->undone[i]);
    free(w->live);
    free(w->undone);
    lie_edit_destroy(w->applied);
}

/* ---- the constructor ----------------------------------------------------------- */

void *world_constructor_main(void *arg)
{
    view_world *w = arg;
    size_t step = 16;
    double last_publish = 0.0;
    for (;;) {
        pthread_mutex_lock(&w->cm);
        while (!w->quit && ((atomic_load(&w->n_pending) == 0 && !atomic_load(&w->dirty)) || w->failed || w->held))
            pthread_cond_wait(&w->ccv, &w->cm);
        int quit = w->quit;
        w->stepping = !quit;
        pthread_mutex_unlock(&w->cm);
        if (quit)
            break;
        /* phase 2 reads the scene only: renders go on; edits wait */
        double t0 = lie_time_now();
        pthread_rwlock_rdlock(&w->lock);
        uint64_t epoch = w->epoch;
        size_t remaining = 0;
        lie_env *snap = NULL;
        lie_env_shadows *vis = NULL;
        lie_error err;
        lie_status st = lie_update_step(w->up, step, &remaining, &err);
        /* A snapshot copies every environment (lib/update/update.h, Costs):
         * taken after every step it was most of the catch-up.  Frames keep
         * the last snapshot (pending pairs answered by Embree) until half a
         * second of steps has landed, or the update commits. */
        int publish = remaining == 0 || lie_time_now() - last_publish >= 0.5;
        if (st == LIE_OK && publish)
            st = lie_update_snapshot(w->up, &snap, &err);
        if (st == LIE_OK && publish)
            st = lie_env_shadows_create(w->scene, snap, &vis, &err);
        pthread_rwlock_unlock(&w->lock);
        pthread_rwlock_wrlock(&w->lock);
        if (st != LIE_OK) {
            w->failed = 1;
            w->ctor_err = err;
        } else if (epoch == w->epoch && !publish) {
            atomic_store(&w->n_pending, (int64_t)remaining);
        } else if (epoch == w->epoch) {
            /* no edit came in between: publish */
            last_publish = lie_time_now();
            lie_env_destroy(w->render_env);
            lie_env_shadows_destroy(w->vis);
            w->render_env = snap;
            w->vis = vis;
            snap = NULL;
            vis = NULL;
            /* the version first: whoever sees nothing pending sees the new version */
            atomic_fetch_add(&w->version, 1);
            atomic_store(&w->n_pending, (int64_t)remaining);
            if (remaining == 0)
                atomic_store(&w->dirty, 0); /* committed */
        }
        pthread_rwlock_unlock(&w->lock);
        lie_env_shadows_destroy(vis);
        lie_env_destroy(snap);
        /* Steps of about 100 ms: each re-lays out the whole environments
         * (lib/update/update.h, Costs), so shorter ones spend the catch-up
         * on that; an edit waits for one step at most. */
        double dt = lie_time_now() - t0;
        if (dt < 0.05 && step < (1u << 24))
            step *= 2;
        else if (dt > 0.2 && step > 4)
            step /= 2;
        pthread_mutex_lock(&w->cm);
        w->stepping = 0;
        pthread_cond_broadcast(&w->ccv); /* a hold waiting for the step, or a wait for the commit */
        pthread_mutex_unlock(&w->cm);
    }
    return NULL;
}

void view_world_wait(view_world *w)
{
    if (w->ctor) {
        lie_ctor_wait(w->ctor, -1.0, NULL);
        return;
    }
    pthread_mutex_lock(&w->cm);
    while ((atomic_load(&w->n_pending) > 0 || atomic_load(&w->dirty)) && w->ctor_started && !w->failed && !w->held)
        pthread_cond_wait(&w->ccv, &w->cm);
    pthread_mutex_unlock(&w->cm);
}

/* ---- saving ---------------------------------------------------------------------- */

lie_status view_world_write_record(view_world *w, lie_error *err)
{
    if (!w->opt.record)
        return LIE_OK;
    unsigned char *text = NULL;
    size_t size = 0;
    lie_status st = lie_edit_write(w->applied, &text, &size, err);
    lie_atomic_file af;
    if (st == LIE_OK)
        st = lie_atomic_open(&af, w->opt.record, err);
    if (st == LIE_OK && size && fwrite(text, 1, size, af.fp) != size) {
        lie_atomic_abort(&af);
        st = lie_error_set(err, LIE_ERR_IO, w->opt.record, "write failed");
    } else if (st == LIE_OK) {
        st = lie_atomic_commit(&af, err);
    }
    free(text);
    return st;
}

/* The edit log of a saved cache: the input's n0 entries, then the
 * session's edits as one entry (when there are any), as rst-update CACHE
 * EDITS.yaml writes it, each named relative to the folder of `path` (the
 * saved cache), so that an `add` file resolves from there as rst-update's
 * log does.  *log (its names too: log_free) and *text (the session's
 * written form, which the last entry points into) are the caller's. */
static void log_free(lie_cache_edit *log, int n)
{
    for (int i = 0; log && i < n; i++)
        free(log[i].name);
    free(log);
}

static lie_status session_log(view_world *w, const lie_cache_edit *edits0, int n0, lie_cache_edit **log, int *n,
                              unsigned char **text, const char *path, lie_error *err)
{
    size_t size = 0;
    *log = NULL;
    *n = 0;
    *text = NULL;
    lie_status st = lie_edit_write(w->applied, text, &size, err);
    if (st != LIE_OK)
        return st;
    lie_cache c;
    memset(&c, 0, sizeof c);
    c.edits = calloc((size_t)n0 + 1, sizeof *c.edits);
    int ok = c.edits != NULL;
    for (int i = 0; ok && i < n0; i++) {
        c.edits[i] = edits0[i];
        ok = (c.edits[i].name = strdup(edits0[i].name)) != NULL;
        c.n_edits += ok;
    }
    if (ok && w->applied->n_ops) {
        ok = (c.edits[n0].name = strdup(edit_name(w))) != NULL;
        c.edits[n0].text = *text;
        c.edits[n0].size = size;
        c.n_edits += ok;
    }
    if (!ok) {
        log_free(c.edits, c.n_edits);
        free(*text);
        *text = NULL;
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    st = lie_cache_log_move(&c, n0, w->input, path, w->opt.so.files, err);
    if (st != LIE_OK) {
        log_free(c.edits, c.n_edits);
        free(*text);
        *text = NULL;
        return st;
    }
    lie_cache_log_relative_to(&c, n0, path);
    *log = c.edits;
    *n = c.n_edits;
    return LIE_OK;
}

/* With the constructor: what has landed, now (lie_ctor_cache), a partial
 * cache where units are pending.  The provenance is the input's: its scene
 * file and hash, its edit log and the session's edits as one entry. */
static lie_status save_ctor(view_world *w, const char *path, lie_error *err)
{
    lie_cache prov;
    memset(&prov, 0, sizeof prov);
    prov.scene_path = w->cache ? w->cache->scene_path : w->input;
    prov.scene_hash = w->loaded_hash;
    unsigned char *text = NULL;
    lie_status st = session_log(w, w->cache ? w->cache->edits : NULL, w->cache ? w->n_edits0 : 0, &prov.edits,
                                &prov.n_edits, &text, path, err);
    lie_cache *c = NULL;
    if (st == LIE_OK) {
        pthread_rwlock_rdlock(&w->lock);
        st = lie_ctor_cache(w->ctor, &prov, &c, err);
        pthread_rwlock_unlock(&w->lock);
    }
    log_free(prov.edits, prov.n_edits);
    free(text);
    if (st == LIE_OK)
        st = lie_cache_write(path, c, NULL, err);
    lie_cache_destroy(c);
    return st;
}

/* A whole cache while the update is pending: the last snapshot (finished
 * units hold their final content), every unit with a pending leaf left
 * unbuilt, as a partial cache of the edited scene (lie-build --resume with
 * the edit files finishes it to rst-update's bytes).  Never waits for the
 * constructor. */
static lie_status save_partial(view_world *w, const char *path, lie_error *err)
{
    pthread_rwlock_rdlock(&w->lock);
    lie_cache c = *w->cache;
    unsigned char *text = NULL;
    lie_env *env = NULL;
    lie_status st = session_log(w, c.edits, w->n_edits0, &c.edits, &c.n_edits, &text, path, err);
    lie_cache_edit *log = st == LIE_OK ? c.edits : NULL;
    int n_log = st == LIE_OK ? c.n_edits : 0;
    if (st == LIE_OK)
        st = lie_env_compact_units(w->render_env, &env, err);
    c.emitters = NULL;
    if (st == LIE_OK) {
        env->partial = 1;
        c.env = env;
        st = lie_cache_set_state(&c, w->scene, err);
    }
    if (st == LIE_OK)
        st = lie_cache_write(path, &c, NULL, err);
    pthread_rwlock_unlock(&w->lock);
    free(c.emitters);
    lie_env_destroy(env);
    log_free(log, n_log);
    free(text);
    return st;
}

lie_status view_world_save(view_world *w, const char *path, lie_error *err)
{
    if (w->failed)
        return unusable(w, err);
    if (w->ctor)
        return save_ctor(w, path, err);
    if (view_world_busy(w))
        return save_partial(w, path, err);
    view_world_wait(w);
    if (w->failed)
        return w->ctor_err.status ? (*err = w->ctor_err, err->status) : unusable(w, err);
    /* Committed: the cache holds the edited scene's state and environments.
     * Its log holds one entry per edit applied; a saved cache holds the
     * session as one entry, as rst-update CACHE EDITS.yaml writes it. */
    pthread_rwlock_rdlock(&w->lock);
    lie_cache c = *w->cache;
    unsigned char *text = NULL;
    lie_status st = session_log(w, c.edits, w->n_edits0, &c.edits, &c.n_edits, &text, path, err);
    if (st == LIE_OK)
        st = lie_cache_write(path, &c, NULL, err);
    pthread_rwlock_unlock(&w->lock);
    log_free(c.edits, c.n_edits); /* session_log's (NULL when it failed) */
    free(text);
    return st;
}
