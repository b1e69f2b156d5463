/* Private to lib/scene. */
#ifndef LIE_SCENE_INTERNAL_H
#define LIE_SCENE_INTERNAL_H

#include "scene/scene.h"

/* An area emitter's hull points and plane frame (see lie_emitter), from its
 * triangles and double_sided flag. */
void lie_scene_emitter_shape(const lie_scene *s, lie_emitter *e);
/* The oriented box hull of triangles tris[0..n_tris) (tris NULL: first,
 * first + 1, ...): 8 corners, or *n_hull 0 for few triangles. */
void lie_scene_hull_of(const lie_scene *s, const uint32_t *tris, uint32_t first, uint32_t n_tris, lie_vec3 hull[8],
                       int *n_hull);

#endif
