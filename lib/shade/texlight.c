/* SPDX-License-Identifier: Apache-2.0 */
/* Emitters with an emissive texture sampled by their light (texlight.h). */
#include "shade/texlight.h"

#include <stdlib.h>
#include <string.h>

/* cells per side of a triangle's grid at most: 64 x 64 cells */
#define MAX_RES 64
/* texels per cell, about */
#define CELL_TEXELS 2.0

typedef struct tri_dist {
    uint32_t first_cell; /* into cell_cdf */
    int res;             /* res^2 cells: the triangle cut into res^2 congruent ones (subtriangle) */
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

/* Cell c (of R^2) of a triangle cut R times along each edge: its corners'
 * barycentric coordinates (b1, b2).  Cell i R + j is the upright triangle
 * at (i, j) where i + j < R, else the inverted one at (R-1-i, R-1-j): all
 * congruent, of area 1 / R^2 of the triangle's, and their images in
 * texture space are the texture triangle's, small (uv is affine). */
static void subtriangle(int R, uint32_t c, float v[3][2])
{
    int i = (int)(c / (uint32_t)R), j = (int)(c % (uint32_t)R);
    const float k = 1.0f / (float)R;
    if (i + j < R) {
        v[0][0] = (float)i * k, v[0][1] = (float)j * k;
        v[1][0] = (float)(i + 1) * k, v[1][1] = (float)j * k;
        v[2][0] = (float)i * k, v[2][1] = (float)(j + 1) * k;
    } else {
        i = R - 1 - i, j = R - 1 - j;
        v[0][0] = (float)(i + 1) * k, v[0][1] = (float)(j + 1) * k;
        v[1][0] = (float)i * k, v[1][1] = (float)(j + 1) * k;
        v[2][0] = (float)(i + 1) * k, v[2][1] = (float)j * k;
    }
}

static float lum3(const float c[3]) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* The texture's light as a pyramid of maxima: level 0 a texel's luminance
 * (times the emissive factor), level k + 1 the largest of 2 x 2 of level
 * k, so that the brightest texel of a rectangle is a few reads at the
 * level where it spans two texels. */
typedef struct max_pyramid {
    float *level[16];
    int w[16], h[16];
    int n;
} max_pyramid;

static void pyramid_free(max_pyramid *m)
{
    for (int k = 0; k < m->n; k++)
        free(m->level[k]);
    memset(m, 0, sizeof *m);
}

static int pyramid_make(const lie_texture *t, const float rad[3], max_pyramid *m)
{
    memset(m, 0, sizeof *m);
    int w = t->width, h = t->height;
    float *l0 = malloc(sizeof(float) * (size_t)w * (size_t)h);
    if (!l0)
        return 0;
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
        float px[4];
        lie_texture_texel(t, i, px);
        /* a NaN texel is dark, as a negative one */
        const float c[3] = {rad[0] * (px[0] > 0.0f ? px[0] : 0.0f), rad[1] * (px[1] > 0.0f ? px[1] : 0.0f),
                            rad[2] * (px[2] > 0.0f ? px[2] : 0.0f)};
        l0[i] = lum3(c);
    }
    m->level[0] = l0, m->w[0] = w, m->h[0] = h, m->n = 1;
    while ((w > 1 || h > 1) && m->n < 16) {
        int w2 = (w + 1) / 2, h2 = (h + 1) / 2;
        const float *a = m->level[m->n - 1];
        float *b = malloc(sizeof(float) * (size_t)w2 * (size_t)h2);
        if (!b) {
            pyramid_free(m);
            return 0;
        }
        for (int y = 0; y < h2; y++)
            for (int x = 0; x < w2; x++) {
                float v = 0.0f;
                for (int dy = 0; dy < 2; dy++)
                    for (int dx = 0; dx < 2; dx++) {
                        int xx = 2 * x + dx, yy = 2 * y + dy;
                        if (xx < w && yy < h && a[(size_t)yy * (size_t)w + (size_t)xx] > v)
                            v = a[(size_t)yy * (size_t)w + (size_t)xx];
                    }
                b[(size_t)y * (size_t)w2 + (size_t)x] = v;
            }
        m->level[m->n] = b, m->w[m->n] = w2, m->h[m->n] = h2, m->n++;
        w = w2, h = h2;
    }
    return 1;
}

/* The brightest texel that bilinear lookups at texture coordinates within
 * [u0, u1] x [v0, v1] can reach (the whole texture's when the rectangle
 * wraps over an edge). */
