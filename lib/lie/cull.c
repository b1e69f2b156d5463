/* SPDX-License-Identifier: Apache-2.0 */
/* Shaft culling (§4.1.2): the triangles that meet a patch-emitter pair's
 * hull, for conservative lists and for completing sampled ones
 * (lib/lie/cull.h). */
#include "lie/cull.h"
#include "lie/shaft.h"

#include <stdlib.h>

/* ---- conservative blocker lists (§4.1.2, shaft culling) ------------------ */

static void collect_candidate(void *ctx, uint32_t tri)
{
    worker *w = ctx;
    if (!LIE_PUSH(w->cand, w->n_cand, w->cap_cand, tri))
        w->nomem = 1;
}

static float v3_axis(lie_vec3 v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }

/* Candidates for the triangles that meet the convex hull of hull[0..nh)
 * (grown by tol when tol > 0) into w->cand, sorted and unique: Embree box
 * queries over the hull cut into slabs along its longest axis.  A slab's
 * box bounds the hull's part in it: the hull's points inside, and where
 * the segments between two points cross the slab's planes (the vertices of
 * a convex hull cut by a plane lie on such segments).  A long oblique
 * shaft so stops dragging in everything under its bounding box: a
 * terrain patch's shaft to a ceiling light touched thousands of ground
 * triangles.  Every triangle meeting the hull is among the candidates. */
#define SHAFT_SLABS 4

void lie_cull_candidates(const build_ctx *c, worker *w, const lie_vec3 *hull, int nh, float tol)
{
    lie_box3 all = lie_box3_empty();
    for (int i = 0; i < nh; i++)
        lie_box3_grow(&all, hull[i]);
    float grow = lie_maxf(tol, 0.0f) + 1e-6f * lie_pair_hull_scale(hull, nh);
    w->n_cand = 0;
    int a = 0;
    lie_vec3 ext = lie_v3_sub(all.hi, all.lo);
    if (ext.y > v3_axis(ext, a))
        a = 1;
    if (ext.z > v3_axis(ext, a))
        a = 2;
    float lo = v3_axis(all.lo, a), hi = v3_axis(all.hi, a), width = (hi - lo) / (float)SHAFT_SLABS;
    lie_box3 slab[SHAFT_SLABS];
    int n_slabs = 1;
    if (nh <= 64 && width > 0.0f && isfinite(width)) {
        n_slabs = SHAFT_SLABS;
        for (int k = 0; k < n_slabs; k++)
            slab[k] = lie_box3_empty();
        for (int i = 0; i < nh; i++) {
            float f = (v3_axis(hull[i], a) - lo) / width; /* NaN falls in slab 0, never through a cast */
            int k = f >= 1.0f ? (f < (float)n_slabs ? (int)f : n_slabs - 1) : 0;
            lie_box3_grow(&slab[k], hull[i]);
        }
        for (int i = 0; i < nh; i++)
            for (int j = i + 1; j < nh; j++) {
                float pa = v3_axis(hull[i], a), pb = v3_axis(hull[j], a);
                if (pa == pb)
                    continue;
                for (int k = 1; k < n_slabs; k++) {
                    float y = lo + (float)k * width;
                    if ((y - pa) * (y - pb) > 0.0f)
                        continue;
                    float t = (y - pa) / (pb - pa);
                    lie_vec3 x = lie_v3_add(hull[i], lie_v3_scale(lie_v3_sub(hull[j], hull[i]), t));
                    lie_box3_grow(&slab[k - 1], x);
                    lie_box3_grow(&slab[k], x);
                }
            }
        /* rounding of the crossing points: widen by their size's epsilon */
        grow += 1e-5f * lie_maxf(lie_v3_maxabs(all.lo), lie_v3_maxabs(all.hi));
    } else {
        slab[0] = all;
    }
    for (int k = 0; k < n_slabs; k++) {
        if (lie_box3_is_empty(&slab[k]))
            continue;
        lie_box3 b = slab[k];
        b.lo = lie_v3_sub(b.lo, lie_v3(grow, grow, grow));
        b.hi = lie_v3_add(b.hi, lie_v3(grow, grow, grow));
        lie_rt_box_query(c->rt, b, collect_candidate, w);
    }
    w->n_cand = lie_sort_unique(w->cand, w->n_cand);
}

