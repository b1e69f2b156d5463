/* lie-view: look at a scene through its LIE cache, move through it and
 * edit it, with soft shadows that are correct in every frame (§3).
 *   lie-view CACHE|SCENE.gltf [options] */
#include "view.h"

#include <SDL.h>
#include <getopt.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

const char *view_prog = "lie-view";
#define prog view_prog

static void usage(FILE *fp)
{
    fprintf(fp,
            "usage: %s CACHE|SCENE.gltf [options]\n"
            "\n"
            "An interactive window on a LIE cache (or a glTF scene, with Embree for every\n"
            "shadow ray).  Frames come coarse first while the view moves and refine to every\n"
            "light sample when it is still.  Edits apply at once: the units the ray segment\n"
            "trees flag are answered by Embree until the constructor thread has rebuilt them.\n"
            "\n"
            "  -s, --size WxH          window and image size (default %dx%d)\n"
            "      --light-samples N   light samples of the refined frame (default %d)\n"
            "      --max-depth D       mirror reflection depth (default %d)\n"
            "      --camera SPEC       start from a scene camera or eye=..,target=..[,up=..][,fov=..]\n"
            "      --threads N         render threads (default: all cores)\n"
            "      --constructor-threads N  threads rebuilding flagged units (default 1)\n"
            "      --script FILE       run commands from FILE (below), then keep the window\n"
            "                          open unless it says quit\n"
            "      --record EDITS.yaml write the session's edits there (formats/edit.md);\n"
            "                          rst-update CACHE EDITS.yaml (named as here) gives\n"
            "                          the bytes --save writes\n"
            "      --save OUT.lie      write the cache at exit (and on Ctrl+S)\n"
            "      --allow-external-uris  let the glTF reference files outside its folder\n"
            "      --stats[=json]      at exit: frames, fps while moving, update times, pending\n"
            "  -q, --quiet             print nothing but errors and what is asked for\n"
            "  -h, --help              this help\n"
            "      --version           print the version\n"
            "\n"
            "Mouse: left drag orbits about the target, a click selects the object under the\n"
            "cursor, left drag on the selection moves it in the plane facing the camera\n"
            "(Shift: along its main axis; Ctrl: rotates it), right or middle drag pans, the\n"
            "wheel dollies.  Keys: W A S D fly, PageUp/PageDown up and down, F frames the\n"
            "selection (or the scene), C cycles the scene's cameras, M cycles the view\n"
            "(shaded, Figure 10 complexity, patches), B cycles the selection's base colour,\n"
            "[ and ] its roughness, - and = an emitter's strength, Delete removes it,\n"
            "Ctrl+Z undo, Ctrl+Y redo, P prints the camera as a lie-render --camera spec,\n"
            "Ctrl+S saves the cache, O toggles the overlay, Q or Escape quits.\n"
            "\n"
            "Script commands: frames N, orbit YAW PITCH, dolly F, select NODE, pick X Y,\n"
            "drag DX DY DZ, rotate AX AY AZ DEG, set-material FIELDS, set-emission FIELDS\n"
            "(FIELDS as in edit files: base-color: [r, g, b], roughness: r, strength: s),\n"
            "remove (the selection), undo, redo, wait (until no unit is pending),\n"
            "screenshot FILE.png, quit.\n",
            prog, 512, 512, LIE_LIGHT_SAMPLES_DEFAULT, LIE_MAX_DEPTH_DEFAULT);
}

#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

enum {
    OPT_LIGHT_SAMPLES = 256, OPT_MAX_DEPTH, OPT_CAMERA, OPT_CTOR_THREADS, OPT_SCRIPT, OPT_RECORD,
    OPT_SAVE
};

static const struct option long_opts[] = {
    {"size", required_argument, NULL, 's'},
    {"light-samples", required_argument, NULL, OPT_LIGHT_SAMPLES},
    {"max-depth", required_argument, NULL, OPT_MAX_DEPTH},
    {"camera", required_argument, NULL, OPT_CAMERA},
    {"constructor-threads", required_argument, NULL, OPT_CTOR_THREADS},
    {"script", required_argument, NULL, OPT_SCRIPT},
    {"record", required_argument, NULL, OPT_RECORD},
    {"save", required_argument, NULL, OPT_SAVE},
    {NULL, 0, NULL, 0},
};

