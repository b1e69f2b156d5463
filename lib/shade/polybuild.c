/* SPDX-License-Identifier: Apache-2.0 */
/* Building a polygonal light (polylight.h): an emitter's triangles grouped
 * by plane into parts, each part's triangles merged into convex pieces.
 *
 * The closed forms (Lambert's edge sum, the LTC integral, the shadows'
 * back-projection) work on convex polygons in a plane.  Real emitters are
 * strips of hundreds of small triangles, bevelled signs and letters, panels
 * with holes: not one convex polygon, often not one plane.  Every planar
 * region is a disjoint union of convex polygons, and the emitter's own
 * triangulation already is one; merging neighbours across shared edges
 * while the union stays convex (Hertel & Mehlhorn 1983, "Fast
 * triangulation of simple polygons", whose removal of inessential
 * diagonals leaves at most four times the fewest convex pieces) makes it a
 * short one.  Double precision throughout, as in polylight.c. */
#include "shade/polylight.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Room kept in a piece for the two hemisphere cuts and the splits of
 * polylight.c (each cut of a convex polygon adds at most one vertex). */
#define PIECE_MAXV (LIE_POLY_MAXV - 4)

/* sin of the angle under which three points count as on one line: the
 * vertices of float meshes stray from a straight edge by ~1e-7 of its
 * length, and a piece that keeps such a vertex is no less exact, only
 * longer. */
#define STRAIGHT 1e-6

static double turn2(const double *o, const double *a, const double *b)
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

/* The turn at a on the way p -> a -> q, against its tolerance: 1 a strict
 * left turn, 0 straight, -1 a right turn. */
static int corner(const double *p, const double *a, const double *q)
{
    double t = turn2(p, a, q);
    double l = sqrt(((a[0] - p[0]) * (a[0] - p[0]) + (a[1] - p[1]) * (a[1] - p[1])) *
                    ((q[0] - a[0]) * (q[0] - a[0]) + (q[1] - a[1]) * (q[1] - a[1])));
    return t > STRAIGHT * l ? 1 : t < -STRAIGHT * l ? -1 : 0;
}

typedef struct build {
    const lie_scene *s;
    lie_emitter_polygon pg;
    double size;         /* the emitter's box diagonal */
    /* the triangles, largest first */
    uint32_t *order;
    /* per triangle: unit normal and offset (double), its part */
    double *tn, *td;
    int32_t *part;
    /* the pieces so far */
    lie_poly2 *polys;
    int n_polys, cap_polys;
    /* the parts' boundaries so far: vertices (s, t), edges (vertex pairs) */
    double *bv;
    int32_t *be;
    int n_bv, cap_bv, n_be, cap_be;
} build;

/* Room for m more boundary vertices and edges. */
static int boundary_room(build *b, int m)
{
    if (b->n_bv + m > b->cap_bv) {
        int cap = 2 * (b->n_bv + m);
        double *nv = realloc(b->bv, sizeof *nv * 2 * (size_t)cap);
        if (!nv)
            return -1;
        b->bv = nv, b->cap_bv = cap;
    }
    if (b->n_be + m > b->cap_be) {
        int cap = 2 * (b->n_be + m);
        int32_t *ne = realloc(b->be, sizeof *ne * 2 * (size_t)cap);
        if (!ne)
            return -1;
        b->be = ne, b->cap_be = cap;
    }
    return 0;
}

static int push_piece(build *b, const lie_poly2 *p)
{
    if (b->n_polys == LIE_POLYLIGHT_MAX_PIECES)
        return 0;
    if (b->n_polys == b->cap_polys) {
        int cap = b->cap_polys ? 2 * b->cap_polys : 16;
        lie_poly2 *np = realloc(b->polys, sizeof *np * (size_t)cap);
        if (!np)
            return -1;
        b->polys = np;
        b->cap_polys = cap;
    }
    b->polys[b->n_polys++] = *p;
    return 1;
}

static int by_area(const void *x, const void *y, void *ctx)
{
    const float *area = ctx;
    uint32_t a = *(const uint32_t *)x, c = *(const uint32_t *)y;
    float aa = area[a], ac = area[c];
    if (aa != ac)
        return aa > ac ? -1 : 1;
    return a < c ? -1 : a > c;
}

