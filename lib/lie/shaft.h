/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/lie: the exact shaft test of conservative mode. */
#ifndef LIE_SHAFT_H
#define LIE_SHAFT_H

#include "core/core.h"

/* 1 if triangle `tri` meets the convex hull of hull[0..n_hull), or comes
 * within `tol` of it; 0 only when a separating plane is proven. */
int lie_hull_meets_triangle(const lie_vec3 *hull, int n_hull, const lie_vec3 tri[3], double tol);

/* The same for two convex hulls of points. */
int lie_hull_meets_hull(const lie_vec3 *a, int na, const lie_vec3 *b, int nb, double tol);

/* A quick separating-axis prefilter for one hull: its extent along a few
 * directions likely to separate (the patch's and emitter's normals, the
 * shaft's side directions, and for hulls of up to LIE_SAT_FACE_POINTS
 * points the normals of the hull's faces).  A triangle wholly beyond the extent along any
 * of them cannot meet the hull (exact: any direction is a valid axis). */
#define LIE_SAT_MAX 48
#define LIE_SAT_FACE_POINTS 24
typedef struct lie_sat {
    int n;
    lie_vec3 d[LIE_SAT_MAX];
    float lo[LIE_SAT_MAX], hi[LIE_SAT_MAX];
} lie_sat;
void lie_sat_init(lie_sat *sat, const lie_vec3 *hull, int n_hull, int n_patch, lie_vec3 patch_normal,
                  const lie_vec3 *emitter_normal, float tol);
/* 1 if an axis separates the triangle from the hull. */
int lie_sat_rejects(const lie_sat *sat, const lie_vec3 tri[3]);

#endif
