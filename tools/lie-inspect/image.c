/* SPDX-License-Identifier: Apache-2.0 */
/* lie-inspect image CACHE -o OUT.png: the paper's Figure 10, a false-colour
 * picture of the local illumination environments seen from a camera.  The
 * colours come from the renderer's complexity layer (lie_complexity_colour:
 * green visible, blue occluded, black to white by blocker count for
 * partial, red complex or not built), so this image and lie-render's
 * `--aov complexity` agree pixel for pixel.  Only eye rays are traced. */
#include "inspect.h"

#include <stdlib.h>

int inspect_image(const char *path, const inspect_options *o)
{
    inspect_cache l;
    lie_error err;
    lie_error_clear(&err);
    if (inspect_load(path, &l, &err) != LIE_OK) {
        inspect_unload(&l);
        return inspect_fail(&err, 1);
    }
    lie_scene_options so = lie_scene_options_default();
    so.allow_external_uris = o->external;
    lie_scene *s = NULL;
    lie_rt *rt = NULL;
    lie_env_shadows *lv = NULL;
    lie_frame *frame = NULL;
    uint8_t *rgb = NULL;
    lie_camera cam;
    lie_file_set *files = so.files = lie_file_set_create(LIE_FILES_NAMES); /* the PNG must be no input */
    lie_status st = files ? lie_file_set_note(files, path, &err) : lie_error_set(&err, LIE_ERR_NOMEM, path, "out of memory");
    if (st == LIE_OK)
        st = lie_cache_load_scene(l.cache, path, o->scene, &so, &s, &err);
    if (st == LIE_OK)
        st = lie_file_set_claim(files, o->output, NULL, &err);
    if (st == LIE_OK && !o->quiet)
        lie_print_scene_warnings(inspect_prog, s, path);
    if (st == LIE_OK && o->emitter >= s->n_emitters)
        st = lie_error_set(&err, LIE_ERR_ARG, path, "--emitter %d: the scene has %d emitters", o->emitter,
                           s->n_emitters);
    if (st == LIE_OK) {
        st = lie_camera_parse(s, o->camera, &cam, &err);
        if (st != LIE_OK && !err.file[0])
            snprintf(err.file, sizeof err.file, "%s", path);
    }
    if (st == LIE_OK)
        st = lie_env_shadows_create(s, l.cache->env, &lv, &err);
    if (st == LIE_OK)
        st = lie_rt_create(s, &rt, &err);
    if (st == LIE_OK) {
        lie_render_options ro = lie_render_options_default();
        ro.width = o->width;
        ro.height = o->height;
        ro.threads = o->threads;
        ro.visibility = LIE_VIS_LIE;
        ro.oracle = lie_env_shadows_oracle(lv);
        ro.aovs = LIE_AOV_COMPLEXITY;
        ro.aov_emitter = o->emitter;
        ro.eye_only = 1;
        ro.progress = !o->quiet;
        st = lie_render(s, rt, &cam, &ro, &frame, NULL, &err);
    }
    const lie_aov *aov = st == LIE_OK ? lie_frame_find_aov(frame, "complexity") : NULL;
    if (st == LIE_OK && !aov)
        st = lie_error_set(&err, LIE_ERR_NOMEM, path, "out of memory");
    if (st == LIE_OK) {
        size_t n = (size_t)frame->width * (size_t)frame->height * 3;
        rgb = malloc(n);
        if (!rgb)
            st = lie_error_set(&err, LIE_ERR_NOMEM, path, "out of memory");
        /* display values in [0, 1]: scaled, not sRGB-encoded */
        for (size_t i = 0; rgb && i < n; i++) {
            float v = aov->data[i];
            v = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;
            rgb[i] = (uint8_t)(v * 255.0f + 0.5f);
        }
    }
    if (st == LIE_OK)
        st = lie_png_write_rgb8(o->output, frame->width, frame->height, rgb, &err);
    free(rgb);
    lie_frame_destroy(frame);
    lie_rt_destroy(rt);
    lie_env_shadows_destroy(lv);
    lie_scene_destroy(s);
    lie_file_set_destroy(files);
    inspect_unload(&l);
    return st == LIE_OK ? 0 : inspect_fail(&err, 1);
}
