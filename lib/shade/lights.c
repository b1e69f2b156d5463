/* SPDX-License-Identifier: Apache-2.0 */
/* Emitter sample patterns.  The paper (§6.1) uses "the same sample points on
 * the emitters every time": banding instead of pixel noise.  We use a
 * Hammersley set per emitter, shifted by a hash of the emitter's index, and
 * map it onto the emitter's triangles in proportion to their area. */
#include "shade/internal.h"

#include <stdlib.h>
#include <string.h>

static float wrap01(float x)
{
    x -= floorf(x);
    return x < 1.0f ? x : 0.0f;
}

void lie_light_pattern_shift(int e, float *su, float *sv)
{
    uint64_t h = lie_hash_u64x4(0x6c696768745f7061ull /* "light_pa" */, (uint64_t)e, 0, 0);
    *su = lie_hash_to_unit(h);
    *sv = lie_hash_to_unit(h << 24);
}

lie_status lie_light_samples_alloc(lie_light_samples *ls, int n)
{
    memset(ls, 0, sizeof *ls);
    if (n < 1)
        n = 1;
    /* One block, 11 arrays of floats and the triangles', each padded to a
     * multiple of 16 (64 bytes) so vector loops may read whole registers. */
    size_t stride = ((size_t)n + 15) & ~(size_t)15;
    float *block = aligned_alloc(64, sizeof(float) * 12 * stride);
    if (!block)
        return LIE_ERR_NOMEM;
    memset(block, 0, sizeof(float) * 12 * stride);
    ls->tri = (uint32_t *)(void *)(block + 11 * stride);
    float **arr[11] = {&ls->x, &ls->y, &ls->z, &ls->nx, &ls->ny, &ls->nz, &ls->r, &ls->g, &ls->b, &ls->s, &ls->t};
    for (int k = 0; k < 11; k++)
        *arr[k] = block + (size_t)k * stride;
    ls->n = n;
    return LIE_OK;
}

void lie_light_samples_free(lie_light_samples *ls)
{
    if (ls && ls->x)
        free(ls->x);
    if (ls)
        memset(ls, 0, sizeof *ls);
}

void lie_light_samples_generate(const lie_scene *s, int e, int n, float su, float sv,
                                lie_light_samples *out)
{
    lie_light_samples_generate_with(s, e, n, su, sv, NULL, out);
}

static void generate(const lie_scene *s, int e, int n, float su, float sv, const lie_texlight *tl,
                     const lie_light_groups *G, int group, const lie_vec3 *o, lie_light_samples *out)
{
    const lie_emitter *em = &s->emitters[e];
    lie_emitter_sample q;
    if (lie_emitter_is_delta(em)) {
        /* its one point (a direction for a light at infinity) and intensity */
        lie_emitter_sample_point(s, e, 0.5f, 0.5f, &q);
        out->n = 1;
        out->x[0] = q.p.x;
        out->y[0] = q.p.y;
        out->z[0] = q.p.z;
        out->nx[0] = q.n.x;
        out->ny[0] = q.n.y;
        out->nz[0] = q.n.z;
        out->r[0] = q.le[0];
        out->g[0] = q.le[1];
        out->b[0] = q.le[2];
        out->uniform = 0;
        out->planar = 0;
        return;
    }
    out->n = n;
    out->uniform = lie_emitter_uniform(s, e);
    out->planar = em->planar;
    const lie_vec3 O = em->plane_o, U = em->plane_u, V = em->plane_v, N = em->plane_n;
    if (em->planar) {
        float f[4][3] = {{O.x, O.y, O.z}, {U.x, U.y, U.z}, {V.x, V.y, V.z}, {N.x, N.y, N.z}};
        memcpy(out->po, f[0], sizeof out->po);
        memcpy(out->pu, f[1], sizeof out->pu);
        memcpy(out->pv, f[2], sizeof out->pv);
        memcpy(out->pn, f[3], sizeof out->pn);
        out->smin = out->tmin = INFINITY;
        out->smax = out->tmax = -INFINITY;
    }
    for (int i = 0; i < n; i++) {
        float u1 = wrap01(((float)i + 0.5f) / (float)n + su);
        float u2 = wrap01(lie_radical_inverse2((uint32_t)i) + sv);
        if (G)
            lie_light_group_sample(s, G, group, tl, o, u1, u2, &q);
        else if (tl)
            lie_texlight_sample(s, e, tl, u1, u2, &q);
        else
            lie_emitter_sample_point(s, e, u1, u2, &q);
        lie_vec3 p = q.p;
        /* Le / (pdf n): the estimate is the plain sum of weight x G x f x V */
        float w = q.inv_pdf / (float)n;
        out->tri[i] = q.tri;
        if (em->planar) {
            /* onto the plane, and back: the point is then exactly what the
             * linear forms of lib/shade describe */
            double qx = (double)p.x - O.x, qy = (double)p.y - O.y, qz = (double)p.z - O.z;
            float ps = (float)(qx * U.x + qy * U.y + qz * U.z), pt = (float)(qx * V.x + qy * V.y + qz * V.z);
            out->s[i] = ps;
            out->t[i] = pt;
            out->smin = lie_fminf(out->smin, ps);
            out->smax = lie_fmaxf(out->smax, ps);
            out->tmin = lie_fminf(out->tmin, pt);
            out->tmax = lie_fmaxf(out->tmax, pt);
            p = lie_v3(O.x + ps * U.x + pt * V.x, O.y + ps * U.y + pt * V.y, O.z + ps * U.z + pt * V.z);
        }
        out->x[i] = p.x;
        out->y[i] = p.y;
        out->z[i] = p.z;
        out->nx[i] = q.n.x;
        out->ny[i] = q.n.y;
        out->nz[i] = q.n.z;
        out->r[i] = q.le[0] * w;
        out->g[i] = q.le[1] * w;
        out->b[i] = q.le[2] * w;
    }
    /* the padding up to a whole vector: (s, t) that no linear form admits */
    for (int i = n; i < lie_light_samples_padded(out); i++)
        out->s[i] = out->t[i] = NAN;
}

void lie_light_samples_generate_with(const lie_scene *s, int e, int n, float su, float sv, const lie_texlight *tl,
                                     lie_light_samples *out)
{
    generate(s, e, n, su, sv, tl, NULL, -1, NULL, out);
}

void lie_light_samples_generate_group(const lie_scene *s, const lie_light_groups *G, int j, int n, float su, float sv,
                                      const lie_texlight *tl, const lie_vec3 *o, lie_light_samples *out)
{
    generate(s, G->g[j].emitter, n, su, sv, tl, G, j, o, out);
}
