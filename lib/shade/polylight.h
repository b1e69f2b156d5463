/* SPDX-License-Identifier: Apache-2.0 */
/* Polygonal lights: an area emitter of one radiance, as convex polygons
 * in each of its planes, lighting Lambert receivers in closed form.
 *
 * Unshadowed: the projected solid angle of a polygon seen from a point with
 * normal n is Lambert's edge sum (Arvo 1995, "Applications of irradiance
 * tensors", eq. 11):
 *
 *   Omega_perp = 1/2 sum_i theta_i (n . gamma_i),
 *
 * theta_i the angle subtended by edge i and gamma_i the unit normal of the
 * plane through the point and that edge; irradiance is L Omega_perp.  The
 * polygon is first clipped to the receiver's hemisphere (the tangent plane
 * through the point), so every piece lies above it.
 *
 * Shadowed, exactly: the part of the emitter a point sees is the emitter
 * minus the shadows of its blockers, each blocker projected from the point
 * onto the emitter's plane (back-projection: Nishita & Nakamae 1985,
 * Drettakis & Fiume 1994).  A blocker is first cut to the slab between the
 * point and the emitter; its shadow is then the intersection of the
 * half-planes its edge planes through the point cut from the emitter's
 * plane, linear forms in the plane's (s, t) with no division by depth.
 * The visible region is kept as a list of convex polygons; a blocker is
 * subtracted from each by splitting it along the shadow's edges.  The edge
 * sum of the remaining pieces is the answer: no samples, no noise. */
#ifndef LIE_SHADE_POLYLIGHT_H
#define LIE_SHADE_POLYLIGHT_H

#include "scene/scene.h"

#define LIE_POLY_MAXV 16    /* vertices of one convex piece */
#define LIE_POLY_MAXP 2048  /* pieces of one visible region */
#define LIE_POLY_MAXF 32    /* edges of one shadow */

/* One convex polygon in the (s, t) coordinates of its part's plane,
 * counter-clockwise about the part's normal. */
typedef struct lie_poly2 {
    int n;
    int part;              /* the emitter's planar part it lies in */
    double s0, s1, t0, t1; /* its box (while subtracting shadows) */
    double s[LIE_POLY_MAXV], t[LIE_POLY_MAXV];
} lie_poly2;

/* One plane of the emitter: its frame, its convex pieces polys[first,
 * first + n), and its boundary: the edges of its triangles that no other
 * triangle of the part runs back along (shared edges cancel in the edge
 * sum), bv[first_bv + be[2 k]] -> bv[first_bv + be[2 k + 1]] for k in
 * [first_be, first_be + n_be), as (s, t) pairs, and a box holding it.
 * A part wholly above a point's tangent planes is summed over its boundary
 * (about half the edges of its pieces on a strip); one the planes cut, over
 * its clipped pieces. */
typedef struct lie_polypart {
    double po[3], pu[3], pv[3], pn[3];
    int first, n;
    int first_bv, first_be, n_be;
    double s0, s1, t0, t1;       /* the box of its boundary in (s, t) */
} lie_polypart;

/* Any emitter of one radiance made of triangles: its triangles grouped by
 * plane into parts (one part for a planar emitter), each part's triangles
 * merged into convex pieces.  A part whose triangles tile their convex
 * hull (a quad, a tessellated panel) is one piece; otherwise adjacent
 * triangles are merged across shared edges while the union stays convex
 * (Hertel & Mehlhorn 1983, on the given triangulation), so a strip of
 * hundreds of triangles, an L-shaped or holed panel become a few pieces
 * whose union is exactly the emitter.  Pieces of one part never overlap;
 * parts may face each other (a box, a bevelled strip), and then an own
 * triangle of one part can shadow another part. */
typedef struct lie_polylight {
    int emitter;
    uint32_t first_tri, n_tris; /* its own triangles */
    int two_sided;
    float radiance[3];
    double area;                 /* of its triangles */
    int n_parts;
    lie_polypart *parts;
    int n_polys;                 /* pieces, over all parts */
    lie_poly2 *polys;
    int32_t *tri_part;           /* per own triangle (first_tri + i), its part; -1: of no area */
    double *bv;                  /* boundary vertices (s, t), all parts */
    int32_t *be;                 /* boundary edges, vertex pairs within a part */
} lie_polylight;

