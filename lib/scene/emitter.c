/* SPDX-License-Identifier: Apache-2.0 */
/* The emitter interface (lib/scene/scene.h): each call looks up the
 * emitter type's table (lib/scene/internal.h) and runs its operation.  This
 * is the one place that chooses by lie_emitter_type; the types themselves
 * are emitter_area.c, emitter_point.c and emitter_directional.c. */
#include "scene/internal.h"

#include <string.h>

static const lie_emitter_class *const classes[] = {
    [LIE_EMITTER_AREA] = &lie_emitter_area_class,
    [LIE_EMITTER_POINT] = &lie_emitter_point_class,
    [LIE_EMITTER_DIRECTIONAL] = &lie_emitter_directional_class,
};

static const lie_emitter_class *class_of(const lie_emitter *em) { return classes[em->type]; }

const char *lie_emitter_type_name(lie_emitter_type t)
{
    return (unsigned)t < sizeof classes / sizeof *classes ? classes[t]->name : "unknown";
}

int lie_emitter_hull_cap(const lie_emitter *em) { return class_of(em)->hull_cap(em); }

int lie_emitter_hull_points(const lie_scene *s, int e, const lie_vec3 V[3], float far, lie_vec3 *out)
{
    const lie_emitter *em = &s->emitters[e];
    return class_of(em)->hull_points(s, em, V, far, out);
}

const lie_vec3 *lie_emitter_facing(const lie_scene *s, int e)
{
    const lie_emitter *em = &s->emitters[e];
    const lie_emitter_class *k = class_of(em);
    return k->facing ? k->facing(s, em) : NULL;
}

uint32_t lie_emitter_target(const lie_scene *s, int e, float u1, float u2, lie_vec3 p, float far, lie_vec3 *q,
                            lie_vec3 *n, int *one_sided)
{
    return class_of(&s->emitters[e])->target(s, e, u1, u2, p, far, q, n, one_sided);
}

int lie_emitter_can_reach(const lie_scene *s, int e, uint32_t tri, const lie_vec3 V[3], lie_vec3 ng, int two_sided)
{
    const lie_emitter *em = &s->emitters[e];
    return class_of(em)->can_reach(s, em, tri, V, ng, two_sided);
}

int lie_emitter_extent(const lie_scene *s, int e, const lie_vec3 **pts)
{
    const lie_emitter *em = &s->emitters[e];
    const lie_emitter_class *k = class_of(em);
    *pts = NULL;
    return k->extent ? k->extent(s, em, pts) : 0;
}

void lie_emitter_bounding_sphere(const lie_scene *s, int e, float sphere[4])
{
    const lie_emitter *em = &s->emitters[e];
    class_of(em)->bounding_sphere(s, em, sphere);
}

int lie_emitter_is_delta(const lie_emitter *em) { return class_of(em)->delta; }

void lie_emitter_sample_point(const lie_scene *s, int e, float u1, float u2, lie_emitter_sample *out)
{
    class_of(&s->emitters[e])->sample_point(s, e, u1, u2, out);
}

float lie_emitter_pdf(const lie_scene *s, int e)
{
    const lie_emitter *em = &s->emitters[e];
    return class_of(em)->pdf(em);
}

int lie_emitter_uniform(const lie_scene *s, int e)
{
    const lie_emitter *em = &s->emitters[e];
    const lie_emitter_class *k = class_of(em);
    return k->uniform ? k->uniform(s, em) : 0;
}

int lie_emitter_light_at(const lie_scene *s, int e, lie_vec3 o, float far, lie_emitter_incident *out)
{
    const lie_emitter *em = &s->emitters[e];
    const lie_emitter_class *k = class_of(em);
    if (k->incident)
        return k->incident(em, o, far, out);
    memset(out, 0, sizeof *out);
    return 0;
}

int lie_emitter_polygon_of(const lie_scene *s, int e, lie_emitter_polygon *out)
{
    const lie_emitter *em = &s->emitters[e];
    const lie_emitter_class *k = class_of(em);
    return k->polygon ? k->polygon(s, em, out) : 0;
}

void lie_emitter_power(const lie_scene *s, int e, float phi[3])
{
    const lie_emitter *em = &s->emitters[e];
    class_of(em)->power(s, em, phi);
}

void lie_emitter_delta_sample(const lie_emitter *em, lie_vec3 p, lie_emitter_sample *out)
{
    out->p = p;
    out->n = em->direction;
    memcpy(out->le, em->intensity, sizeof out->le);
    out->inv_pdf = 1.0f;
    out->tri = UINT32_MAX;
}

float lie_emitter_delta_pdf(const lie_emitter *em)
{
    (void)em;
    return 0.0f;
}