/* ---- merging one part's triangles ---------------------------------------- */

typedef struct mesh2 {
    int nv;
    double *xy;          /* welded vertices (s, t) */
    int nh;              /* half-edges: 3 per triangle, h = 3 t + k */
    int *from, *next, *prev, *twin, *root, *corners;
    unsigned char *alive;
} mesh2;

static void mesh2_free(mesh2 *m)
{
    free(m->xy), free(m->from), free(m->next), free(m->prev), free(m->twin), free(m->root), free(m->corners),
        free(m->alive);
}

static int find_root(int *root, int i)
{
    while (root[i] != i) {
        root[i] = root[root[i]];
        i = root[i];
    }
    return i;
}

static int by_point(const void *x, const void *y, void *ctx)
{
    const double *pts = ctx;
    const double *p = &pts[2 * *(const int *)x], *q = &pts[2 * *(const int *)y];
    if (p[0] != q[0])
        return p[0] < q[0] ? -1 : 1;
    if (p[1] != q[1])
        return p[1] < q[1] ? -1 : 1;
    return *(const int *)x < *(const int *)y ? -1 : *(const int *)x > *(const int *)y;
}

typedef struct edge_key {
    int lo, hi, h;
} edge_key;

static int by_edge(const void *x, const void *y)
{
    const edge_key *a = x, *b = y;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi)
        return a->hi < b->hi ? -1 : 1;
    return a->h < b->h ? -1 : a->h > b->h;
}

typedef struct cand {
    double len2;
    int h;
} cand;

static int by_length(const void *x, const void *y)
{
    const cand *a = x, *b = y;
    if (a->len2 != b->len2)
        return a->len2 > b->len2 ? -1 : 1;
    return a->h < b->h ? -1 : a->h > b->h;
}

static const double *V(const mesh2 *m, int v) { return &m->xy[2 * v]; }
static int to_of(const mesh2 *m, int h) { return m->from[m->next[h]]; }

/* The part's triangles (pts: 6 doubles each, counter-clockwise) as a
 * half-edge mesh: corners welded where their coordinates are equal, twins
 * where exactly two half-edges run the same edge in opposite directions
 * (an edge of three triangles, or two of one winding, is left a border). */
static int mesh2_make(mesh2 *m, const double *pts, int nt)
{
    memset(m, 0, sizeof *m);
    const int nc = 3 * nt;
    m->nh = nc;
    m->xy = malloc(sizeof *m->xy * 2 * (size_t)nc);
    int *idx = malloc(sizeof *idx * (size_t)nc);
    edge_key *keys = malloc(sizeof *keys * (size_t)nc);
    m->from = malloc(sizeof(int) * (size_t)nc);
    m->next = malloc(sizeof(int) * (size_t)nc);
    m->prev = malloc(sizeof(int) * (size_t)nc);
    m->twin = malloc(sizeof(int) * (size_t)nc);
    m->root = malloc(sizeof(int) * (size_t)nt);
    m->corners = malloc(sizeof(int) * (size_t)nt);
    m->alive = malloc((size_t)nc);
    if (!m->xy || !idx || !keys || !m->from || !m->next || !m->prev || !m->twin || !m->root || !m->corners ||
        !m->alive) {
        free(idx), free(keys);
        return -1;
    }
    for (int i = 0; i < nc; i++)
        idx[i] = i;
    qsort_r(idx, (size_t)nc, sizeof *idx, by_point, (void *)pts);
    int nv = 0;
    for (int i = 0; i < nc; i++) {
        const double *p = &pts[2 * idx[i]];
        if (i == 0 || p[0] != m->xy[2 * (nv - 1)] || p[1] != m->xy[2 * (nv - 1) + 1]) {
            m->xy[2 * nv] = p[0], m->xy[2 * nv + 1] = p[1];
            nv++;
        }
        m->from[idx[i]] = nv - 1;
    }
    m->nv = nv;
    for (int t = 0; t < nt; t++) {
        m->root[t] = t;
        m->corners[t] = 3;
        for (int k = 0; k < 3; k++) {
            int h = 3 * t + k;
            m->next[h] = 3 * t + (k + 1) % 3;
            m->prev[h] = 3 * t + (k + 2) % 3;
            m->twin[h] = -1;
            m->alive[h] = 1;
        }
    }
    for (int h = 0; h < nc; h++) {
        int a = m->from[h], b = to_of(m, h);
        keys[h] = (edge_key){a < b ? a : b, a < b ? b : a, h};
    }
    qsort(keys, (size_t)nc, sizeof *keys, by_edge);
    for (int i = 0; i < nc;) {
        int j = i + 1;
        while (j < nc && keys[j].lo == keys[i].lo && keys[j].hi == keys[i].hi)
            j++;
        if (j - i == 2 && m->from[keys[i].h] != m->from[keys[i + 1].h]) {
            m->twin[keys[i].h] = keys[i + 1].h;
            m->twin[keys[i + 1].h] = keys[i].h;
        }
        i = j;
    }
    free(idx);
    free(keys);
    return 0;
}

