/* SPDX-License-Identifier: Apache-2.0 */
/* lib/scene: bilinear texture lookup with glTF's sampler wrap modes.
 *
 * Texel (i, j) has its centre at ((i + 0.5) / w, (j + 0.5) / h); row 0 is
 * v = 0, the first row of the image (glTF's top).  The four texels around
 * (u, v) are wrapped one by one, so a lookup near an edge blends with the
 * texel the wrap mode puts across it (the opposite edge for REPEAT, the
 * edge texel itself for CLAMP_TO_EDGE and MIRRORED_REPEAT). */
#include "scene/scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Reduce a coordinate to the range where the wrap repeats, so the texel
 * positions below stay small integers even for u = 1e9. */
static float texture_reduce(float u, lie_wrap wrap)
{
    if (!isfinite(u))
        return 0.0f;
    switch (wrap) {
    case LIE_WRAP_CLAMP:
        return fminf(fmaxf(u, 0.0f), 1.0f);
    case LIE_WRAP_MIRROR:
        return u - 2.0f * floorf(0.5f * u); /* [0, 2): one mirrored period */
    case LIE_WRAP_REPEAT:
    default:
        return u - floorf(u);
    }
}

/* Texel index i (possibly -1 or up to 2n - 1 after reduction) to [0, n). */
int lie_texture_wrap_index(long long i, int n, lie_wrap wrap)
{
    switch (wrap) {
    case LIE_WRAP_CLAMP:
        return i < 0 ? 0 : (i >= n ? n - 1 : (int)i);
    case LIE_WRAP_MIRROR: {
        int m = (int)(i % (2 * (long long)n));
        if (m < 0)
            m += 2 * n;
        return m < n ? m : 2 * n - 1 - m;
    }
    case LIE_WRAP_REPEAT:
    default: {
        int m = (int)(i % n);
        return m < 0 ? m + n : m;
    }
    }
}

void lie_texture_free(lie_texture *t)
{
    free(t->rgba);
    free(t->codes); /* libstb's buffer (stbi_image_free is free: its default STBI_FREE), or a copy */
    free(t->code_value[0]);
    free(t->code_value[1]);
    t->rgba = NULL;
    t->codes = NULL;
    t->code_value[0] = t->code_value[1] = NULL;
}

void lie_texture_texels(const lie_texture *t, size_t first, size_t n, float *out)
{
    /* a run at a time, each representation its own loop (the scene's hash
     * reads every texel at every flatten) */
    if (t->rgba) {
        memcpy(out, t->rgba + 4 * first, sizeof(float) * 4 * n);
    } else if (t->code_bits == 8) {
        const unsigned char *c = (const unsigned char *)t->codes + 4 * first;
        const float *col = t->code_value[0], *alpha = t->code_value[1];
        for (size_t i = 0; i < n; i++, c += 4, out += 4) {
            out[0] = col[c[0]], out[1] = col[c[1]], out[2] = col[c[2]];
            out[3] = alpha[c[3]];
        }
    } else {
        for (size_t i = 0; i < n; i++)
            lie_texture_texel(t, first + i, out + 4 * i);
    }
}

void lie_texture_sample(const lie_texture *t, float u, float v, float rgba[4])
{
    if (!lie_texture_has_texels(t)) {
        rgba[0] = rgba[1] = rgba[2] = rgba[3] = 1.0f;
        return;
    }
    int w = t->width, h = t->height;
    float x = texture_reduce(u, t->wrap_s) * (float)w - 0.5f;
    float y = texture_reduce(v, t->wrap_t) * (float)h - 0.5f;
    float x0f = floorf(x), y0f = floorf(y);
    float fx = x - x0f, fy = y - y0f;
    int x0 = (int)x0f, y0 = (int)y0f;
    int xa = lie_texture_wrap_index(x0, w, t->wrap_s), xb = lie_texture_wrap_index(x0 + 1, w, t->wrap_s);
    int ya = lie_texture_wrap_index(y0, h, t->wrap_t), yb = lie_texture_wrap_index(y0 + 1, h, t->wrap_t);
    float p00[4], p10[4], p01[4], p11[4];
    lie_texture_texel(t, (size_t)ya * (size_t)w + (size_t)xa, p00);
    lie_texture_texel(t, (size_t)ya * (size_t)w + (size_t)xb, p10);
    lie_texture_texel(t, (size_t)yb * (size_t)w + (size_t)xa, p01);
    lie_texture_texel(t, (size_t)yb * (size_t)w + (size_t)xb, p11);
    for (int c = 0; c < 4; c++) {
        float top = p00[c] + fx * (p10[c] - p00[c]);
        float bottom = p01[c] + fx * (p11[c] - p01[c]);
        rgba[c] = top + fy * (bottom - top);
    }
}

