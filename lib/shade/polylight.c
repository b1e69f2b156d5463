/* SPDX-License-Identifier: Apache-2.0 */
/* Polygonal lights in closed form (polylight.h): Lambert's edge sum over
 * the convex pieces of an emitter's planes, and the visible pieces left by
 * back-projected blockers (the pieces are built in polybuild.c).  Double precision throughout: the pieces are
 * cut by lines that nearly coincide (a blocker edge on the emitter's edge,
 * neighbouring blockers sharing an edge), and the edge sum of a thin
 * sliver must come out as thin.
 * Size: one job, the closed forms over an emitter's pieces: unshadowed,
 * visible and LTC share the clipping of pieces by planes and blockers. */
#include "shade/polylight.h"
#include "shade/ltc.h"

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

double lie_poly_area(const lie_poly2 *p)
{
    double a = 0.0;
    for (int i = 0, j = p->n - 1; i < p->n; j = i++)
        a += p->s[j] * p->t[i] - p->s[i] * p->t[j];
    return 0.5 * a;
}

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

/* Andrew's monotone chain. */
int lie_poly_convex_hull(double *pts, int n, double *hull)
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

lie_status lie_polylight_work_init(lie_polylight_work *w, int max_blockers)
{
    w->cap = max_blockers > 0 ? max_blockers : 1;
    w->a = malloc(sizeof *w->a * LIE_POLY_MAXP);
    w->idx = malloc(sizeof *w->idx * 2 * (size_t)w->cap);
    w->pts = malloc(sizeof *w->pts * 2 * (6 * (size_t)w->cap + 1));
    w->whole = malloc(sizeof *w->whole * LIE_POLYLIGHT_MAX_PIECES);
    w->n = w->n_whole = 0;
    if (!w->a || !w->idx || !w->pts || !w->whole) {
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
    LIE_FREE(w->whole);
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
        in->n = ni, in->part = p->part;
    if (out)
        out->n = no, out->part = p->part;
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

/* Part P's view from o and its pieces above both tangent planes into out;
 * returns their count, 0 if o sees nothing of the part (behind a one-sided
 * part, in its plane).  *d: the signed depth of the plane (< 0: o in
 * front). */
static int part_pieces(const lie_polylight *L, int part, lie_vec3 o, lie_vec3 n, lie_vec3 ng, view *vw, double *d,
                       lie_poly2 *out)
{
    const lie_polypart *P = &L->parts[part];
    const d3 O = {o.x, o.y, o.z};
    vw->w = d3_sub((d3){P->po[0], P->po[1], P->po[2]}, O);
    vw->u = (d3){P->pu[0], P->pu[1], P->pu[2]};
    vw->v = (d3){P->pv[0], P->pv[1], P->pv[2]};
    const d3 pn = {P->pn[0], P->pn[1], P->pn[2]};
    *d = d3_dot(pn, vw->w);
    if (!(*d < 0.0) && !(L->two_sided && *d > 0.0))
        return 0;
    const form fr = form_of(vw, d3_of(n)), fg = form_of(vw, d3_of(ng));
    int m = 0;
    double fv[LIE_POLY_MAXV], lo, hi;
    /* a piece is read where it lies and written once, to out[m] (a
     * point sees most pieces whole: copies were most of this loop) */
    for (int k = P->first; k < P->first + P->n; k++) {
        const lie_poly2 *a = &L->polys[k];
        lie_poly2 b;
        eval(a, fr, fv, &lo, &hi);
        if (hi <= 0.0)
            continue;
        if (lo < 0.0) {
            split(a, fv, &out[m], NULL); /* room kept at create: no overflow */
            a = &out[m];
        }
        eval(a, fg, fv, &lo, &hi);
        if (hi <= 0.0)
            continue;
        if (lo < 0.0) {
            split(a, fv, &b, NULL);
            out[m] = b;
            a = &out[m];
        }
        if (a->n >= 3) {
            if (a != &out[m])
                out[m] = *a;
            m++;
        }
    }
    return m;
}

/* The edge sums of pieces p[0..m) of one part, as a projected solid angle:
 * the pieces of a part share a winding, seen from either side. */
static double part_sum(const view *vw, const lie_poly2 *p, int m, d3 n)
{
    double sum = 0.0;
    for (int k = 0; k < m; k++)
        sum += edge_sum(vw, &p[k], n);
    return 0.5 * fabs(sum);
}

/* Lambert's edge sum over part P's boundary edges, seen through vw:
 * twice its projected solid angle, signed by its winding. */
static double boundary_sum(const lie_polylight *L, const lie_polypart *P, const view *vw, d3 n)
{
    const double *bv = L->bv + 2 * (size_t)P->first_bv;
    const int32_t *be = L->be + 2 * (size_t)P->first_be;
    double sum = 0.0;
    for (int k = 0; k < P->n_be; k++) {
        const double *a = &bv[2 * be[2 * k]], *b = &bv[2 * be[2 * k + 1]];
        d3 qa = {vw->w.x + a[0] * vw->u.x + a[1] * vw->v.x, vw->w.y + a[0] * vw->u.y + a[1] * vw->v.y,
                 vw->w.z + a[0] * vw->u.z + a[1] * vw->v.z};
        d3 qb = {vw->w.x + b[0] * vw->u.x + b[1] * vw->v.x, vw->w.y + b[0] * vw->u.y + b[1] * vw->v.y,
                 vw->w.z + b[0] * vw->u.z + b[1] * vw->v.z};
        d3 c = d3_cross(qa, qb);
        double cl = sqrt(d3_dot(c, c));
        if (cl > 0.0)
            sum += atan2(cl, d3_dot(qa, qb)) * (d3_dot(n, c) / cl);
    }
    return sum;
}

/* Whether all of part P lies strictly above the plane of form f (its
 * box's corners do: the least of a linear form over a box is at a corner). */
static int part_above(const lie_polypart *P, form f)
{
    return f.c + fmin(f.cs * P->s0, f.cs * P->s1) + fmin(f.ct * P->t0, f.ct * P->t1) > 0.0;
}

double lie_polylight_unshadowed(const lie_polylight *L, lie_vec3 o, lie_vec3 n, lie_vec3 ng,
                                lie_polylight_work *w)
{
    double omega = 0.0, d;
    const d3 N = d3_of(n);
    int m = 0;
    w->n_whole = 0;
    for (int j = 0; j < L->n_parts; j++) {
        const lie_polypart *P = &L->parts[j];
        view vw;
        vw.w = d3_sub((d3){P->po[0], P->po[1], P->po[2]}, d3_of(o));
        vw.u = (d3){P->pu[0], P->pu[1], P->pu[2]};
        vw.v = (d3){P->pv[0], P->pv[1], P->pv[2]};
        if (P->n > 1 && part_above(P, form_of(&vw, N)) && part_above(P, form_of(&vw, d3_of(ng)))) {
            /* wholly above both tangent planes: no clipping, and the
             * boundary alone (shared edges cancel) */
            d = P->pn[0] * vw.w.x + P->pn[1] * vw.w.y + P->pn[2] * vw.w.z;
            if (!(d < 0.0) && !(L->two_sided && d > 0.0))
                continue;
            omega += 0.5 * fabs(boundary_sum(L, P, &vw, N));
            w->whole[w->n_whole++] = j;
            continue;
        }
        int mp = part_pieces(L, j, o, n, ng, &vw, &d, w->a + m); /* pieces <= LIE_POLYLIGHT_MAX_PIECES: room */
        omega += part_sum(&vw, w->a + m, mp, N);
        m += mp;
    }
    w->n = m;
    return omega;
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

double lie_triangle_unshadowed(const lie_vec3 P[3], int two_sided, lie_vec3 o, lie_vec3 n, lie_vec3 ng)
{
    const d3 O = d3_of(o);
    d3 q[8], tmp[8];
    for (int k = 0; k < 3; k++)
        q[k] = d3_sub(d3_of(P[k]), O);
    /* seen from its front (or either side, two-sided) */
    d3 fn = d3_cross(d3_sub(q[1], q[0]), d3_sub(q[2], q[0]));
    double side = d3_dot(fn, q[0]);
    if (!(side < 0.0) && !(two_sided && side > 0.0))
        return 0.0;
    /* the part above both tangent planes */
    int m = clip3(q, 3, d3_of(n), 0.0, 1, tmp);
    if (m >= 3)
        m = clip3(q, m, d3_of(ng), 0.0, 1, tmp);
    if (m < 3)
        return 0.0;
    const d3 N = d3_of(n);
    double sum = 0.0;
    for (int i = 0, j = m - 1; i < m; j = i++) {
        d3 c = d3_cross(q[j], q[i]);
        double cl = sqrt(d3_dot(c, c));
        if (cl > 0.0)
            sum += atan2(cl, d3_dot(q[j], q[i])) * (d3_dot(N, c) / cl);
    }
    return 0.5 * fabs(sum);
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
    int nh = lie_poly_convex_hull(pts, np, hp);
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
    d->part = p->part;
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
 * Returns -1 on overflow (more than cap pieces). */
static int subtract(lie_poly2 *cur, int *m_io, int cap, const shadow *sh, double tiny)
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
            if (m >= cap || split(&in, fv, &tmp, &cur[m]) < 0)
                return -1;
            if (cur[m].n >= 3 && fabs(lie_poly_area(&cur[m])) > tiny) {
                piece_box(&cur[m]);
                m++;
            }
            poly_copy(&in, &tmp);
        }
        if (e < sh->nf) {
            if (m >= cap)
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

/* Part j of the emitter as seen from o past the blockers: its visible
 * pieces into cur (room for cap), their count in *m_out; returns the
 * part's projected solid angle, or -1 on overflow. */
static double part_visible(const lie_polylight *L, int j, lie_vec3 o, lie_vec3 n, lie_vec3 ng, const lie_vec3 *tri_p,
                           const int32_t *solid, const uint32_t *blockers, int n_blockers, float eps,
                           lie_polylight_work *w, lie_poly2 *cur, int cap, int *m_out)
{
    view vw;
    double d;
    int m = part_pieces(L, j, o, n, ng, &vw, &d, cur);
    *m_out = 0;
    if (m == 0)
        return 0.0;
    const d3 pn = {L->parts[j].pn[0], L->parts[j].pn[1], L->parts[j].pn[2]};
    const d3 k = d > 0.0 ? pn : (d3){-pn.x, -pn.y, -pn.z}; /* depth away from o */
    const double D = fabs(d), reach = D - (double)eps;
    if (!(reach > 0.0))
        return 0.0; /* o within eps of the part's plane */
    const double tiny = 1e-12 * L->area;
    const d3 O = {o.x, o.y, o.z};
    for (int i = 0; i < m; i++)
        piece_box(&cur[i]);
    /* Convex solids first, each as one shadow (the hull of its faces'
     * projections); their faces are then done.  The rest one by one. */
    enum { MAX_GROUPS = 16 };
    int32_t gid[MAX_GROUPS];
    int ng_ = 0;
    uint32_t *done = w->idx; /* 1: answered by its solid's hull */
    memset(done, 0, sizeof *done * (size_t)n_blockers);
    if (solid) {
        for (int b = 0; b < n_blockers; b++) {
            int32_t id = solid[blockers[b]];
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
            for (int b = 0; b < n_blockers; b++)
                if (solid[blockers[b]] == gid[g])
                    idx[ni++] = blockers[b];
            if (ni < 2)
                continue;
            shadow sh;
            if (!shadow_of_solid(&vw, k, D, reach, tri_p, O, idx, ni, w->pts, &sh))
                continue;
            if (subtract(cur, &m, cap, &sh, tiny) < 0)
                return -1.0;
            for (int b = 0; b < n_blockers; b++)
                if (solid[blockers[b]] == gid[g])
                    done[b] = 1;
        }
    }
    for (int b = 0; b < n_blockers && m > 0; b++) {
        uint32_t t = blockers[b];
        if (done[b] || (t - L->first_tri < L->n_tris && L->tri_part[t - L->first_tri] == j))
            continue; /* answered by its solid, or a triangle of this very part */
        const lie_vec3 *P = &tri_p[3 * (size_t)t];
        shadow sh;
        if (!shadow_of_triangle(&vw, k, D, reach, d3_sub(d3_of(P[0]), O), d3_sub(d3_of(P[1]), O),
                                d3_sub(d3_of(P[2]), O), &sh))
            continue;
        if (subtract(cur, &m, cap, &sh, tiny) < 0)
            return -1.0;
    }
    *m_out = m;
    return part_sum(&vw, cur, m, d3_of(n));
}

int lie_polylight_visible(const lie_polylight *L, lie_vec3 o, lie_vec3 n, lie_vec3 ng, const lie_vec3 *tri_p,
                          const int32_t *solid, const uint32_t *blockers, int n_blockers, float eps,
                          lie_polylight_work *w, double *omega)
{
    *omega = 0.0;
    w->n = w->n_whole = 0;
    if (n_blockers > w->cap)
        return -1;
    int m = 0;
    double sum = 0.0;
    for (int j = 0; j < L->n_parts; j++) {
        int mp;
        double om = part_visible(L, j, o, n, ng, tri_p, solid, blockers, n_blockers, eps, w, w->a + m,
                                 LIE_POLY_MAXP - m, &mp);
        if (om < 0.0)
            return -1;
        sum += om;
        m += mp;
    }
    *omega = sum;
    w->n = m;
    return 0;
}

/* radiance-free LTC integral of piece p (of its part's plane) from o, added to acc */
static void piece_ltc(const lie_polylight *L, const lie_ltc_shading *sh, lie_vec3 o, const lie_poly2 *p, float acc[3])
{
    const lie_polypart *P = &L->parts[p->part];
    const double wx = P->po[0] - o.x, wy = P->po[1] - o.y, wz = P->po[2] - o.z;
    lie_vec3 v[LIE_POLY_MAXV];
    for (int i = 0; i < p->n; i++) {
        double s = p->s[i], t = p->t[i];
        v[i] = lie_v3((float)(wx + s * P->pu[0] + t * P->pv[0]), (float)(wy + s * P->pu[1] + t * P->pv[1]),
                      (float)(wz + s * P->pu[2] + t * P->pv[2]));
    }
    float f[3];
    lie_ltc_polygon(sh, v, p->n, f);
    acc[0] += f[0], acc[1] += f[1], acc[2] += f[2];
}

void lie_polylight_ltc(const lie_polylight *L, const lie_ltc_shading *sh, lie_vec3 o, const lie_polylight_work *w,
                       float out[3])
{
    float acc[3] = {0.0f, 0.0f, 0.0f};
    for (int k = 0; k < w->n; k++)
        piece_ltc(L, sh, o, &w->a[k], acc);
    for (int k = 0; k < w->n_whole; k++) { /* above both tangent planes: the pieces as they are */
        const lie_polypart *P = &L->parts[w->whole[k]];
        for (int i = P->first; i < P->first + P->n; i++)
            piece_ltc(L, sh, o, &L->polys[i], acc);
    }
    for (int c = 0; c < 3; c++)
        out[c] = L->radiance[c] * acc[c];
}
