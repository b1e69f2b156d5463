/* SPDX-License-Identifier: Apache-2.0 */
/* Ray segment trees (§5.1–5.3). */
#include "rst/rst.h"

#include <stdlib.h>
#include <string.h>

#define LEAF_MAX 32   /* split a leaf holding more regions than this */
#define MAX_DEPTH 4   /* at most 32^4 cells per tree */
#define MAX_SPREAD 2  /* a region meeting more children than this stays in the parent */

/* A 5D box: line intercepts (p, q) on plane A0 and (r, s) on plane A1
 * (p, r along axis b; q, s along axis c), and t, the stretch of axis a. */
typedef struct box5 {
    float lo[5], hi[5]; /* p q r s t */
} box5;

typedef struct entry {
    uint32_t node;       /* env node */
    box5 b;              /* clipped to the cell that holds it */
} entry;

typedef struct tnode {
    box5 cell;
    int32_t child;       /* first of 32 children in the pool, or -1 */
    entry *e;
    uint32_t n, cap;
} tnode;

typedef struct tree {
    int a, b, c;         /* axis of the planes, and the two others */
    float A0, A1;
    tnode *nodes;
    uint32_t n_nodes, cap_nodes;
    uint64_t stored;     /* region copies held in this tree's leaves */
    int nomem;
} tree;

typedef struct fb_region {
    uint32_t node;
    lie_box3 box;        /* world bounds of the hull */
} fb_region;

struct lie_rst {
    tree t[3];
    fb_region *fb;
    uint32_t n_fb, cap_fb;
    uint64_t stored;     /* the trees' stored, summed once built */
    int nomem;
};

/* min and max that compile to one instruction (fminf/fmaxf are library
 * calls on x86 for their NaN rules; a NaN bound fails the root-cell test
 * in region_box and lands in the fallback list anyway) */
static inline float mn(float a, float b) { return a < b ? a : b; }
static inline float mx(float a, float b) { return a > b ? a : b; }

static float axis_of(lie_vec3 v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }

static int box5_overlap(const box5 *x, const box5 *y)
{
    for (int k = 0; k < 5; k++)
        if (x->lo[k] > y->hi[k] || x->hi[k] < y->lo[k])
            return 0;
    return 1;
}

/* Does the set of points {line in box's (p,q,r,s) at a in box's t} meet
 * the world box?  At parameter u = (a - A0) / (A1 - A0) the lines' b
 * coordinate spans [p0 + u (r0 - p0), p1 + u (r1 - p1)] (likewise c), so
 * each overlap condition is linear in u: intersect the intervals. */
static int box5_meets(const tree *t, const box5 *x, const lie_box3 *w)
{
    float wa0 = axis_of(w->lo, t->a), wa1 = axis_of(w->hi, t->a);
    float z0 = mx(x->lo[4], wa0), z1 = mn(x->hi[4], wa1);
    if (z0 > z1)
        return 0;
    float inv = 1.0f / (t->A1 - t->A0);
    double u0 = (z0 - t->A0) * inv, u1 = (z1 - t->A0) * inv;
    const float wb0 = axis_of(w->lo, t->b), wb1 = axis_of(w->hi, t->b);
    const float wc0 = axis_of(w->lo, t->c), wc1 = axis_of(w->hi, t->c);
    /* four constraints f(u) = k0 + u k1 <= 0 */
    double k[4][2] = {
        {x->lo[0] - wb1, x->lo[2] - x->lo[0]},   /* lower b edge <= wb1 */
        {wb0 - x->hi[0], -(x->hi[2] - x->hi[0])}, /* upper b edge >= wb0 */
        {x->lo[1] - wc1, x->lo[3] - x->lo[1]},
        {wc0 - x->hi[1], -(x->hi[3] - x->hi[1])},
    };
    /* tolerance: float rounding in intercepts must never drop a region */
    double tol = 1e-5 * (fabs(t->A1) + fabs(t->A0) + 1.0);
    for (int i = 0; i < 4; i++) {
        double c0 = k[i][0] - tol, c1 = k[i][1];
        if (c1 == 0.0) {
            if (c0 > 0.0)
                return 0;
        } else if (c1 > 0.0) {
            u1 = fmin(u1, -c0 / c1);
        } else {
            u0 = fmax(u0, -c0 / c1);
        }
        if (u0 > u1)
            return 0;
    }
    return 1;
}

