/* SPDX-License-Identifier: Apache-2.0 */
/* --camera values: a scene camera by name or index, or an explicit
 * "eye=X,Y,Z,target=X,Y,Z[,up=X,Y,Z][,fov=DEG|ortho=HEIGHT]". */
#include "shade/shade.h"

#include <stdlib.h>
#include <string.h>

static int parse_floats(const char **p, float *v, int n)
{
    for (int i = 0; i < n; i++) {
        char *end;
        v[i] = strtof(*p, &end);
        if (end == *p || !isfinite(v[i]))
            return 0;
        *p = end;
        if (i + 1 < n) {
            if (**p != ',')
                return 0;
            (*p)++;
        }
    }
    return 1;
}

lie_view lie_view_make(const lie_camera *cam, int width, int height)
{
    lie_view v;
    v.eye = cam->eye;
    v.fwd = lie_v3_norm(cam->forward);
    v.right = lie_v3_norm(lie_v3_cross(v.fwd, cam->up));
    v.up = lie_v3_cross(v.right, v.fwd);
    v.ortho = cam->ymag > 0.0f && isfinite(cam->ymag);
    float yfov = cam->yfov > 0.0f && cam->yfov < (float)M_PI ? cam->yfov : 0.7853982f;
    v.half_h = v.ortho ? cam->ymag : tanf(0.5f * yfov);
    v.half_w = v.half_h * (float)width / (float)height;
    return v;
}

void lie_view_ray(const lie_view *v, float x, float y, int width, int height, lie_vec3 *org, lie_vec3 *dir)
{
    float nx = (2.0f * x / (float)width - 1.0f) * v->half_w;
    float ny = (1.0f - 2.0f * y / (float)height) * v->half_h;
    lie_vec3 off = lie_v3_add(lie_v3_scale(v->right, nx), lie_v3_scale(v->up, ny));
    if (v->ortho) {
        *org = lie_v3_add(v->eye, off);
        *dir = v->fwd;
    } else {
        *org = v->eye;
        *dir = lie_v3_norm(lie_v3_add(v->fwd, off));
    }
}

lie_view_exr lie_view_exr_make(const lie_view *v)
{
    lie_view_exr e;
    memset(&e, 0, sizeof e);
    /* world to camera: the camera's axes as columns, -eye projected on them
     * in the last row */
    const lie_vec3 ax[3] = {v->right, v->up, v->fwd};
    float *w = e.world_to_camera;
    for (int c = 0; c < 3; c++) {
        w[0 * 4 + c] = ax[c].x;
        w[1 * 4 + c] = ax[c].y;
        w[2 * 4 + c] = ax[c].z;
        w[3 * 4 + c] = -lie_v3_dot(v->eye, ax[c]);
    }
    w[15] = 1.0f;
    /* camera to NDC: x_ndc = (1 + x / half_w) / 2, y_ndc = (1 - y / half_h) / 2,
     * with x, y divided by z first for a perspective view (w = z) */
    float p[16] = {0};
    p[0 * 4 + 0] = 0.5f / v->half_w;
    p[1 * 4 + 1] = -0.5f / v->half_h;
    if (v->ortho) {
        p[3 * 4 + 0] = 0.5f;
        p[3 * 4 + 1] = 0.5f;
        p[2 * 4 + 2] = 1.0f;
        p[3 * 4 + 3] = 1.0f;
    } else {
        p[2 * 4 + 0] = 0.5f;
        p[2 * 4 + 1] = 0.5f;
        p[3 * 4 + 2] = 1.0f;
        p[2 * 4 + 3] = 1.0f;
    }
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) {
            double acc = 0.0;
            for (int k = 0; k < 4; k++)
                acc += (double)w[r * 4 + k] * (double)p[k * 4 + c];
            e.world_to_ndc[r * 4 + c] = (float)acc;
        }
    for (int k = 0; k < 16; k++) { /* no -0 in the header */
        e.world_to_camera[k] += 0.0f;
        e.world_to_ndc[k] += 0.0f;
    }
    e.screen_window_width = 2.0f * v->half_w;
    return e;
}