/* ---- the session ------------------------------------------------------- */

typedef struct session {
    view_world *w;
    view_render *r;
    view_render_options ro;
    int quiet, overlay, mode, sel, cam_index;
    view_orbit orbit;
    lie_camera cam;
    char spec[512];
    const char *save;
    /* statistics */
    uint64_t frames, moving_frames;
    double moving_seconds, last_present;
    uint64_t last_images, cam_gen, shown_cam_gen;
    double change_t;        /* the first camera change since the last image */
    double last_change_t;
    int prev_moving;
    double fps_window_start;
    int fps_window_frames;
    float fps;
    uint64_t level_pixels;
    char message[160];
    double message_until;
    /* edit latency: the first image of an edit's world version, the constructor's catch-up */
    double await_t0, last_edit_end;
    uint64_t await_version;
    int catching_up;
    double *first_ms, *catchup_ms, *refine_ms;
    int n_first, n_catchup, n_refine;
    int refining;           /* the camera changed: time until every level is done */
} session;

static void push_ms(double **arr, int *n, double ms)
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

static void say(session *S, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void say(session *S, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(S->message, sizeof S->message, fmt, ap);
    va_end(ap);
    S->message_until = lie_time_now() + 3.0;
    if (!S->quiet)
        fprintf(stderr, "%s: %s\n", prog, S->message);
}

/* The camera is always what its spec parses to (so it prints exactly). */
static void camera_update(session *S)
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

/* A node for an edit file: its name when that names it alone, else '#N'. */
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
        snprintf(buf, size, "'#%d'", node);
}

static lie_status edit(session *S, int join, lie_error *err, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static lie_status edit(session *S, int join, lie_error *err, const char *fmt, ...)
{
    char text[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    double t0 = lie_time_now();
    lie_status st = view_world_edit(S->w, text, join, err);
    if (st == LIE_OK)
        edited(S, t0);
    return st;
}

static lie_status edit_move(session *S, lie_vec3 d, int join, lie_error *err)
{
    char ref[64];
    node_ref(S, S->sel, ref, sizeof ref);
    return edit(S, join, err, "- move: {node: %s, by: [%.9g, %.9g, %.9g]}\n", ref, d.x, d.y, d.z);
}

static lie_status edit_rotate(session *S, lie_vec3 axis, float degrees, int join, lie_error *err)
{
    char ref[64];
    node_ref(S, S->sel, ref, sizeof ref);
    return edit(S, join, err, "- rotate: {node: %s, axis: [%.9g, %.9g, %.9g], degrees: %.9g}\n", ref, axis.x, axis.y,
                axis.z, degrees);
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

static void select_node(session *S, int node)
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

typedef struct drag_state {
    int active, orbiting, dragging, panning, moved, join, axis;
    int x0, y0, lastx, lasty;
    float depth;            /* of the grabbed point along the view */
    lie_vec3 pending;       /* motion not yet applied */
    double last_flush;
    float pending_yaw, pending_pitch;
} drag_state;

static lie_vec3 view_axis(const lie_camera *c, int which)
{
    lie_vec3 f = lie_v3_norm(c->forward);
    lie_vec3 r = lie_v3_norm(lie_v3_cross(f, c->up));
    return which == 0 ? r : lie_v3_cross(r, f);
}

static void flush_drag(session *S, drag_state *d)
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
            st = edit_rotate(S, view_axis(&S->cam, 0), d->pending_pitch, d->join, &err);
            d->join = st == LIE_OK;
        }
        report(S, st, &err);
    }
    d->pending = lie_v3(0.0f, 0.0f, 0.0f);
    d->pending_yaw = d->pending_pitch = 0.0f;
}

