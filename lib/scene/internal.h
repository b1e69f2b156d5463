/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/scene. */
#ifndef LIE_SCENE_INTERNAL_H
#define LIE_SCENE_INTERNAL_H

#include "scene/scene.h"

/* An area emitter's hull points and plane frame (see lie_emitter), from its
 * triangles and double_sided flag. */
void lie_scene_emitter_shape(const lie_scene *s, lie_emitter *e);
/* The oriented box hull of triangles tris[0..n_tris) (tris NULL: first,
 * first + 1, ...): 8 corners, or *n_hull 0 for few triangles. */
void lie_scene_hull_of(const lie_scene *s, const uint32_t *tris, uint32_t first, uint32_t n_tris, lie_vec3 hull[8],
                       int *n_hull);
/* A point by area on triangles tris[0..n) (tris NULL: first, first + 1,
 * ...) of cumulative areas cdf[] and total area `area`; returns its
 * triangle (see lie_emitter_point). */
uint32_t lie_scene_point_on(const lie_scene *s, const uint32_t *tris, uint32_t first, uint32_t n, const float *cdf,
                            float area, float u1, float u2, lie_vec3 *p, lie_vec3 *nrm, float *b1, float *b2);
/* Whether area emitter em's triangles tris[0..n) (tris NULL: first,
 * first + 1, ...) may light patch V (see lie_emitter_can_reach). */
int lie_scene_area_may_reach(const lie_scene *s, const lie_emitter *em, const uint32_t *tris, uint32_t first,
                             uint32_t n, const lie_vec3 V[3], lie_vec3 ng, int two_sided);

/* One emitter type's implementation of the emitter interface (scene.h):
 * each type fills one table in its own file; lib/scene/emitter.c picks the
 * table by lie_emitter.type, the only switch on it. */
typedef struct lie_emitter_class {
    const char *name;
    int delta; /* a point, spot or direction: one sample */
    int (*hull_cap)(const lie_emitter *em);
    int (*hull_points)(const lie_scene *s, const lie_emitter *em, const lie_vec3 V[3], float far, lie_vec3 *out);
    const lie_vec3 *(*facing)(const lie_scene *s, const lie_emitter *em);
    uint32_t (*target)(const lie_scene *s, int e, float u1, float u2, lie_vec3 p, float far, lie_vec3 *q,
                       lie_vec3 *n, int *one_sided);
    int (*can_reach)(const lie_scene *s, const lie_emitter *em, uint32_t tri, const lie_vec3 V[3], lie_vec3 ng,
                     int two_sided);
    int (*extent)(const lie_scene *s, const lie_emitter *em, const lie_vec3 **pts);
    void (*bounding_sphere)(const lie_scene *s, const lie_emitter *em, float sphere[4]);
    void (*sample_point)(const lie_scene *s, int e, float u1, float u2, lie_emitter_sample *out);
    float (*pdf)(const lie_emitter *em);
    int (*uniform)(const lie_scene *s, const lie_emitter *em);
    int (*incident)(const lie_emitter *em, lie_vec3 o, float far, lie_emitter_incident *out);
    int (*polygon)(const lie_scene *s, const lie_emitter *em, lie_emitter_polygon *out);
    void (*power)(const lie_scene *s, const lie_emitter *em, float phi[3]);
} lie_emitter_class;

/* A delta light's only sample: point p (a direction for one at infinity),
 * its facing, its intensity, inv_pdf 1; and its pdf, 0 (a delta). */
void lie_emitter_delta_sample(const lie_emitter *em, lie_vec3 p, lie_emitter_sample *out);
float lie_emitter_delta_pdf(const lie_emitter *em);

extern const lie_emitter_class lie_emitter_area_class;        /* emitter_area.c */
extern const lie_emitter_class lie_emitter_point_class;       /* emitter_point.c: point and spot */
extern const lie_emitter_class lie_emitter_directional_class; /* emitter_directional.c */

#endif