void lie_scene_slot_uv(const lie_scene *s, const lie_material *m, int k, uint32_t tri, float b1, float b2,
                       float *u, float *v)
{
    const float *uv = m->tex_set[k] == 1 && s->tri_uv1 ? &s->tri_uv1[6 * (size_t)tri] : &s->tri_uv[6 * (size_t)tri];
    float b0 = 1.0f - b1 - b2;
    lie_material_tex_xf_apply(m->tex_xf[k], b0 * uv[0] + b1 * uv[2] + b2 * uv[4], b0 * uv[1] + b1 * uv[3] + b2 * uv[5], u,
                     v);
}

int lie_scene_solid_at(const lie_scene *s, uint32_t tri, float b1, float b2)
{
    const lie_material *m = lie_scene_material(s, s->tri_material[tri]);
    if (!m->alpha_mask)
        return 1;
    float b0 = 1.0f - b1 - b2, a = m->base_color[3];
    if (m->base_color_tex >= 0 && m->base_color_tex < s->n_textures) {
        float tu, tv, rgba[4];
        lie_scene_slot_uv(s, m, LIE_TEX_BASE_COLOR, tri, b1, b2, &tu, &tv);
        lie_texture_sample(&s->textures[m->base_color_tex], tu, tv, rgba);
        a *= rgba[3];
    }
    if (s->tri_color) {
        const float *c = &s->tri_color[12 * (size_t)tri];
        a *= b0 * c[3] + b1 * c[7] + b2 * c[11];
    }
    return a >= m->alpha_cutoff;
}

float lie_texture_code_value(size_t i, size_t levels, int srgb)
{
    double c = (double)i / (double)(levels - 1);
    return (float)(srgb ? (c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4)) : c);
}

void lie_scene_transmittance(const lie_scene *s, uint32_t tri, float b1, float b2, float rgb[3])
{
    const lie_material *m = lie_scene_material(s, s->tri_material[tri]);
    rgb[0] = rgb[1] = rgb[2] = 1.0f;
    if (!lie_scene_solid_at(s, tri, b1, b2))
        return;
    float b0 = 1.0f - b1 - b2, tr = m->transmission, metallic = m->metallic;
    float base[3] = {m->base_color[0], m->base_color[1], m->base_color[2]};
    float t[4], u, v;
    if (m->transmission_tex >= 0 && m->transmission_tex < s->n_textures) {
        lie_scene_slot_uv(s, m, LIE_TEX_TRANSMISSION, tri, b1, b2, &u, &v);
        lie_texture_sample(&s->textures[m->transmission_tex], u, v, t);
        tr *= t[0];
    }
    if (m->base_color_tex >= 0 && m->base_color_tex < s->n_textures) {
        lie_scene_slot_uv(s, m, LIE_TEX_BASE_COLOR, tri, b1, b2, &u, &v);
        lie_texture_sample(&s->textures[m->base_color_tex], u, v, t);
        for (int k = 0; k < 3; k++)
            base[k] *= t[k];
    }
    if (m->mr_tex >= 0 && m->mr_tex < s->n_textures) {
        lie_scene_slot_uv(s, m, LIE_TEX_METALLIC_ROUGHNESS, tri, b1, b2, &u, &v);
        lie_texture_sample(&s->textures[m->mr_tex], u, v, t);
        metallic *= t[2];
    }
    if (s->tri_color) {
        const float *c = &s->tri_color[12 * (size_t)tri];
        for (int k = 0; k < 3; k++)
            base[k] *= b0 * c[k] + b1 * c[4 + k] + b2 * c[8 + k];
    }
    float share = (1.0f - fminf(fmaxf(metallic, 0.0f), 1.0f)) * fminf(fmaxf(tr, 0.0f), 1.0f);
    for (int k = 0; k < 3; k++)
        rgb[k] = share * fminf(fmaxf(base[k], 0.0f), 1.0f);
}