static void handle_key(session *S, const SDL_KeyboardEvent *k, int *quit)
{
    SDL_Keycode key = k->keysym.sym;
    int ctrl = (k->keysym.mod & KMOD_CTRL) != 0, shift = (k->keysym.mod & KMOD_SHIFT) != 0;
    float step = 0.05f * S->orbit.dist;
    lie_error err;
    lie_status st = LIE_OK;
    if (key == SDLK_q || key == SDLK_ESCAPE) {
        *quit = 1;
    } else if (ctrl && key == SDLK_z && !shift) {
        int done;
        double t0 = lie_time_now();
        st = view_world_undo(S->w, &done, &err);
        if (st == LIE_OK && done)
            edited(S, t0);
        if (st == LIE_OK)
            say(S, done ? "undone" : "nothing to undo");
    } else if (ctrl && (key == SDLK_y || (key == SDLK_z && shift))) {
        int done;
        double t0 = lie_time_now();
        st = view_world_redo(S->w, &done, &err);
        if (st == LIE_OK && done)
            edited(S, t0);
        if (st == LIE_OK)
            say(S, done ? "redone" : "nothing to redo");
    } else if (ctrl && key == SDLK_s) {
        const char *out = S->save ? S->save : "lie-view.lie";
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
        char ref[64];
        node_ref(S, S->sel, ref, sizeof ref);
        st = edit(S, 0, &err, "- remove: {node: %s}\n", ref);
        if (st == LIE_OK)
            S->sel = -1;
    } else if (S->sel >= 0 && key == SDLK_b) {
        static const float palette[6][3] = {{0.8f, 0.1f, 0.1f}, {0.1f, 0.6f, 0.15f}, {0.15f, 0.25f, 0.8f},
                                            {0.85f, 0.75f, 0.2f}, {0.9f, 0.9f, 0.9f}, {0.1f, 0.1f, 0.1f}};
        static int next;
        const float *c = palette[next++ % 6];
        char ref[64];
        node_ref(S, S->sel, ref, sizeof ref);
        st = edit(S, 0, &err, "- set-material: {node: %s, base-color: [%.9g, %.9g, %.9g]}\n", ref, c[0], c[1], c[2]);
    } else if (S->sel >= 0 && (key == SDLK_LEFTBRACKET || key == SDLK_RIGHTBRACKET)) {
        const lie_material *m = sel_material(S, NULL);
        float r = m ? m->roughness : 1.0f;
        r += key == SDLK_RIGHTBRACKET ? 0.1f : -0.1f;
        r = r < 0.0f ? 0.0f : r > 1.0f ? 1.0f : r;
        char ref[64];
        node_ref(S, S->sel, ref, sizeof ref);
        st = edit(S, 0, &err, "- set-material: {node: %s, roughness: %.9g}\n", ref, r);
        if (st == LIE_OK)
            say(S, "roughness %.2f", r);
    } else if (S->sel >= 0 && (key == SDLK_MINUS || key == SDLK_EQUALS || key == SDLK_PLUS)) {
        float strength = 0.0f;
        sel_material(S, &strength);
        if (strength <= 0.0f) {
            say(S, "the selection does not emit");
        } else {
            strength *= key == SDLK_MINUS ? 0.5f : 2.0f;
            char ref[64];
            node_ref(S, S->sel, ref, sizeof ref);
            st = edit(S, 0, &err, "- set-emission: {node: %s, strength: %.9g}\n", ref, strength);
            if (st == LIE_OK)
                say(S, "emission strength %g", strength);
        }
    }
    report(S, st, &err);
}

/* ---- scripts ----------------------------------------------------------------- */

typedef struct script_run {
    view_script *sc;
    const char *path;
    int next;
    int waiting;            /* 0 none, 1 frames, 2 pending */
    uint64_t until_images;
    int failed;
    lie_error err;
} script_run;

