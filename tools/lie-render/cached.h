/* SPDX-License-Identifier: Apache-2.0 */
/* lie-render SCENE --path PATH.yaml --cache C.lie (tools/lie-render/cached.c):
 * the camera path's frames, each rendered once the units its view lacks
 * are built (lib/update, lie_ctor), the cache kept on disk between frames. */
#ifndef LIE_RENDER_CACHED_H
#define LIE_RENDER_CACHED_H

#include "output.h"

typedef struct cached_run {
    const char *cache_file;   /* read if it exists (an interrupted run), written after each frame's build */
    const char *scene_file;   /* as lie-build records it */
    int view_width, view_height;
    lie_scene *scene;         /* borrowed */
    const lie_rt *rt;
    const lie_camera_path *cpath;
    lie_render_options *ro;
    int quiet, verbose;
    int whole;                /* every frame of the path asked for (no --frames): the cache ends whole */
    uint64_t units_built;     /* triangles built by this run, and renders done again */
    int rerenders;
} cached_run;

/* Render frames todo[0 .. n_todo) of the path into fo, building before each
 * what its view lacks; rs and the times add up as render_here's do. */
lie_status cached_render(cached_run *cr, frame_out *fo, const int *todo, int n_todo, lie_render_stats *rs,
                         double *t_render, double *t_write, int *rendered, lie_error *err);

#endif
