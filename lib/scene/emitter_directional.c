/* SPDX-License-Identifier: Apache-2.0 */
/* Directional lights (KHR_lights_punctual): a delta in direction, from
 * infinitely far away; shadow segments end `far` from the point
 * (lie_pair_ray_far, lib/lie/pair.h).  Their part of the emitter interface
 * (lib/scene/scene.h, lib/scene/internal.h). */
#include "scene/internal.h"

#include <string.h>

static int directional_hull_cap(const lie_emitter *em)
{
    (void)em;
    return 3;
}

/* The patch moved `far` against the light's direction. */
static int directional_hull_points(const lie_scene *s, const lie_emitter *em, const lie_vec3 V[3], float far,
                                   lie_vec3 *out)
{
    (void)s;
    for (int k = 0; k < 3; k++)
        out[k] = lie_v3_add(V[k], lie_v3_scale(em->direction, -far));
    return 3;
}

static uint32_t directional_target(const lie_scene *s, int e, float u1, float u2, lie_vec3 p, float far, lie_vec3 *q,
                                   lie_vec3 *n, int *one_sided)
{
    (void)u1, (void)u2;
    *q = lie_v3_add(p, lie_v3_scale(s->emitters[e].direction, -far));
    *n = lie_v3(0, 0, 0);
    *one_sided = 0;
    return UINT32_MAX;
}

static int directional_can_reach(const lie_scene *s, const lie_emitter *em, uint32_t tri, const lie_vec3 V[3],
                                 lie_vec3 ng, int two_sided)
{
    (void)s, (void)tri, (void)V;
    float d = -lie_v3_dot(ng, em->direction);
    return two_sided ? d != 0.0f : !(d <= 0.0f);
}

static void directional_bounding_sphere(const lie_scene *s, const lie_emitter *em, float sphere[4])
{
    (void)s, (void)em;
    sphere[0] = sphere[1] = sphere[2] = 0.0f;
    sphere[3] = -1.0f; /* at infinity: no sphere holds it */
}

/* The "point" of a light at infinity is the unit direction towards it. */
static void directional_sample_point(const lie_scene *s, int e, float u1, float u2, lie_emitter_sample *out)
{
    (void)u1, (void)u2;
    const lie_emitter *em = &s->emitters[e];
    lie_emitter_delta_sample(em, lie_v3(-em->direction.x, -em->direction.y, -em->direction.z), out);
}

static int directional_incident(const lie_emitter *em, lie_vec3 o, float far, lie_emitter_incident *out)
{
    (void)o;
    out->wi = lie_v3_scale(em->direction, -1.0f);
    out->dist = far;
    for (int k = 0; k < 3; k++)
        out->li[k] = em->intensity[k] * 1.0f;
    return 1;
}

/* pi r^2 E over the disc of the scene's bounding sphere (pbrt-v4's
 * DistantLight::Phi). */
static void directional_power(const lie_scene *s, const lie_emitter *em, float phi[3])
{
    lie_vec3 ext = lie_box3_is_empty(&s->bounds) ? lie_v3(0, 0, 0) : lie_v3_sub(s->bounds.hi, s->bounds.lo);
    double r = 0.5 * lie_v3_len(ext);
    for (int c = 0; c < 3; c++)
        phi[c] = (float)(M_PI * r * r * em->intensity[c]);
}

const lie_emitter_class lie_emitter_directional_class = {
    .name = "directional",
    .delta = 1,
    .hull_cap = directional_hull_cap,
    .hull_points = directional_hull_points,
    .facing = NULL,
    .target = directional_target,
    .can_reach = directional_can_reach,
    .extent = NULL, /* at infinity: no points hold it */
    .bounding_sphere = directional_bounding_sphere,
    .sample_point = directional_sample_point,
    .pdf = lie_emitter_delta_pdf,
    .uniform = NULL,
    .incident = directional_incident,
    .polygon = NULL,
    .power = directional_power,
};
