/* The triangles a camera sees, directly or in mirrors, and where on them
 * (lie-build --view, §4.3.1 and §4.3.3). */
#include "shade/shade.h"

#include <stdlib.h>

/* Every hit of the views' pixel rays (2 x 2 a pixel) and of their mirror
 * bounces, as triangle << 32 | its patch key (lie_pixels_key), appended to
 * *hits; or, when mask is not NULL, only marked there. */
static lie_status sample_views(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n_cams, int width,
                               int height, int max_depth, uint8_t *mask, uint64_t **hits, size_t *n_hits,
                               lie_error *err)
{
    if (width < 1 || height < 1)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "view size %dx%d out of range", width, height);
    size_t cap = 0;
    for (int c = 0; c < n_cams; c++) {
        const lie_view v = lie_view_make(&cams[c], 2 * width, 2 * height);
        for (int y = 0; y < 2 * height; y++)
            for (int x = 0; x < 2 * width; x++) {
                lie_vec3 org, d;
                lie_view_ray(&v, (float)x + 0.5f, (float)y + 0.5f, 2 * width, 2 * height, &org, &d);
                for (int depth = 0; depth <= max_depth; depth++) {
                    lie_hit hit;
                    if (!lie_rt_intersect(rt, org, d, 0.0f, INFINITY, 1, &hit))
                        break;
                    if (mask)
                        mask[hit.tri] = 1;
                    else if (!LIE_PUSH(*hits, *n_hits, cap,
                                       (uint64_t)hit.tri << 32 | lie_pixels_key(hit.u, hit.v)))
                        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory for the views' pixels");
                    lie_surface sf;
                    lie_surface_from_hit(s, &hit, d, &sf);
                    if (!sf.mirror)
                        break;
                    float dn = lie_v3_dot(d, sf.n);
                    d = lie_v3_norm(lie_v3_sub(d, lie_v3_scale(sf.n, 2.0f * dn)));
                    org = lie_ray_origin(sf.p, sf.ng, lie_ray_eps(sf.p));
                }
            }
    }
    return LIE_OK;
}

lie_status lie_camera_mark_visible(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n_cams,
                                   int width, int height, int max_depth, uint8_t *mask, lie_error *err)
{
    return sample_views(s, rt, cams, n_cams, width, height, max_depth, mask, NULL, NULL, err);
}

lie_status lie_camera_pixels(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n_cams, int width,
                             int height, int max_depth, lie_pixels **out, lie_error *err)
{
    *out = NULL;
    uint64_t *hits = NULL;
    size_t n_hits = 0;
    lie_status st = sample_views(s, rt, cams, n_cams, width, height, max_depth, NULL, &hits, &n_hits, err);
    if (st == LIE_OK && (st = lie_pixels_create(s->n_tris, 4, hits, n_hits, out, err)) != LIE_OK && !err->file[0])
        snprintf(err->file, sizeof err->file, "%s", s->path);
    free(hits);
    return st;
}
