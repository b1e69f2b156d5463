/* SPDX-License-Identifier: Apache-2.0 */
/* lie-view's session: the camera, the selection, edits from keys, drags
 * and script lines (tools/lie-view/session.h). */
#include "session.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#define prog view_prog

void session_push_ms(double **arr, int *n, double ms)
{
    double *a = realloc(*arr, sizeof *a * ((size_t)*n + 1));
    if (a) {
        a[(*n)++] = ms;
        *arr = a;
    }
}

/* After an edit that started at t0: wait for its first image and for the
 * constructor (the benchmark's latencies). */
static void edited(session *S, double t0)
{
    S->await_t0 = t0;
    S->await_version = view_world_version(S->w);
    S->last_edit_end = lie_time_now();
    S->catching_up = 1;
}

/* Undo the last group of edits, or redo it; *done: whether there was one. */
static lie_status undo_redo(session *S, int redo, int *done, lie_error *err)
{
    double t0 = lie_time_now();
    lie_status st = redo ? view_world_redo(S->w, done, err) : view_world_undo(S->w, done, err);
    if (st == LIE_OK && *done)
        edited(S, t0);
    return st;
}

static void say(session *S, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void say(session *S, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char raw[sizeof S->message];
    vsnprintf(raw, sizeof raw, fmt, ap);
    va_end(ap);
    /* names come from the scene file: no control byte reaches the terminal */
    lie_escape_controls(S->message, sizeof S->message, raw);
    S->message_until = lie_time_now() + 3.0;
    if (!S->quiet)
        fprintf(stderr, "%s: %s\n", prog, S->message);
}

void session_camera_update(session *S)
{
    char spec[512];
    view_orbit_spec(&S->orbit, spec, sizeof spec);
    if (strcmp(spec, S->spec) == 0)
        return;
    lie_camera c;
    lie_error err;
    view_world_read_lock(S->w);
    lie_status st = lie_camera_parse(view_world_scene(S->w), spec, &c, &err);
    view_world_read_unlock(S->w);
    if (st != LIE_OK)
        return; /* a degenerate view (eye on target): keep the last camera */
    snprintf(S->spec, sizeof S->spec, "%s", spec);
    S->cam = c;
    if (S->cam_gen == S->shown_cam_gen)
        S->change_t = lie_time_now();
    S->cam_gen++;
    S->refining = 1;
    S->last_change_t = lie_time_now();
}

/* A node for an edit: its name when that names it alone, else "#N". */
static void node_ref(session *S, int node, char *buf, size_t size)
{
    const lie_scene *s = view_world_scene(S->w);
    const char *name = s->nodes[node].name;
    int plain = name && *name;
    for (const char *p = name; plain && *p; p++)
        plain = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || *p == '_' ||
                *p == '-' || *p == '.';
    int found = -1;
    lie_error err;
    if (plain && lie_edit_find_node(s, name, &found, "", 0, 0, &err) == LIE_OK && found == node)
        snprintf(buf, size, "%s", name);
    else
        snprintf(buf, size, "#%d", node);
}

/* Apply one operation on the selection (its node set here) as an edit. */
static lie_status edit(session *S, lie_edit_op op, int join, lie_error *err)
{
    char ref[64];
    node_ref(S, S->sel, ref, sizeof ref);
    op.node = ref;
    lie_edit *e = view_world_new_edit(S->w);
    lie_status st = e ? lie_edit_append(e, &op, err) : lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    double t0 = lie_time_now();
    if (st == LIE_OK)
        st = view_world_edit(S->w, e, join, err);
    lie_edit_destroy(e);
    if (st == LIE_OK)
        edited(S, t0);
    return st;
}

/* The world box of the selection's subtree: its triangles and point lights. */
static lie_box3 sel_box(session *S)
{
    const lie_scene *s = view_world_scene(S->w);
    lie_box3 b = lie_box3_empty();
    uint8_t *in = calloc((size_t)s->n_nodes + 1, 1);
    if (!in)
        return b;
    view_node_subtree(s, S->sel, in);
    for (int i = 0; i < s->n_instances; i++)
        if (in[s->instances[i].node])
            for (uint32_t t = 3 * s->instances[i].first_tri; t < 3 * (s->instances[i].first_tri + s->instances[i].n_tris); t++)
                lie_box3_grow(&b, s->tri_p[t]);
    for (int i = 0; i < s->n_emitters; i++)
        if (s->emitters[i].type == LIE_EMITTER_POINT && in[s->emitters[i].node])
            lie_box3_grow(&b, s->emitters[i].position);
    free(in);
    return b;
}

/* A move clamped so the selection stays inside the coordinate range
 * (LIE_COORD_MAX, lib/core/core.h): a drag or a script's drag of any size
 * gives a defined result, never an edit the scene refuses. */
static lie_vec3 clamp_move(session *S, lie_vec3 d)
{
    view_world_read_lock(S->w);
    lie_box3 b = sel_box(S);
    view_world_read_unlock(S->w);
    const float m = 0.99f * LIE_COORD_MAX; /* a margin for the transforms' rounding */
    float lo[3] = {-2.0f * m, -2.0f * m, -2.0f * m}, hi[3] = {2.0f * m, 2.0f * m, 2.0f * m};
    if (!lie_box3_is_empty(&b)) {
        const float blo[3] = {b.lo.x, b.lo.y, b.lo.z}, bhi[3] = {b.hi.x, b.hi.y, b.hi.z};
        for (int k = 0; k < 3; k++) {
            lo[k] = -m - blo[k];
            hi[k] = m - bhi[k];
        }
    }
    float v[3] = {d.x, d.y, d.z};
    for (int k = 0; k < 3; k++)
        v[k] = v[k] < lo[k] ? lo[k] : v[k] > hi[k] ? hi[k] : v[k];
    return lie_v3(v[0], v[1], v[2]);
}

/* A drag's motion and turns are floats: their nine digits are the edit's
 * values (lie_edit_float_value), what the record holds. */
static lie_status edit_move(session *S, lie_vec3 d, int join, lie_error *err)
{
    d = clamp_move(S, d);
    return edit(S, lie_edit_op_move_by(NULL, lie_edit_float_value(d.x), lie_edit_float_value(d.y),
                                       lie_edit_float_value(d.z)),
                join, err);
}

static lie_status edit_rotate(session *S, lie_vec3 axis, float degrees, int join, lie_error *err)
{
    return edit(S, lie_edit_op_rotate(NULL, lie_edit_float_value(axis.x), lie_edit_float_value(axis.y),
                                      lie_edit_float_value(axis.z), lie_edit_float_value(degrees)),
                join, err);
}

/* The first material of the selection's subtree, for the keys that step it. */
static const lie_material *sel_material(session *S, float *strength)
{
    const lie_scene *s = view_world_scene(S->w);
    uint8_t *in = calloc((size_t)s->n_nodes + 1, 1);
    const lie_material *m = NULL;
    if (!in)
        return NULL;
    view_node_subtree(s, S->sel, in);
    for (int i = 0; i < s->n_instances && !m; i++)
        if (in[s->instances[i].node])
            m = lie_scene_material(s, s->instances[i].material);
    free(in);
    if (m && strength)
        *strength = fmaxf(m->emissive[0], fmaxf(m->emissive[1], m->emissive[2]));
    return m;
}

static void report(session *S, lie_status st, const lie_error *err)
{
    if (st != LIE_OK)
        say(S, "%s", err->msg);
}

void session_select(session *S, int node)
{
    S->sel = node;
    char name[128];
    view_world_read_lock(S->w);
    view_node_name(view_world_scene(S->w), node, name, sizeof name);
    view_world_read_unlock(S->w);
    if (node >= 0)
        say(S, "selected %s", name);
}

/* ---- the window loop ------------------------------------------------------- */


lie_vec3 session_view_axis(const lie_camera *c, int which)
{
    lie_vec3 f = lie_v3_norm(c->forward);
    lie_vec3 r = lie_v3_norm(lie_v3_cross(f, c->up));
    return which == 0 ? r : lie_v3_cross(r, f);
}

void session_flush_drag(session *S, drag_state *d)
{
    lie_error err;
    lie_status st = LIE_OK;
    if (d->dragging && S->sel >= 0) {
        lie_vec3 v = d->pending;
        if (v.x != 0.0f || v.y != 0.0f || v.z != 0.0f) {
            if (d->axis >= 0) {
                float keep[3] = {v.x, v.y, v.z};
                for (int k = 0; k < 3; k++)
                    if (k != d->axis)
                        keep[k] = 0.0f;
                v = lie_v3(keep[0], keep[1], keep[2]);
            }
            st = edit_move(S, v, d->join, &err);
            d->join = st == LIE_OK;
        }
        if (st == LIE_OK && d->pending_yaw != 0.0f) {
            st = edit_rotate(S, lie_v3(0.0f, 1.0f, 0.0f), d->pending_yaw, d->join, &err);
            d->join = st == LIE_OK;
        }
        if (st == LIE_OK && d->pending_pitch != 0.0f) {
            st = edit_rotate(S, session_view_axis(&S->cam, 0), d->pending_pitch, d->join, &err);
            d->join = st == LIE_OK;
        }
        report(S, st, &err);
    }
    d->pending = lie_v3(0.0f, 0.0f, 0.0f);
    d->pending_yaw = d->pending_pitch = 0.0f;
}

void session_key(session *S, const SDL_KeyboardEvent *k, int *quit)
{
    SDL_Keycode key = k->keysym.sym;
    int ctrl = (k->keysym.mod & KMOD_CTRL) != 0, shift = (k->keysym.mod & KMOD_SHIFT) != 0;
    float step = 0.05f * S->orbit.dist;
    lie_error err;
    lie_status st = LIE_OK;
    if (key == SDLK_q || key == SDLK_ESCAPE) {
        *quit = 1;
    } else if (ctrl && (key == SDLK_y || key == SDLK_z)) {
        int done, redo = key == SDLK_y || shift;
        st = undo_redo(S, redo, &done, &err);
        if (st == LIE_OK)
            say(S, done ? (redo ? "redone" : "undone") : (redo ? "nothing to redo" : "nothing to undo"));
    } else if (ctrl && key == SDLK_s) {
        const char *out = S->save ? S->save : "lie-view.lie";
        st = S->save ? LIE_OK : lie_file_set_check(S->files, out, &err); /* --save was claimed at the start */
        if (st == LIE_OK)
            st = view_world_save(S->w, out, &err);
        if (st == LIE_OK)
            say(S, "wrote %s", out);
    } else if (key == SDLK_w) {
        view_orbit_fly(&S->orbit, step, 0.0f, 0.0f);
    } else if (key == SDLK_s) {
        view_orbit_fly(&S->orbit, -step, 0.0f, 0.0f);
    } else if (key == SDLK_a) {
        view_orbit_fly(&S->orbit, 0.0f, -step, 0.0f);
    } else if (key == SDLK_d) {
        view_orbit_fly(&S->orbit, 0.0f, step, 0.0f);
    } else if (key == SDLK_PAGEUP) {
        view_orbit_fly(&S->orbit, 0.0f, 0.0f, step);
    } else if (key == SDLK_PAGEDOWN) {
        view_orbit_fly(&S->orbit, 0.0f, 0.0f, -step);
    } else if (key == SDLK_f) {
        view_world_read_lock(S->w);
        const lie_scene *s = view_world_scene(S->w);
        view_orbit_frame(&S->orbit, S->sel >= 0 ? view_node_bounds(s, S->sel) : s->bounds);
        view_world_read_unlock(S->w);
    } else if (key == SDLK_c) {
        view_world_read_lock(S->w);
        const lie_scene *s = view_world_scene(S->w);
        if (s->n_cameras > 0) {
            S->cam_index = (S->cam_index + 1) % s->n_cameras;
            view_orbit_from_camera(&S->orbit, &s->cameras[S->cam_index], s);
            say(S, "camera %d: %s", S->cam_index, s->cameras[S->cam_index].name ? s->cameras[S->cam_index].name : "");
        } else {
            lie_camera c = lie_scene_default_camera(s);
            view_orbit_from_camera(&S->orbit, &c, s);
            say(S, "the scene has no camera: the default view");
        }
        view_world_read_unlock(S->w);
    } else if (key == SDLK_m) {
        if (!view_world_has_cache(S->w)) {
            say(S, "complexity and patch views need a cache");
        } else {
            S->mode = (S->mode + 1) % 3;
            say(S, "view: %s", S->mode == 0 ? "shaded" : S->mode == 1 ? "complexity (Figure 10)" : "patches");
        }
    } else if (key == SDLK_p) {
        printf("%s\n", S->spec);
        fflush(stdout);
    } else if (key == SDLK_o) {
        S->overlay = !S->overlay;
    } else if (S->sel >= 0 && (key == SDLK_DELETE || key == SDLK_BACKSPACE)) {
        st = edit(S, lie_edit_op_remove(NULL), 0, &err);
        if (st == LIE_OK)
            S->sel = -1;
    } else if (S->sel >= 0 && key == SDLK_b) {
        static const float palette[6][3] = {{0.8f, 0.1f, 0.1f}, {0.1f, 0.6f, 0.15f}, {0.15f, 0.25f, 0.8f},
                                            {0.85f, 0.75f, 0.2f}, {0.9f, 0.9f, 0.9f}, {0.1f, 0.1f, 0.1f}};
        static int next;
        st = edit(S, lie_edit_op_set_material(NULL, LIE_EDIT_HAS_BASE_COLOR, palette[next++ % 6], 0.0f, 0.0f), 0, &err);
    } else if (S->sel >= 0 && (key == SDLK_LEFTBRACKET || key == SDLK_RIGHTBRACKET)) {
        const lie_material *m = sel_material(S, NULL);
        float r = m ? m->roughness : 1.0f;
        r += key == SDLK_RIGHTBRACKET ? 0.1f : -0.1f;
        r = r < 0.0f ? 0.0f : r > 1.0f ? 1.0f : r;
        st = edit(S, lie_edit_op_set_material(NULL, LIE_EDIT_HAS_ROUGHNESS, NULL, 0.0f, r), 0, &err);
        if (st == LIE_OK)
            say(S, "roughness %.2f", r);
    } else if (S->sel >= 0 && (key == SDLK_MINUS || key == SDLK_EQUALS || key == SDLK_PLUS)) {
        float strength = 0.0f;
        sel_material(S, &strength);
        if (strength <= 0.0f) {
            say(S, "the selection does not emit");
        } else {
            strength *= key == SDLK_MINUS ? 0.5f : 2.0f;
            st = edit(S, lie_edit_op_set_emission(NULL, LIE_EDIT_HAS_STRENGTH, NULL, strength), 0, &err);
            if (st == LIE_OK)
                say(S, "emission strength %g", strength);
        }
    }
    report(S, st, &err);
}

/* ---- scripts ----------------------------------------------------------------- */

/* The node or an ancestor removed: it is not in the scene. */
static int node_removed(const lie_scene *s, int node)
{
    for (int a = node, hops = 0; a >= 0 && a < s->n_nodes && hops <= s->n_nodes; a = s->nodes[a].parent, hops++)
        if (s->nodes[a].removed)
            return 1;
    return 0;
}

/* One case per script command (lie-view --help), each a few lines: one
 * piece, as the commands share the run's waiting state. */
int session_script_step(session *S, script_run *R, uint64_t images, int idle)
{
    if (R->waiting == 1 && images < R->until_images && !idle)
        return 0;
    if (R->waiting == 2 && view_world_busy(S->w) && (R->deadline == 0.0 || lie_time_now() < R->deadline))
        return 0;
    if (R->waiting == 4 && view_world_units_built(S->w) < R->until_units && view_world_busy(S->w))
        return 0;
    R->deadline = 0.0;
    if (R->waiting == 3) {
        uint64_t n = view_render_full_count(S->r);
        if (n < R->until_images) {
            /* one frame at a time: each asked for once the last is done */
            if (R->redraws > 0 && n + (uint64_t)R->redraws >= R->until_images) {
                R->redraws--;
                view_render_again(S->r);
            }
            return 0;
        }
    }
    R->waiting = 0;
    while (R->next < R->sc->n) {
        const view_cmd *c = &R->sc->cmds[R->next++];
        lie_status st = LIE_OK;
        lie_error err;
        lie_error_clear(&err);
        switch (c->kind) {
        case VIEW_CMD_FRAMES:
            R->waiting = 1;
            R->until_images = images + (uint64_t)c->v[0];
            session_camera_update(S);
            view_render_request(S->r, &S->cam, S->mode, S->sel);
            return 0;
        case VIEW_CMD_ORBIT:
            view_orbit_rotate(&S->orbit, (float)c->v[0], (float)c->v[1]);
            session_camera_update(S);
            break;
        case VIEW_CMD_DOLLY:
            view_orbit_dolly(&S->orbit, (float)c->v[0]);
            session_camera_update(S);
            break;
        case VIEW_CMD_SELECT: {
            int node;
            view_world_read_lock(S->w);
            st = lie_edit_find_node(view_world_scene(S->w), c->arg, &node, R->path, c->line, 1, &err);
            if (st == LIE_OK && node_removed(view_world_scene(S->w), node)) /* nothing to act on: refused */
                st = lie_error_set_at(&err, LIE_ERR_ARG, R->path, c->line, 1, "select: node '%s' was removed", c->arg);
            view_world_read_unlock(S->w);
            if (st == LIE_OK)
                session_select(S, node);
            break;
        }
        case VIEW_CMD_PICK:
            view_world_read_lock(S->w);
            S->sel = view_node_under(view_world_scene(S->w), view_world_rt(S->w), &S->cam, S->ro.width,
                                     S->ro.height, (float)c->v[0] + 0.5f, (float)c->v[1] + 0.5f, NULL);
            view_world_read_unlock(S->w);
            session_select(S, S->sel);
            break;
        case VIEW_CMD_DRAG:
        case VIEW_CMD_ROTATE:
        case VIEW_CMD_SET_MATERIAL:
        case VIEW_CMD_SET_EMISSION:
        case VIEW_CMD_REMOVE:
            if (S->sel < 0) {
                st = lie_error_set_at(&err, LIE_ERR_ARG, R->path, c->line, 1, "nothing is selected");
                break;
            }
            if (c->kind == VIEW_CMD_DRAG)
                st = edit_move(S, lie_v3((float)c->v[0], (float)c->v[1], (float)c->v[2]), 0, &err);
            else if (c->kind == VIEW_CMD_REMOVE) {
                st = edit(S, lie_edit_op_remove(NULL), 0, &err);
                if (st == LIE_OK)
                    S->sel = -1;
            } else if (c->kind == VIEW_CMD_ROTATE)
                st = edit(S, lie_edit_op_rotate(NULL, c->v[0], c->v[1], c->v[2], c->v[3]), 0, &err);
            else
                st = edit(S, c->fields->ops[0], 0, &err);
            break;
        case VIEW_CMD_UNDO:
        case VIEW_CMD_REDO: {
            int done;
            st = undo_redo(S, c->kind == VIEW_CMD_REDO, &done, &err);
            break;
        }
        case VIEW_CMD_WAIT:
        case VIEW_CMD_WAIT_AT_MOST: /* until no unit is pending (or S seconds) */
            R->waiting = 2;
            R->deadline = c->kind == VIEW_CMD_WAIT_AT_MOST ? lie_time_now() + c->v[0] : 0.0;
            return 0;
        case VIEW_CMD_WAIT_UNITS: /* until N units have landed (or none is pending) */
            R->waiting = 4;
            R->until_units = (uint64_t)c->v[0];
            return 0;
        case VIEW_CMD_SCREENSHOT:
            session_camera_update(S);
            view_render_request(S->r, &S->cam, S->mode, S->sel);
            st = view_render_screenshot(S->r, c->arg, &err);
            break;
        case VIEW_CMD_QUIT:
            return 1;
        case VIEW_CMD_PAUSE: /* units stop landing until resume (or the end) */
            if (!R->paused)
                view_world_hold(S->w);
            R->paused = 1;
            break;
        case VIEW_CMD_RESUME:
            if (R->paused)
                view_world_release(S->w);
            R->paused = 0;
            break;
        case VIEW_CMD_REDRAW: /* the full frame again, N times, each measured */
            R->waiting = 3;
            R->until_images = view_render_full_count(S->r) + (uint64_t)c->v[0];
            R->redraws = (int)c->v[0] - 1;
            view_render_again(S->r);
            return 0;
        }
        if (st != LIE_OK) {
            /* the script's file and line, whatever the command went through
             * (an edit's own text is the viewer's, not the user's); keep the
             * library's message */
            char msg[sizeof err.msg];
            snprintf(msg, sizeof msg, "%s", err.msg);
            lie_error_set_at(&R->err, st, R->path, c->line, 1, "%s", msg);
            R->failed = 1;
            return 1;
        }
    }
    return 0;
}