/* Merge the pieces on both sides of half-edge h if their union is a convex
 * piece of at most PIECE_MAXV corners; returns whether it did. */
static int try_merge(mesh2 *m, int h)
{
    int g = m->twin[h];
    int P = find_root(m->root, h / 3), Q = find_root(m->root, g / 3);
    if (P == Q)
        return 0; /* the same piece on both sides: the edge bounds a hole */
    int a = m->from[h], b = m->from[g];
    int x = m->from[m->prev[h]], y = to_of(m, m->next[g]);
    int z = m->from[m->prev[g]], w = to_of(m, m->next[h]);
    if (x == y || z == w)
        return 0; /* the pieces share the next edge too (collinear): merging here leaves a spike */
    int ca = corner(V(m, x), V(m, a), V(m, y)), cb = corner(V(m, z), V(m, b), V(m, w));
    if (ca < 0 || cb < 0)
        return 0; /* the union turns right at a or b: not convex */
    int n = m->corners[P] + m->corners[Q] + ca + cb;
    n -= corner(V(m, x), V(m, a), V(m, b)) > 0;
    n -= corner(V(m, b), V(m, a), V(m, y)) > 0;
    n -= corner(V(m, a), V(m, b), V(m, w)) > 0;
    n -= corner(V(m, z), V(m, b), V(m, a)) > 0;
    if (n > PIECE_MAXV)
        return 0;
    int ph = m->prev[h], nh = m->next[h], pg = m->prev[g], ng = m->next[g];
    m->next[ph] = ng, m->prev[ng] = ph;
    m->next[pg] = nh, m->prev[nh] = pg;
    m->alive[h] = m->alive[g] = 0;
    m->root[Q] = P;
    m->corners[P] = n;
    return 1;
}

/* One part: the triangles tris[0..nt) (scene indices) in the plane (O, U,
 * V, N) as convex pieces into b.  Returns 1, 0 when they make too many
 * pieces, -1 out of memory. */