/* The emitter as planar parts of convex pieces, or *out = NULL with LIE_OK
 * when the closed form does not serve it: not an area emitter, an emissive
 * texture (radiance not constant), or more than LIE_POLYLIGHT_MAX_PIECES
 * pieces (the edge sum would cost more than samples).  The caller owns
 * *out (lie_polylight_destroy). */
#define LIE_POLYLIGHT_MAX_PIECES 1024
lie_status lie_polylight_create(const lie_scene *s, int e, lie_polylight **out);
void lie_polylight_destroy(lie_polylight *L);

/* Per-worker workspace for blocker lists up to max_blockers long. */
typedef struct lie_polylight_work {
    lie_poly2 *a;    /* the pieces */
    int n;           /* how many the last unshadowed() or visible() left in a (0 on -1) */
    int *whole;      /* parts the last unshadowed() took whole (their pieces are not in a) */
    int n_whole;
    uint32_t *idx;   /* 2 cap */
    double *pts;     /* 2 (6 cap + 1) */
    int cap;
} lie_polylight_work;
lie_status lie_polylight_work_init(lie_polylight_work *w, int max_blockers);
void lie_polylight_work_free(lie_polylight_work *w);

/* Seen from o, with shading normal n and geometric normal ng (both unit):
 * the projected solid angle (about n) of the emitter's part above both
 * tangent planes, so that the irradiance is radiance x this.  The parts of
 * a non-planar emitter are summed as if none hid another (the LIE's lists
 * hold the emitter's own triangles where they do). */
double lie_polylight_unshadowed(const lie_polylight *L, lie_vec3 o, lie_vec3 n, lie_vec3 ng,
                                lie_polylight_work *w);

/* The same for the part that segments from o reach past the blocker
 * triangles tri_p[3 b], tri_p[3 b + 1], tri_p[3 b + 2] for b in blockers
 * (an own triangle shadows only the other parts of the emitter); a blocker within `eps` of the
 * emitter's plane blocks nothing there, as shadow segments stop eps short.
 * solid (per triangle, its closed convex solid or -1; may be NULL, see
 * lie_solids_find) lets the faces of one solid cast one shadow.
 * Returns 0 and fills *omega, or -1 when the region needs more pieces
 * than LIE_POLY_MAXP or a piece more than LIE_POLY_MAXV vertices (the
 * caller then samples). */
int lie_polylight_visible(const lie_polylight *L, lie_vec3 o, lie_vec3 n, lie_vec3 ng, const lie_vec3 *tri_p,
                          const int32_t *solid, const uint32_t *blockers, int n_blockers, float eps, lie_polylight_work *w,
                          double *omega);

/* Shared by polylight.c and polybuild.c: the signed area of a piece, and
 * the convex hull of pts (n x 2, sorted in place) counter-clockwise into
 * hull (room for n + 1 points); returns its vertex count. */
double lie_poly_area(const lie_poly2 *p);
int lie_poly_convex_hull(double *pts, int n, double *hull);

struct lie_ltc_shading;
/* For a receiver that is not Lambert: radiance x the LTC integral
 * (ltc.h) over the pieces that the last lie_polylight_unshadowed or
 * lie_polylight_visible left in w, each mapped from its part's plane to
 * directions from o. */
void lie_polylight_ltc(const lie_polylight *L, const struct lie_ltc_shading *sh, lie_vec3 o,
                       const lie_polylight_work *w, float out[3]);

/* The projected solid angle (sr) about n of triangle P seen from o, its
 * part above the tangent planes of n and ng, 0 from behind a one-sided
 * triangle (its front: counter-clockwise): one triangle's closed form
 * (Lambert's edge sum, as lie_polylight_unshadowed), for the light groups
 * of the budgeted samplers (sampler.h). */
double lie_triangle_unshadowed(const lie_vec3 P[3], int two_sided, lie_vec3 o, lie_vec3 n, lie_vec3 ng);

#endif
