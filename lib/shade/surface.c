/* SPDX-License-Identifier: Apache-2.0 */
/* Surfaces at ray hits, and the glTF metallic-roughness BRDF in scalar form
 * (the vectorised form used for shading lives in direct.c; tests hold the
 * two to each other). */
#include "shade/shade.h"

#include <string.h>

/* Cosine of the steepest a normal-mapped shading normal may lean from the
 * geometric normal: a map bending it to or past the surface's plane (in
 * error, or by scale) would light the surface from behind. */
#define NORMAL_MAP_HORIZON 0.01f

/* The shading normal bent by material m's normal map at (b1, b2) of
 * triangle g: n the interpolated normal, ng the geometric one, both on the
 * front side.  glTF 2.0 §3.9.3: the texel's RGB maps to [-1, 1]^3 in the
 * frame (tangent, bitangent = cross(n, tangent) * w, n), X and Y times the
 * scale.  The result is kept NORMAL_MAP_HORIZON above the geometric
 * plane, as pbrt-v4 and Blender keep shading normals in the geometric
 * hemisphere: the normal is moved toward ng until it is. */
static lie_vec3 normal_mapped(const lie_scene *s, const lie_material *m, uint32_t g, float b1, float b2, lie_vec3 n,
                              lie_vec3 ng)
{
    const float *T = &s->tri_tan[12 * (size_t)g];
    float b0 = 1.0f - b1 - b2;
    lie_vec3 t = lie_v3(b0 * T[0] + b1 * T[4] + b2 * T[8], b0 * T[1] + b1 * T[5] + b2 * T[9],
                        b0 * T[2] + b1 * T[6] + b2 * T[10]);
    t = lie_v3_norm(lie_v3_sub(t, lie_v3_scale(n, lie_v3_dot(n, t))));
    if (!(lie_v3_dot(t, t) > 0.5f))
        return n; /* no tangent plane here (a degenerate frame): the map cannot be read */
    float w = b0 * T[3] + b1 * T[7] + b2 * T[11];
    lie_vec3 b = lie_v3_scale(lie_v3_cross(n, t), w < 0.0f ? -1.0f : 1.0f);
    float tx[4], xu, xv;
    lie_scene_slot_uv(s, m, LIE_TEX_NORMAL, g, b1, b2, &xu, &xv);
    lie_texture_sample(&s->textures[m->normal_tex], xu, xv, tx);
    float x = (2.0f * tx[0] - 1.0f) * m->normal_scale, y = (2.0f * tx[1] - 1.0f) * m->normal_scale,
          z = 2.0f * tx[2] - 1.0f;
    lie_vec3 nm = lie_v3_norm(lie_v3_add(lie_v3_add(lie_v3_scale(t, x), lie_v3_scale(b, y)), lie_v3_scale(n, z)));
    if (!(lie_v3_dot(nm, nm) > 0.5f))
        return n;
    float c = lie_v3_dot(nm, ng);
    if (c < NORMAL_MAP_HORIZON) {
        nm = lie_v3_norm(lie_v3_add(nm, lie_v3_scale(ng, NORMAL_MAP_HORIZON - c)));
        if (!(lie_v3_dot(nm, nm) > 0.5f))
            return ng;
    }
    return nm;
}