static int part_pieces(build *b, int part, const uint32_t *tris, int nt, const double *O, const double *U,
                       const double *Vv)
{
    const lie_scene *s = b->s;
    double *pts = malloc(sizeof *pts * 6 * (size_t)nt), *hull = malloc(sizeof *hull * 2 * (3 * (size_t)nt + 1));
    double *tmp = malloc(sizeof *tmp * 6 * (size_t)nt);
    if (!pts || !hull || !tmp) {
        free(pts), free(hull), free(tmp);
        return -1;
    }
    double area = 0.0;
    for (int i = 0; i < nt; i++) {
        double q[3][2];
        for (int k = 0; k < 3; k++) {
            lie_vec3 P = s->tri_p[3 * (size_t)tris[i] + (size_t)k];
            double d[3] = {P.x - O[0], P.y - O[1], P.z - O[2]};
            q[k][0] = d[0] * U[0] + d[1] * U[1] + d[2] * U[2];
            q[k][1] = d[0] * Vv[0] + d[1] * Vv[1] + d[2] * Vv[2];
        }
        double t = turn2(q[0], q[1], q[2]);
        area += 0.5 * fabs(t);
        for (int k = 0; k < 3; k++) { /* counter-clockwise */
            int src = t < 0.0 ? 2 - k : k;
            pts[6 * i + 2 * k] = q[src][0];
            pts[6 * i + 2 * k + 1] = q[src][1];
        }
    }
    memcpy(tmp, pts, sizeof *tmp * 6 * (size_t)nt);
    int nh = lie_poly_convex_hull(tmp, 3 * nt, hull);
    free(tmp);
    int r = 1;
    lie_poly2 p = {0};
    p.part = part;
    if (nh >= 3 && nh <= PIECE_MAXV) {
        p.n = nh;
        for (int k = 0; k < nh; k++)
            p.s[k] = hull[2 * k], p.t[k] = hull[2 * k + 1];
    }
    free(hull);
    if (p.n && fabs(lie_poly_area(&p) - area) <= 1e-5 * area) {
        /* the triangles tile their hull (a quad, a tessellated panel): one
         * piece, its own boundary */
        free(pts);
        if (boundary_room(b, p.n) < 0)
            return -1;
        for (int k = 0; k < p.n; k++) {
            b->bv[2 * (b->n_bv + k)] = p.s[k], b->bv[2 * (b->n_bv + k) + 1] = p.t[k];
            b->be[2 * (b->n_be + k)] = k, b->be[2 * (b->n_be + k) + 1] = (k + 1) % p.n;
        }
        b->n_bv += p.n, b->n_be += p.n;
        return push_piece(b, &p);
    }
    mesh2 m;
    if (mesh2_make(&m, pts, nt) < 0) {
        mesh2_free(&m);
        free(pts);
        return -1;
    }
    free(pts);
    /* the boundary: half-edges with no twin, before merging removes any */
    int *local = malloc(sizeof *local * (size_t)m.nv + 1);
    if (!local || boundary_room(b, m.nh) < 0) {
        free(local);
        mesh2_free(&m);
        return -1;
    }
    for (int v = 0; v < m.nv; v++)
        local[v] = -1;
    int nbv = 0;
    for (int h = 0; h < m.nh; h++) {
        if (m.twin[h] >= 0)
            continue;
        const int ends[2] = {m.from[h], to_of(&m, h)};
        for (int k = 0; k < 2; k++) {
            if (local[ends[k]] < 0) {
                local[ends[k]] = nbv;
                b->bv[2 * (b->n_bv + nbv)] = V(&m, ends[k])[0];
                b->bv[2 * (b->n_bv + nbv) + 1] = V(&m, ends[k])[1];
                nbv++;
            }
            b->be[2 * b->n_be + k] = local[ends[k]];
        }
        b->n_be++;
    }
    b->n_bv += nbv;
    free(local);
    cand *cs = malloc(sizeof *cs * (size_t)m.nh + 1);
    if (!cs) {
        mesh2_free(&m);
        return -1;
    }
    /* the longest shared edges first: removing them leaves the fattest pieces */
    int nc = 0;
    for (int h = 0; h < m.nh; h++)
        if (m.twin[h] > h) {
            const double *a = V(&m, m.from[h]), *c = V(&m, to_of(&m, h));
            cs[nc++] = (cand){(c[0] - a[0]) * (c[0] - a[0]) + (c[1] - a[1]) * (c[1] - a[1]), h};
        }
    qsort(cs, (size_t)nc, sizeof *cs, by_length);
    for (int i = 0; i < nc; i++)
        try_merge(&m, cs[i].h);
    free(cs);
    /* each piece's boundary, straight corners dropped */
    unsigned char *seen = calloc((size_t)m.nh + 1, 1);
    int *cyc = malloc(sizeof *cyc * (size_t)m.nh + 1);
    if (!seen || !cyc)
        r = -1;
    for (int h0 = 0; r == 1 && h0 < m.nh; h0++) {
        if (!m.alive[h0] || seen[h0])
            continue;
        int nc2 = 0, h = h0;
        do {
            seen[h] = 1;
            cyc[nc2++] = m.from[h];
            h = m.next[h];
        } while (h != h0 && nc2 < m.nh);
        p.n = 0;
        for (int i = 0; i < nc2 && r == 1; i++) {
            int pv = cyc[(i + nc2 - 1) % nc2], cv = cyc[i], nv = cyc[(i + 1) % nc2];
            if (corner(V(&m, pv), V(&m, cv), V(&m, nv)) == 0)
                continue;
            if (p.n == PIECE_MAXV)
                r = 0; /* cannot happen: merges count corners */
            else
                p.s[p.n] = V(&m, cv)[0], p.t[p.n] = V(&m, cv)[1], p.n++;
        }
        if (r == 1 && p.n >= 3)
            r = push_piece(b, &p);
    }
    free(seen);
    free(cyc);
    mesh2_free(&m);
    return r;
}

