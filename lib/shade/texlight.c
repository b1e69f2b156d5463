/* Emitters with an emissive texture sampled by their light (texlight.h). */
#include "shade/texlight.h"

#include <stdlib.h>
#include <string.h>

/* cells per side of a triangle's grid at most: 64 x 64 cells */
#define MAX_RES 64

typedef struct tri_dist {
    uint32_t first_cell; /* into cell_cdf */
    int res;             /* res x res cells over the unit square lie_sample_triangle maps */
    float weight;        /* its light: area x mean cell weight */
} tri_dist;

struct lie_texlight {
    const lie_texture *tex;
    const lie_material *mat;
    uint32_t first_tri, n_tris;
    tri_dist *tris;
    double *tri_cdf;     /* n_tris, cumulative weight */
    double *cell_cdf;    /* per triangle res^2, cumulative cell weight, the last its sum */
    double total;
    float scale;
};

static float lum3(const float c[3]) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* The brightest texel (luminance of radiance x texel) that bilinear
 * lookups at texture coordinates within [u0, u1] x [v0, v1] can reach. */
static float max_texel(const lie_texture *t, const float rad[3], float u0, float u1, float v0, float v1)
{
    const int w = t->width, h = t->height;
    /* a lookup at x (in texels) reads texels floor(x - 1/2) and the next;
     * a thousandth of a texel more each side, against rounding */
    long long x0 = (long long)floorf(u0 * (float)w - 0.501f), x1 = (long long)floorf(u1 * (float)w - 0.499f) + 1;
    long long y0 = (long long)floorf(v0 * (float)h - 0.501f), y1 = (long long)floorf(v1 * (float)h - 0.499f) + 1;
    if (x1 - x0 >= w)
        x0 = 0, x1 = w - 1;
    if (y1 - y0 >= h)
        y0 = 0, y1 = h - 1;
    float m = 0.0f;
    for (long long y = y0; y <= y1; y++) {
        const float *row = t->rgba + (size_t)lie_texture_wrap_index(y, h, t->wrap_t) * (size_t)w * 4;
        for (long long x = x0; x <= x1; x++) {
            const float *px = row + (size_t)lie_texture_wrap_index(x, w, t->wrap_s) * 4;
            const float c[3] = {rad[0] * fmaxf(px[0], 0.0f), rad[1] * fmaxf(px[1], 0.0f), rad[2] * fmaxf(px[2], 0.0f)};
            m = fmaxf(m, lum3(c));
        }
    }
    return m;
}

void lie_texlight_destroy(lie_texlight *t)
{
    if (!t)
        return;
    free(t->tris);
    free(t->tri_cdf);
    free(t->cell_cdf);
    free(t);
}

lie_status lie_texlight_create(const lie_scene *s, int e, lie_texlight **out)
{
    *out = NULL;
    const lie_emitter *em = &s->emitters[e];
    if (lie_emitter_is_delta(em) || em->n_tris == 0 || lie_emitter_uniform(s, e))
        return LIE_OK;
    const lie_material *mat = lie_scene_material(s, s->tri_material[em->first_tri]);
    if (mat->emissive_tex < 0 || mat->emissive_tex >= s->n_textures)
        return LIE_OK;
    const lie_texture *tex = &s->textures[mat->emissive_tex];
    if (!tex->rgba || tex->width <= 0 || tex->height <= 0)
        return LIE_OK;
    lie_texlight *t = calloc(1, sizeof *t);
    if (!t)
        return LIE_ERR_NOMEM;
    t->tex = tex;
    t->mat = mat;
    t->first_tri = em->first_tri;
    t->n_tris = em->n_tris;
    t->tris = malloc(sizeof *t->tris * em->n_tris);
    t->tri_cdf = malloc(sizeof *t->tri_cdf * em->n_tris);
    if (!t->tris || !t->tri_cdf) {
        lie_texlight_destroy(t);
        return LIE_ERR_NOMEM;
    }
    /* each triangle's grid: about four cells per texel it covers (the
     * cells of the warped square are long near a corner) */
    size_t cells = 0;
    for (uint32_t k = 0; k < em->n_tris; k++) {
        uint32_t g = em->first_tri + k;
        float u[3], v[3];
        const float bb[3][2] = {{0, 0}, {1, 0}, {0, 1}};
        for (int j = 0; j < 3; j++)
            lie_scene_slot_uv(s, mat, LIE_TEX_EMISSIVE, g, bb[j][0], bb[j][1], &u[j], &v[j]);
        double texels = 0.5 * fabs(((double)u[1] - u[0]) * ((double)v[2] - v[0]) - ((double)u[2] - u[0]) * ((double)v[1] - v[0])) *
                        tex->width * tex->height;
        double r = ceil(2.0 * sqrt(isfinite(texels) ? texels : 0.0));
        t->tris[k].res = r < 1.0 ? 1 : r > MAX_RES ? MAX_RES : (int)r;
        t->tris[k].first_cell = (uint32_t)cells;
        cells += (size_t)t->tris[k].res * (size_t)t->tris[k].res;
    }
    t->cell_cdf = malloc(sizeof *t->cell_cdf * (cells + 1));
    if (!t->cell_cdf) {
        lie_texlight_destroy(t);
        return LIE_ERR_NOMEM;
    }
    double acc = 0.0, area = 0.0;
    for (uint32_t k = 0; k < em->n_tris; k++) {
        uint32_t g = em->first_tri + k;
        const int R = t->tris[k].res;
        double *cdf = t->cell_cdf + t->tris[k].first_cell;
        double sum = 0.0;
        for (int i = 0; i < R; i++)
            for (int j = 0; j < R; j++) {
                /* the cell's corners in texture space bound it (its image
                 * in the triangle is a quadrilateral, uv affine there);
                 * its weight is the mean light at 3 x 3 points of it, plus
                 * a sixteenth of the brightest texel its lookups reach, so
                 * that no cell with light is left out */
                float u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY, mean = 0.0f;
                for (int c = 0; c < 9; c++) {
                    float b1, b2, tu, tv, rgba[4];
                    float a1 = ((float)i + 0.5f * (float)(c % 3)) / (float)R, a2 = ((float)j + 0.5f * (float)(c / 3)) / (float)R;
                    lie_sample_triangle(fminf(a1, 1.0f), fminf(a2, 1.0f), &b1, &b2);
                    lie_scene_slot_uv(s, mat, LIE_TEX_EMISSIVE, g, b1, b2, &tu, &tv);
                    u0 = fminf(u0, tu), u1 = fmaxf(u1, tu), v0 = fminf(v0, tv), v1 = fmaxf(v1, tv);
                    lie_texture_sample(tex, tu, tv, rgba);
                    const float le[3] = {em->radiance[0] * fmaxf(rgba[0], 0.0f), em->radiance[1] * fmaxf(rgba[1], 0.0f),
                                         em->radiance[2] * fmaxf(rgba[2], 0.0f)};
                    mean += lum3(le) / 9.0f;
                }
                float m = isfinite(u0 + u1 + v0 + v1) ? max_texel(tex, em->radiance, u0, u1, v0, v1) : lum3(em->radiance);
                m = m > 0.0f ? mean + m / 16.0f : 0.0f;
                sum += m;
                cdf[i * R + j] = sum;
            }
        t->tris[k].weight = (float)(s->tri_area[g] * sum / ((double)R * R));
        acc += t->tris[k].weight;
        t->tri_cdf[k] = acc;
        area += s->tri_area[g];
    }
    t->total = acc;
    float full = lum3(em->radiance);
    t->scale = area > 0.0 && full > 0.0f ? (float)(acc / (area * full)) : 0.0f;
    *out = t;
    return LIE_OK;
}

