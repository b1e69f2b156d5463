/* SPDX-License-Identifier: Apache-2.0 */
/* Shaft culling (§4.1.2): the triangles that meet a patch-emitter pair's
 * hull, for conservative lists and for completing sampled ones
 * (lib/lie/cull.h). */
#include "lie/cull.h"
#include "lie/shaft.h"

#include <stdlib.h>
#include <string.h>

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
                         size_t limit, int own_block)
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
        if (t == tri || (!own_block && own_emitter_tri(s, t, e)) || !(s->tri_area[t] > 0.0f))
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
    return shaft_upto(c, w, tri, V, two_sided, e, SIZE_MAX, 0);
}

size_t lie_cull_exact(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e,
                      size_t limit)
{
    /* a planar emitter's own triangles end every segment; those of one
     * that is not (a cube, a lamp's body) can block its other side */
    const lie_emitter *em = &c->s->emitters[c->s->clusters[e].emitter];
    int own_block = !(em->type == LIE_EMITTER_AREA && em->planar);
    size_t n = shaft_upto(c, w, tri, V, two_sided, e, limit + 1, own_block);
    if (w->nomem)
        return 0;
    if (!LIE_GROW(w->hits, w->cap_hits, n)) {
        w->nomem = 1;
        return 0;
    }
    memcpy(w->hits, w->cand, n * sizeof *w->hits);
    w->n_hits = n;
    return n;
}

int lie_cull_shaft_empty(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e)
{
    return shaft_upto(c, w, tri, V, two_sided, e, 1, 0) == 0 && !w->nomem;
}

/* Sampling finds a blocker's triangles where segments happened to hit it;
 * the rest of the same object inside the shaft blocks other rays.  Add every
 * triangle of an instance already in the list that meets the shaft, until
 * the list holds more than `limit`: the list decides splits (a leaf gets
 * its exact list, lib/lie/subdiv.c), and past complex_cap only its being
 * past counts.  In a corridor whose emitters run its length a shaft holds
 * most of the scene: expanding those lists whole was nine tenths of a
 * build (perf, scifi_hallway). */
#define EXPAND_SCAN_MAX 256 /* instances up to this many triangles are scanned whole */

