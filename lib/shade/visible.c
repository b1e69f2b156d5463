/* The triangles a camera sees, directly or in mirrors (lie-build --view). */
#include "shade/shade.h"

lie_status lie_camera_mark_visible(const lie_scene *s, const lie_rt *rt, const lie_camera *cams, int n_cams,
                                   int width, int height, int max_depth, uint8_t *mask, lie_error *err)
{
    if (width < 1 || height < 1)
        return lie_error_set(err, LIE_ERR_ARG, s->path, "view size %dx%d out of range", width, height);
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
                    mask[hit.tri] = 1;
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