void lie_surface_from_hit(const lie_scene *s, const lie_hit *hit, lie_vec3 ray_dir, lie_surface *sf)
{
    uint32_t g = hit->tri;
    float b1 = hit->u, b2 = hit->v, b0 = 1.0f - b1 - b2;
    const lie_vec3 *P = &s->tri_p[3 * (size_t)g];
    const lie_vec3 *N = &s->tri_n[3 * (size_t)g];
    sf->tri = g;
    sf->b1 = b1;
    sf->b2 = b2;
    sf->p = lie_v3_add(lie_v3_add(lie_v3_scale(P[0], b0), lie_v3_scale(P[1], b1)), lie_v3_scale(P[2], b2));
    sf->wo = lie_v3_scale(ray_dir, -1.0f);
    lie_vec3 ng = s->tri_ng[g];
    lie_vec3 n = lie_v3_norm(lie_v3_add(lie_v3_add(lie_v3_scale(N[0], b0), lie_v3_scale(N[1], b1)),
                                        lie_v3_scale(N[2], b2)));
    if (lie_v3_dot(n, n) < 0.5f)
        n = ng;
    const lie_material *m = lie_scene_material(s, s->tri_material[g]);
    if (m->normal_tex >= 0 && m->normal_tex < s->n_textures && s->tri_tan)
        n = normal_mapped(s, m, g, b1, b2, n, ng);
    int front = lie_v3_dot(ng, sf->wo) >= 0.0f;
    if (!front) {
        /* Seen from behind (double-sided, or a ray that was not culled):
         * shade the side the viewer is on. */
        ng = lie_v3_scale(ng, -1.0f);
        n = lie_v3_scale(n, -1.0f);
    }
    sf->ng = ng;
    sf->n = n;
    float base[4] = {m->base_color[0], m->base_color[1], m->base_color[2], m->base_color[3]};
    if (s->tri_color) { /* COLOR_0 multiplies the base colour (glTF 2.0 §3.7.2.1) */
        const float *col = &s->tri_color[12 * (size_t)g];
        for (int k = 0; k < 4; k++)
            base[k] *= b0 * col[k] + b1 * col[4 + k] + b2 * col[8 + k];
    }
    float metallic = m->metallic, roughness = m->roughness;
    if (m->base_color_tex >= 0 && m->base_color_tex < s->n_textures) {
        float t[4];
        float xu, xv;
        lie_scene_slot_uv(s, m, LIE_TEX_BASE_COLOR, g, b1, b2, &xu, &xv);
        lie_texture_sample(&s->textures[m->base_color_tex], xu, xv, t);
        for (int k = 0; k < 4; k++)
            base[k] *= t[k];
    }
    if (m->mr_tex >= 0 && m->mr_tex < s->n_textures) {
        float t[4];
        float xu, xv;
        lie_scene_slot_uv(s, m, LIE_TEX_METALLIC_ROUGHNESS, g, b1, b2, &xu, &xv);
        lie_texture_sample(&s->textures[m->mr_tex], xu, xv, t);
        roughness *= t[1];
        metallic *= t[2];
    }
    metallic = fminf(fmaxf(metallic, 0.0f), 1.0f);
    roughness = fminf(fmaxf(roughness, 0.0f), 1.0f);
    for (int k = 0; k < 3; k++) {
        sf->base_color[k] = base[k];
        sf->diffuse[k] = base[k] * (1.0f - metallic);
        sf->f0[k] = 0.04f * (1.0f - metallic) + base[k] * metallic;
    }
    /* alpha is clamped so D stays finite; roughness below ~0.03 on a
     * non-mirror is shaded as slightly rough. */
    sf->alpha = fmaxf(roughness * roughness, 1e-3f);
    sf->mirror = metallic >= 1.0f && roughness <= LIE_MIRROR_ROUGHNESS;
    sf->lambert = metallic <= 0.0f && roughness >= 1.0f;
    int emits = m->emissive[0] > 0.0f || m->emissive[1] > 0.0f || m->emissive[2] > 0.0f;
    if (emits && (front || m->double_sided)) {
        float e[4] = {1.0f, 1.0f, 1.0f, 1.0f};
        if (m->emissive_tex >= 0 && m->emissive_tex < s->n_textures) {
            float xu, xv;
            lie_scene_slot_uv(s, m, LIE_TEX_EMISSIVE, g, b1, b2, &xu, &xv);
            lie_texture_sample(&s->textures[m->emissive_tex], xu, xv, e);
        }
        for (int k = 0; k < 3; k++)
            sf->emission[k] = m->emissive[k] * e[k];
    } else {
        memset(sf->emission, 0, sizeof sf->emission);
    }
}

void lie_brdf_eval_cos(const lie_surface *sf, lie_vec3 wi, float out[3])
{
    float nl = lie_v3_dot(sf->n, wi);
    if (nl <= 0.0f || sf->mirror) {
        out[0] = out[1] = out[2] = 0.0f;
        return;
    }
    if (sf->lambert) {
        for (int k = 0; k < 3; k++)
            out[k] = sf->diffuse[k] * (float)M_1_PI * nl;
        return;
    }
    float nv = fmaxf(lie_v3_dot(sf->n, sf->wo), 1e-4f);
    lie_vec3 h = lie_v3_norm(lie_v3_add(wi, sf->wo));
    float nh = fmaxf(lie_v3_dot(sf->n, h), 0.0f);
    float vh = fmaxf(lie_v3_dot(sf->wo, h), 0.0f);
    float a2 = sf->alpha * sf->alpha;
    float dd = nh * nh * (a2 - 1.0f) + 1.0f;
    float D = a2 / ((float)M_PI * dd * dd);
    float V = 0.5f / (nl * sqrtf(nv * nv * (1.0f - a2) + a2) + nv * sqrtf(nl * nl * (1.0f - a2) + a2));
    float x = 1.0f - vh, s5 = x * x * x * x * x;
    for (int k = 0; k < 3; k++) {
        float F = sf->f0[k] + (1.0f - sf->f0[k]) * s5;
        out[k] = (sf->diffuse[k] * (float)M_1_PI * (1.0f - F) + F * D * V) * nl;
    }
}