/* ---- grouping by plane --------------------------------------------------- */

/* The triangles' planes: a triangle joins the first part (largest triangle
 * first) whose normal is within 0.26 degrees of its own (either way for a
 * two-sided emitter) and whose plane holds its vertices to 1e-5 of the
 * emitter's size, as lib/scene/emitter_area.c tests a planar emitter. */
static int group(build *b, lie_polypart **parts_out, int *n_parts_out)
{
    const lie_scene *s = b->s;
    const uint32_t n = b->pg.n_tris, f = b->pg.first_tri;
    lie_polypart *parts = NULL;
    int np = 0, cap = 0;
    const double tol = 1e-5 * b->size;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t t = b->order[i];
        uint32_t k = t - f;
        b->part[k] = -1;
        if (!(s->tri_area[t] > 0.0f))
            continue;
        const lie_vec3 g = s->tri_ng[t];
        const double gn[3] = {g.x, g.y, g.z};
        int found = -1;
        for (int j = 0; j < np && found < 0; j++) {
            const double *pn = parts[j].pn;
            double c = gn[0] * pn[0] + gn[1] * pn[1] + gn[2] * pn[2];
            if (!(c > 0.99999) && !(b->pg.two_sided && c < -0.99999))
                continue;
            int in = 1;
            for (int q = 0; q < 3 && in; q++) {
                lie_vec3 P = s->tri_p[3 * (size_t)t + (size_t)q];
                double d = (P.x - parts[j].po[0]) * pn[0] + (P.y - parts[j].po[1]) * pn[1] + (P.z - parts[j].po[2]) * pn[2];
                in = fabs(d) <= tol;
            }
            if (in)
                found = j;
        }
        if (found < 0) {
            if (np == cap) {
                cap = cap ? 2 * cap : 8;
                lie_polypart *nparts = realloc(parts, sizeof *nparts * (size_t)cap);
                if (!nparts) {
                    free(parts);
                    return -1;
                }
                parts = nparts;
            }
            lie_polypart *P = &parts[np];
            memset(P, 0, sizeof *P);
            const lie_vec3 *A = &s->tri_p[3 * (size_t)t];
            /* the frame: the normal of the part's largest triangle in double
             * (its float normal would tilt the plane by ~1e-7, and every
             * vertex projected onto it with it), oriented as that normal; an
             * in-plane axis along its first edge */
            double u[3] = {(double)A[1].x - A[0].x, (double)A[1].y - A[0].y, (double)A[1].z - A[0].z};
            double w2[3] = {(double)A[2].x - A[0].x, (double)A[2].y - A[0].y, (double)A[2].z - A[0].z};
            double nn[3] = {u[1] * w2[2] - u[2] * w2[1], u[2] * w2[0] - u[0] * w2[2], u[0] * w2[1] - u[1] * w2[0]};
            double nl = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
            double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
            if (!(nl > 0.0) || !(ul > 0.0) || !isfinite(nl))
                continue; /* a sliver with no direction: too thin to emit */
            const double sg = nn[0] * gn[0] + nn[1] * gn[1] + nn[2] * gn[2] < 0.0 ? -1.0 : 1.0;
            for (int q = 0; q < 3; q++) {
                P->pn[q] = sg * nn[q] / nl;
                P->pu[q] = u[q] / ul; /* in the plane: u is an edge of the triangle */
            }
            const double *N = P->pn;
            P->pv[0] = N[1] * P->pu[2] - N[2] * P->pu[1];
            P->pv[1] = N[2] * P->pu[0] - N[0] * P->pu[2];
            P->pv[2] = N[0] * P->pu[1] - N[1] * P->pu[0];
            for (int q = 0; q < 3; q++) { /* the centroid, on the plane */
                const double c = ((double)(&A[0].x)[q] + (&A[1].x)[q] + (&A[2].x)[q]) / 3.0;
                P->po[q] = c;
            }
            found = np++;
        }
        b->part[k] = found;
    }
    *parts_out = parts;
    *n_parts_out = np;
    return 0;
}

