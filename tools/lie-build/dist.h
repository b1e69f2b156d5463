/* SPDX-License-Identifier: Apache-2.0 */
/* lie-build under mpirun (tools/lie-build/dist.c). */
#ifndef LIE_BUILD_DIST_H
#define LIE_BUILD_DIST_H

#include "dist/dist.h"
#include "lie.h"

/* Build the env across the ranks: ranges of units handed out dynamically,
 * gathered and joined on rank 0 (*out there; NULL on other ranks). */
lie_status build_dist(const lie_scene *s, const lie_rt *rt, const lie_build_params *p, const lie_pixels *px,
                      lie_env **out, lie_build_stats *stats, lie_error *err);

/* The scene (- for stdin) and, when path_file is not NULL, the camera path:
 * under mpirun read on rank 0, the scene with every file it references,
 * and broadcast (lie_dist_load).  *scene and *cpath are the caller's, also
 * when an error is returned (NULL then, or to destroy). */
lie_status build_load_inputs(const char *input, const char *path_file, const lie_scene_options *so,
                             lie_scene **scene, lie_camera_path **cpath, lie_error *err);

#endif
