/* SPDX-License-Identifier: Apache-2.0 */
/* Light samplers (sampler.h): the emitters' bounds and importance, the
 * uniform and power samplers, and the choice by name. */
#include "shade/sampler.h"

#include <stdlib.h>
#include <string.h>

static const struct {
    const char *name;
    lie_light_sampler_kind kind;
} sampler_names[] = {
    {"tree", LIE_SAMPLER_TREE},
    {"power", LIE_SAMPLER_POWER},
    {"uniform", LIE_SAMPLER_UNIFORM},
    {"per-emitter", LIE_SAMPLER_PER_EMITTER},
};

int lie_light_sampler_parse(const char *name, lie_light_sampler_kind *out)
{
    for (size_t i = 0; i < sizeof sampler_names / sizeof sampler_names[0]; i++)
        if (strcmp(name, sampler_names[i].name) == 0) {
            *out = sampler_names[i].kind;
            return 1;
        }
    return 0;
}

const char *lie_light_sampler_name(lie_light_sampler_kind k)
{
    for (size_t i = 0; i < sizeof sampler_names / sizeof sampler_names[0]; i++)
        if (sampler_names[i].kind == k)
            return sampler_names[i].name;
    return "?";
}

static float luminance(const float c[3]) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

void lie_light_bounds_tris(const lie_scene *s, const uint32_t *tris, uint32_t first, uint32_t n, int two_sided,
                           lie_light_bounds *b)
{
    for (int a = 0; a < 3; a++)
        b->lo[a] = INFINITY, b->hi[a] = -INFINITY;
    double ax = 0, ay = 0, az = 0;
    for (uint32_t i = first; i < first + n; i++) {
        uint32_t t = tris ? tris[i] : i;
        const lie_vec3 *P = &s->tri_p[3 * (size_t)t];
        for (int k = 0; k < 3; k++) {
            const float q[3] = {P[k].x, P[k].y, P[k].z};
            for (int a = 0; a < 3; a++) {
                b->lo[a] = fminf(b->lo[a], q[a]);
                b->hi[a] = fmaxf(b->hi[a], q[a]);
            }
        }
        lie_vec3 g = s->tri_ng[t];
        double w = s->tri_area[t];
        ax += w * g.x, ay += w * g.y, az += w * g.z;
    }
    double len = sqrt(ax * ax + ay * ay + az * az);
    b->two_sided = two_sided;
    b->cos_e = 0.0f; /* Lambertian: light leaves within 90 degrees of the normal */
    if (!(len > 0.0) || two_sided) {
        b->axis[0] = 0.0f, b->axis[1] = 0.0f, b->axis[2] = 1.0f;
        b->cos_o = -1.0f; /* every direction */
        return;
    }
    b->axis[0] = (float)(ax / len), b->axis[1] = (float)(ay / len), b->axis[2] = (float)(az / len);
    float c = 1.0f;
    for (uint32_t i = first; i < first + n; i++) {
        lie_vec3 g = s->tri_ng[tris ? tris[i] : i];
        c = fminf(c, g.x * b->axis[0] + g.y * b->axis[1] + g.z * b->axis[2]);
    }
    /* a little wider than measured, against the rounding of the normals */
    b->cos_o = c > -1.0f ? fmaxf(c - 1e-4f, -1.0f) : -1.0f;
}

