/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/shade: light samplers, which share a shading point's
 * budget of light samples among the emitters (lie_light_sampler_kind in
 * shade.h).  pbrt-v4's LightSampler is the model: one interface, a file per
 * kind (sampler.c: uniform and power; lighttree.c: the light BVH).
 *
 * A sampler distributes n samples at once, systematically: the n points
 * (k + u) / n, k = 0 .. n - 1, fall into consecutive intervals of [0, 1),
 * one per emitter, as long as the emitter's probability.  So an emitter of
 * probability p takes floor(n p) or ceil(n p) samples, never a random
 * number of them, and a pick costs O(log emitters) however many samples it
 * takes. */
#ifndef LIE_SHADE_SAMPLER_H
#define LIE_SHADE_SAMPLER_H

#include "shade/shade.h"

/* One emitter's share of a point's samples: `count` of the n, chosen with
 * probability `pmf` each.  Its estimate is weighed by count / (n pmf). */
typedef struct lie_light_pick {
    int emitter;
    int count;
    float pmf;
} lie_light_pick;

/* What the samplers know of an emitter (pbrt-v4's LightBounds): its power
 * (the luminance of lie_emitter_power, times the mean of an emissive
 * texture), a box around it, and the cone of its normals: every point
 * emits within theta_e of a normal that lies within theta_o of `axis`.
 * `infinite`: a directional light (no box). */
typedef struct lie_light_bounds {
    float lo[3], hi[3];
    float axis[3];
    float cos_o, cos_e;
    float phi;
    int two_sided;
    int infinite;
} lie_light_bounds;

/* Every emitter's bounds; `texture_power` (NULL: none) scales emitter e's
 * power by the mean of its emissive texture (lib/shade/texlight.h).
 * *out: free(). */
lie_status lie_light_bounds_all(const lie_scene *s, const float *texture_power, lie_light_bounds **out);
/* The box and normal cone of triangles tris[first .. first + n) of s (tris
 * NULL: triangles first .. first + n): the axis is the area-weighted mean
 * normal, theta_o the widest angle of a triangle's normal from it (every
 * direction when two-sided), theta_e 90 degrees (Lambertian emitters).
 * Leaves phi and `infinite` alone. */
void lie_light_bounds_tris(const lie_scene *s, const uint32_t *tris, uint32_t first, uint32_t n, int two_sided,
                           lie_light_bounds *b);
/* A bound on the light of b at point p with normal n (NULL: any
 * direction), in the units of phi / distance^2 (pbrt-v4's
 * LightBounds::Importance); 0 only where nothing of b can reach p. */
float lie_light_importance(const lie_light_bounds *b, lie_vec3 p, const lie_vec3 *n);
/* The same bounds with what the importance derives from them alone made
 * once (a light tree asks each node's at every point): its centre, sphere
 * and the sine of theta_o.  lie_light_cone_importance gives exactly
 * lie_light_importance's value. */
typedef struct lie_light_cone {
    float c[3], r2, dmin;
    float axis[3];
    float cos_o, sin_o, cos_e;
    float phi;
    int two_sided, infinite;
} lie_light_cone;
void lie_light_cone_of(const lie_light_bounds *b, lie_light_cone *k);
float lie_light_cone_importance(const lie_light_cone *k, lie_vec3 p, const lie_vec3 *n);

/* Light groups (lightgroup.c): what the samplers choose among.  An emitter
 * of more than a few triangles is cut in space into groups of a few, each
 * a light with its own bounds; a delta light or a small emitter is one
 * group, `whole`, sampled as the emitter. */
typedef struct lie_light_group {
    int emitter;
    uint32_t first, n;     /* its triangles: tris[first .. first + n) of its groups */
    double total;          /* their summed weight (texels' light, or area) */
    double emitter_total;  /* the same over its emitter's groups */
    int whole;
} lie_light_group;
typedef struct lie_light_groups {
    int n;
    lie_light_group *g;
    uint32_t *tris;             /* scene triangles, group by group */
    double *cdf;                /* beside tris: cumulative weight within the group */
    lie_light_bounds *bounds;   /* per group, the emitter's for a whole one */
    int split;                  /* 0: every emitter whole (closed forms asked for) */
} lie_light_groups;
struct lie_texlight;
/* The groups of every emitter of s: tl[e] (NULL, or tl NULL: by area)
 * weighs emitter e's triangles, eb[e] its bounds (as lie_light_bounds_all
 * gives them) its power; split 0 keeps every emitter whole (for frames
 * that ask for closed forms, LIE_EXACT_ONLY).  *out:
 * lie_light_groups_destroy. */
lie_status lie_light_groups_create(const lie_scene *s, struct lie_texlight *const *tl, const lie_light_bounds *eb,
                                   int split, lie_light_groups **out);
void lie_light_groups_destroy(lie_light_groups *G);
/* A point of group j (not whole) from (u1, u2), inv_pdf the inverse of its
 * density in area measure over the group; tl its emitter's distribution,
 * or NULL for an emitter of one radiance, whose triangles are then sampled
 * by the solid angle they subtend from o where o (may be NULL) is near. */
void lie_light_group_sample(const lie_scene *s, const lie_light_groups *G, int j, const struct lie_texlight *tl,
                            const lie_vec3 *o, float u1, float u2, lie_emitter_sample *out);

typedef struct lie_light_sampler lie_light_sampler;
typedef struct lie_light_sampler_class {
    const char *name;
    /* over n lights of the given bounds */
    lie_status (*create)(const lie_light_bounds *bounds, int n, void **state);
    void (*destroy)(void *state);
    /* n samples at point p with normal n_ among the lights, from the
     * rotation u in [0, 1): picks in out (room for min(n, lights)),
     * returns how many; a pick's `emitter` is the light's index */
    int (*distribute)(const void *state, lie_vec3 p, lie_vec3 n_, int n, double u, lie_light_pick *out);
} lie_light_sampler_class;

struct lie_light_sampler {
    const lie_light_sampler_class *cls;
    void *state;
};

extern const lie_light_sampler_class lie_light_sampler_uniform, lie_light_sampler_power, lie_light_sampler_tree;

/* The sampler of kind k (not LIE_SAMPLER_PER_EMITTER) over n lights. */
lie_status lie_light_sampler_create(lie_light_sampler_kind k, const lie_light_bounds *bounds, int n,
                                    lie_light_sampler *out);
void lie_light_sampler_destroy(lie_light_sampler *ls);

/* How many of the points (k + u) / n, k = 0 .. n - 1, lie in [0, x):
 * the systematic count that every sampler shares. */
static inline int lie_systematic_below(double x, int n, double u)
{
    double k = ceil(x * (double)n - u);
    return k < 0.0 ? 0 : k > (double)n ? n : (int)k;
}

/* Systematic picks over weights w[0 .. m) (summing to `total` > 0), ids
 * their emitters: out gets the entries with a count; returns how many. */
int lie_light_pick_weights(const float *w, const int *ids, int m, double total, int n, double u, lie_light_pick *out);

#endif