float lie_texlight_power_scale(const lie_texlight *t) { return t ? t->scale : 1.0f; }

/* the first index whose cumulative value exceeds x (binary search) */
static uint32_t cdf_find(const double *cdf, uint32_t n, double x)
{
    uint32_t lo = 0, hi = n - 1;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (x < cdf[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

void lie_texlight_sample(const lie_scene *s, int e, const lie_texlight *t, float u1, float u2, lie_emitter_sample *out)
{
    const lie_emitter *em = &s->emitters[e];
    memset(out, 0, sizeof *out);
    if (!(t->total > 0.0)) {
        out->p = s->tri_p[3 * (size_t)t->first_tri];
        out->n = s->tri_ng[t->first_tri];
        out->tri = t->first_tri;
        return; /* a black emitter: weight 0 */
    }
    /* the triangle by u1, then the cell by the rest of u1 (its row-major
     * index), the point in the cell by what is left of u1 and by u2 */
    double x = (double)u1 * t->total;
    uint32_t k = cdf_find(t->tri_cdf, t->n_tris, x);
    double lo = k > 0 ? t->tri_cdf[k - 1] : 0.0, w = t->tri_cdf[k] - lo;
    double r = w > 0.0 ? (x - lo) / w : 0.5;
    const tri_dist *td = &t->tris[k];
    const int R = td->res;
    const double *cdf = t->cell_cdf + td->first_cell;
    const uint32_t nc = (uint32_t)R * (uint32_t)R;
    double csum = cdf[nc - 1];
    double y = r * csum;
    uint32_t c = cdf_find(cdf, nc, y);
    double clo = c > 0 ? cdf[c - 1] : 0.0, cw = cdf[c] - clo;
    float r2 = cw > 0.0 ? (float)((y - clo) / cw) : 0.5f;
    r2 = fminf(fmaxf(r2, 0.0f), 0.99999994f);
    int i = (int)(c / (uint32_t)R), j = (int)(c % (uint32_t)R);
    float a1 = ((float)i + r2) / (float)R, a2 = ((float)j + u2) / (float)R;
    float b1, b2;
    lie_sample_triangle(fminf(a1, 0.99999994f), fminf(a2, 0.99999994f), &b1, &b2);
    uint32_t g = t->first_tri + k;
    const lie_vec3 *P = &s->tri_p[3 * (size_t)g];
    float b0 = 1.0f - b1 - b2;
    out->p = lie_v3_add(lie_v3_add(lie_v3_scale(P[0], b0), lie_v3_scale(P[1], b1)), lie_v3_scale(P[2], b2));
    out->n = s->tri_ng[g];
    out->tri = g;
    float rgba[4], tu, tv;
    lie_scene_slot_uv(s, t->mat, LIE_TEX_EMISSIVE, g, b1, b2, &tu, &tv);
    lie_texture_sample(t->tex, tu, tv, rgba);
    for (int q = 0; q < 3; q++)
        out->le[q] = em->radiance[q] * rgba[q];
    /* density: P(triangle) P(cell | triangle) / (the cell's area) */
    double pdf = (w / t->total) * (cw / csum) * (double)nc / (double)s->tri_area[g];
    out->inv_pdf = pdf > 0.0 && isfinite(pdf) ? (float)(1.0 / pdf) : 0.0f;
}