/* The box of part P's boundary vertices bv[0..n) in (s, t), so of the part. */
static void part_box(lie_polypart *P, const double *bv, int n)
{
    P->s0 = P->t0 = INFINITY, P->s1 = P->t1 = -INFINITY;
    for (int i = 0; i < n; i++) {
        P->s0 = fmin(P->s0, bv[2 * i]), P->s1 = fmax(P->s1, bv[2 * i]);
        P->t0 = fmin(P->t0, bv[2 * i + 1]), P->t1 = fmax(P->t1, bv[2 * i + 1]);
    }
}

lie_status lie_polylight_create(const lie_scene *s, int e, lie_polylight **out)
{
    *out = NULL;
    build b;
    memset(&b, 0, sizeof b);
    b.s = s;
    if (!lie_emitter_polygon_of(s, e, &b.pg))
        return LIE_OK; /* not triangles of one radiance: sampled */
    const uint32_t n = b.pg.n_tris, f = b.pg.first_tri;
    lie_polylight *L = calloc(1, sizeof *L);
    b.order = malloc(sizeof *b.order * n);
    b.part = malloc(sizeof *b.part * n);
    uint32_t *tris = malloc(sizeof *tris * n);
    lie_polypart *parts = NULL;
    int np = 0;
    lie_status st = L && b.order && b.part && tris ? LIE_OK : LIE_ERR_NOMEM;
    if (st == LIE_OK) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t i = 0; i < 3 * n; i++) {
            const float *p = &s->tri_p[3 * (size_t)f + i].x;
            for (int q = 0; q < 3; q++)
                lo[q] = p[q] < lo[q] ? p[q] : lo[q], hi[q] = p[q] > hi[q] ? p[q] : hi[q];
        }
        b.size = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                      (hi[2] - lo[2]) * (hi[2] - lo[2]));
        for (uint32_t i = 0; i < n; i++)
            b.order[i] = f + i;
        qsort_r(b.order, n, sizeof *b.order, by_area, (void *)s->tri_area);
        if (group(&b, &parts, &np) < 0)
            st = LIE_ERR_NOMEM;
    }
    int ok = st == LIE_OK;
    for (int j = 0; ok && j < np; j++) {
        int nt = 0;
        for (uint32_t i = 0; i < n; i++)
            if (b.part[i] == j)
                tris[nt++] = f + i;
        lie_polypart *P = &parts[j];
        P->first = b.n_polys;
        P->first_bv = b.n_bv;
        P->first_be = b.n_be;
        int r = part_pieces(&b, j, tris, nt, P->po, P->pu, P->pv);
        if (r < 0)
            st = LIE_ERR_NOMEM;
        ok = r > 0;
        P->n = b.n_polys - P->first;
        P->n_be = b.n_be - P->first_be;
        part_box(P, b.bv + 2 * (size_t)P->first_bv, b.n_bv - P->first_bv);
    }
    free(tris);
    free(b.order);
    if (!ok || np == 0) {
        free(parts);
        free(b.part);
        free(b.polys);
        free(b.bv);
        free(b.be);
        free(L);
        return st; /* too many pieces (or no area): sampled */
    }
    L->emitter = e;
    L->first_tri = f;
    L->n_tris = n;
    L->two_sided = b.pg.two_sided;
    memcpy(L->radiance, b.pg.radiance, sizeof L->radiance);
    for (uint32_t i = 0; i < n; i++)
        L->area += b.part[i] >= 0 ? (double)s->tri_area[f + i] : 0.0;
    L->n_parts = np;
    L->parts = parts;
    L->n_polys = b.n_polys;
    L->polys = b.polys;
    L->tri_part = b.part;
    L->bv = b.bv;
    L->be = b.be;
    *out = L;
    return LIE_OK;
}

void lie_polylight_destroy(lie_polylight *L)
{
    if (!L)
        return;
    free(L->parts);
    free(L->polys);
    free(L->tri_part);
    free(L->bv);
    free(L->be);
    free(L);
}
