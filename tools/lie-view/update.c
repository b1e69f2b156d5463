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
 * Undo applies an edit that restores what a group changed (a node's local
 * transform as it was, its materials as they were), so the record of the
 * session stays a plain edit file that rst-update replays exactly.  A
 * removal is undone by `restore`; an added object has no such inverse in
 * formats/edit.md and is not undone. */
#include "world_internal.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* ---- text ----------------------------------------------------------------- */

typedef struct buf {
    char *s;
    size_t n, cap;
    int nomem;
} buf;

static void put(buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(buf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (k < 0 || b->nomem)
        return;
    if (b->n + (size_t)k + 1 > b->cap) {
        size_t cap = (b->n + (size_t)k + 1) * 2;
        char *s = realloc(b->s, cap);
        if (!s) {
            b->nomem = 1;
            return;
        }
        b->s = s;
        b->cap = cap;
    }
    va_start(ap, fmt);
    vsnprintf(b->s + b->n, (size_t)k + 1, fmt, ap);
    va_end(ap);
    b->n += (size_t)k;
}

/* A node as edit files name it: '#N' always names it alone. */
static void ref(char *out, size_t size, int node) { snprintf(out, size, "'#%d'", node); }

/* The edit restoring what `e` is about to change, or NULL (*removes set)
 * when it adds a node (edit files have no operation taking an added node
 * out again; a removal is undone by `restore`).  Absolute values, so the order of the restoring
 * operations does not matter: a node's local transform, and per mesh node
 * of a subtree the first material's colour, metallic, roughness and
 * emission (a base colour texture that set-material dropped stays dropped). */
static char *inverse_of(const lie_scene *s, const lie_edit *e, int *removes)
{
    buf b = {0};
    uint8_t *done_tf = calloc((size_t)s->n_nodes + 1, 1), *done_mat = calloc((size_t)s->n_nodes + 1, 1);
    uint8_t *in = calloc((size_t)s->n_nodes + 1, 1);
    *removes = 0;
    for (int i = 0; done_tf && done_mat && in && i < e->n_ops; i++) {
        const lie_edit_op *op = &e->ops[i];
        int node;
        lie_error err;
        if (op->kind == LIE_EDIT_ADD) {
            *removes = 1;
            break;
        }
        if (lie_edit_find_node(s, op->node, &node, e->name, op->line, op->col, &err) != LIE_OK)
            continue;
        char r[32];
        if (op->kind == LIE_EDIT_REMOVE || op->kind == LIE_EDIT_RESTORE) {
            ref(r, sizeof r, node);
            put(&b, "- %s: {node: %s}\n", op->kind == LIE_EDIT_REMOVE ? "restore" : "remove", r);
            continue;
        }
        if (op->kind == LIE_EDIT_SET_MATERIAL || op->kind == LIE_EDIT_SET_EMISSION) {
            view_node_subtree(s, node, in);
            for (int n = 0; n < s->n_nodes; n++) {
                if (!in[n] || done_mat[n] || s->nodes[n].mesh < 0 || s->meshes[s->nodes[n].mesh].n_prims == 0)
                    continue;
                done_mat[n] = 1;
                const lie_material *m = lie_scene_material(s, s->meshes[s->nodes[n].mesh].prims[0].material);
                float peak = fmaxf(m->emissive[0], fmaxf(m->emissive[1], m->emissive[2]));
                ref(r, sizeof r, n);
                put(&b, "- set-material: {node: %s, base-color: [%.9g, %.9g, %.9g], metallic: %.9g, roughness: %.9g}\n",
                    r, m->base_color[0], m->base_color[1], m->base_color[2], m->metallic, m->roughness);
                if (peak > 0.0f)
                    put(&b, "- set-emission: {node: %s, emissive: [%.9g, %.9g, %.9g], strength: %.9g}\n", r,
                        m->emissive[0] / peak, m->emissive[1] / peak, m->emissive[2] / peak, peak);
                else
                    put(&b, "- set-emission: {node: %s, emissive: [0, 0, 0]}\n", r);
            }
        } else if (!done_tf[node]) {
            done_tf[node] = 1;
            const double *m = s->nodes[node].local.m;
            ref(r, sizeof r, node);
            put(&b, "- set-transform: {node: %s, matrix: [", r);
            for (int k = 0; k < 16; k++)
                put(&b, "%s%.17g", k ? ", " : "", m[k]);
            put(&b, "]}\n");
        }
    }
    int nomem = !done_tf || !done_mat || !in || b.nomem;
    free(done_tf);
    free(done_mat);
    free(in);
    if (nomem || *removes) {
        free(b.s);
        return NULL;
    }
    return b.s ? b.s : strdup("");
}

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

/* Parse, check the nodes, and if `inverse` is given work out the restoring
 * edit first. */
static lie_status prepare(view_world *w, const char *yaml, lie_edit **out, char **inverse, lie_error *err)
{
    *out = NULL;
    lie_status st = lie_edit_parse((const unsigned char *)yaml, strlen(yaml), edit_name(w), out, err);
    for (int i = 0; st == LIE_OK && i < (*out)->n_ops; i++) {
        const lie_edit_op *op = &(*out)->ops[i];
        int node;
        if (op->kind == LIE_EDIT_ADD)
            continue;
        st = lie_edit_find_node(w->scene, op->node, &node, (*out)->name, op->line, op->col, err);
        if (st == LIE_OK && w->scene->nodes[node].removed && op->kind != LIE_EDIT_RESTORE)
            st = lie_error_set_at(err, LIE_ERR_ARG, (*out)->name, op->line, op->col, "node '%s' was removed",
                                  op->node);
    }
    if (st == LIE_OK && inverse) {
        int removes;
        *inverse = inverse_of(w->scene, *out, &removes);
        if (!*inverse && !removes)
            st = lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
    }
    if (st != LIE_OK) {
        lie_edit_destroy(*out);
        *out = NULL;
    }
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
static lie_status apply(view_world *w, const lie_edit *e, const char *yaml, lie_error *err)
{
    double t0 = lie_time_now();
    lie_status st = LIE_OK;
    pthread_rwlock_wrlock(&w->lock);
    if (w->ctor)
        lie_ctor_hold(w->ctor); /* the unit in progress is dropped: the scene changes under it */
    if (w->up) {
        st = lie_update_edit(w->up, e, err); /* e holds yaml as its text (lie_edit_text) */
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
    if (st == LIE_OK) {
        size_t k = strlen(yaml);
        char *a = realloc(w->applied, w->n_applied + k + 1);
        if (a) {
            memcpy(a + w->n_applied, yaml, k + 1);
            w->applied = a;
            w->n_applied += k;
        } else {
            st = lie_error_set(err, LIE_ERR_NOMEM, w->input, "out of memory");
        }
    }
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

static int push_group(view_world *w, char *text, char *inverse)
{
    view_group *g = realloc(w->live, sizeof *g * ((size_t)w->n_live + 1));
    if (!g)
        return 0;
    w->live = g;
    g[w->n_live].text = text;
    g[w->n_live].inverse = inverse;
    w->n_live++;
    return 1;
}

static lie_status unusable(view_world *w, lie_error *err)
{
    return lie_error_set(err, LIE_ERR_ARG, w->input, "an earlier edit failed: edits are off");
}

lie_status view_world_edit(view_world *w, const char *yaml, int join, lie_error *err)
{
    if (w->failed)
        return unusable(w, err);
    join = join && w->n_live > 0;
    lie_edit *e = NULL;
    char *inverse = NULL;
    lie_status st = prepare(w, yaml, &e, join ? NULL : &inverse, err);
    if (st == LIE_OK)
        st = apply(w, e, yaml, err);
    lie_edit_destroy(e);
    if (st != LIE_OK) {
        free(inverse);
        return st;
    }
    /* the group: one drag's steps join; its inverse is from before the first */
    if (join) {
        view_group *g = &w->live[w->n_live - 1];
        size_t a = strlen(g->text), b = strlen(yaml);
        char *t = realloc(g->text, a + b + 1);
        if (t) {
            memcpy(t + a, yaml, b + 1);
            g->text = t;
        }
    } else {
        char *t = strdup(yaml);
        if (!t || !push_group(w, t, inverse)) {
            free(t);
            free(inverse);
        }
    }
    for (int i = 0; i < w->n_undone; i++)
        free(w->undone[i]);
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
    lie_edit *e = NULL;
    lie_status st = *g->inverse ? prepare(w, g->inverse, &e, NULL, err) : LIE_OK;
    if (st == LIE_OK && e)
        st = apply(w, e, g->inverse, err);
    lie_edit_destroy(e);
    if (st != LIE_OK)
        return st;
    char **u = realloc(w->undone, sizeof *u * ((size_t)w->n_undone + 1));
    if (u) {
        w->undone = u;
        u[w->n_undone++] = g->text;
    } else {
        free(g->text);
    }
    free(g->inverse);
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
    char *text = w->undone[w->n_undone - 1];
    lie_edit *e = NULL;
    char *inverse = NULL;
    lie_status st = prepare(w, text, &e, &inverse, err);
    if (st == LIE_OK)
        st = apply(w, e, text, err);
    lie_edit_destroy(e);
    if (st != LIE_OK) {
        free(inverse);
        return st;
    }
    w->n_undone--;
    if (!push_group(w, text, inverse)) {
        free(text);
        free(inverse);
    }
    *done = 1;
    return LIE_OK;
}

void world_free_session(view_world *w)
{
    for (int i = 0; i < w->n_live; i++) {
        free(w->live[i].text);
        free(w->live[i].inverse);
    }
    for (int i = 0; i < w->n_undone; i++)
        free(w->undone[i]);
    free(w->live);
    free(w->undone);
    free(w->applied);
}

/* ---- the constructor ----------------------------------------------------------- */

void *world_constructor_main(void *arg)
{
    view_world *w = arg;
    size_t step = 16;
    double last_publish = 0.0;
    for (;;) {
        pthread_mutex_lock(&w->cm);
        while (!w->quit && ((atomic_load(&w->n_pending) == 0 && !atomic_load(&w->dirty)) || w->failed))
            pthread_cond_wait(&w->ccv, &w->cm);
        int quit = w->quit;
        pthread_mutex_unlock(&w->cm);
        if (quit)
            break;
        /* phase 2 reads the scene only: renders go on; edits wait */
        double t0 = lie_time_now();
        pthread_rwlock_rdlock(&w->lock);
        uint64_t epoch = w->epoch;
        size_t remaining = 0;
        lie_env *snap = NULL;
        lie_lie_vis *vis = NULL;
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
            st = lie_lie_vis_create(w->scene, snap, &vis, &err);
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
            lie_lie_vis_destroy(w->vis);
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
        lie_lie_vis_destroy(vis);
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
        if ((atomic_load(&w->n_pending) == 0 && !atomic_load(&w->dirty)) || w->failed)
            pthread_cond_broadcast(&w->ccv);
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
    while ((atomic_load(&w->n_pending) > 0 || atomic_load(&w->dirty)) && w->ctor_started && !w->failed)
        pthread_cond_wait(&w->ccv, &w->cm);
    pthread_mutex_unlock(&w->cm);
}

/* ---- saving ---------------------------------------------------------------------- */

lie_status view_world_write_record(view_world *w, lie_error *err)
{
    if (!w->opt.record)
        return LIE_OK;
    lie_atomic_file af;
    lie_status st = lie_atomic_open(&af, w->opt.record, err);
    if (st != LIE_OK)
        return st;
    if (w->n_applied && fwrite(w->applied, 1, w->n_applied, af.fp) != w->n_applied) {
        lie_atomic_abort(&af);
        return lie_error_set(err, LIE_ERR_IO, w->opt.record, "write failed");
    }
    return lie_atomic_commit(&af, err);
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
    int n0 = w->cache ? w->n_edits0 : 0;
    lie_cache_edit *log = malloc(sizeof *log * ((size_t)n0 + 1));
    if (!log)
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    if (n0)
        memcpy(log, w->cache->edits, sizeof *log * (size_t)n0);
    prov.edits = log;
    prov.n_edits = n0;
    if (w->n_applied) {
        log[n0].name = (char *)edit_name(w);
        log[n0].text = (unsigned char *)w->applied;
        log[n0].size = w->n_applied;
        prov.n_edits++;
    }
    pthread_rwlock_rdlock(&w->lock);
    lie_cache *c = NULL;
    lie_status st = lie_ctor_cache(w->ctor, &prov, &c, err);
    pthread_rwlock_unlock(&w->lock);
    free(log);
    if (st == LIE_OK)
        st = lie_cache_write(path, c, NULL, err);
    lie_cache_destroy(c);
    return st;
}

lie_status view_world_save(view_world *w, const char *path, lie_error *err)
{
    if (w->failed)
        return unusable(w, err);
    if (w->ctor)
        return save_ctor(w, path, err);
    view_world_wait(w);
    if (w->failed)
        return w->ctor_err.status ? (*err = w->ctor_err, err->status) : unusable(w, err);
    /* Committed: the cache holds the edited scene's state and environments.
     * Its log holds one entry per edit applied; a saved cache holds the
     * session as one entry, as rst-update CACHE EDITS.yaml writes it. */
    pthread_rwlock_rdlock(&w->lock);
    lie_cache c = *w->cache;
    lie_cache_edit *log = malloc(sizeof *log * ((size_t)w->n_edits0 + 1));
    lie_status st = LIE_OK;
    if (!log) {
        st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    } else {
        memcpy(log, c.edits, sizeof *log * (size_t)w->n_edits0);
        c.edits = log;
        c.n_edits = w->n_edits0;
        if (w->n_applied) {
            log[c.n_edits].name = (char *)edit_name(w);
            log[c.n_edits].text = (unsigned char *)w->applied;
            log[c.n_edits].size = w->n_applied;
            c.n_edits++;
        }
        st = lie_cache_write(path, &c, NULL, err);
    }
    pthread_rwlock_unlock(&w->lock);
    free(log);
    return st;
}
