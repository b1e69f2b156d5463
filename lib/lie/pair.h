/* SPDX-License-Identifier: Apache-2.0 */
/* Pair geometry (lib/lie/pair.c): what a patch-emitter pair is, as
 * lie-build, the ray segment trees (lib/rst) and the renderer must all see
 * it for the LIE image to equal the reference.  The emitter side of a pair
 * is a cluster (lie_cluster): `e` below is a cluster index. */
#ifndef LIE_PAIR_H
#define LIE_PAIR_H

#include "core/core.h"
#include "rt/rt.h"
#include "scene/scene.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

/* How far shadow segments towards directional emitters reach: past the
 * scene's bounds (4 times their largest extent plus 4 times their
 * diagonal), rounded up to a power of two.  Their shafts depend on it, so
 * the rounding keeps it, and them, unchanged by edits that grow the bounds
 * a little; an update rebuilds the units of lights at infinity whenever
 * it does change (lib/update/mark.c). */
float lie_pair_ray_far(const lie_scene *s);
/* The size of the coordinates a pair's hull tests round at: the largest
 * coordinate magnitude among hull[0..n), at least 1.  Tolerances of shaft
 * tests are relative to it (float spacing grows with magnitude), never to
 * scene-wide sizes, so that a unit's list does not change when an edit
 * elsewhere grows the scene. */
float lie_pair_hull_scale(const lie_vec3 *hull, int n);
/* The renderer's largest shadow-ray offset on triangle tri. */
float lie_pair_eps(const lie_scene *s, uint32_t tri);
/* The hull of a pair, as lie-build and the ray segment trees see it: the
 * patch's corners V, lifted by lie_pair_eps on the side(s) it is shaded
 * from, and the emitter's points (vertices; a point light's position; for a
 * directional light the patch moved lie_pair_ray_far towards it).  `out` must
 * hold lie_pair_hull_cap(s, e) points; returns how many were written. */
int lie_pair_hull_cap(const lie_scene *s, int e);
int lie_pair_hull_points(const lie_scene *s, uint32_t tri, const lie_vec3 V[3], int e, lie_vec3 *out);
/* The hull's layout: first the patch's points (each corner, then it lifted
 * on the front, then on the back when two-sided), then the emitter's. */
static inline int lie_pair_hull_patch_points(int two_sided) { return two_sided ? 9 : 6; }
/* Whether triangle tri is shaded from both sides (a double-sided material). */
static inline int lie_pair_two_sided(const lie_scene *s, uint32_t tri)
{
    return lie_scene_material(s, s->tri_material[tri])->double_sided != 0;
}
/* 1 if the convex hull of hull[0..n) meets the box or comes within tol of
 * it; 0 only when a separating plane is proven. */
int lie_pair_hull_meets_box(const lie_vec3 *hull, int n, lie_box3 box, float tol);

/* 1 when no point of patch V of triangle tri (shaded from both sides when
 * two_sided) can receive light from any point of emitter e with a non-zero
 * geometric term: exactly the pairs whose every shadow sample the renderer
 * would weight 0. */
int lie_pair_unlit(const lie_scene *s, uint32_t tri, const lie_vec3 V[3], int two_sided, int e);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
