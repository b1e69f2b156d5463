/* SPDX-License-Identifier: Apache-2.0 */
/* A program of the library's users, built by tests/tools/t0600-install.sh as C11 (prog.c)
 * and as C++17 (the same text as prog.cpp) against the installed headers and liblie.so
 * through `pkg-config --cflags --libs lie`: it reads a cache, loads the scene it describes,
 * renders it from the scene's first camera through the cache's environments, and writes the
 * image and the cache again.
 *     prog CACHE IMAGE CACHE_OUT */
#include <lie.h>
#include <stdio.h>

static int fail(const lie_error *err)
{
    fprintf(stderr, "prog: %s\n", err->msg);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: prog CACHE IMAGE CACHE_OUT\n");
        return 2;
    }
    lie_error err;
    lie_cache *c = NULL;
    lie_scene *s = NULL;
    lie_rt *rt = NULL;
    lie_env_shadows *vis = NULL;
    lie_frame *f = NULL;
    int rc = 1;
    lie_scene_options so = lie_scene_options_default();
    lie_render_options ro = lie_render_options_default();
    lie_render_stats st;
    lie_camera cam;
    lie_error_clear(&err);
    if (lie_cache_read(argv[1], &c, &err) != LIE_OK || lie_cache_load_scene(c, argv[1], NULL, &so, &s, &err) != LIE_OK ||
        lie_rt_create(s, &rt, &err) != LIE_OK || lie_env_shadows_create(s, c->env, &vis, &err) != LIE_OK ||
        lie_scene_camera(s, NULL, &cam, &err) != LIE_OK) {
        rc = fail(&err);
        goto done;
    }
    ro.width = 64;
    ro.height = 48;
    ro.light_samples = 16;
    ro.threads = 2;
    ro.visibility = LIE_VIS_LIE;
    ro.oracle = lie_env_shadows_oracle(vis);
    if (lie_render(s, rt, &cam, &ro, &f, &st, &err) != LIE_OK || lie_frame_write(argv[2], f, NULL, &err) != LIE_OK ||
        lie_cache_write(argv[3], c, NULL, &err) != LIE_OK) {
        rc = fail(&err);
        goto done;
    }
    printf("%s %u triangles, %llu shading points\n", lie_version_string(), (unsigned)s->n_tris,
           (unsigned long long)st.shading_points);
    rc = 0;
done:
    lie_frame_destroy(f);
    lie_env_shadows_destroy(vis);
    lie_rt_destroy(rt);
    lie_scene_destroy(s);
    lie_cache_destroy(c);
    return rc;
}