static int tree_push_node(tree *t, const box5 *cell)
{
    if (t->n_nodes == t->cap_nodes) {
        uint32_t nc = t->cap_nodes ? 2 * t->cap_nodes : 64;
        tnode *nn = realloc(t->nodes, sizeof *nn * nc);
        if (!nn)
            return -1;
        t->nodes = nn;
        t->cap_nodes = nc;
    }
    tnode *n = &t->nodes[t->n_nodes];
    memset(n, 0, sizeof *n);
    n->cell = *cell;
    n->child = -1;
    return (int)t->n_nodes++;
}

static int leaf_add(tnode *n, const entry *e)
{
    if (n->n == n->cap) {
        uint32_t nc = n->cap ? 2 * n->cap : 8;
        entry *ne = realloc(n->e, sizeof *ne * nc);
        if (!ne)
            return 0;
        n->e = ne;
        n->cap = nc;
    }
    n->e[n->n++] = *e;
    return 1;
}

static entry clip(const entry *e, const box5 *cell)
{
    entry r = *e;
    for (int k = 0; k < 5; k++) {
        r.b.lo[k] = mx(r.b.lo[k], cell->lo[k]);
        r.b.hi[k] = mn(r.b.hi[k], cell->hi[k]);
    }
    return r;
}

static void insert(tree *t, uint32_t ni, const entry *e, int depth);

static void split(tree *t, uint32_t ni, int depth)
{
    box5 cell = t->nodes[ni].cell;
    int first = -1;
    for (int k = 0; k < 32; k++) {
        box5 c;
        for (int d = 0; d < 5; d++) {
            float mid = 0.5f * (cell.lo[d] + cell.hi[d]);
            c.lo[d] = (k >> d) & 1 ? mid : cell.lo[d];
            c.hi[d] = (k >> d) & 1 ? cell.hi[d] : mid;
        }
        int idx = tree_push_node(t, &c);
        if (idx < 0) {
            t->nomem = 1;
            return;
        }
        if (k == 0)
            first = idx;
    }
    tnode *n = &t->nodes[ni];
    entry *old = n->e;
    uint32_t count = n->n;
    n->e = NULL;
    n->n = n->cap = 0;
    n->child = first;
    t->stored -= count;
    for (uint32_t i = 0; i < count; i++)
        insert(t, ni, &old[i], depth);
    free(old);
}

static void insert(tree *t, uint32_t ni, const entry *e, int depth)
{
    tnode *n = &t->nodes[ni];
    if (n->child >= 0) {
        int32_t first = n->child;
        int hits = 0;
        for (int k = 0; k < 32; k++)
            hits += box5_overlap(&e->b, &t->nodes[first + k].cell);
        if (hits > MAX_SPREAD) {
            /* a wide region: copying it into most children would multiply
             * memory; it stays here and queries test it on the way down */
            if (!leaf_add(n, e))
                t->nomem = 1;
            else
                t->stored++;
            return;
        }
        for (int k = 0; k < 32; k++) {
            const box5 *cell = &t->nodes[first + k].cell;
            if (box5_overlap(&e->b, cell)) {
                entry c = clip(e, cell);
                insert(t, (uint32_t)(first + k), &c, depth + 1);
            }
        }
        return;
    }
    if (!leaf_add(n, e)) {
        t->nomem = 1;
        return;
    }
    t->stored++;
    if (n->n > LEAF_MAX && depth < MAX_DEPTH)
        split(t, ni, depth);
}

/* The region of a pair for the tree of axis a, from its hull points:
 * extremes of the intercepts are reached at pairs of extreme points (a
 * central projection maps a convex set's vertices to its image's). */