/* The separating-axis prefilter for the hull in w->hull. */
static void pair_sat(const build_ctx *c, const worker *w, int nh, uint32_t tri, int two_sided, int e, float tol,
                     lie_sat *sat)
{
    const lie_vec3 *ne = lie_cluster_facing(c->s, e);
    lie_sat_init(sat, w->hull, nh, lie_pair_hull_patch_points(two_sided), c->s->tri_ng[tri], ne, tol);
}

/* The pair's hull into w->hull (see lie_pair_hull_points). */
static int pair_hull(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int e)
{
    if (!LIE_GROW(w->hull, w->cap_hull, lie_pair_hull_cap(c->s, e))) {
        w->nomem = 1;
        return 0;
    }
    return lie_pair_hull_points(c->s, tri, V, e, w->hull);
}

/* The emitter triangles a pair's shaft leaves out: the whole emitter's, or,
 * for one cluster of several (lie_cluster), the cluster's own; the other
 * clusters' triangles can block it as any triangle can. */
static int own_emitter_tri(const lie_scene *s, uint32_t t, int e)
{
    int em = s->clusters[e].emitter;
    return s->emitters[em].n_clusters > 1 ? s->tri_cluster[t] == e : s->tri_emitter[t] == em;
}

/* Every triangle other than the patch's own and the emitter's that enters
 * the pair's shaft, into w->cand (sorted, unique); returns how many.  Only
 * these can block a segment of the pair.  Triangles that merely touch the
 * shaft's boundary — a wall meeting the floor at the patch's edge, the
 * floor's neighbouring triangle — are left out: the hull's corners are
 * pulled in by a thousandth and contact does not count. */
static size_t shaft_upto(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e,
                         size_t limit)
{
    const lie_scene *s = c->s;
    lie_vec3 ctr = lie_v3_scale(lie_v3_add(V[0], lie_v3_add(V[1], V[2])), 1.0f / 3.0f);
    lie_vec3 W[3];
    for (int k = 0; k < 3; k++)
        W[k] = lie_v3_add(ctr, lie_v3_scale(lie_v3_sub(V[k], ctr), 0.999f));
    int nh = pair_hull(c, w, tri, W, e);
    if (!nh)
        return 0;
    int n_patch = lie_pair_hull_patch_points(two_sided);
    lie_vec3 ectr = lie_v3(0, 0, 0);
    for (int i = n_patch; i < nh; i++)
        ectr = lie_v3_add(ectr, w->hull[i]);
    ectr = lie_v3_scale(ectr, 1.0f / (float)(nh - n_patch));
    for (int i = n_patch; i < nh; i++)
        w->hull[i] = lie_v3_add(ectr, lie_v3_scale(lie_v3_sub(w->hull[i], ectr), 0.999f));
    float tol = -1e-7f * lie_pair_hull_scale(w->hull, nh); /* negative: contact is not entry */
    lie_cull_candidates(c, w, w->hull, nh, tol);
    lie_sat sat;
    pair_sat(c, w, nh, tri, two_sided, e, 0.0f, &sat);
    size_t m = 0;
    for (size_t i = 0; i < w->n_cand && m < limit; i++) {
        uint32_t t = w->cand[i];
        if (t == tri || own_emitter_tri(s, t, e) || !(s->tri_area[t] > 0.0f))
            continue;
        if (lie_sat_rejects(&sat, &s->tri_p[3 * (size_t)t]))
            continue;
        if (lie_hull_meets_triangle(w->hull, nh, &s->tri_p[3 * (size_t)t], tol))
            w->cand[m++] = t;
    }
    w->n_cand = lie_sort_unique(w->cand, m);
    return w->n_cand;
}

size_t lie_cull_shaft(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e)
{
    return shaft_upto(c, w, tri, V, two_sided, e, SIZE_MAX);
}

int lie_cull_shaft_empty(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e)
{
    return shaft_upto(c, w, tri, V, two_sided, e, 1) == 0 && !w->nomem;
}