/* Run commands until one has to wait; returns 1 when the script says quit. */
static int script_step(session *S, script_run *R, uint64_t images, int idle)
{
    if (R->waiting == 1 && images < R->until_images && !idle)
        return 0;
    if (R->waiting == 2 && view_world_busy(S->w))
        return 0;
    R->waiting = 0;
    while (R->next < R->sc->n) {
        const view_cmd *c = &R->sc->cmds[R->next++];
        lie_status st = LIE_OK;
        lie_error err;
        lie_error_clear(&err);
        char ref[64];
        switch (c->kind) {
        case VIEW_CMD_FRAMES:
            R->waiting = 1;
            R->until_images = images + (uint64_t)c->v[0];
            camera_update(S);
            view_render_request(S->r, &S->cam, S->mode, S->sel);
            return 0;
        case VIEW_CMD_ORBIT:
            view_orbit_rotate(&S->orbit, (float)c->v[0], (float)c->v[1]);
            camera_update(S);
            break;
        case VIEW_CMD_DOLLY:
            view_orbit_dolly(&S->orbit, (float)c->v[0]);
            camera_update(S);
            break;
        case VIEW_CMD_SELECT: {
            int node;
            view_world_read_lock(S->w);
            st = lie_edit_find_node(view_world_scene(S->w), c->arg, &node, R->path, c->line, 1, &err);
            view_world_read_unlock(S->w);
            if (st == LIE_OK)
                select_node(S, node);
            break;
        }
        case VIEW_CMD_PICK:
            view_world_read_lock(S->w);
            S->sel = view_node_under(view_world_scene(S->w), view_world_rt(S->w), &S->cam, S->ro.width,
                                     S->ro.height, (float)c->v[0] + 0.5f, (float)c->v[1] + 0.5f, NULL);
            view_world_read_unlock(S->w);
            select_node(S, S->sel);
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
            node_ref(S, S->sel, ref, sizeof ref);
            if (c->kind == VIEW_CMD_DRAG)
                st = edit_move(S, lie_v3((float)c->v[0], (float)c->v[1], (float)c->v[2]), 0, &err);
            else if (c->kind == VIEW_CMD_REMOVE) {
                st = edit(S, 0, &err, "- remove: {node: %s}\n", ref);
                if (st == LIE_OK)
                    S->sel = -1;
            } else if (c->kind == VIEW_CMD_ROTATE)
                st = edit(S, 0, &err, "- rotate: {node: %s, axis: [%.17g, %.17g, %.17g], degrees: %.17g}\n", ref,
                          c->v[0], c->v[1], c->v[2], c->v[3]);
            else
                st = edit(S, 0, &err, "- %s: {node: %s, %s}\n",
                          c->kind == VIEW_CMD_SET_MATERIAL ? "set-material" : "set-emission", ref, c->arg);
            break;
        case VIEW_CMD_UNDO:
        case VIEW_CMD_REDO: {
            int done;
            double t0 = lie_time_now();
            st = c->kind == VIEW_CMD_UNDO ? view_world_undo(S->w, &done, &err) : view_world_redo(S->w, &done, &err);
            if (st == LIE_OK && done)
                edited(S, t0);
            break;
        }
        case VIEW_CMD_WAIT:
            R->waiting = 2;
            return 0;
        case VIEW_CMD_SCREENSHOT:
            camera_update(S);
            view_render_request(S->r, &S->cam, S->mode, S->sel);
            st = view_render_screenshot(S->r, c->arg, &err);
            break;
        case VIEW_CMD_QUIT:
            return 1;
        }
        if (st != LIE_OK) {
            R->err = err;
            if (!R->err.line) {
                /* name the script line; keep the library's message */
                char msg[sizeof err.msg];
                snprintf(msg, sizeof msg, "%s", err.msg);
                lie_error_set_at(&R->err, st, R->path, c->line, 1, "%s", msg);
            }
            R->failed = 1;
            return 1;
        }
    }
    return 0;
}

/* ---- statistics and overlay ---------------------------------------------------- */