static int region_box(const tree *t, const lie_vec3 *P, int np, const lie_vec3 *E, int ne, box5 *out)
{
    for (int k = 0; k < 5; k++) {
        out->lo[k] = INFINITY;
        out->hi[k] = -INFINITY;
    }
    for (int i = 0; i < np; i++)
        for (int j = 0; j < ne; j++) {
            float pa = axis_of(P[i], t->a), qa = axis_of(E[j], t->a);
            float d = qa - pa;
            if (!(fabsf(d) > 0.0f))
                return 0;
            float pb = axis_of(P[i], t->b), pc = axis_of(P[i], t->c);
            float db = axis_of(E[j], t->b) - pb, dc = axis_of(E[j], t->c) - pc;
            float f0 = (t->A0 - pa) / d, f1 = (t->A1 - pa) / d;
            float v[4] = {pb + f0 * db, pc + f0 * dc, pb + f1 * db, pc + f1 * dc};
            for (int k = 0; k < 4; k++) {
                out->lo[k] = mn(out->lo[k], v[k]);
                out->hi[k] = mx(out->hi[k], v[k]);
            }
        }
    for (int i = 0; i < np + ne; i++) {
        float a = axis_of(i < np ? P[i] : E[i - np], t->a);
        out->lo[4] = mn(out->lo[4], a);
        out->hi[4] = mx(out->hi[4], a);
    }
    /* a hair wider: intercepts are computed in float */
    for (int k = 0; k < 5; k++) {
        float m = 1e-5f * (fabsf(out->lo[k]) + fabsf(out->hi[k]) + 1.0f);
        out->lo[k] -= m;
        out->hi[k] += m;
    }
    for (int k = 0; k < 5; k++)
        if (!(out->lo[k] >= t->nodes[0].cell.lo[k] && out->hi[k] <= t->nodes[0].cell.hi[k]))
            return 0; /* outside the root cell: keep it in the fallback list */
    return 1;
}

/* One region to insert: the node of a patch tree, its patch and emitter. */
typedef struct region_item {
    uint32_t node, tri;
    lie_patch_path path;
    int e;
} region_item;

/* What a region becomes: a 5D box in the tree of `axis`, or (axis -1) a
 * world box in the fallback list. */
typedef struct region_out {
    int axis;
    box5 b;
    lie_box3 world;
} region_out;

typedef struct build_state {
    const lie_scene *s;
    const lie_env *env;
    lie_rst *r;
    region_item *items;
    region_out *outs;
    size_t n_items, cap_items;
    lie_vec3 *hull; /* per worker, hull_cap points each */
    int hull_cap;
    int nomem;
} build_state;

enum { REGION_CHUNK = 64 };

static void compute_region(build_state *bs, const region_item *it, lie_vec3 *hull, region_out *out)
{
    const lie_scene *s = bs->s;
    lie_vec3 V[3];
    lie_patch_world(it->path, &s->tri_p[3 * (size_t)it->tri], V);
    int n = lie_pair_hull_points(s, it->tri, V, it->e, hull);
    int np = lie_pair_hull_patch_points(lie_pair_two_sided(s, it->tri));
    const lie_vec3 *P = hull, *E = hull + np;
    int ne = n - np;
    /* the axis along which patch and emitter are farthest apart */
    int best = -1;
    float best_gap = 0.0f;
    for (int a = 0; a < 3; a++) {
        float p0 = INFINITY, p1 = -INFINITY, e0 = INFINITY, e1 = -INFINITY;
        for (int i = 0; i < np; i++) {
            p0 = mn(p0, axis_of(P[i], a));
            p1 = mx(p1, axis_of(P[i], a));
        }
        for (int j = 0; j < ne; j++) {
            e0 = mn(e0, axis_of(E[j], a));
            e1 = mx(e1, axis_of(E[j], a));
        }
        float gap = mx(e0 - p1, p0 - e1);
        if (gap > best_gap) {
            best_gap = gap;
            best = a;
        }
    }
    if (best >= 0 && region_box(&bs->r->t[best], P, np, E, ne, &out->b)) {
        out->axis = best;
        return;
    }
    out->axis = -1;
    out->world = lie_box3_empty();
    for (int i = 0; i < n; i++)
        lie_box3_grow(&out->world, hull[i]);
}

/* lie_parallel_for body: insert the regions of tree `axis`, in item order. */
static void insert_axis(void *ctx, size_t axis, int worker)
{
    build_state *bs = ctx;
    tree *t = &bs->r->t[axis];
    for (size_t i = 0; i < bs->n_items && !t->nomem; i++) {
        const region_out *o = &bs->outs[i];
        if (o->axis != (int)axis)
            continue;
        entry en;
        en.node = bs->items[i].node;
        en.b = o->b;
        insert(t, 0, &en, 0);
    }
}

