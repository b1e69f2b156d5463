/* SPDX-License-Identifier: Apache-2.0 */
/* Point and spot lights (KHR_lights_punctual): a delta in position, with
 * an optional cone and range.  Their part of the emitter interface
 * (lib/scene/scene.h, lib/scene/internal.h). */
#include "scene/internal.h"

#include <string.h>

static int point_hull_cap(const lie_emitter *em)
{
    (void)em;
    return 3;
}

static int point_hull_points(const lie_scene *s, const lie_emitter *em, const lie_vec3 V[3], float far, lie_vec3 *out)
{
    (void)s, (void)V, (void)far;
    out[0] = em->position;
    return 1;
}

static uint32_t point_target(const lie_scene *s, int e, float u1, float u2, lie_vec3 p, float far, lie_vec3 *q,
                             lie_vec3 *n, int *one_sided)
{
    (void)u1, (void)u2, (void)p, (void)far;
    *q = s->emitters[e].position;
    *n = lie_v3(0, 0, 0);
    *one_sided = 0;
    return UINT32_MAX;
}

/* A point or spot light reaches nothing past its range (KHR_lights_punctual:
 * the renderer's falloff is 0 from `range` on) nor outside its outer cone.
 * Tested on a sphere holding the patch, grown by the shading points' offset
 * from the surface and a rounding margin, so only patches the renderer
 * surely weights 0 are culled. */
static int point_may_reach(const lie_emitter *em, const lie_vec3 V[3])
{
    lie_vec3 c = lie_v3_scale(lie_v3_add(V[0], lie_v3_add(V[1], V[2])), 1.0f / 3.0f);
    float r = 0.0f, mag = lie_v3_maxabs(em->position);
    for (int k = 0; k < 3; k++) {
        r = fmaxf(r, lie_v3_len(lie_v3_sub(V[k], c)));
        mag = fmaxf(mag, lie_v3_maxabs(V[k]));
    }
    /* ten times the largest shadow-ray offset (lie_ray_eps_bound, lib/rt/rt.h) */
    r += 1e-3f * fmaxf(mag, 1.0f);
    lie_vec3 to = lie_v3_sub(c, em->position);
    float dist = lie_v3_len(to);
    if (em->range > 0.0f && dist - r >= em->range * (1.0f + 1e-5f))
        return 0;
    if (em->cos_outer > -1.5f && dist > r) {
        /* the sphere's directions from the light lie within asin(r / dist)
         * of its centre's; all outside the outer cone (with a margin) */
        double axis = acos(fmax(-1.0, fmin(1.0, (double)lie_v3_dot(em->direction, to) / (double)dist)));
        double outer = acos(fmax(-1.0, fmin(1.0, (double)em->cos_outer)));
        if (axis - asin((double)r / (double)dist) > outer + 1e-4)
            return 0;
    }
    return 1;
}

static int point_can_reach(const lie_scene *s, const lie_emitter *em, uint32_t tri, const lie_vec3 V[3], lie_vec3 ng,
                           int two_sided)
{
    (void)s, (void)tri;
    float d = lie_v3_dot(ng, lie_v3_sub(em->position, V[0]));
    if (!(two_sided ? d != 0.0f : !(d <= 0.0f)))
        return 0;
    if (em->range > 0.0f || em->cos_outer > -1.5f)
        return point_may_reach(em, V);
    return 1;
}

static int point_extent(const lie_scene *s, const lie_emitter *em, const lie_vec3 **pts)
{
    (void)s;
    *pts = &em->position;
    return 1;
}

static void point_bounding_sphere(const lie_scene *s, const lie_emitter *em, float sphere[4])
{
    (void)s;
    sphere[0] = em->position.x;
    sphere[1] = em->position.y;
    sphere[2] = em->position.z;
    sphere[3] = 0.0f;
}

static void point_sample_point(const lie_scene *s, int e, float u1, float u2, lie_emitter_sample *out)
{
    (void)u1, (void)u2;
    lie_emitter_delta_sample(&s->emitters[e], s->emitters[e].position, out);
}

/* Inverse-square falloff, KHR_lights_punctual's recommended spot falloff
 * (a smooth step between the cones, squared) and range window. */
static int point_incident(const lie_emitter *em, lie_vec3 o, float far, lie_emitter_incident *out)
{
    (void)far;
    lie_vec3 d = lie_v3_sub(em->position, o);
    float d2 = lie_v3_dot(d, d);
    float dist = sqrtf(d2);
    lie_vec3 wi = dist > 0.0f ? lie_v3_scale(d, 1.0f / dist) : lie_v3(0.0f, 0.0f, 1.0f);
    float atten = d2 > 0.0f ? 1.0f / d2 : 0.0f;
    if (em->cos_outer > -1.5f) {
        float scale = 1.0f / fmaxf(0.001f, em->cos_inner - em->cos_outer);
        float cd = -lie_v3_dot(em->direction, wi);
        float a = fminf(fmaxf((cd - em->cos_outer) * scale, 0.0f), 1.0f);
        atten *= a * a;
    }
    if (em->range > 0.0f) {
        float r = dist / em->range, r4 = r * r * r * r;
        atten *= fminf(fmaxf(1.0f - r4, 0.0f), 1.0f);
    }
    out->wi = wi;
    out->dist = dist;
    for (int k = 0; k < 3; k++)
        out->li[k] = em->intensity[k] * atten;
    return 1;
}

/* 4 pi I for a point light; a spot's cone as pbrt-v4's SpotLight::Phi. */
static void point_power(const lie_scene *s, const lie_emitter *em, float phi[3])
{
    (void)s;
    double k = em->cos_outer > -1.5f ? 2.0 * M_PI * (1.0 - 0.5 * ((double)em->cos_inner + em->cos_outer)) : 4.0 * M_PI;
    for (int c = 0; c < 3; c++)
        phi[c] = (float)(k * em->intensity[c]);
}

const lie_emitter_class lie_emitter_point_class = {
    .name = "point",
    .delta = 1,
    .hull_cap = point_hull_cap,
    .hull_points = point_hull_points,
    .facing = NULL,
    .target = point_target,
    .can_reach = point_can_reach,
    .extent = point_extent,
    .bounding_sphere = point_bounding_sphere,
    .sample_point = point_sample_point,
    .pdf = lie_emitter_delta_pdf,
    .uniform = NULL,
    .incident = point_incident,
    .polygon = NULL,
    .power = point_power,
};
