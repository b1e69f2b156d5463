/* SPDX-License-Identifier: Apache-2.0 */
/* The asynchronous constructor (§4.3, §4.3.1): local illumination
 * environments built while a program renders from them, those its current
 * view sees first (lib/update/update.h, lie_ctor).
 *
 * The live env.  Units land a triangle at a time (a triangle's units are
 * one contiguous range, lie_env_build_units), so the env a renderer reads
 * is kept in place: one root per unit, pointing at node 0 (a shared
 * LIE_CLASS_NONE leaf) until its unit lands, and node and list arrays that
 * only grow at their ends.  Publishing a triangle appends its nodes and
 * lists and points its roots at them, under the write side of env_lock,
 * which renders take for reading: the cost of a landing is the size of
 * what landed (and a doubling of the arrays now and then), never a copy
 * of the whole env.  A unit built again (the views grew, an edit reached
 * it) leaves its old nodes unreachable; lie_env_compact lays the env out
 * as one build does when it is saved.
 *
 * The order.  Triangles are taken by the pixels their hits cover in the
 * current view (lie_camera_pixels: mirrors included), then by their hits
 * in all the views, then by index: what the camera sees most lands first.
 * A new view reorders what is pending and adds its triangles.
 *
 * What is built is what lie-build --view gives for the same views (or,
 * without views, lie-build's whole build): a unit depends on its triangle,
 * its cluster and its triangle's pixels only (lib/lie/lie.h), so building
 * units one by one, in any order and on any thread, gives the same trees.
 * A view added later changes the pixels of triangles already built; those
 * whose decisions the new pixels can change (lie_env_tri_stale) are built
 * again.  An edit (lie_ctor_edited) sends back the landed units whose
 * shafts the edited geometry may reach, and their nodes it may reach are
 * recomputed, the others copied, as rst-update recomputes them (§5.3;
 * lie_env_build_units with the units' old trees). */
#include "update/internal.h"
#include "shade/shade.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* READY: built, waiting to land (counted pending, as BUSY is) */
enum { TRI_UNSEEN = 0, TRI_PENDING = 1, TRI_BUSY = 2, TRI_BUILT = 3, TRI_READY = 4 };

/* Pixels shared by the workers building from them and the constructor,
 * freed by whoever lets go last. */
typedef struct pxref {
    lie_pixels *px;
    int refs;
} pxref;

/* Units of a triangle, built, waiting for the write side of env_lock: all
 * of them, or (after an edit) a run of the units it sent back, the
 * triangle's last run marked. */
typedef struct ready_part {
    uint32_t t;
    int last;
    lie_env_part part;
    pxref *px; /* the pixels it was built for */
} ready_part;

struct lie_ctor {
    lie_scene *s;
    const lie_rt *rt;
    lie_ctor_options o;
    lie_build_params p; /* one thread per build: the constructor's threads are the parallelism */
    size_t ne;
    /* the live env (env_lock) */
    pthread_rwlock_t env_lock;
    lie_env env;
    size_t cap_nodes, cap_pool;
    _Atomic uint64_t version;
    uint32_t longest;
    /* the queue (m) */
    pthread_mutex_t m;
    pthread_cond_t cv;      /* work arrived, a hold ended, quit */
    pthread_cond_t idle_cv; /* a worker put its work down */
    uint8_t *state;         /* per triangle */
    uint32_t *order;
    size_t n_order, cursor;
    int order_dirty;
    int views_mode;         /* built for views (lie-build --view), or whole (lie-build) */
    pxref *px;              /* the views' pixels (NULL: no view yet, or a whole build) */
    pxref *cur;             /* the current view's pixels: the order (NULL: none yet) */
    lie_cache_views views;
    lie_camera want;
    int want_set;
    int fixed;              /* the views were given at the start: lie_ctor_view orders only */
    int resample;           /* an edit changed the scene: the views are sampled again */
    int resampling;         /* a thread is at it: nothing is built meanwhile */
    uint64_t edits;         /* edits so far (a sampling of an older scene is dropped) */
    int hold, quit, busy, failed;
    lie_error err;
    volatile sig_atomic_t stop;
    uint64_t pending;       /* triangles pending, being built or ready */
    ready_part *ready;      /* built, not landed yet (see land_ready) */
    size_t n_ready, cap_ready;
    /* After an edit a pending triangle may keep most of its units: only
     * those an edit reached (redo, per unit) are built again, the others
     * stay landed (some_tri: triangle t is pending so).  Invariant: a
     * triangle without some_tri has no redo unit.  A redo unit whose own
     * patch and emitter stayed keeps its old tree in the env, unreachable
     * from its root (redo_root: that tree's root, 0 for a unit built
     * afresh), and nflags marks the old trees' nodes an edit may have
     * changed (n_nflags: the env's nodes at the last edit; nodes landed
     * since are in no old tree): only those are recomputed. */
    uint8_t *redo, *some_tri;
    uint32_t *redo_root;
    uint8_t *nflags;
    size_t n_nflags;
    uint64_t units_built, nodes_built;
    double t0;
    lie_ctor_sample *samples;
    size_t n_samples, cap_samples;
    /* the geometry the landed units were built on (edits compare against it) */
    lie_vec3 *tri_p;
    lie_emitter *em;        /* the emitters as they were (their geometry and light; pointers unused) */
    int n_em;
    uint32_t n_tris;
    float max_tri_area, ray_far;
    double whole_area;      /* lie_whole_area: a whole build's model reads it */
    pthread_t *tids;
    int n_threads;
};

lie_ctor_options lie_ctor_options_default(void)
{
    lie_ctor_options o;
    memset(&o, 0, sizeof o);
    o.threads = 0;
    o.params = lie_build_params_default();
    o.view_width = o.view_height = 512;
    o.max_depth = LIE_MAX_DEPTH_DEFAULT;
    return o;
}

/* ---- pixels ------------------------------------------------------------------ */

static pxref *px_wrap(lie_pixels *px)
{
    pxref *r = malloc(sizeof *r);
    if (!r) {
        lie_pixels_destroy(px);
        return NULL;
    }
    r->px = px;
    r->refs = 1;
    return r;
}

/* Call with m held. */
static void px_drop(pxref *r)
{
    if (r && --r->refs == 0) {
        lie_pixels_destroy(r->px);
        free(r);
    }
}

static uint64_t tri_hits(const pxref *r, uint32_t t) { return r ? r->px->first[t + 1] - r->px->first[t] : 0; }

/* Whether the views see triangle t (every triangle is seen by a whole build). */
static int seen_by(const lie_ctor *c, const pxref *px, uint32_t t) { return !c->views_mode || tri_hits(px, t) > 0; }

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* ---- the live env (env_lock held for writing, or no reader yet) ---------------- */

static int reserve(void **a, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 1;
    size_t n = *cap ? *cap : 1024;
    while (n < need)
        n *= 2;
    void *b = realloc(*a, n * elem);
    if (!b)
        return 0;
    *a = b;
    *cap = n;
    return 1;
}

/* Every unit of triangle t back to the shared unbuilt leaf: all of them
 * to build again. */
static void unland(lie_ctor *c, uint32_t t)
{
    for (size_t e = 0; e < c->ne; e++) {
        c->env.root[(size_t)t * c->ne + e] = 0;
        c->redo[(size_t)t * c->ne + e] = 0;
        c->redo_root[(size_t)t * c->ne + e] = 0;
    }
    c->some_tri[t] = 0;
}

/* Triangle t's redo units are done (all landed). */
static void redone(lie_ctor *c, uint32_t t)
{
    memset(c->redo + (size_t)t * c->ne, 0, c->ne);
    memset(c->redo_root + (size_t)t * c->ne, 0, sizeof *c->redo_root * c->ne);
    c->some_tri[t] = 0;
}

