/* Private to lib/scene. */
#ifndef LIE_SCENE_INTERNAL_H
#define LIE_SCENE_INTERNAL_H

#include "scene/scene.h"

/* An area emitter's hull points and plane frame (see lie_emitter), from its
 * triangles and double_sided flag. */
void lie_scene_emitter_shape(const lie_scene *s, lie_emitter *e);

#endif
