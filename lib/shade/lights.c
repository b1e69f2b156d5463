/* Emitter sample patterns.  The paper (§6.1) uses "the same sample points on
 * the emitters every time": banding instead of pixel noise.  We use a
 * Hammersley set per emitter, shifted by a hash of the emitter's index, and
 * map it onto the emitter's triangles in proportion to their area. */
#include "shade/shade.h"

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
    const lie_emitter *em = &s->emitters[e];
    if (em->type != LIE_EMITTER_AREA) {
        out->n = 1;
        out->x[0] = em->type == LIE_EMITTER_POINT ? em->position.x : -em->direction.x;
        out->y[0] = em->type == LIE_EMITTER_POINT ? em->position.y : -em->direction.y;
        out->z[0] = em->type == LIE_EMITTER_POINT ? em->position.z : -em->direction.z;
        out->nx[0] = em->direction.x;
        out->ny[0] = em->direction.y;
        out->nz[0] = em->direction.z;
        out->r[0] = em->intensity[0];
        out->g[0] = em->intensity[1];
        out->b[0] = em->intensity[2];
        out->uniform = 0;
        out->planar = 0;
        return;
    }
    const lie_material *mat = lie_scene_material(s, s->tri_material[em->first_tri]);
    const lie_texture *tex = mat->emissive_tex >= 0 && mat->emissive_tex < s->n_textures
                                 ? &s->textures[mat->emissive_tex]
                                 : NULL;
    float w = em->area / (float)n;
    out->n = n;
    out->uniform = tex == NULL;
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
        lie_vec3 p, ng;
        float b1, b2;
        uint32_t g = lie_emitter_point(s, e, u1, u2, &p, &ng, &b1, &b2);
        out->tri[i] = g;
        float le[3] = {em->radiance[0], em->radiance[1], em->radiance[2]};
        if (tex) {
            float rgba[4], xu, xv;
            lie_scene_slot_uv(s, mat, LIE_TEX_EMISSIVE, g, b1, b2, &xu, &xv);
            lie_texture_sample(tex, xu, xv, rgba);
            for (int k = 0; k < 3; k++)
                le[k] *= rgba[k];
        }
        if (em->planar) {
            /* onto the plane, and back: the point is then exactly what the
             * linear forms of lib/shade describe */
            double qx = (double)p.x - O.x, qy = (double)p.y - O.y, qz = (double)p.z - O.z;
            float ps = (float)(qx * U.x + qy * U.y + qz * U.z), pt = (float)(qx * V.x + qy * V.y + qz * V.z);
            out->s[i] = ps;
            out->t[i] = pt;
            out->smin = fminf(out->smin, ps);
            out->smax = fmaxf(out->smax, ps);
            out->tmin = fminf(out->tmin, pt);
            out->tmax = fmaxf(out->tmax, pt);
            p = lie_v3(O.x + ps * U.x + pt * V.x, O.y + ps * U.y + pt * V.y, O.z + ps * U.z + pt * V.z);
        }
        out->x[i] = p.x;
        out->y[i] = p.y;
        out->z[i] = p.z;
        out->nx[i] = ng.x;
        out->ny[i] = ng.y;
        out->nz[i] = ng.z;
        out->r[i] = le[0] * w;
        out->g[i] = le[1] * w;
        out->b[i] = le[2] * w;
    }
    /* the padding up to a whole vector: (s, t) that no linear form admits */
    for (int i = n; i < lie_light_samples_padded(out); i++)
        out->s[i] = out->t[i] = NAN;
}
