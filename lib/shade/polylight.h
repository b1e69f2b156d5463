/* SPDX-License-Identifier: Apache-2.0 */
/* Polygonal lights: a planar area emitter of one radiance, as convex
 * polygons in its plane, lighting Lambert receivers in closed form.
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
#define LIE_POLY_MAXP 512   /* pieces of one visible region */
#define LIE_POLY_MAXF 32    /* edges of one shadow */

/* One convex polygon in the emitter plane's (s, t) coordinates,
 * counter-clockwise about plane_n. */
typedef struct lie_poly2 {
    int n;
    double s0, s1, t0, t1; /* its box (while subtracting shadows) */
    double s[LIE_POLY_MAXV], t[LIE_POLY_MAXV];
} lie_poly2;

typedef struct lie_polylight {
    int emitter;
    uint32_t first_tri, n_tris; /* its own triangles: never its blockers */
    int two_sided;
    float radiance[3];
    double po[3], pu[3], pv[3], pn[3];
    double area;                 /* of its triangles, in the plane */
    int n_polys;                 /* the convex hull (when it is the emitter), else its triangles */
    lie_poly2 *polys;
} lie_polylight;

/* The emitter as convex polygons, or *out = NULL with LIE_OK when the
 * closed form does not serve it: not an area emitter, not planar, an
 * emissive texture (radiance not constant), or more than
 * LIE_POLYLIGHT_MAX_TRIS triangles whose union is not convex.  The caller
 * owns *out (lie_polylight_destroy). */
#define LIE_POLYLIGHT_MAX_TRIS 16
lie_status lie_polylight_create(const lie_scene *s, int e, lie_polylight **out);
void lie_polylight_destroy(lie_polylight *L);

/* Per-worker workspace for blocker lists up to max_blockers long. */
typedef struct lie_polylight_work {
    lie_poly2 *a;    /* the pieces */
    int n;           /* how many the last unshadowed() or visible() left in a (0 on -1) */
    uint32_t *idx;   /* 2 cap */
    double *pts;     /* 2 (6 cap + 1) */
    int cap;
} lie_polylight_work;
lie_status lie_polylight_work_init(lie_polylight_work *w, int max_blockers);
void lie_polylight_work_free(lie_polylight_work *w);

/* Seen from o, with shading normal n and geometric normal ng (both unit):
 * the projected solid angle (about n) of the emitter's part above both
 * tangent planes, so that the irradiance is radiance x this. */
double lie_polylight_unshadowed(const lie_polylight *L, lie_vec3 o, lie_vec3 n, lie_vec3 ng,
                                lie_polylight_work *w);

/* The same for the part that segments from o reach past the blocker
 * triangles tri_p[3 b], tri_p[3 b + 1], tri_p[3 b + 2] for b in blockers
 * (the emitter's own triangles are skipped); a blocker within `eps` of the
 * emitter's plane blocks nothing there, as shadow segments stop eps short.
 * solid (per triangle, its closed convex solid or -1; may be NULL, see
 * lie_solids_find) lets the faces of one solid cast one shadow.
 * Returns 0 and fills *omega, or -1 when the region needs more pieces
 * than LIE_POLY_MAXP or a piece more than LIE_POLY_MAXV vertices (the
 * caller then samples). */
int lie_polylight_visible(const lie_polylight *L, lie_vec3 o, lie_vec3 n, lie_vec3 ng, const lie_vec3 *tri_p,
                          const int32_t *solid, const uint32_t *blockers, int n_blockers, float eps, lie_polylight_work *w,
                          double *omega);

#endif
