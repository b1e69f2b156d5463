/* SPDX-License-Identifier: Apache-2.0 */
/* lib/rt: Embree 3 over the scene's world triangles.  One Embree geometry
 * holds every triangle, so Embree's primID is the global triangle index.
 * Queries: closest hit (optionally skipping back faces of single-sided
 * materials), occlusion over [tnear, tfar] one ray at a time, in 8-wide
 * packets or as a stream, and every triangle along a segment (lie-build).
 * Errors from Embree come back as lie_status, never as prints. */
#ifndef LIE_RT_H
#define LIE_RT_H

#include "core/core.h"
#include "scene/scene.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

#define LIE_NO_HIT 0xFFFFFFFFu

typedef struct lie_rt lie_rt;

typedef struct lie_hit {
    uint32_t tri;          /* global triangle index or LIE_NO_HIT */
    float t;
    float u, v;            /* barycentrics of vertices 1 and 2 */
} lie_hit;

/* Rays for batched occlusion, structure of arrays.  On return occluded[i]
 * is 1 or 0 for i < n.  The caller owns the arrays (capacity >= n). */
typedef struct lie_ray_batch {
    float *ox, *oy, *oz, *dx, *dy, *dz, *tnear, *tfar;
    uint8_t *occluded;
    int n;
} lie_ray_batch;

typedef enum lie_ray_mode {
    LIE_RAYS_SINGLE = 0,   /* rtcOccluded1 per ray */
    LIE_RAYS_PACKET = 1,   /* rtcOccluded8 packets */
    LIE_RAYS_STREAM = 2    /* rtcOccluded1M, coherent */
} lie_ray_mode;

/* Build the Embree scene over s's current world.  s must outlive the rt
 * (shading reads materials through the scene; rt only needs geometry). */
lie_status lie_rt_create(const lie_scene *s, lie_rt **out, lie_error *err);
void lie_rt_destroy(lie_rt *rt);

/* Closest hit along org + t*dir, t in [tnear, tfar].  With cull_backfaces,
 * hits on the back of triangles whose material is not double-sided are
 * skipped (glTF's single-sided surfaces are invisible from behind).
 * Returns 1 on a hit. */
int lie_rt_intersect(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar,
                     int cull_backfaces, lie_hit *hit);

/* Closest hits of up to 8 rays org[i] + t dir[i] (an 8-wide packet:
 * coherent camera rays), t in [0, inf); hits[i].tri is LIE_NO_HIT on a
 * miss. */
void lie_rt_intersect8(const lie_rt *rt, const lie_vec3 *org, const lie_vec3 *dir, int n, int cull_backfaces,
                       lie_hit *hits);

/* 1 if anything lies on the segment [tnear, tfar]. */
int lie_rt_occluded(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar);

/* Occlusion for a batch of rays; fills b->occluded. */
void lie_rt_occluded_batch(const lie_rt *rt, lie_ray_batch *b, lie_ray_mode mode);

/* Every triangle met by the segment [tnear, tfar], except those listed in
 * `exclude` (sorted or not, n_exclude small).  Appends to out (capacity
 * *cap, grown with realloc); *n is the count (may contain duplicates).
 * Returns LIE_ERR_NOMEM if growing fails. */
lie_status lie_rt_all_hits(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar,
                           const uint32_t *exclude, int n_exclude, uint32_t **out, size_t *n,
                           size_t *cap);

/* lie_rt_all_hits for n <= 8 segments at once, traced as one packet
 * (Embree's coherent packet traversal: a pair's segments run between one
 * patch and one emitter): segment k's hits, less exclude[k][0 ..
 * n_exclude[k]), are appended to *out; bit k of *blocked says whether it
 * had any.  A function of the segments alone, as lie_rt_all_hits is (the
 * packet's triangle tests are Embree's for packets, which may round
 * otherwise than its single-ray ones on an edge). */