static float max_texel(const lie_texture *t, const max_pyramid *m, float u0, float u1, float v0, float v1)
{
    const int w = t->width, h = t->height;
    /* a lookup at x (in texels) reads texels floor(x - 1/2) and the next;
     * a thousandth of a texel more each side, against rounding */
    long long x0 = (long long)floorf(u0 * (float)w - 0.501f), x1 = (long long)floorf(u1 * (float)w - 0.499f) + 1;
    long long y0 = (long long)floorf(v0 * (float)h - 0.501f), y1 = (long long)floorf(v1 * (float)h - 0.499f) + 1;
    const int top = m->n - 1;
    if (x0 < 0 || y0 < 0 || x1 >= w || y1 >= h) {
        /* over an edge: texel by texel as the wrap modes fold it, or the
         * whole texture's brightest for a large rectangle */
        if (x1 - x0 > 16 || y1 - y0 > 16)
            return m->level[top][0];
        float v = 0.0f;
        for (long long y = y0; y <= y1; y++)
            for (long long x = x0; x <= x1; x++)
                v = fmaxf(v, m->level[0][(size_t)lie_texture_wrap_index(y, h, t->wrap_t) * (size_t)w +
                                         (size_t)lie_texture_wrap_index(x, w, t->wrap_s)]);
        return v;
    }
    int k = 0;
    while (k < top && ((x1 >> k) - (x0 >> k) > 1 || (y1 >> k) - (y0 >> k) > 1))
        k++;
    float v = 0.0f;
    for (long long y = y0 >> k; y <= y1 >> k; y++)
        for (long long x = x0 >> k; x <= x1 >> k; x++)
            v = fmaxf(v, m->level[k][(size_t)y * (size_t)m->w[k] + (size_t)x]);
    return v;
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

/* The emissive texture of emitter e, if its samples should follow it. */
static const lie_texture *texture_of(const lie_scene *s, int e, const lie_material **mat)
{
    const lie_emitter *em = &s->emitters[e];
    if (lie_emitter_is_delta(em) || em->n_tris == 0 || lie_emitter_uniform(s, e))
        return NULL;
    *mat = lie_scene_material(s, s->tri_material[em->first_tri]);
    int k = (*mat)->emissive_tex;
    if (k < 0 || k >= s->n_textures || !lie_texture_has_texels(&s->textures[k]))
        return NULL;
    return &s->textures[k];
}

/* The cells of triangles [k0, k1) of a texlight: their cumulative
 * weights, and per triangle the sum in cell_sum[k]. */
typedef struct cells_job {
    const lie_scene *s;
    const lie_emitter *em;
    const lie_material *mat;
    const lie_texture *tex;
    const max_pyramid *pyr;
    lie_texlight *t;
    double *cell_sum;
} cells_job;

#define CELLS_TRIS 32 /* triangles per item of the parallel loop */

static void cells_run(void *ctx, size_t item, int worker)
{
    (void)worker;
    const cells_job *jb = ctx;
    const lie_scene *s = jb->s;
    const lie_emitter *em = jb->em;
    const lie_material *mat = jb->mat;
    const lie_texture *tex = jb->tex;
    const max_pyramid *pyr = jb->pyr;
    lie_texlight *t = jb->t;
    uint32_t k0 = (uint32_t)item * CELLS_TRIS, k1 = k0 + CELLS_TRIS < em->n_tris ? k0 + CELLS_TRIS : em->n_tris;
    for (uint32_t k = k0; k < k1; k++) {
        uint32_t g = em->first_tri + k;
        const int R = t->tris[k].res;
        double *cdf = t->cell_cdf + t->tris[k].first_cell;
        double sum = 0.0;
        for (int i = 0; i < R; i++)
            for (int j = 0; j < R; j++) {
                /* the cell's corners in texture space bound it (uv is
                 * affine on the triangle); its weight is the light at its
                 * centre, plus a sixty-fourth of the brightest texel its
                 * lookups reach, so that no cell with light is left out
                 * and a dark one takes no sample */
                float u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
                float cv[3][2];
                subtriangle(R, (uint32_t)(i * R + j), cv);
                for (int c = 0; c < 3; c++) {
                    float tu, tv;
                    lie_scene_slot_uv(s, mat, LIE_TEX_EMISSIVE, g, cv[c][0], cv[c][1], &tu, &tv);
                    u0 = fminf(u0, tu), u1 = fmaxf(u1, tu), v0 = fminf(v0, tv), v1 = fmaxf(v1, tv);
                }
                float tu, tv, rgba[4];
                lie_scene_slot_uv(s, mat, LIE_TEX_EMISSIVE, g, (cv[0][0] + cv[1][0] + cv[2][0]) / 3.0f,
                                  (cv[0][1] + cv[1][1] + cv[2][1]) / 3.0f, &tu, &tv);
                lie_texture_sample(tex, tu, tv, rgba);
                const float le[3] = {em->radiance[0] * (rgba[0] > 0.0f ? rgba[0] : 0.0f),
                                     em->radiance[1] * (rgba[1] > 0.0f ? rgba[1] : 0.0f),
                                     em->radiance[2] * (rgba[2] > 0.0f ? rgba[2] : 0.0f)};
                float m = isfinite(u0 + u1 + v0 + v1) ? max_texel(tex, pyr, u0, u1, v0, v1) : lum3(em->radiance);
                m = m > 0.0f ? lum3(le) + m / 64.0f : 0.0f;
                sum += m;
                cdf[i * R + j] = sum;
            }
        jb->cell_sum[k] = sum;
    }
}

/* The distribution of emitter e over the pyramid of its texture's light. */
static lie_status texlight_build(const lie_scene *s, int e, const lie_material *mat, const lie_texture *tex,
                                 const max_pyramid *pyr, int threads, lie_texlight **out)
{
    const lie_emitter *em = &s->emitters[e];
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
    /* each triangle's grid: a cell to about CELL_TEXELS texels it covers */
    size_t cells = 0;
    for (uint32_t k = 0; k < em->n_tris; k++) {
        uint32_t g = em->first_tri + k;
        float u[3], v[3];
        const float bb[3][2] = {{0, 0}, {1, 0}, {0, 1}};
        for (int j = 0; j < 3; j++)
            lie_scene_slot_uv(s, mat, LIE_TEX_EMISSIVE, g, bb[j][0], bb[j][1], &u[j], &v[j]);
        double texels = 0.5 * fabs(((double)u[1] - u[0]) * ((double)v[2] - v[0]) - ((double)u[2] - u[0]) * ((double)v[1] - v[0])) *
                        tex->width * tex->height;
        double r = ceil(sqrt((isfinite(texels) ? texels : 0.0) / CELL_TEXELS));
        t->tris[k].res = r < 1.0 ? 1 : r > MAX_RES ? MAX_RES : (int)r;
        t->tris[k].first_cell = (uint32_t)cells;
        cells += (size_t)t->tris[k].res * (size_t)t->tris[k].res;
    }
    t->cell_cdf = malloc(sizeof *t->cell_cdf * (cells + 1));
    if (!t->cell_cdf) {
        lie_texlight_destroy(t);
        return LIE_ERR_NOMEM;
    }
    /* the cells, triangles in parallel (each writes its own slice) */
    double *cell_sum = malloc(sizeof *cell_sum * ((size_t)em->n_tris + 1));
    if (!cell_sum) {
        lie_texlight_destroy(t);
        return LIE_ERR_NOMEM;
    }
    cells_job jb = {s, em, mat, tex, pyr, t, cell_sum};
    lie_status st = lie_parallel_for(((size_t)em->n_tris + CELLS_TRIS - 1) / CELLS_TRIS, threads, cells_run, &jb, NULL, NULL);
    if (st != LIE_OK) {
        free(cell_sum);
        lie_texlight_destroy(t);
        return st;
    }
    double acc = 0.0, area = 0.0;
    for (uint32_t k = 0; k < em->n_tris; k++) {
        uint32_t g = em->first_tri + k;
        const int R = t->tris[k].res;
        double sum = cell_sum[k];
        t->tris[k].weight = (float)(s->tri_area[g] * sum / ((double)R * R));
        acc += t->tris[k].weight;
        t->tri_cdf[k] = acc;
        area += s->tri_area[g];
    }
    free(cell_sum);
    t->total = acc;
    float full = lum3(em->radiance);
    t->scale = area > 0.0 && full > 0.0f ? (float)(acc / (area * full)) : 0.0f;
    *out = t;
    return LIE_OK;
}

lie_status lie_texlight_create(const lie_scene *s, int e, lie_texlight **out)
{
    *out = NULL;
    const lie_material *mat = NULL;
    const lie_texture *tex = texture_of(s, e, &mat);
    if (!tex)
        return LIE_OK;
    max_pyramid pyr;
    if (!pyramid_make(tex, s->emitters[e].radiance, &pyr))
        return LIE_ERR_NOMEM;
    lie_status st = texlight_build(s, e, mat, tex, &pyr, 1, out);
    pyramid_free(&pyr);
    return st;
}

lie_status lie_texlight_create_all(const lie_scene *s, lie_texlight **out, int threads)
{
    /* emitters of one material share their texture's pyramid: an
     * instanced sign of many emitters makes it once */
    max_pyramid pyr;
    memset(&pyr, 0, sizeof pyr);
    const lie_texture *have = NULL;
    float rad[3] = {0.0f, 0.0f, 0.0f};
    lie_status st = LIE_OK;
    for (int e = 0; st == LIE_OK && e < s->n_emitters; e++) {
        out[e] = NULL;
        const lie_material *mat = NULL;
        const lie_texture *tex = texture_of(s, e, &mat);
        if (!tex)
            continue;
        const float *r = s->emitters[e].radiance;
        if (tex != have || memcmp(rad, r, sizeof rad) != 0) {
            pyramid_free(&pyr);
            have = NULL;
            if (!pyramid_make(tex, r, &pyr)) {
                st = LIE_ERR_NOMEM;
                break;
            }
            have = tex;
            memcpy(rad, r, sizeof rad);
        }
        st = texlight_build(s, e, mat, tex, &pyr, threads, &out[e]);
    }
    pyramid_free(&pyr);
    return st;
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

float lie_texlight_tri_weight(const lie_texlight *t, uint32_t k) { return t->tris[k].weight; }

void lie_texlight_sample_tri(const lie_scene *s, int e, const lie_texlight *t, uint32_t k, float r, float u2,
                             lie_emitter_sample *out)
{
    const lie_emitter *em = &s->emitters[e];
    memset(out, 0, sizeof *out);
    /* the cell by r (its row-major index), the point in the cell by what
     * is left of r and by u2 */
    const tri_dist *td = &t->tris[k];
    const int R = td->res;
    const double *cdf = t->cell_cdf + td->first_cell;
    const uint32_t nc = (uint32_t)R * (uint32_t)R;
    double csum = cdf[nc - 1];
    uint32_t g = t->first_tri + k;
    if (!(csum > 0.0)) {
        out->p = s->tri_p[3 * (size_t)g];
        out->n = s->tri_ng[g];
        out->tri = g;
        return; /* a black triangle: weight 0 */
    }
    double y = (double)r * csum;
    uint32_t c = cdf_find(cdf, nc, y);
    double clo = c > 0 ? cdf[c - 1] : 0.0, cw = cdf[c] - clo;
    float r2 = cw > 0.0 ? (float)((y - clo) / cw) : 0.5f;
    r2 = fminf(fmaxf(r2, 0.0f), LIE_BELOW_ONE);
    float cv[3][2], sb1, sb2;
    subtriangle(R, c, cv);
    lie_sample_triangle(r2, fminf(u2, LIE_BELOW_ONE), &sb1, &sb2);
    float b1 = cv[0][0] + sb1 * (cv[1][0] - cv[0][0]) + sb2 * (cv[2][0] - cv[0][0]);
    float b2 = cv[0][1] + sb1 * (cv[1][1] - cv[0][1]) + sb2 * (cv[2][1] - cv[0][1]);
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
    /* density on the triangle: P(cell) / (the cell's area) */
    double pdf = (cw / csum) * (double)nc / (double)s->tri_area[g];
    out->inv_pdf = pdf > 0.0 && isfinite(pdf) ? (float)(1.0 / pdf) : 0.0f;
}

void lie_texlight_sample(const lie_scene *s, int e, const lie_texlight *t, float u1, float u2, lie_emitter_sample *out)
{
    if (!(t->total > 0.0)) {
        memset(out, 0, sizeof *out);
        out->p = s->tri_p[3 * (size_t)t->first_tri];
        out->n = s->tri_ng[t->first_tri];
        out->tri = t->first_tri;
        return; /* a black emitter: weight 0 */
    }
    /* the triangle by u1, then the point in it by the rest of u1 and u2 */
    double x = (double)u1 * t->total;
    uint32_t k = cdf_find(t->tri_cdf, t->n_tris, x);
    double lo = k > 0 ? t->tri_cdf[k - 1] : 0.0, w = t->tri_cdf[k] - lo;
    double r = w > 0.0 ? (x - lo) / w : 0.5;
    lie_texlight_sample_tri(s, e, t, k, (float)r, u2, out);
    /* density: P(triangle) times the density on it */
    double pt = w / t->total;
    out->inv_pdf = pt > 0.0 && out->inv_pdf > 0.0f ? (float)((double)out->inv_pdf / pt) : 0.0f;
}
