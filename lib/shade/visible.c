/* SPDX-License-Identifier: Apache-2.0 */
/* The triangles a camera sees, directly or in mirrors, and where on them
 * (lie-build --view, §4.3.1 and §4.3.3). */
#include "shade/shade.h"

#include <stdlib.h>
#include <string.h>

/* One image row of one view per item, each into its own buffer: the
 * threads touch disjoint slots, and lie_pixels_create sorts the hits, so
 * the result does not depend on the schedule. */
typedef struct view_rows {
    const lie_scene *s;
    const lie_rt *rt;
    const lie_camera *cams;
    int width, height, max_depth;
    uint8_t *mask;      /* mark only (lie_camera_mark_visible), or: */
    uint64_t **hits;    /* per row: triangle << 32 | its patch key (lie_pixels_key) */
    size_t *n_hits, *cap_hits;
    int nomem;          /* set by any row that ran out of memory */
} view_rows;

static void sample_row(void *ctx, size_t item, int worker)
{
    (void)worker;
    view_rows *r = ctx;
    int W = 2 * r->width, H = 2 * r->height, y = (int)(item % (size_t)H);
    const lie_view v = lie_view_make(&r->cams[item / (size_t)H], W, H);
    for (int x = 0; x < W; x++) {
        lie_vec3 org, d;
        lie_view_ray(&v, (float)x + 0.5f, (float)y + 0.5f, W, H, &org, &d);
        for (int depth = 0; depth <= r->max_depth; depth++) {
            lie_hit hit;
            if (!lie_rt_intersect(r->rt, org, d, 0.0f, INFINITY, 1, &hit))
                break;
            if (r->mask)
                r->mask[hit.tri] = 1; /* one worker: see sample_views */
            else if (!LIE_PUSH(r->hits[item], r->n_hits[item], r->cap_hits[item],
                               (uint64_t)hit.tri << 32 | lie_pixels_key(hit.u, hit.v)))
                r->nomem = 1;
            lie_surface sf;
            lie_surface_from_hit(r->s, &hit, d, &sf);
            if (!sf.mirror)
                break;
            float dn = lie_v3_dot(d, sf.n);
            d = lie_v3_norm(lie_v3_sub(d, lie_v3_scale(sf.n, 2.0f * dn)));
            org = lie_ray_origin(sf.p, sf.ng, lie_ray_eps(sf.p));
        }
    }
}

/* Every hit of the views' pixel rays (2 x 2 a pixel) and of their mirror
 * bounces: into mask, or as pixels (*px). */
static lie_status sample_views(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n_cams, int width,
                               int height, int max_depth, uint8_t *mask, lie_pixels **px, lie_error *err)
{
    if (width < 1 || height < 1)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "view size %dx%d out of range", width, height);
    size_t rows = (size_t)n_cams * 2 * (size_t)height;
    view_rows r = {s, rt, cams, width, height, max_depth, mask, NULL, NULL, NULL, 0};
    if (!mask) {
        r.hits = calloc(rows + 1, sizeof *r.hits);
        r.n_hits = calloc(rows + 1, sizeof *r.n_hits);
        r.cap_hits = calloc(rows + 1, sizeof *r.cap_hits);
        r.nomem = !r.hits || !r.n_hits || !r.cap_hits;
    }
    /* rows in parallel when each keeps its own hits; one worker marks the
     * shared mask */
    lie_status st = r.nomem ? LIE_ERR_NOMEM : lie_parallel_for(rows, mask ? 1 : 0, sample_row, &r, NULL, NULL);
    if (st == LIE_OK && r.nomem)
        st = LIE_ERR_NOMEM;
    uint64_t *all = NULL;
    size_t n = 0;
    for (size_t i = 0; st == LIE_OK && !mask && i < rows; i++)
        n += r.n_hits[i];
    if (st == LIE_OK && !mask && !(all = malloc(sizeof *all * (n + 1))))
        st = LIE_ERR_NOMEM;
    for (size_t i = 0, k = 0; st == LIE_OK && !mask && i < rows; k += r.n_hits[i], i++)
        if (r.n_hits[i])
            memcpy(all + k, r.hits[i], sizeof *all * r.n_hits[i]);
    for (size_t i = 0; r.hits && i < rows; i++)
        free(r.hits[i]);
    free(r.hits);
    free(r.n_hits);
    free(r.cap_hits);
    if (st != LIE_OK) {
        free(all);
        return lie_error_set(err, st, s->path, "sampling the views' pixels: %s", lie_status_str(st));
    }
    if (!mask) {
        st = lie_pixels_create(s->n_tris, 4, all, n, px, err);
        if (st != LIE_OK && !err->file[0])
            snprintf(err->file, sizeof err->file, "%s", s->path);
    }
    free(all);
    return st;
}

lie_status lie_camera_mark_visible(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n_cams,
                                   int width, int height, int max_depth, uint8_t *mask, lie_error *err)
{
    return sample_views(s, rt, cams, n_cams, width, height, max_depth, mask, NULL, err);
}

lie_status lie_camera_pixels(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n_cams, int width,
                             int height, int max_depth, lie_pixels **out, lie_error *err)
{
    *out = NULL;
    return sample_views(s, rt, cams, n_cams, width, height, max_depth, NULL, out, err);
}
