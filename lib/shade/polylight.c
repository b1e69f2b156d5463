/* SPDX-License-Identifier: Apache-2.0 */
/* Polygonal lights in closed form (polylight.h): Lambert's edge sum over
 * convex pieces of a planar emitter, and the visible pieces left by
 * back-projected blockers.  Double precision throughout: the pieces are
 * cut by lines that nearly coincide (a blocker edge on the emitter's edge,
 * neighbouring blockers sharing an edge), and the edge sum of a thin
 * sliver must come out as thin. */
#include "shade/polylight.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct d3 {
    double x, y, z;
} d3;

static inline d3 d3_sub(d3 a, d3 b) { return (d3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static inline double d3_dot(d3 a, d3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline d3 d3_cross(d3 a, d3 b)
{
    return (d3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline d3 d3_of(lie_vec3 v) { return (d3){v.x, v.y, v.z}; }
static inline d3 d3_lerp(d3 a, d3 b, double t) { return (d3){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)}; }

static double poly_area(const lie_poly2 *p)
{
    double a = 0.0;
    for (int i = 0, j = p->n - 1; i < p->n; j = i++)
        a += p->s[j] * p->t[i] - p->s[i] * p->t[j];
    return 0.5 * a;
}

/* ---- building ------------------------------------------------------------ */

static int cmp_pt(const void *a, const void *b)
{
    const double *p = a, *q = b;
    if (p[0] != q[0])
        return p[0] < q[0] ? -1 : 1;
    return p[1] < q[1] ? -1 : p[1] > q[1];
}

static double turn(const double *o, const double *a, const double *b)
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

/* Andrew's monotone chain: the convex hull of pts (n x 2, sorted in place)
 * counter-clockwise into hull; returns its vertex count. */
static int convex_hull(double *pts, int n, double *hull)
{
    qsort(pts, (size_t)n, 2 * sizeof *pts, cmp_pt);
    int k = 0;
    for (int i = 0; i < n; i++) {
        while (k >= 2 && turn(&hull[2 * (k - 2)], &hull[2 * (k - 1)], &pts[2 * i]) <= 0.0)
            k--;
        hull[2 * k] = pts[2 * i], hull[2 * k + 1] = pts[2 * i + 1], k++;
    }
    for (int i = n - 2, lo = k + 1; i >= 0; i--) {
        while (k >= lo && turn(&hull[2 * (k - 2)], &hull[2 * (k - 1)], &pts[2 * i]) <= 0.0)
            k--;
        hull[2 * k] = pts[2 * i], hull[2 * k + 1] = pts[2 * i + 1], k++;
    }
    return k > 1 ? k - 1 : k;
}

lie_status lie_polylight_create(const lie_scene *s, int e, lie_polylight **out)
{
    *out = NULL;
    lie_emitter_polygon pg;
    if (!lie_emitter_polygon_of(s, e, &pg))
        return LIE_OK; /* not a polygon of one radiance: sampled */
    const size_t nv = 3 * (size_t)pg.n_tris;
    double *pts = malloc(sizeof *pts * 2 * nv), *hull = malloc(sizeof *hull * 2 * (nv + 1));
    lie_polylight *L = calloc(1, sizeof *L);
    if (!pts || !hull || !L) {
        free(pts), free(hull), free(L);
        return LIE_ERR_NOMEM;
    }
    L->emitter = e;
    L->first_tri = pg.first_tri;
    L->n_tris = pg.n_tris;
    L->two_sided = pg.two_sided;
    memcpy(L->radiance, pg.radiance, sizeof L->radiance);
    const lie_vec3 fr[4] = {pg.o, pg.u, pg.v, pg.n};
    double *dst[4] = {L->po, L->pu, L->pv, L->pn};
    for (int k = 0; k < 4; k++)
        dst[k][0] = fr[k].x, dst[k][1] = fr[k].y, dst[k][2] = fr[k].z;
    const d3 O = d3_of(pg.o), U = d3_of(pg.u), V = d3_of(pg.v);
    for (size_t i = 0; i < nv; i++) {
        d3 q = d3_sub(d3_of(s->tri_p[3 * (size_t)pg.first_tri + i]), O);
        pts[2 * i] = d3_dot(q, U);
        pts[2 * i + 1] = d3_dot(q, V);
    }
    double area = 0.0;
    for (uint32_t t = 0; t < pg.n_tris; t++) {
        const double *a = &pts[6 * t];
        area += 0.5 * fabs(turn(a, a + 2, a + 4));
    }
    L->area = area;
    /* the triangles as they are (counter-clockwise), before the hull sorts pts */
    lie_poly2 *tris = NULL;
    if (pg.n_tris <= LIE_POLYLIGHT_MAX_TRIS) {
        tris = malloc(sizeof *tris * pg.n_tris);
        if (!tris) {
            free(pts), free(hull), free(L);
            return LIE_ERR_NOMEM;
        }
        for (uint32_t t = 0; t < pg.n_tris; t++) {
            const double *a = &pts[6 * t];
            int flip = turn(a, a + 2, a + 4) < 0.0;
            tris[t].n = 3;
            for (int k = 0; k < 3; k++) {
                int src = flip ? 2 - k : k;
                tris[t].s[k] = a[2 * src];
                tris[t].t[k] = a[2 * src + 1];
            }
        }
    }
    int nh = convex_hull(pts, (int)nv, hull);
    lie_poly2 h = {0};
    h.n = nh <= LIE_POLY_MAXV - 4 ? nh : 0; /* room for the two hemisphere cuts and splits */
    for (int k = 0; k < h.n; k++)
        h.s[k] = hull[2 * k], h.t[k] = hull[2 * k + 1];
    free(pts);
    free(hull);
    if (h.n >= 3 && fabs(poly_area(&h) - area) <= 1e-5 * area) {
        /* the triangles tile their hull (a quad, a tessellated panel): one piece */
        free(tris);
        L->polys = malloc(sizeof *L->polys);
        if (!L->polys) {
            free(L);
            return LIE_ERR_NOMEM;
        }
        L->polys[0] = h;
        L->n_polys = 1;
    } else if (tris) {
        L->polys = tris;
        L->n_polys = (int)pg.n_tris;
    } else {
        free(L);
        return LIE_OK; /* many triangles, not convex: sampled */
    }
    *out = L;
    return LIE_OK;
}

void lie_polylight_destroy(lie_polylight *L)
{
    if (!L)
        return;
    free(L->polys);
    free(L);
}

lie_status lie_polylight_work_init(lie_polylight_work *w, int max_blockers)
{
    w->cap = max_blockers > 0 ? max_blockers : 1;
    w->a = malloc(sizeof *w->a * LIE_POLY_MAXP);
    w->idx = malloc(sizeof *w->idx * 2 * (size_t)w->cap);
    w->pts = malloc(sizeof *w->pts * 2 * (6 * (size_t)w->cap + 1));
    if (!w->a || !w->idx || !w->pts) {
        lie_polylight_work_free(w);
        return LIE_ERR_NOMEM;
    }
    return LIE_OK;
}

void lie_polylight_work_free(lie_polylight_work *w)
{
    if (!w)
        return;
    LIE_FREE(w->a);
    LIE_FREE(w->idx);
    LIE_FREE(w->pts);
}

/* ---- per shading point --------------------------------------------------- */

/* A linear form f(s, t) = c + cs s + ct t on the emitter's plane. */
typedef struct form {
    double c, cs, ct;
} form;

/* The shading point's view of the emitter: w = po - o and the frame. */
typedef struct view {
    d3 w, u, v;
} view;

static form form_of(const view *vw, d3 m) { return (form){d3_dot(m, vw->w), d3_dot(m, vw->u), d3_dot(m, vw->v)}; }

/* Split convex p by f: the part where f >= 0 into in, f <= 0 into out
 * (either may be NULL).  Returns -1 if a part would overflow. */
static int split(const lie_poly2 *p, const double *fv, lie_poly2 *in, lie_poly2 *out)
{
    int ni = 0, no = 0;
    for (int i = 0; i < p->n; i++) {
        int j = i + 1 == p->n ? 0 : i + 1;
        double fi = fv[i], fj = fv[j];
        if (fi >= 0.0 && in) {
            if (ni >= LIE_POLY_MAXV)
                return -1;
            in->s[ni] = p->s[i], in->t[ni] = p->t[i], ni++;
        }
        if (fi <= 0.0 && out) {
            if (no >= LIE_POLY_MAXV)
                return -1;
            out->s[no] = p->s[i], out->t[no] = p->t[i], no++;
        }
        if ((fi > 0.0 && fj < 0.0) || (fi < 0.0 && fj > 0.0)) {
            double a = fi / (fi - fj);
            double s = p->s[i] + a * (p->s[j] - p->s[i]), t = p->t[i] + a * (p->t[j] - p->t[i]);
            if (in) {
                if (ni >= LIE_POLY_MAXV)
                    return -1;
                in->s[ni] = s, in->t[ni] = t, ni++;
            }
            if (out) {
                if (no >= LIE_POLY_MAXV)
                    return -1;
                out->s[no] = s, out->t[no] = t, no++;
            }
        }
    }
    if (in)
        in->n = ni;
    if (out)
        out->n = no;
    return 0;
}

static void eval(const lie_poly2 *p, form f, double *fv, double *lo, double *hi)
{
    double a = INFINITY, b = -INFINITY;
    for (int i = 0; i < p->n; i++) {
        double x = f.c + f.cs * p->s[i] + f.ct * p->t[i];
        fv[i] = x;
        a = x < a ? x : a;
        b = x > b ? x : b;
    }
    *lo = a, *hi = b;
}

/* Lambert's edge sum of one piece, about n: twice its projected solid
 * angle, signed by its winding.  theta = atan2(|a x b|, a . b) keeps
 * short edges accurate where acos would not. */
static double edge_sum(const view *vw, const lie_poly2 *p, d3 n)
{
    d3 q[LIE_POLY_MAXV];
    for (int i = 0; i < p->n; i++) {
        double s = p->s[i], t = p->t[i];
        q[i] = (d3){vw->w.x + s * vw->u.x + t * vw->v.x, vw->w.y + s * vw->u.y + t * vw->v.y,
                    vw->w.z + s * vw->u.z + t * vw->v.z};
    }
    double sum = 0.0;
    for (int i = 0, j = p->n - 1; i < p->n; j = i++) {
        d3 c = d3_cross(q[j], q[i]);
        double cl = sqrt(d3_dot(c, c));
        if (cl > 0.0)
            sum += atan2(cl, d3_dot(q[j], q[i])) * (d3_dot(n, c) / cl);
    }
    return sum;
}

/* The view from o, and the emitter's pieces above both tangent planes into
 * w->a; returns their count, 0 if o sees nothing of the emitter (behind a
 * one-sided emitter, in its plane). */
static int visible_pieces(const lie_polylight *L, lie_vec3 o, lie_vec3 n, lie_vec3 ng, view *vw,
                          lie_polylight_work *w)
{
    const d3 O = {o.x, o.y, o.z};
    vw->w = d3_sub((d3){L->po[0], L->po[1], L->po[2]}, O);
    vw->u = (d3){L->pu[0], L->pu[1], L->pu[2]};
    vw->v = (d3){L->pv[0], L->pv[1], L->pv[2]};
    const d3 pn = {L->pn[0], L->pn[1], L->pn[2]};
    double d = d3_dot(pn, vw->w); /* < 0: o in front of the emitter */
    if (!(d < 0.0) && !(L->two_sided && d > 0.0))
        return 0;
    const form fr = form_of(vw, d3_of(n)), fg = form_of(vw, d3_of(ng));
    int m = 0;
    double fv[LIE_POLY_MAXV], lo, hi;
    for (int k = 0; k < L->n_polys; k++) {
        lie_poly2 a = L->polys[k], b;
        eval(&a, fr, fv, &lo, &hi);
        if (hi <= 0.0)
            continue;
        if (lo < 0.0) {
            split(&a, fv, &b, NULL); /* room kept at create: no overflow */
            a = b;
        }
        eval(&a, fg, fv, &lo, &hi);
        if (hi <= 0.0)
            continue;
        if (lo < 0.0) {
            split(&a, fv, &b, NULL);
            a = b;
        }
        if (a.n >= 3)
            w->a[m++] = a;
    }
    return m;
}

double lie_polylight_unshadowed(const lie_polylight *L, lie_vec3 o, lie_vec3 n, lie_vec3 ng,
                                lie_polylight_work *w)
{
    view vw;
    int m = visible_pieces(L, o, n, ng, &vw, w);
    w->n = m;
    double sum = 0.0;
    const d3 N = d3_of(n);
    for (int k = 0; k < m; k++)
        sum += edge_sum(&vw, &w->a[k], N);
    return 0.5 * fabs(sum);
}

/* Sutherland-Hodgman of a 3D polygon against k . q >= c (keep), in place
 * through tmp; returns the new count. */
static int clip3(d3 *q, int nq, d3 k, double c, int keep_above, d3 *tmp)
{
    int m = 0;
    for (int i = 0; i < nq; i++) {
        int j = i + 1 == nq ? 0 : i + 1;
        double fi = d3_dot(k, q[i]) - c, fj = d3_dot(k, q[j]) - c;
        if (!keep_above)
            fi = -fi, fj = -fj;
        if (fi >= 0.0)
            tmp[m++] = q[i];
        if ((fi > 0.0 && fj < 0.0) || (fi < 0.0 && fj > 0.0))
            tmp[m++] = d3_lerp(q[i], q[j], fi / (fi - fj));
    }
    memcpy(q, tmp, sizeof *q * (size_t)m);
    return m;
}

/* A shadow: forms whose common non-negative part it is, and its box. */
typedef struct shadow {
    int nf;
    form f[LIE_POLY_MAXF];
    double s0, s1, t0, t1;
} shadow;

static void shadow_box_empty(shadow *sh) { sh->s0 = sh->t0 = INFINITY, sh->s1 = sh->t1 = -INFINITY; }

/* Grow the box by the projection of q (relative to o, depth l > 0). */
static void shadow_box_grow(shadow *sh, const view *vw, double D, d3 q, double l)
{
    if (!(l > 1e-9 * D)) {
        sh->s0 = sh->t0 = -INFINITY, sh->s1 = sh->t1 = INFINITY;
        return;
    }
    double k = D / l;
    double s = k * d3_dot(q, vw->u) - d3_dot(vw->w, vw->u), t = k * d3_dot(q, vw->v) - d3_dot(vw->w, vw->v);
    sh->s0 = s < sh->s0 ? s : sh->s0, sh->s1 = s > sh->s1 ? s : sh->s1;
    sh->t0 = t < sh->t0 ? t : sh->t0, sh->t1 = t > sh->t1 ? t : sh->t1;
}

/* The shadow of blocker (a, b, c) (relative to o) on the emitter's plane;
 * returns 0 when it casts none (wholly behind o or beyond the plane's
 * reach, its plane through o, degenerate). */
static int shadow_of_triangle(const view *vw, d3 k, double D, double reach, d3 a, d3 b, d3 c, shadow *sh)
{
    d3 nt = d3_cross(d3_sub(b, a), d3_sub(c, a));
    double h = d3_dot(nt, a);
    double scale = sqrt(d3_dot(nt, nt)) * sqrt(d3_dot(a, a));
    if (!(fabs(h) > 1e-12 * scale))
        return 0; /* its plane holds o: a shadow of no area */
    d3 q[5] = {a, b, c}, tmp[5];
    int nq = 3;
    double la = d3_dot(k, a), lb = d3_dot(k, b), lc = d3_dot(k, c);
    if ((la <= 0.0 && lb <= 0.0 && lc <= 0.0) || (la >= reach && lb >= reach && lc >= reach))
        return 0;
    if (la < 0.0 || lb < 0.0 || lc < 0.0)
        nq = clip3(q, nq, k, 0.0, 1, tmp); /* a segment leaves o forward */
    if (nq >= 3 && (la > reach || lb > reach || lc > reach))
        nq = clip3(q, nq, k, reach, 0, tmp); /* and stops short of the emitter */
    if (nq < 3)
        return 0;
    const double sg = h > 0.0 ? 1.0 : -1.0;
    int m = 0;
    shadow_box_empty(sh);
    for (int i = 0, j = nq - 1; i < nq; j = i++) {
        shadow_box_grow(sh, vw, D, q[i], d3_dot(k, q[i]));
        d3 e = d3_cross(q[j], q[i]);
        double el = d3_dot(e, e), qq = d3_dot(q[j], q[j]) * d3_dot(q[i], q[i]);
        if (!(el > 1e-24 * qq))
            continue; /* a repeated vertex: no edge */
        e = (d3){sg * e.x, sg * e.y, sg * e.z};
        sh->f[m++] = form_of(vw, e);
    }
    sh->nf = m;
    return m >= 3;
}

/* The shadow of a closed convex solid that o is outside of, from its
 * listed faces idx[0..n): the cone from o over their vertices (within the
 * solid's shadow cone, and holding the shadows of the faces that block).
 * A front face's plane separates o from the solid, so its inward normal c
 * has c . q > 0 for every vertex q (relative to o): the vertices projected
 * centrally onto c . x = 1 stay finite even for a solid standing beside o,
 * and their 2D convex hull gives the cone's extreme rays.  Returns 0 when
 * it does not apply (no listed face faces o, a vertex reaches the
 * emitter's plane, too many hull edges). */
static int shadow_of_solid(const view *vw, d3 k, double D, double reach, const lie_vec3 *tri_p, d3 O,
                           const uint32_t *idx, int n, double *pts, shadow *sh)
{
    d3 c = {0.0, 0.0, 0.0};
    double best = 0.0;
    for (int j = 0; j < n; j++) {
        const lie_vec3 *P = &tri_p[3 * (size_t)idx[j]];
        d3 a = d3_sub(d3_of(P[0]), O), b = d3_sub(d3_of(P[1]), O), cc = d3_sub(d3_of(P[2]), O);
        d3 nt = d3_cross(d3_sub(b, a), d3_sub(cc, a));
        double len = sqrt(d3_dot(nt, nt));
        double dist = len > 0.0 ? -d3_dot(nt, a) / len : 0.0; /* > 0: o in front of this outward face */
        if (dist > best)
            best = dist, c = (d3){-nt.x / len, -nt.y / len, -nt.z / len};
    }
    if (!(best > 0.0))
        return 0;
    /* a frame (e1, e2) of the plane c . x = 1 */
    d3 t = fabs(c.x) < 0.6 ? (d3){1.0, 0.0, 0.0} : (d3){0.0, 1.0, 0.0};
    d3 e1 = d3_cross(c, t);
    double l1 = sqrt(d3_dot(e1, e1));
    e1 = (d3){e1.x / l1, e1.y / l1, e1.z / l1};
    d3 e2 = d3_cross(c, e1);
    int np = 0;
    for (int j = 0; j < n; j++) {
        const lie_vec3 *P = &tri_p[3 * (size_t)idx[j]];
        for (int i = 0; i < 3; i++) {
            d3 q = d3_sub(d3_of(P[i]), O);
            if (!(d3_dot(k, q) < reach))
                return 0; /* reaches the emitter: the depth decides, not the cone */
            double z = d3_dot(c, q);
            if (!(z > 0.0))
                return 0;
            pts[2 * np] = d3_dot(e1, q) / z;
            pts[2 * np + 1] = d3_dot(e2, q) / z;
            np++;
        }
    }
    double *hp = pts + 2 * np; /* the hull after the points (room for 3n + 1 more) */
    int nh = convex_hull(pts, np, hp);
    if (nh < 3 || nh > LIE_POLY_MAXF)
        return 0;
    /* back to rays, counter-clockwise about c: inside is m . d >= 0 */
    d3 r[LIE_POLY_MAXF];
    shadow_box_empty(sh);
    for (int i = 0; i < nh; i++) {
        const double x = hp[2 * i], y = hp[2 * i + 1];
        r[i] = (d3){c.x + x * e1.x + y * e2.x, c.y + x * e1.y + y * e2.y, c.z + x * e1.z + y * e2.z};
        shadow_box_grow(sh, vw, D, r[i], d3_dot(k, r[i]));
    }
    for (int i = 0; i < nh; i++)
        sh->f[i] = form_of(vw, d3_cross(r[i], r[(i + 1) % nh]));
    sh->nf = nh;
    return 1;
}

/* *d = *p, only as far as p's vertices go */
static inline void poly_copy(lie_poly2 *d, const lie_poly2 *p)
{
    d->n = p->n;
    d->s0 = p->s0, d->s1 = p->s1, d->t0 = p->t0, d->t1 = p->t1;
    memcpy(d->s, p->s, sizeof *d->s * (size_t)p->n);
    memcpy(d->t, p->t, sizeof *d->t * (size_t)p->n);
}

static void piece_box(lie_poly2 *p)
{
    double s0 = INFINITY, s1 = -INFINITY, t0 = INFINITY, t1 = -INFINITY;
    for (int i = 0; i < p->n; i++) {
        s0 = p->s[i] < s0 ? p->s[i] : s0, s1 = p->s[i] > s1 ? p->s[i] : s1;
        t0 = p->t[i] < t0 ? p->t[i] : t0, t1 = p->t[i] > t1 ? p->t[i] : t1;
    }
    p->s0 = s0, p->s1 = s1, p->t0 = t0, p->t1 = t1;
}

/* Subtract a shadow from the pieces cur[0..*m), in place: a piece the
 * shadow misses stays, one it cuts is replaced by its parts outside.
 * Returns -1 on overflow. */
static int subtract(lie_poly2 *cur, int *m_io, const shadow *sh, double tiny)
{
    int m = *m_io;
    const int m0 = m;
    for (int i = 0; i < m0; i++) {
        lie_poly2 *p = &cur[i];
        if (p->n == 0 || p->s1 < sh->s0 || p->s0 > sh->s1 || p->t1 < sh->t0 || p->t0 > sh->t1)
            continue;
        double fv[LIE_POLY_MAXV], lo = 0.0, hi = 0.0;
        int e = 0, cut = 0;
        for (; e < sh->nf; e++) {
            eval(p, sh->f[e], fv, &lo, &hi);
            if (hi <= 0.0)
                break; /* wholly outside this edge: untouched */
            if (lo < 0.0)
                break;
        }
        if (e == sh->nf) {
            p->n = 0; /* wholly in the shadow */
            continue;
        }
        if (hi <= 0.0)
            continue;
        /* cut along the remaining edges: the parts outside are kept */
        lie_poly2 in, tmp;
        tmp.s0 = tmp.s1 = tmp.t0 = tmp.t1 = 0.0; /* split() leaves the box to piece_box() */
        poly_copy(&in, p);
        for (; e < sh->nf; e++) {
            if (cut)
                eval(&in, sh->f[e], fv, &lo, &hi);
            cut = 1;
            if (hi <= 0.0)
                break;
            if (lo >= 0.0)
                continue;
            if (m >= LIE_POLY_MAXP || split(&in, fv, &tmp, &cur[m]) < 0)
                return -1;
            if (cur[m].n >= 3 && fabs(poly_area(&cur[m])) > tiny) {
                piece_box(&cur[m]);
                m++;
            }
            poly_copy(&in, &tmp);
        }
        if (e < sh->nf) {
            if (m >= LIE_POLY_MAXP)
                return -1;
            piece_box(&in);
            poly_copy(&cur[m++], &in); /* the rest lies outside an edge: kept */
        }
        p->n = 0;
    }
    /* fill the holes from the end */
    int k = 0;
    while (k < m) {
        if (cur[k].n) {
            k++;
            continue;
        }
        while (m > k && cur[m - 1].n == 0)
            m--;
        if (m > k + 1) {
            poly_copy(&cur[k], &cur[m - 1]);
            m--;
            k++;
        } else {
            m = k;
        }
    }
    *m_io = m;
    return 0;
}

int lie_polylight_visible(const lie_polylight *L, lie_vec3 o, lie_vec3 n, lie_vec3 ng, const lie_vec3 *tri_p,
                          const int32_t *solid, const uint32_t *blockers, int n_blockers, float eps,
                          lie_polylight_work *w, double *omega)
{
    view vw;
    int m = visible_pieces(L, o, n, ng, &vw, w);
    *omega = 0.0;
    w->n = 0;
    if (m == 0)
        return 0;
    const d3 pn = {L->pn[0], L->pn[1], L->pn[2]};
    const double d = d3_dot(pn, vw.w);
    const d3 k = d > 0.0 ? pn : (d3){-pn.x, -pn.y, -pn.z}; /* depth away from o */
    const double D = fabs(d), reach = D - (double)eps;
    if (!(reach > 0.0))
        return 0; /* o within eps of the emitter's plane */
    const double tiny = 1e-12 * L->area;
    const d3 O = {o.x, o.y, o.z};
    lie_poly2 *cur = w->a;
    for (int i = 0; i < m; i++)
        piece_box(&cur[i]);
    /* Convex solids first, each as one shadow (the hull of its faces'
     * projections); their faces are then done.  The rest one by one. */
    enum { MAX_GROUPS = 16 };
    int32_t gid[MAX_GROUPS];
    int ng_ = 0;
    uint32_t *done = w->idx; /* 1: answered by its solid's hull */
    if (n_blockers > w->cap)
        return -1;
    memset(done, 0, sizeof *done * (size_t)n_blockers);
    if (solid) {
        for (int j = 0; j < n_blockers; j++) {
            int32_t id = solid[blockers[j]];
            if (id < 0)
                continue;
            int g = 0;
            while (g < ng_ && gid[g] != id)
                g++;
            if (g == ng_ && ng_ < MAX_GROUPS)
                gid[ng_++] = id;
        }
        for (int g = 0; g < ng_ && m > 0; g++) {
            uint32_t *idx = w->idx + n_blockers;
            int ni = 0;
            for (int j = 0; j < n_blockers; j++)
                if (solid[blockers[j]] == gid[g])
                    idx[ni++] = blockers[j];
            if (ni < 2)
                continue;
            shadow sh;
            if (!shadow_of_solid(&vw, k, D, reach, tri_p, O, idx, ni, w->pts, &sh))
                continue;
            if (subtract(cur, &m, &sh, tiny) < 0)
                return -1;
            for (int j = 0; j < n_blockers; j++)
                if (solid[blockers[j]] == gid[g])
                    done[j] = 1;
        }
    }
    for (int j = 0; j < n_blockers && m > 0; j++) {
        uint32_t b = blockers[j];
        if (done[j] || b - L->first_tri < L->n_tris)
            continue; /* answered by its solid, or the emitter's own triangle */
        const lie_vec3 *P = &tri_p[3 * (size_t)b];
        shadow sh;
        if (!shadow_of_triangle(&vw, k, D, reach, d3_sub(d3_of(P[0]), O), d3_sub(d3_of(P[1]), O),
                                d3_sub(d3_of(P[2]), O), &sh))
            continue;
        if (subtract(cur, &m, &sh, tiny) < 0)
            return -1;
    }
    double sum = 0.0;
    const d3 N = d3_of(n);
    for (int i = 0; i < m; i++)
        sum += edge_sum(&vw, &cur[i], N);
    *omega = 0.5 * fabs(sum);
    w->n = m;
    return 0;
}
