/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lib/shade: light samples on an emitter with an emissive
 * texture, in proportion to its light (pbrt-v4's DiffuseAreaLight takes
 * its texture's distribution likewise).  A triangle is chosen by the light
 * integrated over its texels, then a point in it by texel luminance, as a
 * piecewise-constant 2D distribution over cells of the triangle; a cell
 * weighs the brightest texel its bilinear lookups can reach, so black
 * texels take no sample and no lit one is ever missed (the estimate stays
 * unbiased). */
#ifndef LIE_SHADE_TEXLIGHT_H
#define LIE_SHADE_TEXLIGHT_H

#include "scene/scene.h"

typedef struct lie_texlight lie_texlight;
/* The distribution of area emitter e; *out NULL where the emitter has no
 * emissive texture (or is a delta light): then sampling by area serves. */
lie_status lie_texlight_create(const lie_scene *s, int e, lie_texlight **out);
void lie_texlight_destroy(lie_texlight *t);
/* The same for every emitter of s into out[0 .. n_emitters). */
lie_status lie_texlight_create_all(const lie_scene *s, lie_texlight **out, int threads);
/* The emitter's light relative to the same emitter untextured: the
 * distribution's integral over the emitter's area, over area x the
 * luminance of its emissive factor (a bound on the texture's mean, for
 * choosing among emitters). */
float lie_texlight_power_scale(const lie_texlight *t);
/* A point of emitter e from (u1, u2) in [0, 1)^2, as
 * lie_emitter_sample_point, inv_pdf the inverse of its density in area
 * measure (0 where the point's cell is dark). */
void lie_texlight_sample(const lie_scene *s, int e, const lie_texlight *t, float u1, float u2, lie_emitter_sample *out);
/* Triangle k's weight (its area times the mean weight of its texels'
 * cells), and a point of it from (r, u2), inv_pdf the inverse of its
 * density on the triangle alone. */
float lie_texlight_tri_weight(const lie_texlight *t, uint32_t k);
void lie_texlight_sample_tri(const lie_scene *s, int e, const lie_texlight *t, uint32_t k, float r, float u2,
                             lie_emitter_sample *out);

#endif
