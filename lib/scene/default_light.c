/* SPDX-License-Identifier: Apache-2.0 */
/* A light for a scene that has none (lie_scene_add_default_light, scene.h), as a modeller's
 * viewport lights geometry that has no lights of its own: a KHR_lights_punctual light added
 * to the document as an ordinary node, so every part of the library sees a normal emitter. */
#include "scene/scene.h"

#include <math.h>

lie_status lie_scene_add_default_light(lie_scene *s, lie_default_light kind, const lie_camera *cam, lie_error *err)
{
    lie_vec3 lo = s->bounds.lo, hi = s->bounds.hi;
    lie_vec3 centre = lie_v3_scale(lie_v3_add(lo, hi), 0.5f);
    lie_light_def l = {.name = "lie-default-light", .color = {1.0f, 1.0f, 1.0f}};
    lie_mat4 at;
    if (kind == LIE_DEFAULT_LIGHT_HEADLIGHT) {
        /* a point light at the eye: 1 lux at the scene's centre (intensity d^2 candela), so a
         * white Lambert surface there shows 1/pi, what --exposure 0 maps to mid-grey */
        double d = lie_v3_len(lie_v3_sub(centre, cam->eye));
        l.type = LIE_LIGHT_POINT;
        l.intensity = (float)(d > 1e-6 ? d * d : 1.0);
        at = lie_mat4_translation(cam->eye.x, cam->eye.y, cam->eye.z);
    } else if (kind == LIE_DEFAULT_LIGHT_SUN) {
        /* a directional light of 1 lux from glTF's up (+y) tilted a little toward +z, so that
         * walls facing +z are lit too; KHR_lights_punctual lights point down their node's -z */
        const double axis[3] = {1.0, 0.0, 0.0};
        l.type = LIE_LIGHT_DIRECTIONAL;
        l.intensity = 1.0f;
        at = lie_mat4_rotation(axis, -60.0 * M_PI / 180.0);
    } else {
        return lie_error_set(err, LIE_ERR_ARG, s->path ? s->path : "scene", "unknown default light %d", (int)kind);
    }
    int li = lie_scene_add_light_def(s, &l);
    if (li < 0 || lie_scene_add_node(s, "lie-default-light", -1, &at, -1, -1, li) < 0)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path ? s->path : "scene", "out of memory");
    return lie_scene_flatten(s, err);
}