lie_status lie_light_bounds_all(const lie_scene *s, const float *texture_power, lie_light_bounds **out)
{
    lie_light_bounds *B = calloc((size_t)s->n_emitters + 1, sizeof *B);
    *out = B;
    if (!B)
        return LIE_ERR_NOMEM;
    for (int e = 0; e < s->n_emitters; e++) {
        const lie_emitter *em = &s->emitters[e];
        lie_light_bounds *b = &B[e];
        float phi[3];
        lie_emitter_power(s, e, phi);
        b->phi = fmaxf(luminance(phi), 0.0f) * (texture_power ? texture_power[e] : 1.0f);
        if (!isfinite(b->phi))
            b->phi = 0.0f;
        for (int a = 0; a < 3; a++)
            b->lo[a] = INFINITY, b->hi[a] = -INFINITY;
        if (!lie_emitter_is_delta(em)) {
            lie_light_bounds_tris(s, NULL, em->first_tri, em->n_tris, em->double_sided, b);
            continue;
        }
        float sphere[4];
        lie_emitter_bounding_sphere(s, e, sphere);
        if (sphere[3] < 0.0f) { /* a light at infinity */
            b->infinite = 1;
            continue;
        }
        const float q[3] = {em->position.x, em->position.y, em->position.z};
        memcpy(b->lo, q, sizeof q);
        memcpy(b->hi, q, sizeof q);
        b->axis[0] = em->direction.x, b->axis[1] = em->direction.y, b->axis[2] = em->direction.z;
        if (em->cos_outer >= -1.0f) {
            /* a spot (pbrt-v4's SpotLight::Bounds): full light within the
             * inner cone, falling off to the outer one */
            b->cos_o = em->cos_inner;
            b->cos_e = cosf(fmaxf(acosf(fminf(fmaxf(em->cos_outer, -1.0f), 1.0f)) -
                                      acosf(fminf(fmaxf(em->cos_inner, -1.0f), 1.0f)),
                                  0.0f));
        } else {
            b->cos_o = -1.0f;
            b->cos_e = 0.0f;
        }
    }
    return LIE_OK;
}

/* cos(max(0, a - b)) and sin(max(0, a - b)) from the sines and cosines of
 * angles a, b in [0, pi] */
static inline float cos_sub_clamped(float sa, float ca, float sb, float cb) { return ca > cb ? 1.0f : ca * cb + sa * sb; }
static inline float sin_sub_clamped(float sa, float ca, float sb, float cb) { return ca > cb ? 0.0f : sa * cb - ca * sb; }

void lie_light_cone_of(const lie_light_bounds *b, lie_light_cone *k)
{
    memset(k, 0, sizeof *k);
    k->infinite = b->infinite;
    k->phi = b->phi;
    if (b->infinite)
        return;
    const float ext[3] = {b->hi[0] - b->lo[0], b->hi[1] - b->lo[1], b->hi[2] - b->lo[2]};
    for (int a = 0; a < 3; a++) {
        k->c[a] = 0.5f * (b->lo[a] + b->hi[a]);
        k->axis[a] = b->axis[a];
    }
    k->r2 = 0.25f * (ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]); /* the box's sphere */
    /* as pbrt-v4: the distance is at least half the box's diagonal, so
     * that points near or in a light's box do not get unbounded weight */
    k->dmin = 0.5f * sqrtf(4.0f * k->r2);
    k->cos_o = b->cos_o;
    k->sin_o = sqrtf(lie_maxf(1.0f - b->cos_o * b->cos_o, 0.0f));
    k->cos_e = b->cos_e;
    k->two_sided = b->two_sided;
}

/* (lie_maxf rather than fmaxf: the baseline build calls libm for fmaxf, and
 * no argument here is NaN but a first one, which both map to the second) */
float lie_light_cone_importance(const lie_light_cone *b, lie_vec3 p, const lie_vec3 *n)
{
    if (b->infinite)
        return b->phi;
    const float r2 = b->r2;
    float v[3] = {p.x - b->c[0], p.y - b->c[1], p.z - b->c[2]};
    float d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    float dd = lie_maxf(d2, b->dmin);
    if (!(d2 > 0.0f)) {
        v[0] = 0.0f, v[1] = 0.0f, v[2] = 1.0f;
    } else {
        float inv = 1.0f / sqrtf(d2);
        v[0] *= inv, v[1] *= inv, v[2] *= inv;
    }
    /* the box's half-angle from p: every direction when p is in its sphere */
    float cos_b = -1.0f, sin_b = 0.0f;
    if (d2 > r2) {
        float s2 = r2 / d2;
        sin_b = sqrtf(s2);
        cos_b = sqrtf(lie_maxf(1.0f - s2, 0.0f));
    }
    float cos_w = v[0] * b->axis[0] + v[1] * b->axis[1] + v[2] * b->axis[2];
    if (b->two_sided)
        cos_w = fabsf(cos_w);
    float sin_w = sqrtf(lie_maxf(1.0f - cos_w * cos_w, 0.0f));
    float cos_x = cos_sub_clamped(sin_w, cos_w, b->sin_o, b->cos_o);
    float sin_x = sin_sub_clamped(sin_w, cos_w, b->sin_o, b->cos_o);
    float cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if (cos_p <= b->cos_e)
        return 0.0f;
    float imp = b->phi * cos_p / dd;
    if (n) {
        /* the receiver's cosine toward the box, at best (one-sided: an
         * opaque surface takes light from above only) */
        float cos_i = -(v[0] * n->x + v[1] * n->y + v[2] * n->z);
        float sin_i = sqrtf(lie_maxf(1.0f - cos_i * cos_i, 0.0f));
        float cos_pi = cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
        imp *= lie_maxf(cos_pi, 0.0f);
    }
    return imp > 0.0f && isfinite(imp) ? imp : 0.0f;
}

