/* SPDX-License-Identifier: Apache-2.0 */
/* Sampling a triangle by the solid angle it subtends (Arvo 1995,
 * "Stratified sampling of spherical triangles", SIGGRAPH '95).
 *
 * Near an emitter, points chosen uniformly by area waste most samples: the
 * integrand cos / d^2 is largest under the point and the area density
 * spreads samples where it is small, so a pixel beside an emissive strip
 * sees a few samples as point lights.  Chosen uniformly over the spherical
 * triangle instead, every direction of the triangle gets the same share and
 * the estimate of the projected solid angle only varies with the receiver's
 * cosine.  Arvo's map from the unit square is continuous and
 * area-preserving, so stratified or low-discrepancy (u1, u2) stay so on the
 * sphere.
 *
 * The map needs the triangle's angles, and its second step 1 - cos of an
 * arc: both lose precision as the solid angle shrinks.  Far away, area
 * sampling is as good (the integrand is nearly constant), so setup refuses
 * tiny solid angles, as pbrt-v4 does (Pharr, Jakob, Humphreys 2023,
 * "Physically Based Rendering", 4th ed., §6.5.4): the caller then samples
 * by area.  Double precision throughout; no allocation; reentrant. */
#ifndef LIE_SHADE_SPHERICAL_H
#define LIE_SHADE_SPHERICAL_H

#include "core/core.h"

/* Below this solid angle (sr) area sampling is as good and better
 * conditioned; above it, nearly a hemisphere, the angles are ill
 * conditioned (pbrt-v4's bounds). */
#define LIE_SPH_MIN_SOLID_ANGLE 3e-4
#define LIE_SPH_MAX_SOLID_ANGLE 6.22

/* A triangle as seen from a point: what sampling needs, set up once per
 * (point, triangle). */
typedef struct lie_sph_tri {
    double o[3];            /* the point */
    double p0[3], e1[3], e2[3], n[3]; /* the triangle: vertex 0, edges, unit normal */
    double a[3], b[3], c[3]; /* unit directions to the vertices */
    double alpha;           /* the angle at a */
    double sin_alpha, cos_alpha, cos_c; /* cos_c = a . b */
    double area;            /* solid angle, sr */
} lie_sph_tri;

/* Set up triangle p[0..2] seen from o.  Returns 1, or 0 when its solid
 * angle is outside [LIE_SPH_MIN_SOLID_ANGLE, LIE_SPH_MAX_SOLID_ANGLE] or o
 * lies in its plane: then sample it by area. */
int lie_sph_tri_setup(lie_vec3 o, const lie_vec3 p[3], lie_sph_tri *t);

/* A sample for (u1, u2) in [0, 1)^2, uniform in solid angle over the
 * triangle (density 1 / t->area per steradian): the unit direction dir,
 * the point where it meets the triangle's plane, that point's barycentrics
 * (b1, b2) of p[1] and p[2] (within rounding of [0, 1]; for texture
 * lookups), and the point's 1/pdf in area measure, area d^2 / |cos| (so
 * that an estimator written for area samples, Le f cos cos' / d^2 times
 * 1/pdf, takes it unchanged).  Returns 0 (nothing written) if the
 * direction runs parallel to the plane, which rounding alone can make. */
typedef struct lie_sph_sample {
    double dir[3];
    double p[3];
    double b1, b2;
    double inv_pdf_area;
} lie_sph_sample;
int lie_sph_tri_sample(const lie_sph_tri *t, double u1, double u2, lie_sph_sample *out);

/* The solid angle of triangle p seen from o (Van Oosterom & Strackee 1983,
 * "The solid angle of a plane triangle"): for densities and tests. */
double lie_sph_tri_solid_angle(lie_vec3 o, const lie_vec3 p[3]);

#endif
