/* SPDX-License-Identifier: Apache-2.0 */
/* The viewer's orbit camera: yaw and pitch about a target, world up +y. */
#include "view.h"

#include <math.h>
#include <stdio.h>

static const float deg = (float)M_PI / 180.0f;

lie_vec3 view_orbit_eye(const view_orbit *o)
{
    float cp = cosf(o->pitch * deg), sp = sinf(o->pitch * deg);
    float cy = cosf(o->yaw * deg), sy = sinf(o->yaw * deg);
    return lie_v3_add(o->target, lie_v3_scale(lie_v3(cp * sy, sp, cp * cy), o->dist));
}

static float clampf(float x, float lo, float hi) { return x < lo ? lo : x > hi ? hi : x; }

/* Navigation stays inside the coordinate range (LIE_CAMERA_COORD_MAX,
 * lib/core/core.h): the target and the distance within a quarter of it
 * each, so the eye is always a camera lie_camera_parse takes.  A dolly or a
 * pan of any size gives this clamped view, never a failure. */
static void keep_in_range(view_orbit *o)
{
    const float lim = 0.25f * LIE_CAMERA_COORD_MAX;
    float *t[3] = {&o->target.x, &o->target.y, &o->target.z};
    for (int k = 0; k < 3; k++)
        *t[k] = isfinite(*t[k]) ? clampf(*t[k], -lim, lim) : 0.0f;
    o->dist = isfinite(o->dist) ? clampf(o->dist, 1e-4f, lim) : lim;
}

void view_orbit_from_camera(view_orbit *o, const lie_camera *c, const lie_scene *s)
{
    lie_vec3 f = lie_v3_norm(c->forward);
    /* the target: where the view direction passes closest to the scene's centre */
    lie_vec3 centre = lie_v3_scale(lie_v3_add(s->bounds.lo, s->bounds.hi), 0.5f);
    float radius = 0.5f * lie_v3_len(lie_v3_sub(s->bounds.hi, s->bounds.lo));
    if (!isfinite(radius) || radius <= 0.0f)
        radius = 1.0f;
    float d = lie_v3_dot(lie_v3_sub(centre, c->eye), f);
    if (!(d > 0.05f * radius))
        d = radius;
    o->target = lie_v3_add(c->eye, lie_v3_scale(f, d));
    o->dist = d;
    o->pitch = clampf(-asinf(clampf(f.y, -1.0f, 1.0f)) / deg, -89.0f, 89.0f);
    o->yaw = atan2f(-f.x, -f.z) / deg;
    o->fov = c->ymag > 0.0f ? 45.0f : c->yfov / deg;
    if (!(o->fov > 1.0f && o->fov < 170.0f))
        o->fov = 45.0f;
    keep_in_range(o);
}

void view_orbit_rotate(view_orbit *o, float dyaw, float dpitch)
{
    o->yaw = fmodf(o->yaw + dyaw, 360.0f);
    o->pitch = clampf(o->pitch + dpitch, -89.0f, 89.0f);
}

void view_orbit_dolly(view_orbit *o, float f)
{
    o->dist = o->dist * (1.0f - f);
    keep_in_range(o);
}

/* Right and up of the view (forward from the eye to the target). */
static void basis(const view_orbit *o, lie_vec3 *fwd, lie_vec3 *right, lie_vec3 *up)
{
    *fwd = lie_v3_norm(lie_v3_sub(o->target, view_orbit_eye(o)));
    *right = lie_v3_norm(lie_v3_cross(*fwd, lie_v3(0.0f, 1.0f, 0.0f)));
    *up = lie_v3_cross(*right, *fwd);
}

void view_orbit_pan(view_orbit *o, float dx, float dy)
{
    lie_vec3 f, r, u;
    basis(o, &f, &r, &u);
    float h = 2.0f * o->dist * tanf(0.5f * o->fov * deg);
    o->target = lie_v3_add(o->target, lie_v3_add(lie_v3_scale(r, -dx * h), lie_v3_scale(u, dy * h)));
    keep_in_range(o);
}

void view_orbit_fly(view_orbit *o, float fwd, float right, float up)
{
    lie_vec3 f, r, u;
    basis(o, &f, &r, &u);
    lie_vec3 d = lie_v3_add(lie_v3_add(lie_v3_scale(f, fwd), lie_v3_scale(r, right)), lie_v3(0.0f, up, 0.0f));
    o->target = lie_v3_add(o->target, d);
    keep_in_range(o);
}

void view_orbit_frame(view_orbit *o, lie_box3 b)
{
    if (lie_box3_is_empty(&b))
        return;
    o->target = lie_v3_scale(lie_v3_add(b.lo, b.hi), 0.5f);
    float r = 0.5f * lie_v3_len(lie_v3_sub(b.hi, b.lo));
    float d = r / sinf(0.5f * o->fov * deg);
    o->dist = d > 1e-3f ? d : 1e-3f;
    keep_in_range(o);
}

void view_orbit_spec(const view_orbit *o, char *buf, size_t size)
{
    lie_vec3 e = view_orbit_eye(o);
    snprintf(buf, size, "eye=%.9g,%.9g,%.9g,target=%.9g,%.9g,%.9g,up=0,1,0,fov=%.9g", e.x, e.y, e.z, o->target.x,
             o->target.y, o->target.z, o->fov);
}