/* Triangle t holds units built: landed, or pending only in some. */
static int has_landed(const lie_ctor *c, uint32_t t)
{
    return c->state[t] == TRI_BUILT || (c->state[t] == TRI_PENDING && c->some_tri[t]);
}

/* Land a part (one triangle's units): its nodes and lists at the arrays' ends. */
static int land(lie_ctor *c, const lie_env_part *part)
{
    uint64_t nn = (uint64_t)c->env.n_nodes + part->n_nodes, np = (uint64_t)c->env.n_pool + part->n_pool;
    if (nn >= 0xFFFFFFF0u || np >= 0xFFFFFFF0u || !reserve((void **)&c->env.nodes, &c->cap_nodes, nn, sizeof(lie_pnode)) ||
        !reserve((void **)&c->env.pool, &c->cap_pool, np + 1, sizeof(uint32_t)))
        return 0;
    uint32_t nb = c->env.n_nodes, pb = c->env.n_pool;
    for (uint32_t i = 0; i < part->n_nodes; i++) {
        lie_pnode x = part->nodes[i];
        if (x.child)
            x.child += nb;
        if (x.cls == LIE_CLASS_PARTIAL) {
            x.list += pb;
            if (x.count > c->longest)
                c->longest = x.count;
        }
        c->env.nodes[nb + i] = x;
    }
    if (part->n_pool)
        memcpy(c->env.pool + pb, part->pool, sizeof *c->env.pool * part->n_pool);
    c->env.n_nodes += part->n_nodes;
    c->env.n_pool += part->n_pool;
    for (uint64_t i = 0; i < part->n_units; i++)
        c->env.root[part->first_unit + i] = nb + part->root[i];
    return 1;
}

static void env_reset(lie_ctor *c)
{
    size_t n_units = (size_t)c->s->n_tris * c->ne;
    for (size_t u = 0; u < n_units; u++)
        c->env.root[u] = c->redo_root[u] = 0;
    c->env.n_nodes = 1;
    c->env.n_pool = 0;
    free(c->nflags); /* the nodes are landed again from 1 */
    c->nflags = NULL;
    c->n_nflags = 0;
}

/* ---- the queue (m held) ------------------------------------------------------- */

static void sample_stats(lie_ctor *c)
{
    double t = lie_time_now() - c->t0;
    /* a sample every 50 ms at most: the curve, not every landing */
    if (c->n_samples && t - c->samples[c->n_samples - 1].seconds < 0.05 && c->pending) {
        c->samples[c->n_samples - 1].units = c->units_built;
        return;
    }
    if (c->n_samples == c->cap_samples) {
        size_t cap = c->cap_samples ? 2 * c->cap_samples : 64;
        lie_ctor_sample *s = realloc(c->samples, sizeof *s * cap);
        if (!s)
            return;
        c->samples = s;
        c->cap_samples = cap;
    }
    c->samples[c->n_samples].seconds = t;
    c->samples[c->n_samples].units = c->units_built;
    c->n_samples++;
}

static void set_state(lie_ctor *c, uint32_t t, int st)
{
    int was = c->state[t];
    c->pending -= (uint64_t)(was == TRI_PENDING || was == TRI_BUSY || was == TRI_READY);
    c->pending += (uint64_t)(st == TRI_PENDING || st == TRI_BUSY || st == TRI_READY);
    c->state[t] = (uint8_t)st;
    if (st == TRI_PENDING && was != TRI_PENDING) {
        c->order_dirty = 1;
        /* work for every idle builder: a view sampled by one of them made
         * the view's triangles pending, and the others slept on */
        pthread_cond_broadcast(&c->cv);
    }
}

/* The pending triangles by decreasing hits in the current view, then in
 * all the views, then by index. */
static int make_order(lie_ctor *c)
{
    uint32_t n = c->s->n_tris;
    size_t k = 0;
    uint64_t *key = malloc(sizeof *key * ((size_t)n + 1));
    uint32_t *ord = realloc(c->order, sizeof *ord * ((size_t)n + 1));
    if (!key || !ord) {
        free(key);
        if (ord)
            c->order = ord;
        return 0;
    }
    c->order = ord;
    /* a sort by one 64-bit key: current hits (20 bits), all hits (12 bits,
     * saturated), index */
    for (uint32_t t = 0; t < n; t++) {
        if (c->state[t] != TRI_PENDING)
            continue;
        uint64_t h = tri_hits(c->cur, t), a = tri_hits(c->px, t);
        h = h > 0xFFFFF ? 0xFFFFF : h;
        a = a > 0xFFF ? 0xFFF : a;
        key[k++] = ((uint64_t)(0xFFFFF - h) << 44) | ((uint64_t)(0xFFF - a) << 32) | t;
    }
    qsort(key, k, sizeof *key, cmp_u64);
    for (size_t i = 0; i < k; i++)
        ord[i] = (uint32_t)key[i];
    free(key);
    c->n_order = k;
    c->cursor = 0;
    c->order_dirty = 0;
    return 1;
}

/* The next triangle to build, or -1. */
static int64_t next_tri(lie_ctor *c)
{
    if (c->order_dirty && !make_order(c))
        return -1;
    while (c->cursor < c->n_order && c->state[c->order[c->cursor]] != TRI_PENDING)
        c->cursor++;
    return c->cursor < c->n_order ? (int64_t)c->order[c->cursor++] : -1;
}

/* Which triangles the views ask for: pending where seen and not landed. */
static void mark_seen(lie_ctor *c)
{
    for (uint32_t t = 0; t < c->s->n_tris; t++)
        if (c->state[t] == TRI_UNSEEN && seen_by(c, c->px, t))
            set_state(c, t, TRI_PENDING);
}

static void fail(lie_ctor *c, const lie_error *err)
{
    if (!c->failed) {
        c->failed = 1;
        c->err = *err;
    }
    pthread_cond_broadcast(&c->idle_cv);
}

/* ---- the workers ------------------------------------------------------------------ */

static int same_camera(const lie_camera *a, const lie_camera *b)
{
    lie_camera x = *a, y = *b;
    x.name = y.name = NULL;
    return memcmp(&x, &y, sizeof x) == 0;
}

