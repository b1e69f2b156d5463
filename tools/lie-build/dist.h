/* lie-build under mpirun (tools/lie-build/dist.c). */
#ifndef LIE_BUILD_DIST_H
#define LIE_BUILD_DIST_H

#include "dist/dist.h"
#include "lie.h"

/* Build the env across the ranks: ranges of units handed out dynamically,
 * gathered and joined on rank 0 (*out there; NULL on other ranks). */
lie_status build_dist(const lie_scene *s, const lie_rt *rt, const lie_build_params *p, const lie_pixels *px,
                      lie_env **out, lie_build_stats *stats, lie_error *err);

#endif