float lie_light_importance(const lie_light_bounds *b, lie_vec3 p, const lie_vec3 *n)
{
    lie_light_cone k;
    lie_light_cone_of(b, &k);
    return lie_light_cone_importance(&k, p, n);
}

int lie_light_pick_weights(const float *w, const int *ids, int m, double total, int n, double u, lie_light_pick *out)
{
    int k = 0, below = 0;
    double acc = 0.0;
    for (int i = 0; i < m; i++) {
        if (!(w[i] > 0.0f))
            continue;
        acc += w[i];
        int upto = i == m - 1 ? n : lie_systematic_below(acc / total, n, u);
        if (upto > below) {
            out[k].emitter = ids ? ids[i] : i;
            out[k].count = upto - below;
            out[k].pmf = (float)(w[i] / total);
            k++;
            below = upto;
        }
    }
    /* the last weighed entry closes the interval whatever the rounding */
    if (below < n && k > 0)
        out[k - 1].count += n - below;
    return k;
}

/* ---- uniform and power: one table of weights for every point ---------- */

typedef struct table_sampler {
    float *w;
    double total;
    int n;
} table_sampler;

static lie_status table_create(const lie_light_bounds *b, int n, int by_power, void **state)
{
    table_sampler *t = calloc(1, sizeof *t);
    if (!t || !(t->w = calloc((size_t)n + 1, sizeof *t->w))) {
        free(t);
        return LIE_ERR_NOMEM;
    }
    t->n = n;
    for (int e = 0; e < n; e++) {
        t->w[e] = by_power ? b[e].phi : (b[e].phi > 0.0f ? 1.0f : 0.0f);
        t->total += t->w[e];
    }
    *state = t;
    return LIE_OK;
}

static lie_status uniform_create(const lie_light_bounds *b, int n, void **state) { return table_create(b, n, 0, state); }
static lie_status power_create(const lie_light_bounds *b, int n, void **state) { return table_create(b, n, 1, state); }

static void table_destroy(void *state)
{
    table_sampler *t = state;
    if (t)
        free(t->w);
    free(t);
}

static int table_distribute(const void *state, lie_vec3 p, lie_vec3 n_, int n, double u, lie_light_pick *out)
{
    (void)p, (void)n_;
    const table_sampler *t = state;
    if (!(t->total > 0.0))
        return 0;
    return lie_light_pick_weights(t->w, NULL, t->n, t->total, n, u, out);
}

const lie_light_sampler_class lie_light_sampler_uniform = {"uniform", uniform_create, table_destroy, table_distribute};
const lie_light_sampler_class lie_light_sampler_power = {"power", power_create, table_destroy, table_distribute};

lie_status lie_light_sampler_create(lie_light_sampler_kind k, const lie_light_bounds *bounds, int n,
                                    lie_light_sampler *out)
{
    out->cls = k == LIE_SAMPLER_UNIFORM ? &lie_light_sampler_uniform
               : k == LIE_SAMPLER_POWER ? &lie_light_sampler_power
                                        : &lie_light_sampler_tree;
    out->state = NULL;
    return out->cls->create(bounds, n, &out->state);
}

void lie_light_sampler_destroy(lie_light_sampler *ls)
{
    if (ls && ls->cls)
        ls->cls->destroy(ls->state);
    if (ls)
        ls->state = NULL;
}
