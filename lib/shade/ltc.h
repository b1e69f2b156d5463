/* SPDX-License-Identifier: Apache-2.0 */
/* lib/shade/ltc.h: the glTF metallic-roughness BRDF integrated over a
 * polygon of constant radiance with linearly transformed cosines (Heitz,
 * Dupuy, Hill, Neubelt, "Real-Time Polygonal-Light Shading with Linearly
 * Transformed Cosines", SIGGRAPH 2016).
 *
 * What is integrated is exactly the BRDF of lie_brdf_eval_cos (surface.c,
 * direct.c: glTF 2.0 Appendix B):
 *
 *   f(wi, wo) cos = [ c_diff / pi (1 - F) + F D V ] (n . wi),
 *   F = f0 + (1 - f0) (1 - v.h)^5,  D GGX,  V height-correlated Smith,
 *   alpha = roughness^2 (clamped to >= 1e-3 as surface.c does),
 *
 * split as the LTC paper (§4.2 and its Fresnel note) splits it:
 *
 *   specular: int_P F D V cos ~ N_s(r, v) [f0 (1 - K_s) + K_s] LTC_s(P)
 *     N_s = int_H D V cos (directional albedo of the specular lobe without
 *     F, the table's "norm") and K_s = int_H D V (1 - v.h)^5 cos / N_s (its
 *     "fresnel"); LTC_s(P) in [0, 1] is the fitted distribution's mass in P.
 *     That takes the Schlick-weighted part D V (1 - v.h)^5 cos to have the
 *     shape of D V cos, which it has not where v.h varies across the lobe
 *     (grazing views: the part toward the mirror direction is weighted
 *     most), so with a ggx_fresnel table (the default one has it) that
 *     part gets its own LTC:
 *       int_P F D V cos ~ f0 N_s LTC_s(P) + (1 - f0) N_s K_s LTC_f(P).
 *     Measured on dielectrics at 75 degrees (`make ltc-bench`): the paper's
 *     split is off by up to 25% on polygons holding much of the lobe, the
 *     second LTC by up to ~10%, as the specular lobe alone.
 *   diffuse:  int_P c_diff/pi (1 - F) cos
 *               = c_diff (1 - f0)/pi int_P (1 - (1 - v.h)^5) cos
 *             ~ c_diff (1 - f0)/pi N_d(v) LTC_d(P),
 *     a second, roughness-independent LTC fitted to (1 - (1 - v.h)^5) cos.
 *   A pure Lambert surface (lie_surface.lambert) gets c_diff/pi int_P cos,
 *   which the edge sum gives exactly (Arvo 1995; the LTC with M = I).
 *
 * The tables are fitted by scripts/ltc-fit.c (`make ltc-tables`) and written
 * as data to lib/shade/ltc_table.dat, whose "#" lines hold the fit's error
 * table; the build turns it into C (scripts/ltc-table.awk).
 *
 * Limits of the approximation (measured in tests/unit/test_ltc.c, reported
 * by `make ltc-bench`): an LTC is a 4-parameter fit of the lobe, so a
 * polygon holding much of the lobe is off by up to ~5% for views up to 60
 * degrees, ~10% at 75 degrees, more toward 85; in a lobe's dim tails the
 * relative error is large (an LTC is exactly 0 beyond its own tilted
 * horizon, GGX is not: light near the horizon on the viewer's side of a
 * rough metal can come out several times too dark), though small against
 * the lobe's whole.  A polygon holding the whole upper hemisphere gives
 * the directional albedo up to the tabulated norms (the fitted
 * distributions' mass below the shading horizon is folded into the
 * norms: within 1%).  Not handled: the perfect
 * mirror (a delta: lie_surface.mirror), emitted textures (radiance must be
 * constant over the polygon), the geometric-normal test of direct.c (only
 * the shading normal's hemisphere is integrated). */
#ifndef LIE_SHADE_LTC_H
#define LIE_SHADE_LTC_H

#include "core/core.h"