static void print_stats(session *S, int json)
{
    int n;
    const double *ms = view_world_update_ms(S->w, &n);
    double fps = S->moving_seconds > 0.0 ? (double)S->moving_frames / S->moving_seconds : 0.0;
    if (json) {
        fprintf(stderr, "{\"tool\":\"lie-view\",\"frames\":%llu,\"moving_frames\":%llu,\"fps_mean\":%.3f,\"update_ms\":[",
                (unsigned long long)S->frames, (unsigned long long)S->moving_frames, fps);
        for (int i = 0; i < n; i++)
            fprintf(stderr, "%s%.3f", i ? "," : "", ms[i]);
        fprintf(stderr, "],\"first_frame_ms\":[");
        for (int i = 0; i < S->n_first; i++)
            fprintf(stderr, "%s%.3f", i ? "," : "", S->first_ms[i]);
        fprintf(stderr, "],\"catchup_ms\":[");
        for (int i = 0; i < S->n_catchup; i++)
            fprintf(stderr, "%s%.3f", i ? "," : "", S->catchup_ms[i]);
        fprintf(stderr, "],\"refine_ms\":[");
        for (int i = 0; i < S->n_refine; i++)
            fprintf(stderr, "%s%.3f", i ? "," : "", S->refine_ms[i]);
        fprintf(stderr, "],\"pending_max\":%lld,\"camera\":", (long long)view_world_pending_max(S->w));
        lie_json_string(stderr, S->spec);
        fprintf(stderr, "}\n");
    } else {
        double sum = 0.0, mx = 0.0;
        for (int i = 0; i < n; i++) {
            sum += ms[i];
            mx = ms[i] > mx ? ms[i] : mx;
        }
        fprintf(stderr,
                "%s: %llu frames, %.1f fps while the view moved (%llu frames)\n"
                "  %d edits, update %.1f ms mean, %.1f ms max; at most %lld units pending\n"
                "  camera %s\n",
                prog, (unsigned long long)S->frames, fps, (unsigned long long)S->moving_frames, n,
                n ? sum / n : 0.0, mx, (long long)view_world_pending_max(S->w), S->spec);
    }
}

static void draw_overlay(session *S, uint32_t *argb)
{
    char line[512], name[128];
    view_world_read_lock(S->w);
    view_node_name(view_world_scene(S->w), S->sel, name, sizeof name);
    view_world_read_unlock(S->w);
    int scale = S->ro.width >= 400 ? 2 : 1;
    snprintf(line, sizeof line, "%.1f fps  %llu px/frame\npending %lld  update %.1f ms\nsel %s%s", S->fps,
             (unsigned long long)S->level_pixels, (long long)view_world_pending(S->w), view_world_last_update_ms(S->w),
             name, S->mode == 1 ? "  [complexity]" : S->mode == 2 ? "  [patches]" : "");
    view_text(argb, S->ro.width, S->ro.height, 4, 4, scale, 0xffffffffu, line);
    if (lie_time_now() < S->message_until)
        view_text(argb, S->ro.width, S->ro.height, 4, S->ro.height - 12 * scale, scale, 0xffffe080u, S->message);
}

static int fail_line(const lie_error *err) { return lie_report_error(prog, err, 1); }