lie_status lie_rt_all_hits8(const lie_rt *rt, const lie_vec3 *org, const lie_vec3 *dir, const float *tnear,
                            const float *tfar, const uint32_t (*exclude)[2], const int *n_exclude, int n,
                            uint32_t **out, size_t *n_out, size_t *cap, unsigned *blocked);

/* 1 if some triangle not in `exclude` meets the segment [tnear, tfar]:
 * exactly when lie_rt_all_hits would report one (the same triangle tests
 * and holes), found with far less traversal. */
int lie_rt_any_hit(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar, const uint32_t *exclude,
                   int n_exclude);

/* Transmissive triangles (lie_material_transmits) are in no occlusion
 * query above (lie_rt_occluded*, lie_rt_all_hits*, lie_rt_any_hit) nor in
 * box queries: they block no shadow segment.  Closest hits see them.
 * Whether the scene has any: */
int lie_rt_transmits(const lie_rt *rt);
/* The light a segment [tnear, tfar] keeps across the transmissive
 * triangles it crosses: rgb = the product of their lie_scene_transmittance
 * at the crossing, taken in triangle order (the same bits on every CPU), 0
 * past 64 of them.  Returns whether it crossed any (rgb 1 when not). */
int lie_rt_transmittance(const lie_rt *rt, lie_vec3 org, lie_vec3 dir, float tnear, float tfar, float rgb[3]);

/* Calls fn(ctx, tri) for every opaque triangle whose bounding box overlaps
 * `box` (each at most once per call is not guaranteed: callers dedupe). */
typedef void (*lie_rt_box_fn)(void *ctx, uint32_t tri);
void lie_rt_box_query(const lie_rt *rt, lie_box3 box, lie_rt_box_fn fn, void *ctx);

/* Shadow-ray conventions, shared by the renderer (lib/shade), lie-build
 * (lib/lie) and the ray segment trees (lib/rst): the LIE image equals the
 * full-visibility one only if they all use these.  A ray leaving surface
 * point p starts lifted off the surface by lie_ray_eps(p) = 1e-4 max(1, |p|)
 * (|p| the largest coordinate magnitude: float spacing grows with it) along
 * the geometric normal of the side it leaves, and a shadow segment stops
 * the same distance short of its target. */
static inline float lie_ray_eps(lie_vec3 p) { return 1e-4f * lie_maxf(lie_v3_maxabs(p), 1.0f); }
/* A bound of lie_ray_eps over points whose coordinates are at most mag in
 * magnitude (lie-build's hulls must contain every origin). */
static inline float lie_ray_eps_bound(float mag) { return 1.0001e-4f * fmaxf(1.0f, mag); }
/* The origin of a ray leaving p on the side `side` (a unit normal). */
static inline lie_vec3 lie_ray_origin(lie_vec3 p, lie_vec3 side, float eps)
{
    return lie_v3_add(p, lie_v3_scale(side, eps));
}
/* Where a segment from the origin to a target len away stops, as a
 * distance along its unit direction ... */
static inline float lie_ray_end(float len, float eps) { return len - eps; }
/* ... and as a fraction of the vector to the target, d2 its squared length
 * (the form the renderer's vectorised loops use). */
static inline float lie_ray_end_scale(float d2, float eps) { return d2 > 0.0f ? 1.0f - eps / sqrtf(d2) : 0.0f; }

/* The shadow segment from surface point p (geometric normal ng, facing the
 * side the segment leaves from) to point q: origin offset off the surface,
 * end short of q, so neither the receiver nor the emitter's own surface
 * counts as a blocker.  Shared by the renderer and lie-build so both ask
 * the same geometric question.  Returns 0 if q is (nearly) at p. */
int lie_shadow_segment(lie_vec3 p, lie_vec3 ng, lie_vec3 q, lie_vec3 *org, lie_vec3 *dir,
                       float *tnear, float *tfar);

/* Scene scale used for ray epsilons (largest bounds extent, at least 1). */
float lie_rt_scale(const lie_rt *rt);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