static void compute_chunk(void *ctx, size_t chunk, int worker)
{
    build_state *bs = ctx;
    size_t i0 = chunk * REGION_CHUNK, i1 = i0 + REGION_CHUNK < bs->n_items ? i0 + REGION_CHUNK : bs->n_items;
    lie_vec3 *hull = bs->hull + (size_t)worker * (size_t)bs->hull_cap;
    for (size_t i = i0; i < i1; i++)
        compute_region(bs, &bs->items[i], hull, &bs->outs[i]);
}

static void add_fallback(lie_rst *r, uint32_t node, lie_box3 box)
{
    if (r->n_fb == r->cap_fb) {
        uint32_t nc = r->cap_fb ? 2 * r->cap_fb : 64;
        fb_region *nf = realloc(r->fb, sizeof *nf * nc);
        if (!nf) {
            r->nomem = 1;
            return;
        }
        r->fb = nf;
        r->cap_fb = nc;
    }
    fb_region *f = &r->fb[r->n_fb++];
    f->node = node;
    f->box = box;
}

static void collect(build_state *bs, uint32_t node, uint32_t tri, lie_patch_path path, int e)
{
    const lie_pnode *x = &bs->env->nodes[node];
    if (x->cls == LIE_CLASS_UNLIT || x->cls == LIE_CLASS_NONE)
        return; /* unlit stays unlit unless the patch or emitter itself changes; none stays unbuilt */
    if (bs->n_items == bs->cap_items) {
        size_t nc = bs->cap_items ? 2 * bs->cap_items : 1024;
        region_item *ni = realloc(bs->items, sizeof *ni * nc);
        if (!ni) {
            bs->nomem = 1;
            return;
        }
        bs->items = ni;
        bs->cap_items = nc;
    }
    region_item it = {node, tri, path, e};
    bs->items[bs->n_items++] = it; /* a root: lie_rst_refine descends */
}

void lie_rst_destroy(lie_rst *r)
{
    if (!r)
        return;
    for (int a = 0; a < 3; a++) {
        for (uint32_t i = 0; i < r->t[a].n_nodes; i++)
            free(r->t[a].nodes[i].e);
        free(r->t[a].nodes);
    }
    free(r->fb);
    free(r);
}