const char *lie_camera_invalid(const lie_camera *c)
{
    if (!lie_v3_within(c->eye, LIE_CAMERA_COORD_MAX))
        return "the eye is outside the coordinate range (+-1e14)";
    float lf = lie_v3_len(c->forward), lu = lie_v3_len(c->up);
    if (!(fabsf(lf - 1.0f) < 1e-3f))
        return "no view direction (eye and target coincide)";
    if (!(fabsf(lu - 1.0f) < 1e-3f) || !(fabsf(lie_v3_dot(c->forward, c->up)) < 1e-3f))
        return "no up direction (up is parallel to the view direction)";
    if (!(c->ymag > 0.0f && c->ymag < 1e30f) && !(c->yfov > 0.0f && c->yfov < (float)M_PI))
        return "no field of view";
    return NULL;
}

lie_status lie_camera_parse(const lie_scene *s, const char *spec, lie_camera *out, lie_error *err)
{
    if (!spec || !strchr(spec, '='))
        return lie_scene_camera(s, spec, out, err);
    lie_camera c;
    memset(&c, 0, sizeof c);
    float eye[3], target[3], up[3] = {0.0f, 1.0f, 0.0f}, fov = 45.0f, height = 0.0f;
    int have_eye = 0, have_target = 0, have_fov = 0;
    const char *p = spec;
    while (*p) {
        const char *eq = strchr(p, '=');
        if (!eq)
            return lie_error_set(err, LIE_ERR_ARG, NULL, "--camera: expected key=value at '%s'", p);
        size_t klen = (size_t)(eq - p);
        const char *v = eq + 1;
        int ok;
        if (klen == 3 && strncmp(p, "eye", 3) == 0) {
            ok = parse_floats(&v, eye, 3);
            have_eye = 1;
        } else if (klen == 6 && strncmp(p, "target", 6) == 0) {
            ok = parse_floats(&v, target, 3);
            have_target = 1;
        } else if (klen == 2 && strncmp(p, "up", 2) == 0) {
            ok = parse_floats(&v, up, 3);
        } else if (klen == 3 && strncmp(p, "fov", 3) == 0) {
            ok = parse_floats(&v, &fov, 1) && fov > 0.0f && fov < 180.0f;
            have_fov = 1;
        } else if (klen == 5 && strncmp(p, "ortho", 5) == 0) {
            ok = parse_floats(&v, &height, 1) && height > 0.0f && height < 1e30f;
        } else {
            return lie_error_set(err, LIE_ERR_ARG, NULL, "--camera: unknown key '%.*s'", (int)klen, p);
        }
        if (!ok || (*v && *v != ','))
            return lie_error_set(err, LIE_ERR_ARG, NULL, "--camera: bad value for '%.*s'", (int)klen, p);
        p = *v ? v + 1 : v;
    }
    if (!have_eye || !have_target)
        return lie_error_set(err, LIE_ERR_ARG, NULL, "--camera: needs both eye= and target=");
    if (have_fov && height > 0.0f)
        return lie_error_set(err, LIE_ERR_ARG, NULL, "--camera: fov= is for a perspective view, ortho= for an orthographic one: not both");
    c.eye = lie_v3(eye[0], eye[1], eye[2]);
    if (!lie_v3_within(c.eye, LIE_CAMERA_COORD_MAX) ||
        !lie_v3_within(lie_v3(target[0], target[1], target[2]), LIE_CAMERA_COORD_MAX))
        return lie_error_set(err, LIE_ERR_ARG, NULL, "--camera: eye and target must lie within +-%g",
                             (double)LIE_CAMERA_COORD_MAX);
    lie_vec3 f = lie_v3_sub(lie_v3(target[0], target[1], target[2]), c.eye);
    if (lie_v3_len(f) <= 0.0f)
        return lie_error_set(err, LIE_ERR_ARG, NULL, "--camera: eye and target coincide");
    c.forward = lie_v3_norm(f);
    lie_vec3 u = lie_v3(up[0], up[1], up[2]);
    u = lie_v3_sub(u, lie_v3_scale(c.forward, lie_v3_dot(u, c.forward)));
    if (lie_v3_len(u) <= 1e-6f)
        return lie_error_set(err, LIE_ERR_ARG, NULL, "--camera: up is parallel to the view direction");
    c.up = lie_v3_norm(u);
    c.yfov = height > 0.0f ? 0.0f : fov * (float)M_PI / 180.0f;
    c.ymag = 0.5f * height; /* ortho=HEIGHT: the view's full height in world units */
    *out = c;
    return LIE_OK;
}