void lie_cull_expand(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e,
                     size_t limit)
{
    const lie_scene *s = c->s;
    size_t n0 = w->n_hits;
    if (n0 == 0 || n0 > limit)
        return;
    const uint32_t id = w->stamp_id; /* the list's triangles carry it (lie_sample_pair) */
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
    for (size_t i = 0; i < n0 && w->n_hits <= limit; i++) {
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
        for (size_t k = 0; k < n_try && w->n_hits <= limit; k++) {
            uint32_t t = scan ? in->first_tri + (uint32_t)k : w->cand[k];
            if (!scan && s->tri_instance[t] != inst)
                continue;
            if (t == tri || w->stamp[t] == id || own_emitter_tri(s, t, e) || !(s->tri_area[t] > 0.0f))
                continue;
            if (lie_sat_rejects(&sat, &s->tri_p[3 * (size_t)t]) ||
                !lie_hull_meets_triangle(w->hull, nh, &s->tri_p[3 * (size_t)t], tol))
                continue;
            if (!LIE_PUSH(w->hits, w->n_hits, w->cap_hits, t)) {
                w->nomem = 1;
                return;
            }
            w->stamp[t] = id;
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

/* ---- proven occlusion ---------------------------------------------------
 *
 * Sampled segments that are all blocked do not prove a pair occluded: a
 * floor patch sees a cube on a table over the table's edge through a gap
 * no segment of the pattern passes (a whole patch would go black).  A
 * plane does prove it.  The pair's segments are the segments between its
 * patch's hull points and its emitter's (the convex hull of both, §4.1.2,
 * is exactly the union of those segments), so if a plane has the patch's
 * points strictly on one side and the emitter's strictly on the other,
 * every segment crosses it once, inside the convex polygon C spanned by
 * where the segments between the points cross it.  The pair is occluded if
 * the list's triangles in that plane cover C: the area C shares with each
 * of them sums to C's own (a mesh's triangles do not overlap; a wall of
 * any tessellation counts, not one triangle alone).  An alpha-masked
 * triangle proves nothing. */

/* Clip the convex polygon p[0..n) (counter-clockwise, 2D) to the half-plane
 * left of a -> b; returns the new count (out holds at most n + 1). */
static int clip_half(const double (*p)[2], int n, const double a[2], const double b[2], double (*out)[2])
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        const double *u = p[i], *v = p[(i + 1) % n];
        double su = (b[0] - a[0]) * (u[1] - a[1]) - (b[1] - a[1]) * (u[0] - a[0]);
        double sv = (b[0] - a[0]) * (v[1] - a[1]) - (b[1] - a[1]) * (v[0] - a[0]);
        if (su >= 0.0) {
            out[m][0] = u[0];
            out[m][1] = u[1];
            m++;
        }
        if ((su >= 0.0) != (sv >= 0.0)) {
            double t = su / (su - sv);
            out[m][0] = u[0] + t * (v[0] - u[0]);
            out[m][1] = u[1] + t * (v[1] - u[1]);
            m++;
        }
    }
    return m;
}

static double poly_area(const double (*p)[2], int n)
{
    double a = 0.0;
    for (int i = 0; i < n; i++)
        a += p[i][0] * p[(i + 1) % n][1] - p[(i + 1) % n][0] * p[i][1];
    return 0.5 * a;
}

static int cmp_pt2(const void *x, const void *y)
{
    const double *a = x, *b = y;
    return a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : a[1] < b[1] ? -1 : a[1] > b[1];
}

/* Counter-clockwise convex hull of p[0..n) (sorted in place) into h;
 * returns its count (h holds n + 1). */
static int hull_2d(double (*p)[2], int n, double (*h)[2])
{
    qsort(p, (size_t)n, sizeof *p, cmp_pt2);
    int k = 0;
    for (int pass = 0; pass < 2; pass++) {
        int lo = k;
        for (int j = 0; j < n; j++) {
            int i = pass ? n - 1 - j : j;
            while (k >= lo + 2 && (h[k - 1][0] - h[k - 2][0]) * (p[i][1] - h[k - 2][1]) -
                                          (h[k - 1][1] - h[k - 2][1]) * (p[i][0] - h[k - 2][0]) <=
                                      0.0)
                k--;
            h[k][0] = p[i][0];
            h[k][1] = p[i][1];
            k++;
        }
        k--; /* the last point is the next chain's first */
    }
    return k;
}

/* The largest hull the test handles: the patch's points times the emitter's. */
#define OCCLUSION_MAX_CROSS 1024

int lie_cull_occlusion_proven(const build_ctx *c, worker *w, uint32_t tri, const lie_vec3 V[3], int two_sided, int e,
                              const uint32_t *list, size_t n_list)
{
    const lie_scene *s = c->s;
    int nh = pair_hull(c, w, tri, V, e);
    int np = lie_pair_hull_patch_points(two_sided);
    if (nh <= np || np * (nh - np) > OCCLUSION_MAX_CROSS)
        return 0; /* an emitter of very many points: not proven here */
    float tol = 1e-6f * lie_rt_scale(c->rt);
    /* a segment stops lie_ray_eps short of its emitter point */
    double far_margin = 2.0 * (double)lie_pair_eps(s, tri) + (double)tol;
    size_t m_max = (size_t)np * (size_t)(nh - np);
    /* the crossings, their hull, two clipping buffers (a clip adds a point
     * a plane: at most hull + 3), the points' distances */
    double *mem = malloc(sizeof *mem * (2 * m_max + 2 * (m_max + 2) + 4 * (m_max + 8) + (size_t)nh));
    if (!mem) {
        w->nomem = 1;
        return 0;
    }
    double(*cross)[2] = (double(*)[2])mem;
    double(*poly)[2] = cross + m_max;
    double(*tmp)[2] = poly + m_max + 2;
    double *dist = mem + 2 * m_max + 2 * (m_max + 2) + 4 * (m_max + 8);
    int proven = 0;
    for (size_t i = 0; i < n_list && !proven; i++) {
        uint32_t t = list[i];
        const lie_vec3 *P = &s->tri_p[3 * (size_t)t];
        lie_vec3 n = s->tri_ng[t];
        if (!(s->tri_area[t] > 0.0f) || lie_scene_material(s, s->tri_material[t])->alpha_mask)
            continue;
        double d0 = (double)lie_v3_dot(n, P[0]);
        int side = 0, ok = 1;
        for (int k = 0; k < nh && ok; k++) {
            dist[k] = (double)lie_v3_dot(n, w->hull[k]) - d0;
            double margin = k < np ? (double)tol : far_margin;
            int sk = dist[k] > margin ? 1 : dist[k] < -margin ? -1 : 0;
            if (k < np && k == 0)
                side = sk;
            ok = sk != 0 && sk == (k < np ? side : -side);
        }
        if (!ok)
            continue;
        /* the plane's frame, and where the points' segments cross it */
        lie_vec3 u = fabsf(n.x) < 0.9f ? lie_v3_norm(lie_v3_cross(n, lie_v3(1, 0, 0)))
                                        : lie_v3_norm(lie_v3_cross(n, lie_v3(0, 1, 0)));
        lie_vec3 v = lie_v3_cross(n, u);
        int m = 0;
        for (int a = 0; a < np; a++)
            for (int b = np; b < nh; b++) {
                double f = dist[a] / (dist[a] - dist[b]);
                lie_vec3 pa = w->hull[a], pb = w->hull[b];
                double x = (double)pa.x + f * ((double)pb.x - (double)pa.x);
                double y = (double)pa.y + f * ((double)pb.y - (double)pa.y);
                double z = (double)pa.z + f * ((double)pb.z - (double)pa.z);
                cross[m][0] = x * u.x + y * u.y + z * u.z;
                cross[m][1] = x * v.x + y * v.y + z * v.z;
                m++;
            }
        int nc = hull_2d(cross, m, poly);
        double need = poly_area((const double(*)[2])poly, nc);
        if (!(need > 0.0))
            continue;
        /* the area of C the coplanar triangles of the list cover */
        double have = 0.0;
        for (size_t j = 0; j < n_list && have < need; j++) {
            uint32_t q = list[j];
            const lie_vec3 *Q = &s->tri_p[3 * (size_t)q];
            if (!(s->tri_area[q] > 0.0f) || lie_scene_material(s, s->tri_material[q])->alpha_mask ||
                fabs(fabsf(lie_v3_dot(s->tri_ng[q], n)) - 1.0f) > 1e-5f)
                continue;
            int coplanar = 1;
            for (int k = 0; k < 3 && coplanar; k++)
                coplanar = fabs((double)lie_v3_dot(n, Q[k]) - d0) <= (double)tol;
            if (!coplanar)
                continue;
            double tq[3][2];
            for (int k = 0; k < 3; k++) {
                tq[k][0] = (double)Q[k].x * u.x + (double)Q[k].y * u.y + (double)Q[k].z * u.z;
                tq[k][1] = (double)Q[k].x * v.x + (double)Q[k].y * v.y + (double)Q[k].z * v.z;
            }
            if ((tq[1][0] - tq[0][0]) * (tq[2][1] - tq[0][1]) - (tq[1][1] - tq[0][1]) * (tq[2][0] - tq[0][0]) < 0.0) {
                double sw[2] = {tq[1][0], tq[1][1]};
                tq[1][0] = tq[2][0], tq[1][1] = tq[2][1];
                tq[2][0] = sw[0], tq[2][1] = sw[1];
            }
            /* C clipped to the triangle: at most nc + 3 points */
            int k = nc;
            double(*src)[2] = tmp, (*dst)[2] = tmp + m_max + 8;
            for (int z = 0; z < nc; z++)
                src[z][0] = poly[z][0], src[z][1] = poly[z][1];
            for (int ed = 0; ed < 3 && k > 0; ed++) {
                k = clip_half((const double(*)[2])src, k, tq[ed], tq[(ed + 1) % 3], dst);
                double(*sw)[2] = src;
                src = dst;
                dst = sw;
            }
            if (k >= 3)
                have += poly_area((const double(*)[2])src, k);
        }
        proven = have >= need * (1.0 - 1e-6);
    }
    free(mem);
    return proven;
}