#ifdef __cplusplus
extern "C" {
#endif
#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

struct lie_surface;

/* One fitted bin: the inverse LTC matrix in the lobe frame (z the shading
 * normal, x toward wo in the plane of n and wo, y = z x x), scaled so that
 * its (1,1) entry is 1 (scale does not change the projected directions):
 *   M^-1 = [[m00, 0, m02], [0, 1, 0], [m20, 0, m22]],
 * and the lobe's two scalars (see the file comment; fresnel is 0 for the
 * diffuse lobe). */
typedef struct lie_ltc_bin {
    float m00, m02, m20, m22;
    float norm, fresnel;
} lie_ltc_bin;

/* The tables: bins at roughness r = i / (n_rough - 1) and at
 * u = sqrt(1 - n.wo) = j / (n_cos - 1), bilinearly interpolated. */
typedef struct lie_ltc_table {
    int n_rough, n_cos;
    const lie_ltc_bin *ggx;     /* [n_rough][n_cos] specular lobe */
    const lie_ltc_bin *diffuse; /* [n_cos] Fresnel-weighted diffuse lobe */
    /* [n_rough][n_cos] the specular lobe's Schlick-weighted part, its norm
     * N_s K_s; NULL: the paper's scalar split alone */
    const lie_ltc_bin *ggx_fresnel;
} lie_ltc_table;

/* The fitted tables compiled into the library (static data: nothing to
 * free, safe from any thread). */
const lie_ltc_table *lie_ltc_table_default(void);

/* A shading point's set-up: everything that depends on (n, wo, roughness,
 * material) and not on the polygon.  Build it once per shading point and
 * call lie_ltc_polygon for each polygon (each visible convex piece of an
 * emitter). */
typedef struct lie_ltc_shading {
    float frame[9];    /* world -> lobe frame, rows x, y, n */
    float spec_m[9];   /* lobe frame -> specular cosine space (M^-1) */
    float fres_m[9];   /* lobe frame -> the Schlick-weighted part's cosine space */
    float diff_m[9];   /* lobe frame -> diffuse cosine space */
    float spec_w[3];   /* RGB weight of LTC_s(P): f0 N_s, or N_s (f0 (1 - K_s) + K_s) */
    float fres_w[3];   /* RGB weight of LTC_f(P): (1 - f0) N_s K_s, or 0 */
    float diff_w[3];   /* RGB weight of LTC_d(P) */
    int has_spec;      /* 0: Lambert only (diff_m is the identity) */
} lie_ltc_shading;

/* Set up the glTF metallic-roughness BRDF at a point: unit shading normal
 * n, unit direction wo toward the viewer (n . wo is clamped to >= 1e-4 as
 * direct.c does), perceptual roughness in [0, 1] (alpha = roughness^2,
 * so pass sqrtf(lie_surface.alpha)), f0 and c_diff as lie_surface.f0 and
 * lie_surface.diffuse. */
void lie_ltc_shading_init(const lie_ltc_table *t, lie_vec3 n, lie_vec3 wo, float roughness,
                          const float f0[3], const float c_diff[3], lie_ltc_shading *sh);
/* Pure Lambert, c_diff / pi (no Fresnel): exact, no table. */
void lie_ltc_shading_lambert(lie_vec3 n, const float c_diff[3], lie_ltc_shading *sh);
/* From a surface (lie_surface_from_hit): Lambert when sf->lambert, else the
 * full BRDF.  sf->mirror is not served (a delta lobe): the caller keeps
 * its sample path for mirrors. */
void lie_ltc_shading_from_surface(const lie_ltc_table *t, const struct lie_surface *sf,
                                  lie_ltc_shading *sh);

/* The most vertices lie_ltc_polygon accepts. */
#define LIE_LTC_MAX_VERTS 32

/* int_P f(wi, wo) cos(theta_i) dwi over the polygon P, RGB, so that a
 * constant-radiance emitter contributes Le * out.  verts: the polygon's
 * n (3 <= n <= LIE_LTC_MAX_VERTS) vertices relative to the shading point
 * (vertex - p), in order around the polygon, either winding; planar
 * convex polygons are what it is meant for (any simple planar polygon
 * works).  The part below the shading normal's horizon is clipped off.
 * Fewer than 3 vertices, a polygon wholly below the horizon, seen edge-on
 * or of zero area give 0.  Facing is the caller's business: the result
 * does not depend on the winding, so a one-sided emitter seen from behind
 * must be culled before.  No allocation; reentrant. */
void lie_ltc_polygon(const lie_ltc_shading *sh, const lie_vec3 *verts, int n, float out[3]);

/* One call for one polygon: lie_ltc_shading_init + lie_ltc_polygon. */
void lie_ltc_polygon_once(const lie_ltc_table *t, lie_vec3 n, lie_vec3 wo, float roughness,
                          const float f0[3], const float c_diff[3], const lie_vec3 *verts, int nv,
                          float out[3]);

/* The clamped-cosine mass, in [0, 1], of polygon `verts` (directions from
 * the origin, n <= LIE_LTC_MAX_VERTS) after the linear map m (row-major
 * 3x3, NULL: identity), clipped to z > 0 in the mapped space:
 *   (1 / 2 pi) | sum_edges acos(a.b) (a x b).z / |a x b| |  (§3 of the paper;
 * Lambert's edge sum).  pi times it with m = NULL is int_P cos. */
float lie_ltc_integrate(const float *m, const lie_vec3 *verts, int n);

#pragma GCC visibility pop
#ifdef __cplusplus
}
#endif

#endif