/* A view asked for (m held on entry and exit; released while sampling). */
static void take_view(lie_ctor *c)
{
    lie_camera cam = c->want;
    cam.name = NULL;
    c->want_set = 0;
    int known = 0;
    for (int i = 0; i < c->views.n_cams; i++)
        known |= same_camera(&c->views.cams[i], &cam);
    int add = c->views_mode && !known && !c->fixed;
    c->busy++;
    pthread_mutex_unlock(&c->m);
    lie_error err;
    lie_pixels *cur = NULL, *merged = NULL;
    lie_status st = lie_camera_pixels(c->s, c->rt, &cam, 1, c->o.view_width, c->o.view_height, c->o.max_depth, &cur,
                                      &err);
    if (st == LIE_OK && add && c->px)
        st = lie_pixels_merge(c->px->px, cur, &merged, &err);
    lie_camera *cams = st == LIE_OK && add ? realloc(c->views.cams, sizeof *cams * ((size_t)c->views.n_cams + 2)) : NULL;
    if (st == LIE_OK && add && !cams)
        st = lie_error_set(&err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    pthread_mutex_lock(&c->m);
    c->busy--;
    if (st != LIE_OK) {
        lie_pixels_destroy(cur);
        lie_pixels_destroy(merged);
        fail(c, &err);
        return;
    }
    pxref *cr = px_wrap(cur);
    if (!cr) {
        lie_pixels_destroy(merged);
        lie_error_set(&err, LIE_ERR_NOMEM, c->s->path, "out of memory");
        fail(c, &err);
        return;
    }
    px_drop(c->cur);
    c->cur = cr;
    c->order_dirty = 1;
    if (add) {
        c->views.cams = cams;
        c->views.cams[c->views.n_cams++] = cam;
        pxref *old = c->px, *nw = merged ? px_wrap(merged) : cr; /* the first view: its pixels are all */
        if (!nw) {
            lie_error_set(&err, LIE_ERR_NOMEM, c->s->path, "out of memory");
            fail(c, &err);
            return;
        }
        if (nw == cr)
            cr->refs++;
        /* landed triangles whose decisions the new pixels change go again;
         * so does one whose units an edit sent back to be recomputed
         * where it reached, if its pixels changed: the rest of their old
         * trees was decided for the old pixels */
        pthread_rwlock_wrlock(&c->env_lock);
        for (uint32_t t = 0; old && t < c->s->n_tris; t++)
            if (has_landed(c, t) &&
                (lie_env_tri_stale(&c->env, c->s, old->px, nw->px, t) ||
                 (c->some_tri[t] && lie_pixels_tri_hash(old->px, t) != lie_pixels_tri_hash(nw->px, t)))) {
                unland(c, t);
                set_state(c, t, TRI_PENDING);
            }
        pthread_rwlock_unlock(&c->env_lock);
        c->px = nw;
        px_drop(old);
        mark_seen(c);
        atomic_fetch_add(&c->version, 1);
    }
    pthread_cond_broadcast(&c->idle_cv);
}

/* After an edit (m held on entry and exit; released while sampling): the
 * views' pixels on the edited scene.  Landed triangles whose pixels changed
 * go again (their units may split otherwise), and triangles the views
 * now see or no longer see are added or dropped.  Until then, units built
 * for the old pixels answer shadow rays as well as any: only how finely
 * they are split differs. */
static void take_resample(lie_ctor *c)
{
    uint64_t edits = c->edits;
    c->resampling = 1;
    c->busy++;
    int n = c->views.n_cams;
    lie_camera *cams = malloc(sizeof *cams * ((size_t)n + 1));
    lie_camera cam = c->want;
    int has_cur = c->cur != NULL;
    if (cams && n)
        memcpy(cams, c->views.cams, sizeof *cams * (size_t)n);
    pthread_mutex_unlock(&c->m);
    lie_error err;
    lie_pixels *px = NULL, *cur = NULL;
    lie_status st = cams ? LIE_OK : lie_error_set(&err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    if (st == LIE_OK && n)
        st = lie_camera_pixels(c->s, c->rt, cams, n, c->o.view_width, c->o.view_height, c->o.max_depth, &px, &err);
    /* the current view is often the only view (one still camera): its
     * pixels are the views' */
    int cur_is_views = has_cur && n == 1 && same_camera(&cams[0], &cam);
    if (st == LIE_OK && has_cur && !cur_is_views)
        st = lie_camera_pixels(c->s, c->rt, &cam, 1, c->o.view_width, c->o.view_height, c->o.max_depth, &cur, &err);
    free(cams);
    pxref *npx = st == LIE_OK && px ? px_wrap(px) : NULL, *ncur = st == LIE_OK && cur ? px_wrap(cur) : NULL;
    if (st == LIE_OK && ((px && !npx) || (cur && !ncur)))
        st = lie_error_set(&err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    if (st == LIE_OK && cur_is_views && npx) {
        ncur = npx;
        npx->refs++;
    }
    pthread_mutex_lock(&c->m);
    c->busy--;
    c->resampling = 0;
    if (st != LIE_OK) {
        px_drop(npx);
        px_drop(ncur);
        fail(c, &err);
        return;
    }
    if (c->edits != edits) { /* another edit meanwhile: sampled again for it */
        px_drop(npx);
        px_drop(ncur);
        pthread_cond_broadcast(&c->idle_cv);
        pthread_cond_broadcast(&c->cv);
        return;
    }
    c->resample = 0;
    if (npx) {
        pthread_rwlock_wrlock(&c->env_lock);
        for (uint32_t t = 0; t < c->s->n_tris; t++) {
            int seen = tri_hits(npx, t) > 0;
            int changed = has_landed(c, t) && lie_pixels_tri_hash(c->px->px, t) != lie_pixels_tri_hash(npx->px, t);
            if (changed)
                unland(c, t);
            if (!seen) {
                unland(c, t);
                set_state(c, t, TRI_UNSEEN);
            } else if (changed) {
                set_state(c, t, TRI_PENDING);
            } else if (seen && c->state[t] == TRI_UNSEEN) {
                set_state(c, t, TRI_PENDING);
            }
        }
        pthread_rwlock_unlock(&c->env_lock);
        px_drop(c->px);
        c->px = npx;
    }
    if (ncur) {
        px_drop(c->cur);
        c->cur = ncur;
    }
    c->order_dirty = 1;
    atomic_fetch_add(&c->version, 1);
    pthread_cond_broadcast(&c->idle_cv);
    pthread_cond_broadcast(&c->cv);
}

/* Land what is ready (m held on entry and exit).  Landing takes env_lock
 * for writing, which a renderer holds for reading while it draws a band
 * (a tenth of a second and more): a builder that waited for it would build
 * one triangle a band.  So builders only try the lock (wait 0) and go on
 * building; what they could not land waits here, and lands at the next
 * try: a builder's next triangle, an idle builder's poll, a reader between
 * two bands (lie_ctor_read_lock) or a hold.  wait: block for the lock (a
 * hold: every unit built must be in the env before the scene changes or
 * the env is saved).  A triangle built for pixels the views have since
 * outgrown goes again if the new ones change it. */
static void land_ready(lie_ctor *c, int wait)
{
    if (c->n_ready == 0)
        return;
    if (wait)
        pthread_rwlock_wrlock(&c->env_lock);
    else if (pthread_rwlock_trywrlock(&c->env_lock) != 0)
        return;
    for (size_t i = 0; i < c->n_ready; i++) {
        ready_part *r = &c->ready[i];
        if (c->failed || !land(c, &r->part)) {
            if (!c->failed) {
                lie_error err;
                lie_error_set(&err, LIE_ERR_NOMEM, c->s->path, "out of memory for the constructor's environments");
                fail(c, &err);
            }
            set_state(c, r->t, TRI_PENDING);
        } else if (!r->last) {
            c->units_built += r->part.n_units; /* more of the triangle follows */
        } else if (r->px && r->px != c->px && lie_env_tri_stale(&c->env, c->s, r->px->px, c->px->px, r->t)) {
            unland(c, r->t);
            set_state(c, r->t, TRI_PENDING);
        } else {
            redone(c, r->t);
            set_state(c, r->t, TRI_BUILT);
            c->units_built += r->part.n_units;
        }
        lie_env_part_free(&r->part);
        px_drop(r->px);
    }
    c->n_ready = 0;
    pthread_rwlock_unlock(&c->env_lock);
    sample_stats(c);
    atomic_fetch_add(&c->version, 1);
    pthread_cond_broadcast(&c->idle_cv);
}

/* The old trees of triangle t's units an edit sent back to be recomputed
 * where it reached (redo_root), copied out of the live env with their
 * flags (m held: the builder reads them while units land and the env's
 * arrays move): old's root[e] is unit e's copy, old_unit[e] e, or -1 for a
 * unit to build afresh.  0: out of memory. */
typedef struct old_trees {
    lie_env env;
    int32_t *old_unit;
    uint8_t *flags;
} old_trees;

static void old_trees_free(old_trees *o)
{
    free(o->env.root);
    free(o->env.nodes);
    free(o->env.pool);
    free(o->old_unit);
    free(o->flags);
    memset(o, 0, sizeof *o);
}

static int old_trees_copy(lie_ctor *c, uint32_t t, const uint8_t *want, old_trees *o)
{
    memset(o, 0, sizeof *o);
    const uint32_t *rr = c->redo_root + (size_t)t * c->ne;
    uint32_t nodes = 0, pool = 0;
    pthread_rwlock_rdlock(&c->env_lock);
    for (size_t e = 0; e < c->ne; e++)
        if (want[e] && rr[e])
            lie_update_subtree_size(&c->env, rr[e], &nodes, &pool);
    if (nodes == 0) {
        pthread_rwlock_unlock(&c->env_lock);
        return 1; /* every unit built afresh */
    }
    o->env.root = malloc(sizeof *o->env.root * (c->ne + 1));
    o->env.nodes = malloc(sizeof *o->env.nodes * ((size_t)nodes + 1));
    o->env.pool = malloc(sizeof *o->env.pool * ((size_t)pool + 1));
    o->old_unit = malloc(sizeof *o->old_unit * (c->ne + 1));
    o->flags = malloc((size_t)nodes + 1);
    int ok = o->env.root && o->env.nodes && o->env.pool && o->old_unit && o->flags;
    for (size_t e = 0; ok && e < c->ne; e++) {
        o->old_unit[e] = -1;
        o->env.root[e] = 0;
        if (!want[e] || !rr[e])
            continue;
        uint32_t idx = o->env.n_nodes++;
        o->env.root[e] = idx;
        o->old_unit[e] = (int32_t)e;
        lie_update_copy_subtree(&c->env, c->nflags, rr[e], &o->env, o->flags, idx);
    }
    pthread_rwlock_unlock(&c->env_lock);
    if (!ok)
        old_trees_free(o);
    return ok;
}

/* Build triangle t (m held on entry and exit): all its units, or those
 * an edit sent back (redo), each run of them one part; it lands when the
 * env is free (land_ready). */
static void build_tri(lie_ctor *c, uint32_t t)
{
    set_state(c, t, TRI_BUSY);
    pxref *px = c->px;
    if (px)
        px->refs++;
    c->busy++;
    uint8_t *want = malloc(c->ne + 1); /* the units to build, read under m */
    int some = c->some_tri[t];
    for (size_t e = 0; want && e < c->ne; e++)
        want[e] = !some || c->redo[(size_t)t * c->ne + e];
    old_trees old;
    memset(&old, 0, sizeof old);
    int old_ok = want && (!some || old_trees_copy(c, t, want, &old));
    pthread_mutex_unlock(&c->m);
    lie_env_part *parts = calloc(c->ne + 1, sizeof *parts);
    size_t n_parts = 0;
    uint64_t nodes = 0;
    lie_error err;
    lie_status st = want && parts && old_ok ? LIE_OK : lie_error_set(&err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    int interrupted = 0;
    for (size_t e = 0; st == LIE_OK && !interrupted && e < c->ne;) {
        if (!want[e]) {
            e++;
            continue;
        }
        size_t e1 = e;
        while (e1 < c->ne && want[e1])
            e1++;
        lie_build_stats bs;
        lie_units_old from = {&old.env, old.old_unit ? old.old_unit + e : NULL, old.flags};
        st = lie_env_build_units(c->s, c->rt, &c->p, px ? px->px : NULL, (uint64_t)t * c->ne + e, e1 - e,
                                 old.old_unit ? &from : NULL, &c->stop, &parts[n_parts], &bs, &err);
        if (st == LIE_OK)
            n_parts++;
        for (int d = 0; st == LIE_OK && d <= LIE_PATCH_MAX_DEPTH; d++)
            nodes += bs.patches_per_depth[d];
        interrupted = st == LIE_OK && bs.units_interrupted > 0;
        e = e1;
    }
    free(want);
    old_trees_free(&old);
    pthread_mutex_lock(&c->m);
    c->busy--;
    if (st == LIE_OK && !interrupted &&
        !reserve((void **)&c->ready, &c->cap_ready, c->n_ready + n_parts + 1, sizeof *c->ready))
        st = lie_error_set(&err, LIE_ERR_NOMEM, c->s->path, "out of memory for the constructor's environments");
    if (st != LIE_OK || interrupted || n_parts == 0) {
        for (size_t i = 0; i < n_parts; i++)
            lie_env_part_free(&parts[i]);
        int nothing = n_parts == 0 && st == LIE_OK && !interrupted; /* no unit was sent back */
        if (nothing)
            c->some_tri[t] = 0;
        set_state(c, t, nothing ? TRI_BUILT : TRI_PENDING);
        if (st != LIE_OK)
            fail(c, &err); /* (interrupted: a hold stopped it, again later) */
        px_drop(px);
    } else {
        c->nodes_built += nodes;
        for (size_t i = 0; i < n_parts; i++) {
            if (i > 0 && px)
                px->refs++;
            c->ready[c->n_ready++] = (ready_part){t, i + 1 == n_parts, parts[i], px};
        }
        set_state(c, t, TRI_READY);
        land_ready(c, 0);
    }
    free(parts);
    pthread_cond_broadcast(&c->idle_cv);
}

/* Wait on cv for at most `seconds` (m held). */
static void timed_wait(pthread_cond_t *cv, pthread_mutex_t *m, double seconds)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    double ns = (double)ts.tv_nsec + seconds * 1e9;
    ts.tv_sec += (time_t)(ns / 1e9);
    ts.tv_nsec = (long)fmod(ns, 1e9);
    pthread_cond_timedwait(cv, m, &ts);
}

static void *worker_main(void *arg)
{
    lie_ctor *c = arg;
    pthread_mutex_lock(&c->m);
    for (;;) {
        while (!c->quit && (c->hold || c->failed || (!c->want_set && !c->resample && c->pending == 0)))
            pthread_cond_wait(&c->cv, &c->m);
        if (c->quit)
            break;
        if (c->resample && !c->resampling && c->busy == 0) {
            take_resample(c);
            continue;
        }
        if (c->resample) { /* nothing is built on the old pixels meanwhile */
            pthread_cond_wait(&c->cv, &c->m);
            continue;
        }
        if (c->want_set) {
            take_view(c);
            continue;
        }
        int64_t t = next_tri(c);
        if (t < 0 && c->n_ready) {
            /* nothing to build but what waits to land: poll the lock */
            land_ready(c, 0);
            if (c->n_ready)
                timed_wait(&c->cv, &c->m, 0.002);
            continue;
        }
        if (t < 0) {
            if (c->order_dirty)
                c->failed = 1; /* out of memory for the order */
            else
                pthread_cond_wait(&c->cv, &c->m); /* the rest is being built */
            continue;
        }
        build_tri(c, (uint32_t)t);
    }
    pthread_mutex_unlock(&c->m);
    return NULL;
}

/* ---- life ----------------------------------------------------------------------- */

/* Whether units are decided by a whole build's model (lie_whole_pixels):
 * no views, and the parameters ask for it. */
static int whole_model(const lie_ctor *c) { return !c->views_mode && c->p.frames && c->p.whole_pixels; }

static void keep_geometry(lie_ctor *c)
{
    memcpy(c->tri_p, c->s->tri_p, sizeof *c->tri_p * 3 * (size_t)c->s->n_tris);
    if (c->s->n_emitters)
        memcpy(c->em, c->s->emitters, sizeof *c->em * (size_t)c->s->n_emitters);
    c->n_em = c->s->n_emitters;
    c->n_tris = c->s->n_tris;
    c->max_tri_area = c->s->max_tri_area;
    c->ray_far = lie_pair_ray_far(c->s);
    c->whole_area = lie_whole_area(c->s);
}

void lie_ctor_destroy(lie_ctor *c)
{
    if (!c)
        return;
    pthread_mutex_lock(&c->m);
    c->quit = 1;
    c->stop = 1;
    pthread_cond_broadcast(&c->cv);
    pthread_mutex_unlock(&c->m);
    for (int i = 0; i < c->n_threads; i++)
        pthread_join(c->tids[i], NULL);
    free(c->tids);
    free(c->env.root);
    free(c->env.nodes);
    free(c->env.pool);
    px_drop(c->px);
    px_drop(c->cur);
    free(c->views.cams);
    free(c->state);
    free(c->redo);
    free(c->redo_root);
    free(c->nflags);
    free(c->some_tri);
    free(c->order);
    free(c->samples);
    for (size_t i = 0; i < c->n_ready; i++) {
        lie_env_part_free(&c->ready[i].part);
        px_drop(c->ready[i].px);
    }
    free(c->ready);
    free(c->tri_p);
    free(c->em);
    pthread_rwlock_destroy(&c->env_lock);
    pthread_mutex_destroy(&c->m);
    pthread_cond_destroy(&c->cv);
    pthread_cond_destroy(&c->idle_cv);
    free(c);
}

/* The env and views a seed cache brings (its landed units kept). */
static lie_status seed(lie_ctor *c, const lie_cache *from, lie_error *err)
{
    const lie_env *e = from->env;
    size_t n_units = (size_t)c->s->n_tris * c->ne;
    if (e->n_tris != c->s->n_tris || (size_t)e->n_clusters != c->ne)
        return lie_error_set(err, LIE_ERR_ARG, c->s->path, "the cache was built for another scene");
    if (!reserve((void **)&c->env.nodes, &c->cap_nodes, (size_t)e->n_nodes + 1, sizeof(lie_pnode)) ||
        !reserve((void **)&c->env.pool, &c->cap_pool, (size_t)e->n_pool + 1, sizeof(uint32_t)))
        return lie_error_set(err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    /* node 0 stays the shared unbuilt leaf: the cache's nodes follow it */
    for (uint32_t i = 0; i < e->n_nodes; i++) {
        lie_pnode x = e->nodes[i];
        if (x.child)
            x.child += 1;
        if (x.cls == LIE_CLASS_PARTIAL && x.count > c->longest)
            c->longest = x.count;
        c->env.nodes[1 + i] = x;
    }
    if (e->n_pool)
        memcpy(c->env.pool, e->pool, sizeof *c->env.pool * e->n_pool);
    c->env.n_nodes = 1 + e->n_nodes;
    c->env.n_pool = e->n_pool;
    for (size_t u = 0; u < n_units; u++)
        c->env.root[u] = e->nodes[e->root[u]].cls == LIE_CLASS_NONE ? 0 : 1 + e->root[u];
    c->p = e->params;
    c->o.params = e->params;
    if (from->views.n_cams) {
        c->o.view_width = from->views.width;
        c->o.view_height = from->views.height;
        c->o.max_depth = from->views.max_depth;
        c->views.cams = malloc(sizeof *c->views.cams * ((size_t)from->views.n_cams + 1));
        if (!c->views.cams)
            return lie_error_set(err, LIE_ERR_NOMEM, c->s->path, "out of memory");
        memcpy(c->views.cams, from->views.cams, sizeof *c->views.cams * (size_t)from->views.n_cams);
        c->views.n_cams = from->views.n_cams;
        lie_pixels *px = NULL;
        lie_status st = lie_camera_pixels(c->s, c->rt, c->views.cams, c->views.n_cams, c->o.view_width,
                                          c->o.view_height, c->o.max_depth, &px, err);
        if (st != LIE_OK)
            return st;
        if (!(c->px = px_wrap(px)))
            return lie_error_set(err, LIE_ERR_NOMEM, c->s->path, "out of memory");
        c->views_mode = 1;
    }
    /* a unit a whole build leaves unbuilt (outside the views, or not paying)
     * is one a partial build may not have reached yet: every seen triangle
     * with an unbuilt unit of a partial cache goes again (giving the same
     * unbuilt units where they do not pay) */
    for (uint32_t t = 0; t < c->s->n_tris; t++) {
        int seen = seen_by(c, c->px, t), any_none = 0;
        for (size_t k = 0; k < c->ne; k++)
            any_none |= c->env.root[(size_t)t * c->ne + k] == 0;
        if (seen)
            set_state(c, t, e->partial && any_none ? TRI_PENDING : TRI_BUILT);
        if (seen && e->partial && any_none)
            unland(c, t);
    }
    return LIE_OK;
}

/* Views given at the start: their pixels, the triangles they see pending. */
static lie_status fixed_views(lie_ctor *c, const lie_camera *cams, int n, lie_error *err)
{
    c->views.cams = malloc(sizeof *c->views.cams * ((size_t)n + 1));
    if (!c->views.cams)
        return lie_error_set(err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    for (int i = 0; i < n; i++) {
        c->views.cams[i] = cams[i];
        c->views.cams[i].name = NULL;
    }
    c->views.n_cams = n;
    lie_pixels *px = NULL;
    lie_status st = lie_camera_pixels(c->s, c->rt, c->views.cams, n, c->o.view_width, c->o.view_height,
                                      c->o.max_depth, &px, err);
    if (st == LIE_OK && !(c->px = px_wrap(px)))
        st = lie_error_set(err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    c->fixed = 1;
    if (st == LIE_OK)
        mark_seen(c);
    return st;
}

lie_status lie_ctor_create(lie_scene *s, const lie_rt *rt, const lie_ctor_options *opt, const lie_cache *from,
                           lie_ctor **out, lie_error *err)
{
    *out = NULL;
    if (!from && lie_build_params_check(&opt->params, err) != LIE_OK)
        return LIE_ERR_ARG;
    lie_ctor *c = calloc(1, sizeof *c);
    if (!c)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    pthread_rwlock_init(&c->env_lock, NULL);
    pthread_mutex_init(&c->m, NULL);
    pthread_cond_init(&c->cv, NULL);
    pthread_cond_init(&c->idle_cv, NULL);
    c->s = s;
    c->rt = rt;
    c->o = *opt;
    c->p = opt->params;
    c->ne = (size_t)s->n_clusters;
    c->t0 = lie_time_now();
    size_t n_units = (size_t)s->n_tris * c->ne;
    c->env.root = malloc(sizeof *c->env.root * (n_units + 1));
    c->state = calloc((size_t)s->n_tris + 1, 1);
    c->redo = calloc(n_units + 1, 1);
    c->redo_root = calloc(n_units + 1, sizeof *c->redo_root);
    c->some_tri = calloc((size_t)s->n_tris + 1, 1);
    c->tri_p = malloc(sizeof *c->tri_p * (3 * (size_t)s->n_tris + 1));
    c->em = malloc(sizeof *c->em * ((size_t)s->n_emitters + 1));
    lie_status st = c->env.root && c->state && c->redo && c->redo_root && c->some_tri && c->tri_p && c->em &&
                            reserve((void **)&c->env.nodes, &c->cap_nodes, 1, sizeof(lie_pnode)) &&
                            reserve((void **)&c->env.pool, &c->cap_pool, 1, sizeof(uint32_t))
                        ? LIE_OK
                        : lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    if (st == LIE_OK) {
        memset(&c->env.nodes[0], 0, sizeof c->env.nodes[0]);
        c->env.nodes[0].cls = LIE_CLASS_NONE;
        env_reset(c);
        keep_geometry(c);
        c->views_mode = !opt->whole;
        if (from) {
            c->views_mode = 0;
            st = seed(c, from, err);
        }
    }
    if (st == LIE_OK) {
        c->env.n_tris = s->n_tris;
        c->env.n_clusters = s->n_clusters;
        c->env.params = c->p;
        c->env.params.threads = 0;
        c->env.scene_hash = s->hash;
        c->p.threads = 1;
        if (!from)
            mark_seen(c);
        c->order_dirty = 1;
        sample_stats(c);
        if (st == LIE_OK && opt->n_views > 0 && !from)
            st = fixed_views(c, opt->views, opt->n_views, err);
        int n = opt->manual ? 0 : opt->threads > 0 ? opt->threads : lie_cpu_count();
        c->tids = calloc((size_t)n + 1, sizeof *c->tids);
        if (!c->tids)
            st = lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
        for (int i = 0; st == LIE_OK && i < n; i++) {
            if (pthread_create(&c->tids[i], NULL, worker_main, c) != 0)
                st = lie_error_set(err, LIE_ERR_NOMEM, s->path, "cannot start a constructor thread");
            else
                c->n_threads++;
        }
    }
    if (st != LIE_OK) {
        lie_ctor_destroy(c);
        return st;
    }
    atomic_store(&c->version, 1);
    *out = c;
    return LIE_OK;
}

/* ---- using it ---------------------------------------------------------------------- */

void lie_ctor_read_lock(lie_ctor *c)
{
    /* between a reader's bands: what the builders could not land, now */
    pthread_mutex_lock(&c->m);
    land_ready(c, 0);
    pthread_mutex_unlock(&c->m);
    pthread_rwlock_rdlock(&c->env_lock);
}
void lie_ctor_read_unlock(lie_ctor *c) { pthread_rwlock_unlock(&c->env_lock); }
const lie_env *lie_ctor_env(const lie_ctor *c) { return &c->env; }
uint32_t lie_ctor_longest(const lie_ctor *c) { return c->longest; }
uint64_t lie_ctor_version(const lie_ctor *c) { return atomic_load(&((lie_ctor *)c)->version); }

void lie_ctor_view(lie_ctor *c, const lie_camera *cam)
{
    pthread_mutex_lock(&c->m);
    c->want = *cam;
    c->want_set = 1;
    pthread_cond_broadcast(&c->cv);
    pthread_mutex_unlock(&c->m);
}

void lie_ctor_hold(lie_ctor *c)
{
    pthread_mutex_lock(&c->m);
    c->hold++;
    c->stop = 1; /* in-flight units are dropped, and built again later */
    while (c->busy > 0)
        pthread_cond_wait(&c->idle_cv, &c->m);
    land_ready(c, 1); /* the units built so far are in the env the holder sees */
    c->stop = 0; /* nothing starts while held */
    pthread_mutex_unlock(&c->m);
}

void lie_ctor_release(lie_ctor *c)
{
    pthread_mutex_lock(&c->m);
    if (c->hold > 0)
        c->hold--;
    pthread_cond_broadcast(&c->cv);
    pthread_mutex_unlock(&c->m);
}

void lie_ctor_get_stats(lie_ctor *c, lie_ctor_stats *st)
{
    pthread_mutex_lock(&c->m);
    st->units = (uint64_t)c->s->n_tris * c->ne;
    st->units_pending = c->pending * c->ne;
    st->units_built = c->units_built;
    st->nodes_built = c->nodes_built;
    st->views = c->views.n_cams;
    st->sampling = c->want_set || c->resample;
    st->samples = c->samples;
    st->n_samples = c->n_samples;
    pthread_mutex_unlock(&c->m);
}

int lie_ctor_wait(lie_ctor *c, double seconds, lie_error *err)
{
    double end = lie_time_now() + seconds;
    pthread_mutex_lock(&c->m);
    while ((c->pending || c->want_set || c->resample || c->busy) && !c->failed && !c->hold) {
        if (seconds >= 0.0) {
            double left = end - lie_time_now();
            if (left <= 0.0)
                break;
            timed_wait(&c->idle_cv, &c->m, left < 0.05 ? left : 0.05);
        } else {
            pthread_cond_wait(&c->idle_cv, &c->m);
        }
    }
    int done = !c->pending && !c->want_set && !c->resample && !c->busy;
    if (c->failed && err)
        *err = c->err;
    int failed = c->failed;
    pthread_mutex_unlock(&c->m);
    return failed ? -1 : done;
}

/* ---- building in the caller's threads ------------------------------------------------ */

typedef struct build_job {
    lie_ctor *c;
    const uint32_t *tris;
    pxref *px;
    lie_error err;
    _Atomic int failed;
    _Atomic uint64_t nodes;
} build_job;

static void build_one(void *ctx, size_t item, int worker)
{
    (void)worker;
    build_job *j = ctx;
    lie_ctor *c = j->c;
    if (atomic_load(&j->failed))
        return;
    uint32_t t = j->tris[item];
    lie_env_part part;
    lie_build_stats bs;
    lie_error err;
    lie_status st = lie_env_build_units(c->s, c->rt, &c->p, j->px ? j->px->px : NULL, (uint64_t)t * c->ne, c->ne,
                                        NULL, NULL, &part, &bs, &err);
    for (int d = 0; st == LIE_OK && d <= LIE_PATCH_MAX_DEPTH; d++)
        atomic_fetch_add(&j->nodes, bs.patches_per_depth[d]);
    if (st == LIE_OK) {
        pthread_rwlock_wrlock(&c->env_lock);
        if (!land(c, &part))
            st = lie_error_set(&err, LIE_ERR_NOMEM, c->s->path, "out of memory for the constructor's environments");
        pthread_rwlock_unlock(&c->env_lock);
    }
    lie_env_part_free(&part);
    if (st != LIE_OK && !atomic_exchange(&j->failed, 1))
        j->err = err;
}

lie_status lie_ctor_build(lie_ctor *c, const uint8_t *mask, const lie_camera *cam, int threads, uint64_t *built,
                          lie_error *err)
{
    if (built)
        *built = 0;
    uint8_t *seen = NULL;
    if (!mask) {
        seen = calloc((size_t)c->s->n_tris + 1, 1);
        if (!seen)
            return lie_error_set(err, LIE_ERR_NOMEM, c->s->path, "out of memory");
        lie_status st = lie_camera_mark_visible(c->s, c->rt, cam, 1, c->o.view_width, c->o.view_height, c->o.max_depth,
                                                seen, err);
        if (st != LIE_OK) {
            free(seen);
            return st;
        }
        mask = seen;
    }
    pthread_mutex_lock(&c->m);
    uint32_t *tris = malloc(sizeof *tris * ((size_t)c->s->n_tris + 1));
    size_t n = 0;
    for (uint32_t t = 0; tris && t < c->s->n_tris; t++)
        if (mask[t] && c->state[t] == TRI_PENDING) {
            tris[n++] = t;
            set_state(c, t, TRI_BUSY);
        }
    build_job j = {c, tris, c->px, {0}, 0, 0};
    if (j.px)
        j.px->refs++;
    c->busy++;
    pthread_mutex_unlock(&c->m);
    lie_status st = tris ? LIE_OK : lie_error_set(err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    if (st == LIE_OK && n)
        st = lie_parallel_for(n, threads, build_one, &j, NULL, NULL);
    if (st == LIE_OK && atomic_load(&j.failed)) {
        *err = j.err;
        st = err->status;
    }
    pthread_mutex_lock(&c->m);
    c->busy--;
    for (size_t i = 0; i < n; i++) {
        if (st == LIE_OK) /* every unit built: none left to redo */
            redone(c, tris[i]);
        set_state(c, tris[i], st == LIE_OK ? TRI_BUILT : TRI_PENDING);
    }
    if (st == LIE_OK) {
        c->units_built += n * c->ne;
        c->nodes_built += atomic_load(&j.nodes);
        sample_stats(c);
        atomic_fetch_add(&c->version, 1);
    }
    px_drop(j.px);
    pthread_cond_broadcast(&c->idle_cv);
    pthread_mutex_unlock(&c->m);
    if (built)
        *built = st == LIE_OK ? n : 0;
    free(tris);
    free(seen);
    return st;
}

/* ---- edits ------------------------------------------------------------------------- */

static lie_box3 tri_box(const lie_vec3 *p)
{
    lie_box3 b = lie_box3_empty();
    for (int k = 0; k < 3; k++)
        lie_box3_grow(&b, p[k]);
    return b;
}

static int boxes_meet(const lie_box3 *a, const lie_box3 *b)
{
    return !lie_box3_is_empty(a) && !lie_box3_is_empty(b) && a->lo.x <= b->hi.x && b->lo.x <= a->hi.x &&
           a->lo.y <= b->hi.y && b->lo.y <= a->hi.y && a->lo.z <= b->hi.z && b->lo.z <= a->hi.z;
}

/* A box holding every point of cluster k's pairs' hulls on its side (its
 * triangles, or its light's sphere); infinite for a light at infinity. */
static lie_box3 cluster_box(const lie_scene *s, int k)
{
    const lie_cluster *cl = &s->clusters[k];
    lie_box3 b = lie_box3_empty();
    if (s->emitters[cl->emitter].n_clusters == 1) {
        float f[4];
        lie_emitter_bounding_sphere(s, cl->emitter, f);
        if (f[3] < 0.0f || !isfinite(f[3])) {
            b.lo = lie_v3(-INFINITY, -INFINITY, -INFINITY);
            b.hi = lie_v3(INFINITY, INFINITY, INFINITY);
            return b;
        }
        lie_box3_grow(&b, lie_v3(f[0] - f[3], f[1] - f[3], f[2] - f[3]));
        lie_box3_grow(&b, lie_v3(f[0] + f[3], f[1] + f[3], f[2] + f[3]));
        return b;
    }
    for (uint32_t i = 0; i < cl->n_tris; i++)
        for (int q = 0; q < 3; q++)
            lie_box3_grow(&b, s->tri_p[3 * (size_t)s->cluster_tris[cl->first + i] + q]);
    return b;
}

static void box_pad(lie_box3 *b, float d)
{
    if (lie_box3_is_empty(b))
        return;
    b->lo = lie_v3(b->lo.x - d, b->lo.y - d, b->lo.z - d);
    b->hi = lie_v3(b->hi.x + d, b->hi.y + d, b->hi.z + d);
}

/* Whether an emitter kept its geometry and light (every field a unit or
 * the cost model reads; not its pointers, which an edit may make anew). */
static int same_emitter(const lie_emitter *a, const lie_emitter *b)
{
    return a->type == b->type && a->first_tri == b->first_tri && a->n_tris == b->n_tris && a->area == b->area &&
           memcmp(a->radiance, b->radiance, sizeof a->radiance) == 0 && a->double_sided == b->double_sided &&
           a->n_hull == b->n_hull && memcmp(a->hull, b->hull, sizeof a->hull) == 0 &&
           memcmp(&a->position, &b->position, sizeof a->position) == 0 &&
           memcmp(&a->direction, &b->direction, sizeof a->direction) == 0 &&
           memcmp(a->intensity, b->intensity, sizeof a->intensity) == 0 && a->cos_inner == b->cos_inner &&
           a->cos_outer == b->cos_outer && a->range == b->range && a->first_cluster == b->first_cluster &&
           a->n_clusters == b->n_clusters;
}

lie_status lie_ctor_edited(lie_ctor *c, const lie_rt *rt, int geometry_only, lie_error *err)
{
    pthread_mutex_lock(&c->m);
    lie_scene *s = c->s;
    c->rt = rt;
    int restart = !geometry_only || s->n_tris != c->n_tris || (size_t)s->n_clusters != c->ne ||
                  s->n_emitters != c->n_em || s->max_tri_area != c->max_tri_area || lie_pair_ray_far(s) != c->ray_far ||
                  (whole_model(c) && lie_whole_area(s) != c->whole_area);
    lie_status st = LIE_OK;
    if (restart && (s->n_tris != c->n_tris || (size_t)s->n_clusters != c->ne)) {
        pthread_mutex_unlock(&c->m);
        return lie_error_set(err, LIE_ERR_UNSUPPORTED, s->path,
                             "the edit changes the scene's triangles or emitters in number: the constructor "
                             "cannot follow it");
    }
    /* the moved geometry, before and after, and its size for the padding */
    lie_box3 before = lie_box3_empty(), after = lie_box3_empty(), all = lie_box3_empty();
    uint8_t *moved = calloc((size_t)s->n_tris + 1, 1);
    /* and per glTF node, before and after: the boxes rst-update refines
     * with (lib/update/update.c, apply_edit), tighter than their union
     * when a group of nodes moves */
    lie_box3 *nb = malloc(sizeof *nb * (2 * (size_t)s->n_nodes + 1));
    for (int i = 0; nb && i < 2 * s->n_nodes; i++)
        nb[i] = lie_box3_empty();
    /* clusters of an emitter the edit moved (or changed): every unit of
     * them goes again, as rst-update builds them afresh (lib/update/mark.c) */
    uint8_t *cl_moved = calloc(c->ne + 1, 1);
    int light_moved = 0;
    if (!moved || !cl_moved || !nb)
        st = lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    for (int e = 0; st == LIE_OK && !restart && e < s->n_emitters; e++)
        if (!same_emitter(&c->em[e], &s->emitters[e])) {
            for (int k = 0; k < s->emitters[e].n_clusters; k++)
                cl_moved[s->emitters[e].first_cluster + k] = 1;
            light_moved = 1;
        }
    for (uint32_t t = 0; st == LIE_OK && t < s->n_tris; t++) {
        const lie_vec3 *a = &c->tri_p[3 * (size_t)t], *b = &s->tri_p[3 * (size_t)t];
        for (int q = 0; q < 3; q++)
            lie_box3_grow(&all, b[q]);
        if (memcmp(a, b, sizeof *a * 3) == 0)
            continue;
        moved[t] = 1;
        int node = s->instances[s->tri_instance[t]].node;
        for (int q = 0; q < 3; q++) {
            lie_box3_grow(&before, a[q]);
            lie_box3_grow(&after, b[q]);
            lie_box3_grow(&nb[2 * node], a[q]);
            lie_box3_grow(&nb[2 * node + 1], b[q]);
        }
        if (s->tri_emitter && s->tri_emitter[t] >= 0) { /* an emitter moved: every unit of it */
            const lie_emitter *em = &s->emitters[s->tri_emitter[t]];
            for (int k = 0; k < em->n_clusters; k++)
                cl_moved[em->first_cluster + k] = 1;
            light_moved = 1;
        }
    }
    /* shadow rays start a little off the surface (lib/rt/rt.h): pad */
    float pad = lie_box3_is_empty(&all) ? 0.0f : 1e-3f * lie_v3_len(lie_v3_sub(all.hi, all.lo));
    box_pad(&before, pad);
    box_pad(&after, pad);
    lie_box3 *cb = st == LIE_OK ? malloc(sizeof *cb * (c->ne + 1)) : NULL;
    if (st == LIE_OK && !cb)
        st = lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    for (size_t k = 0; st == LIE_OK && k < c->ne; k++)
        cb[k] = cluster_box(s, (int)k);
    if (st != LIE_OK) {
        free(moved);
        free(cl_moved);
        free(cb);
        free(nb);
        fail(c, err);
        pthread_mutex_unlock(&c->m);
        return st;
    }
    pthread_rwlock_wrlock(&c->env_lock);
    if (restart)
        env_reset(c);
    /* Which landed units the moved geometry may reach, as rst-update finds
     * them (§5.3): a box holding each unit's shafts (its triangle's and its
     * cluster's) against the moved triangles' boxes picks the candidates,
     * then each candidate root's exact hull against the boxes
     * (lie_rst_refine, as lib/update tightens the ray segment trees'
     * answer) keeps those whose segments can meet moved geometry.  The box
     * of a large emitter holds most of a room: the box test alone sent
     * every unit of the view back.  The refinement flags the nodes down
     * each kept unit's tree that the moved geometry may reach: only those
     * are recomputed (build_tri).  A unit an earlier edit sent back, not
     * recomputed yet, is tested on its old tree (vroot: the roots the
     * refinement sees), and keeps its earlier flags. */
    size_t n_units = (size_t)s->n_tris * c->ne;
    uint8_t *flags = restart ? NULL : calloc((size_t)c->env.n_nodes + 1, 1);
    uint32_t *vroot = flags ? malloc(sizeof *vroot * (n_units + 1)) : NULL;
    double *share = light_moved ? malloc(sizeof *share * (c->ne + 1)) : NULL;
    if ((light_moved && !share) || !vroot) {
        free(flags); /* out of memory (or a restart): everything goes again */
        flags = NULL;
    }
    for (size_t u = 0; flags && u < n_units; u++)
        vroot[u] = c->env.root[u] ? c->env.root[u] : c->redo_root[u];
    uint64_t candidates = 0;
    for (uint32_t t = 0; flags && t < s->n_tris; t++) {
        if (moved[t] || !has_landed(c, t))
            continue;
        lie_box3 tb = tri_box(&s->tri_p[3 * (size_t)t]);
        for (size_t k = 0; k < c->ne; k++) {
            uint32_t r = vroot[(size_t)t * c->ne + k];
            uint32_t cls = c->env.nodes[r].cls;
            /* as the trees leave them out (lib/rst): unlit stays unlit unless
             * its patch or emitter moves, an unbuilt unit stays unbuilt (the
             * cost model's decision reads light, not blockers); and a
             * cluster with no shafts */
            if (r == 0 || cls == LIE_CLASS_UNLIT || cls == LIE_CLASS_NONE || lie_box3_is_empty(&cb[k]) || cl_moved[k])
                continue;
            int meets = !isfinite(cb[k].lo.x);
            if (!meets) {
                lie_box3 u = tb;
                lie_box3_grow(&u, cb[k].lo);
                lie_box3_grow(&u, cb[k].hi);
                meets = boxes_meet(&u, &before) || boxes_meet(&u, &after);
            }
            flags[r] = (uint8_t)meets;
            candidates += (uint64_t)meets;
        }
    }
    /* the refinement's boxes: the moved nodes', unpadded, as rst-update's */
    int n_moved_boxes = 0;
    for (int i = 0; i < 2 * s->n_nodes; i++)
        if (!lie_box3_is_empty(&nb[i]))
            nb[n_moved_boxes++] = nb[i];
    lie_env view = c->env;
    view.root = vroot;
    if (flags && candidates)
        lie_rst_refine(s, &view, nb, n_moved_boxes, flags, 0);
    for (size_t i = 0; flags && i < c->n_nflags; i++)
        flags[i] |= c->nflags[i];
    /* a triangle moved (or everything: restart) goes again whole; one
     * with units the refinement kept goes again in those units only, the
     * others staying landed (units are independent: lib/lie/lie.h) */
    const double area = whole_model(c) ? lie_whole_area(s) : 0.0; /* the whole build's model reads it */
    for (uint32_t t = 0; t < s->n_tris; t++) {
        if (restart || moved[t] || !flags) {
            int was_built = c->state[t] == TRI_BUILT;
            unland(c, t);
            if (was_built)
                set_state(c, t, TRI_PENDING);
            continue;
        }
        if (!has_landed(c, t))
            continue;
        /* the cost model's decision to build a unit for the views reads
         * every emitter's light at its triangle (lie_unit_shares): when an
         * emitter moved, a unit whose decision turns goes again, as
         * rst-update decides it anew (lib/update/mark.c) */
        int decide = light_moved && share && ((c->views_mode && c->px) || whole_model(c));
        double pixels = 0.0;
        if (decide) {
            pixels = c->px ? (double)lie_pixels_hits(c->px->px, t, lie_patch_root()) / (double)c->px->px->rays_per_pixel
                           : lie_whole_pixels(s, &c->p, area, t);
            lie_unit_shares(s, t, lie_pair_ray_far(s), share);
        }
        int any = 0;
        for (size_t k = 0; k < c->ne; k++) {
            size_t u = (size_t)t * c->ne + k;
            uint32_t r = vroot[u];
            /* built afresh: its emitter moved, or the cost model's decision
             * turned; else recomputed where flagged */
            int afresh = r && cl_moved[k];
            if (r && !afresh && decide)
                afresh = (c->env.nodes[r].cls != LIE_CLASS_NONE) != lie_unit_pays_pixels(&c->p, pixels, share[k]);
            if (r && (afresh || flags[r])) {
                c->env.root[u] = 0;
                c->redo[u] = 1;
                c->redo_root[u] = afresh ? 0 : r;
                any = 1;
            }
        }
        if (any) {
            c->some_tri[t] = 1;
            set_state(c, t, TRI_PENDING);
        }
    }
    free(c->nflags);
    c->nflags = flags;
    c->n_nflags = flags ? c->env.n_nodes : 0;
    free(vroot);
    free(share);
    free(cl_moved);
    c->env.scene_hash = s->hash;
    pthread_rwlock_unlock(&c->env_lock);
    /* the views' pixels on the edited scene: sampled by a constructor
     * thread before it builds anything (take_resample), not here */
    c->resample = c->views_mode && c->views.n_cams > 0;
    c->edits++;
    keep_geometry(c);
    c->order_dirty = 1;
    atomic_fetch_add(&c->version, 1);
    free(moved);
    free(cb);
    free(nb);
    pthread_mutex_unlock(&c->m);
    return LIE_OK;
}

/* ---- saving ------------------------------------------------------------------------- */

lie_status lie_ctor_cache(lie_ctor *c, const lie_cache *provenance, lie_cache **out, lie_error *err)
{
    *out = NULL;
    lie_ctor_hold(c);
    pthread_mutex_lock(&c->m);
    /* units built for the pixels of the scene before an edit are not what a
     * build of the edited scene holds: the views are sampled first (one
     * view's rays, not the backlog) */
    if (c->resample && !c->failed)
        take_resample(c);
    lie_status st = c->failed ? (*err = c->err, err->status) : LIE_OK;
    lie_cache *cache = st == LIE_OK ? calloc(1, sizeof *cache) : NULL;
    if (st == LIE_OK && !cache)
        st = lie_error_set(err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    lie_env *env = NULL;
    if (st == LIE_OK) {
        c->env.partial = c->pending > 0;
        st = lie_env_compact(&c->env, &env, err);
        cache->env = env;
    }
    if (st == LIE_OK) {
        env->params = c->o.params;
        env->params.threads = 0;
        cache->scene_path = strdup(provenance->scene_path ? provenance->scene_path : "");
        cache->scene_hash = provenance->scene_hash;
        cache->edits = provenance->n_edits ? calloc((size_t)provenance->n_edits, sizeof *cache->edits) : NULL;
        int ok = cache->scene_path && (!provenance->n_edits || cache->edits);
        for (int i = 0; ok && i < provenance->n_edits; i++) {
            const lie_cache_edit *e = &provenance->edits[i];
            cache->edits[i].name = strdup(e->name);
            cache->edits[i].text = malloc(e->size + 1);
            ok = cache->edits[i].name && cache->edits[i].text;
            if (ok) {
                memcpy(cache->edits[i].text, e->text, e->size);
                cache->edits[i].size = e->size;
                cache->n_edits++;
            }
        }
        if (ok && c->views_mode && c->views.n_cams) {
            cache->views = c->views;
            cache->views.width = c->o.view_width;
            cache->views.height = c->o.view_height;
            cache->views.max_depth = c->o.max_depth;
            cache->views.cams = malloc(sizeof *cache->views.cams * ((size_t)c->views.n_cams + 1));
            ok = cache->views.cams != NULL;
            if (ok)
                memcpy(cache->views.cams, c->views.cams, sizeof *cache->views.cams * (size_t)c->views.n_cams);
            else
                cache->views.n_cams = 0;
        }
        st = ok ? lie_cache_set_state(cache, c->s, err) : lie_error_set(err, LIE_ERR_NOMEM, c->s->path, "out of memory");
    }
    pthread_mutex_unlock(&c->m);
    lie_ctor_release(c);
    if (st != LIE_OK) {
        if (cache)
            lie_cache_destroy(cache);
        else
            lie_env_destroy(env);
        return st;
    }
    *out = cache;
    return LIE_OK;
}