int main(int argc, char **argv)
{
    session S;
    memset(&S, 0, sizeof S);
    S.ro.width = 512;
    S.ro.height = 512;
    S.ro.light_samples = LIE_LIGHT_SAMPLES_DEFAULT;
    S.ro.max_depth = LIE_MAX_DEPTH_DEFAULT;
    S.overlay = 1;
    S.sel = -1;
    view_world_options wo;
    memset(&wo, 0, sizeof wo);
    wo.so = lie_scene_options_default();
    wo.threads = 1;
    const char *camera = NULL, *script_path = NULL;
    long v;
    int c;
    lie_cli cli = {.tool = prog, .usage = usage, .missing = "missing input cache or scene",
                   .takes = LIE_CLI_THREADS | LIE_CLI_EXTERNAL | LIE_CLI_STATS};
    while ((c = lie_cli_next(&cli, argc, argv, "s:", long_opts)) > 0) {
        switch (c) {
        case 's':
            if (!lie_parse_size(optarg, 16384, &S.ro.width, &S.ro.height))
                return usage_error("--size: expected WxH, got '%s'", optarg);
            break;
        case OPT_LIGHT_SAMPLES:
            if (!lie_parse_long(optarg, 0, 1000000, &v))
                return usage_error("--light-samples: expected an integer in 0..1000000, got '%s'", optarg);
            S.ro.light_samples = (int)v;
            break;
        case OPT_MAX_DEPTH:
            if (!lie_parse_long(optarg, 0, 64, &v))
                return usage_error("--max-depth: expected an integer in 0..64, got '%s'", optarg);
            S.ro.max_depth = (int)v;
            break;
        case OPT_CTOR_THREADS:
            if (!lie_parse_long(optarg, 1, 4096, &v))
                return usage_error("--constructor-threads: expected an integer in 1..4096, got '%s'", optarg);
            wo.threads = (int)v;
            break;
        case OPT_CAMERA: camera = optarg; break;
        case OPT_SCRIPT: script_path = optarg; break;
        case OPT_RECORD: wo.record = optarg; break;
        case OPT_SAVE: S.save = optarg; break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli.status;
    wo.so.allow_external_uris = cli.external;
    S.ro.threads = cli.threads;
    S.quiet = cli.quiet;
    const char *input = cli.operand;
    lie_error err;
    lie_error_clear(&err);
    script_run R;
    memset(&R, 0, sizeof R);
    R.path = script_path;
    if (script_path && view_script_read(script_path, &R.sc, &err) != LIE_OK)
        return fail_line(&err);
    /* The display first: without one there is nothing to do.  SDL would
     * fall back to an invisible offscreen driver (and let libwayland print
     * about a missing runtime dir): ask only for the display there is,
     * unless SDL_VIDEODRIVER names one. */
    const char *drv = getenv("SDL_VIDEODRIVER");
    if (!drv || !*drv) {
        const char *x11 = getenv("DISPLAY"), *wl = getenv("WAYLAND_DISPLAY");
        if (!(x11 && *x11) && !(wl && *wl)) {
            fprintf(stderr, "%s: cannot open a window: no display (DISPLAY and WAYLAND_DISPLAY are not set)\n", prog);
            view_script_destroy(R.sc);
            return 1;
        }
        SDL_SetHint(SDL_HINT_VIDEODRIVER, x11 && *x11 ? "x11" : "wayland");
    }
    if (SDL_Init(SDL_INIT_VIDEO) != 0) {
        fprintf(stderr, "%s: cannot open a window: no display (%s)\n", prog, SDL_GetError());
        view_script_destroy(R.sc);
        return 1;
    }
    if (view_world_open(input, &wo, &S.w, &err) != LIE_OK) {
        SDL_Quit();
        view_script_destroy(R.sc);
        return fail_line(&err);
    }
    const lie_scene *scene = view_world_scene(S.w);
    if (!S.quiet)
        lie_print_scene_warnings(prog, scene, input);
    lie_camera start;
    if (lie_camera_parse(scene, camera, &start, &err) != LIE_OK) {
        if (!err.file[0])
            snprintf(err.file, sizeof err.file, "%s", input);
        view_world_close(S.w);
        SDL_Quit();
        view_script_destroy(R.sc);
        return fail_line(&err);
    }
    view_orbit_from_camera(&S.orbit, &start, scene);
    camera_update(&S);
    S.shown_cam_gen = S.cam_gen; /* the first view is not a motion */
    S.refining = 0;
    int rc = 0;
    char title[256];
    snprintf(title, sizeof title, "lie-view: %s", input);
    SDL_Window *win = SDL_CreateWindow(title, SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED, S.ro.width,
                                       S.ro.height, SDL_WINDOW_SHOWN);
    /* no GPU needed: SDL's software renderer and a streaming texture */
    SDL_Renderer *ren = win ? SDL_CreateRenderer(win, -1, SDL_RENDERER_SOFTWARE) : NULL;
    SDL_Texture *tex = ren ? SDL_CreateTexture(ren, SDL_PIXELFORMAT_ARGB8888, SDL_TEXTUREACCESS_STREAMING,
                                               S.ro.width, S.ro.height)
                           : NULL;
    uint32_t *image = calloc((size_t)S.ro.width * (size_t)S.ro.height, sizeof *image);
    uint32_t *shown = calloc((size_t)S.ro.width * (size_t)S.ro.height, sizeof *shown);
    if (!tex || !image || !shown) {
        fprintf(stderr, "%s: cannot open a window: %s\n", prog, !tex ? SDL_GetError() : "out of memory");
        rc = 1;
    }
    if (rc == 0 && view_render_start(S.w, &S.ro, &S.r, &err) != LIE_OK)
        rc = fail_line(&err);
    drag_state D;
    memset(&D, 0, sizeof D);
    int quit = rc != 0;
    S.fps_window_start = lie_time_now();
    while (!quit) {
        SDL_Event ev;
        double loop_start = lie_time_now();
        while (SDL_PollEvent(&ev)) {
            if (ev.type == SDL_QUIT) {
                quit = 1;
            } else if (ev.type == SDL_KEYDOWN) {
                handle_key(&S, &ev.key, &quit);
            } else if (ev.type == SDL_MOUSEBUTTONDOWN) {
                memset(&D, 0, sizeof D);
                D.active = ev.button.button;
                D.axis = -1;
                D.x0 = D.lastx = ev.button.x;
                D.y0 = D.lasty = ev.button.y;
                if (ev.button.button == SDL_BUTTON_LEFT) {
                    lie_vec3 p;
                    view_world_read_lock(S.w);
                    int node = view_node_under(view_world_scene(S.w), view_world_rt(S.w), &S.cam, S.ro.width,
                                               S.ro.height, (float)ev.button.x + 0.5f, (float)ev.button.y + 0.5f, &p);
                    view_world_read_unlock(S.w);
                    if (node >= 0 && node == S.sel) {
                        D.dragging = 1;
                        D.depth = lie_v3_dot(lie_v3_sub(p, S.cam.eye), lie_v3_norm(S.cam.forward));
                    } else {
                        D.orbiting = 1;
                    }
                } else {
                    D.panning = 1;
                }
            } else if (ev.type == SDL_MOUSEMOTION && D.active) {
                int dx = ev.motion.x - D.lastx, dy = ev.motion.y - D.lasty;
                D.lastx = ev.motion.x;
                D.lasty = ev.motion.y;
                if (abs(ev.motion.x - D.x0) + abs(ev.motion.y - D.y0) > 3)
                    D.moved = 1;
                if (!D.moved)
                    continue;
                SDL_Keymod mod = SDL_GetModState();
                if (D.orbiting) {
                    view_orbit_rotate(&S.orbit, -0.4f * (float)dx, 0.4f * (float)dy);
                } else if (D.panning) {
                    view_orbit_pan(&S.orbit, (float)dx / (float)S.ro.height, (float)dy / (float)S.ro.height);
                } else if (D.dragging && (mod & KMOD_CTRL)) {
                    D.pending_yaw += 0.5f * (float)dx;
                    D.pending_pitch += 0.5f * (float)dy;
                } else if (D.dragging) {
                    /* the camera-facing plane through the grabbed point */
                    float h = 2.0f * D.depth * tanf(0.5f * S.cam.yfov);
                    float k = h / (float)S.ro.height;
                    lie_vec3 d = lie_v3_add(lie_v3_scale(view_axis(&S.cam, 0), (float)dx * k),
                                            lie_v3_scale(view_axis(&S.cam, 1), -(float)dy * k));
                    if ((mod & KMOD_SHIFT) && D.axis < 0) {
                        float a[3] = {fabsf(d.x), fabsf(d.y), fabsf(d.z)};
                        D.axis = a[0] >= a[1] && a[0] >= a[2] ? 0 : a[1] >= a[2] ? 1 : 2;
                    }
                    D.pending = lie_v3_add(D.pending, d);
                }
            } else if (ev.type == SDL_MOUSEBUTTONUP && D.active) {
                if (D.dragging)
                    flush_drag(&S, &D);
                else if (D.orbiting && !D.moved) {
                    view_world_read_lock(S.w);
                    int node = view_node_under(view_world_scene(S.w), view_world_rt(S.w), &S.cam, S.ro.width,
                                               S.ro.height, (float)ev.button.x + 0.5f, (float)ev.button.y + 0.5f,
                                               NULL);
                    view_world_read_unlock(S.w);
                    select_node(&S, node);
                }
                memset(&D, 0, sizeof D);
            } else if (ev.type == SDL_MOUSEWHEEL) {
                view_orbit_dolly(&S.orbit, 0.1f * (float)ev.wheel.y);
            }
        }
        /* while dragging, an edit every 40 ms at most: each is a phase 1 of
         * the update over every edit since its last commit */
        if (D.dragging && lie_time_now() - D.last_flush >= 0.04) {
            flush_drag(&S, &D);
            D.last_flush = lie_time_now();
        }
        if (R.sc && !quit) {
            uint64_t images, px, iv;
            int idle;
            view_render_fetch(S.r, NULL, &images, &px, &idle, &iv);
            if (script_step(&S, &R, images, idle))
                quit = 1;
        }
        camera_update(&S);
        view_render_request(S.r, &S.cam, S.mode, S.sel);
        uint64_t images, image_version;
        int idle;
        int fresh = view_render_fetch(S.r, image, &images, &S.level_pixels, &idle, &image_version);
        if (S.await_version && image_version >= S.await_version) {
            push_ms(&S.first_ms, &S.n_first, 1e3 * (lie_time_now() - S.await_t0));
            S.await_version = 0;
        }
        if (S.refining && idle) {
            /* the full --light-samples image of the view since it stopped */
            push_ms(&S.refine_ms, &S.n_refine, 1e3 * (lie_time_now() - S.last_change_t));
            S.refining = 0;
        }
        if (S.catching_up && !view_world_busy(S.w)) {
            push_ms(&S.catchup_ms, &S.n_catchup, 1e3 * (lie_time_now() - S.last_edit_end));
            S.catching_up = 0;
        }
        (void)fresh;
        if (images > S.last_images) {
            /* a whole image (a level) is on screen: a frame; while the
             * camera moves, fps counts the time from the previous moving
             * frame, or from the change that started the motion */
            double now = lie_time_now();
            S.frames += images - S.last_images;
            S.fps_window_frames += (int)(images - S.last_images);
            S.last_images = images;
            int moving = S.shown_cam_gen != S.cam_gen;
            if (moving) {
                S.moving_frames++;
                S.moving_seconds += now - (S.prev_moving ? S.last_present : S.change_t);
            }
            S.prev_moving = moving;
            S.shown_cam_gen = S.cam_gen;
            S.last_present = now;
        }
        double now = lie_time_now();
        if (now - S.fps_window_start >= 0.5) {
            S.fps = (float)S.fps_window_frames / (float)(now - S.fps_window_start);
            S.fps_window_frames = 0;
            S.fps_window_start = now;
        }
        memcpy(shown, image, sizeof *shown * (size_t)S.ro.width * (size_t)S.ro.height);
        if (S.overlay)
            draw_overlay(&S, shown);
        SDL_UpdateTexture(tex, NULL, shown, S.ro.width * (int)sizeof *shown);
        SDL_RenderCopy(ren, tex, NULL, NULL);
        SDL_RenderPresent(ren);
        /* about 120 loops a second: input stays quick, the renderer keeps the cores */
        double spent = lie_time_now() - loop_start;
        if (spent < 0.008)
            SDL_Delay((Uint32)((0.008 - spent) * 1000.0) + 1);
    }
    if (R.failed)
        rc = fail_line(&R.err);
    view_render_stop(S.r);
    if (rc == 0 && view_world_write_record(S.w, &err) != LIE_OK)
        rc = fail_line(&err);
    if (rc == 0 && S.save && view_world_save(S.w, S.save, &err) != LIE_OK)
        rc = fail_line(&err);
    if (rc == 0 && cli.stats)
        print_stats(&S, cli.stats == 2);
    free(image);
    free(shown);
    free(S.first_ms);
    free(S.catchup_ms);
    free(S.refine_ms);
    if (tex)
        SDL_DestroyTexture(tex);
    if (ren)
        SDL_DestroyRenderer(ren);
    if (win)
        SDL_DestroyWindow(win);
    view_world_close(S.w);
    view_script_destroy(R.sc);
    SDL_Quit();
    return rc;
}