lie_status lie_rst_build(const lie_scene *s, const lie_env *env, int threads, lie_rst **out, lie_rst_stats *stats,
                         lie_error *err)
{
    *out = NULL;
    double t0 = lie_time_now();
    lie_rst *r = calloc(1, sizeof *r);
    if (!r)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    /* the planes: the scene's box padded by its size on every side, so the
     * lines of any pair inside the scene cross both planes within it */
    lie_vec3 lo = s->bounds.lo, hi = s->bounds.hi;
    if (lie_box3_is_empty(&s->bounds))
        lo = hi = lie_v3(0, 0, 0);
    lie_vec3 ext = lie_v3_sub(hi, lo);
    float pad = mx(1.0f, mx(ext.x, mx(ext.y, ext.z)));
    for (int a = 0; a < 3; a++) {
        tree *t = &r->t[a];
        t->a = a;
        t->b = (a + 1) % 3;
        t->c = (a + 2) % 3;
        t->A0 = axis_of(lo, a) - 0.01f * pad;
        t->A1 = axis_of(hi, a) + 0.01f * pad;
        box5 root;
        float bl = axis_of(lo, t->b) - 2.0f * pad, bh = axis_of(hi, t->b) + 2.0f * pad;
        float cl = axis_of(lo, t->c) - 2.0f * pad, ch = axis_of(hi, t->c) + 2.0f * pad;
        root.lo[0] = root.lo[2] = bl;
        root.hi[0] = root.hi[2] = bh;
        root.lo[1] = root.lo[3] = cl;
        root.hi[1] = root.hi[3] = ch;
        root.lo[4] = t->A0;
        root.hi[4] = t->A1;
        if (tree_push_node(t, &root) < 0) {
            lie_rst_destroy(r);
            return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
        }
    }
    /* Regions are computed in parallel (each from its own item), then
     * inserted in item order, so the trees do not depend on the schedule. */
    int cap = 0;
    for (int e = 0; e < s->n_clusters; e++)
        cap = cap > lie_pair_hull_cap(s, e) ? cap : lie_pair_hull_cap(s, e);
    int workers = threads > 0 ? threads : lie_cpu_count();
    build_state bs;
    memset(&bs, 0, sizeof bs);
    bs.s = s;
    bs.env = env;
    bs.r = r;
    bs.hull_cap = cap + 1;
    bs.hull = malloc(sizeof(lie_vec3) * (size_t)bs.hull_cap * (size_t)workers);
    for (uint32_t t = 0; t < env->n_tris && bs.hull && !bs.nomem; t++)
        for (int e = 0; e < env->n_clusters; e++)
            collect(&bs, env->root[(size_t)t * (size_t)env->n_clusters + (size_t)e], t, lie_patch_root(), e);
    bs.outs = malloc(sizeof *bs.outs * (bs.n_items + 1));
    lie_status st = LIE_ERR_NOMEM;
    if (bs.hull && bs.outs && !bs.nomem)
        st = lie_parallel_for((bs.n_items + REGION_CHUNK - 1) / REGION_CHUNK, workers, compute_chunk, &bs, NULL,
                              NULL);
    /* the three trees take their regions at once, each in item order */
    if (st == LIE_OK)
        st = lie_parallel_for(3, workers, insert_axis, &bs, NULL, NULL);
    uint64_t fallback = 0;
    for (int a = 0; a < 3; a++) {
        r->stored += r->t[a].stored;
        r->nomem |= r->t[a].nomem;
    }
    for (size_t i = 0; st == LIE_OK && i < bs.n_items && !r->nomem; i++) {
        const region_out *o = &bs.outs[i];
        if (o->axis < 0) {
            add_fallback(r, bs.items[i].node, o->world);
            fallback++;
        }
    }
    size_t n_regions = bs.n_items;
    free(bs.hull);
    free(bs.items);
    free(bs.outs);
    if (st != LIE_OK && st != LIE_ERR_NOMEM) {
        lie_rst_destroy(r);
        return lie_error_set(err, st, s->path, "cannot start worker threads for the ray segment trees");
    }
    if (st != LIE_OK)
        r->nomem = 1;
    if (r->nomem) {
        lie_rst_destroy(r);
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory building ray segment trees");
    }
    if (stats) {
        memset(stats, 0, sizeof *stats);
        stats->regions = n_regions;
        stats->fallback = fallback;
        stats->stored = r->stored;
        size_t bytes = sizeof *r + sizeof(fb_region) * r->cap_fb;
        for (int a = 0; a < 3; a++) {
            stats->tree_nodes += r->t[a].n_nodes;
            bytes += sizeof(tnode) * r->t[a].cap_nodes;
            for (uint32_t i = 0; i < r->t[a].n_nodes; i++)
                bytes += sizeof(entry) * r->t[a].nodes[i].cap;
        }
        stats->bytes = bytes;
        stats->seconds = lie_time_now() - t0;
    }
    *out = r;
    return LIE_OK;
}

static uint64_t query_node(const tree *t, uint32_t ni, const lie_box3 *b, uint8_t *flags)
{
    const tnode *n = &t->nodes[ni];
    if (!box5_meets(t, &n->cell, b))
        return 0;
    uint64_t tested = 0;
    if (n->child >= 0)
        for (int k = 0; k < 32; k++)
            tested += query_node(t, (uint32_t)(n->child + k), b, flags);
    for (uint32_t i = 0; i < n->n; i++) {
        const entry *e = &n->e[i];
        tested++;
        if (!flags[e->node] && box5_meets(t, &e->b, b))
            flags[e->node] = 1;
    }
    return tested;
}

uint64_t lie_rst_query(const lie_rst *r, lie_box3 b, uint8_t *flags)
{
    uint64_t tested = 0;
    for (int a = 0; a < 3; a++)
        tested += query_node(&r->t[a], 0, &b, flags);
    for (uint32_t i = 0; i < r->n_fb; i++) {
        const lie_box3 *x = &r->fb[i].box;
        tested++;
        if (x->lo.x <= b.hi.x && x->hi.x >= b.lo.x && x->lo.y <= b.hi.y && x->hi.y >= b.lo.y &&
            x->lo.z <= b.hi.z && x->hi.z >= b.lo.z)
            flags[r->fb[i].node] = 1;
    }
    return tested;
}