/* Sampling finds a blocker's triangles where segments happened to hit it;
 * the rest of the same object inside the shaft blocks other rays.  Add every
 * triangle of an instance already in the list that meets the shaft. */
#define EXPAND_SCAN_MAX 256 /* instances up to this many triangles are scanned whole */

void lie_cull_expand(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e)
{
    const lie_scene *s = c->s;
    size_t n0 = w->n_hits;
    if (n0 == 0)
        return;
    int nh = pair_hull(c, w, tri, V, e);
    if (!nh)
        return;
    float tol = 1e-6f * lie_pair_hull_scale(w->hull, nh);
    lie_sat sat;
    pair_sat(c, w, nh, tri, two_sided, e, tol, &sat);
    /* A large instance (a terrain, a building exported as one mesh) is not
     * scanned whole: its candidates come from one Embree box query over the
     * shaft's bounds, shared by every large instance of the list. */
    int have_box = 0;
    uint32_t last = UINT32_MAX;
    for (size_t i = 0; i < n0; i++) {
        uint32_t inst = s->tri_instance[w->hits[i]];
        if (inst == last)
            continue; /* hits are sorted, so an instance's triangles are together */
        last = inst;
        const lie_instance *in = &s->instances[inst];
        int scan = in->n_tris <= EXPAND_SCAN_MAX;
        if (!scan && !have_box) {
            lie_cull_candidates(c, w, w->hull, nh, tol);
            if (w->nomem)
                return;
            have_box = 1;
        }
        size_t n_try = scan ? in->n_tris : w->n_cand;
        for (size_t k = 0; k < n_try; k++) {
            uint32_t t = scan ? in->first_tri + (uint32_t)k : w->cand[k];
            if (!scan && s->tri_instance[t] != inst)
                continue;
            if (t == tri || own_emitter_tri(s, t, e) || !(s->tri_area[t] > 0.0f))
                continue;
            if (lie_sat_rejects(&sat, &s->tri_p[3 * (size_t)t]) ||
                !lie_hull_meets_triangle(w->hull, nh, &s->tri_p[3 * (size_t)t], tol))
                continue;
            if (!LIE_PUSH(w->hits, w->n_hits, w->cap_hits, t)) {
                w->nomem = 1;
                return;
            }
        }
    }
    w->n_hits = lie_sort_unique(w->hits, w->n_hits);
}

lie_class lie_cull_conservative(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided,
                                int e, const uint32_t *parent, size_t n_parent, size_t limit,
                                size_t *n_list)
{
    const lie_scene *s = c->s;
    int nh = pair_hull(c, w, tri, V, e);
    w->n_hits = 0;
    *n_list = 0;
    if (!nh)
        return LIE_CLASS_VISIBLE;
    float tol = 1e-6f * lie_pair_hull_scale(w->hull, nh);
    const uint32_t *cand;
    size_t n_cand;
    if (parent) {
        /* a child's hull lies inside its parent's: only the parent's list can meet it */
        cand = parent;
        n_cand = n_parent;
    } else {
        lie_cull_candidates(c, w, w->hull, nh, tol);
        cand = w->cand;
        n_cand = w->n_cand;
    }
    lie_sat sat;
    pair_sat(c, w, nh, tri, two_sided, e, tol, &sat);
    for (size_t i = 0; i < n_cand && w->n_hits <= limit; i++) {
        uint32_t t = cand[i];
        if (t == tri || !(s->tri_area[t] > 0.0f)) /* empty triangles block nothing */
            continue;
        if (lie_sat_rejects(&sat, &s->tri_p[3 * (size_t)t]))
            continue;
        if (lie_hull_meets_triangle(w->hull, nh, &s->tri_p[3 * (size_t)t], tol) &&
            !LIE_PUSH(w->hits, w->n_hits, w->cap_hits, t)) {
            w->nomem = 1;
            return LIE_CLASS_VISIBLE;
        }
    }
    *n_list = w->n_hits;
    /* occlusion is never claimed: proving it needs more than a list */
    return w->n_hits ? LIE_CLASS_PARTIAL : LIE_CLASS_VISIBLE;
}
