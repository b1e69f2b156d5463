/* SPDX-License-Identifier: Apache-2.0 */
/* lie-view: look at a scene through its LIE cache, move through it and
 * edit it, with soft shadows that are correct in every frame (§3).
 *   lie-view CACHE|SCENE.gltf [options]
 * Size: long for a tool's main: options, the window loop and its event
 * dispatch, and the statistics, which share the session. */
#include "session.h"

#include <SDL.h>
#include <getopt.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

const char *view_prog = "lie-view";
#define prog view_prog

static void usage(FILE *fp)
{
    fprintf(fp,
            "Usage: %s CACHE|SCENE.gltf [options]\n"
            "\n"
            "An interactive window on a LIE cache or a glTF scene.  Frames come coarse first\n"
            "while the view moves and refine to every light sample when it is still.  On a\n"
            "scene (or a partial cache) the first frame comes at once, every shadow ray\n"
            "answered by Embree, while constructor threads build the units of what the view\n"
            "sees most first, as lie-build --view would for the views looked from (§4.3.1);\n"
            "frames use each unit as it lands.  Edits apply at once: the units they may\n"
            "change are answered by Embree until the constructor has rebuilt them.\n"
            "\n"
            "  -s, --size WxH          window and image size (default %dx%d)\n"
            "      --exposure EV|auto  exposure in stops, as lie-render --exposure (default 0;\n"
            "                          E and Shift+E step it by a stop); auto: each image's\n"
            "                          own, the stops that take its log-average luminance to\n"
            "                          0.18 (Reinhard et al. 2002), for scenes in physical\n"
            "                          units; screenshots then say it as lie-render's PNGs do\n"
            "      --view-size WxH     the image the constructor samples views at, as\n"
            "                          lie-build --view-size (default 512x512)\n"
            "      --light-samples N   light samples per shading point of the refined frame,\n"
            "                          shared among the emitters (default %d)\n"
            "      --max-depth D       mirror reflection depth (default %d)\n"
            "      --camera SPEC       start from a scene camera or eye=..,target=..[,up=..][,fov=..]\n"
            "      --threads N         render threads (default: all cores)\n"
            "      --constructor-threads N  threads building units (default: all cores)\n"
            "      --script FILE       run commands from FILE (below), then keep the window\n"
            "                          open unless it says quit\n"
            "      --record EDITS.yaml write the session's edits there (formats/edit.md);\n"
            "                          rst-update CACHE EDITS.yaml (named as here) gives\n"
            "                          the bytes --save writes\n"
            "      --save OUT.lie      write the cache at exit (and on Ctrl+S): what has landed,\n"
            "                          a partial cache while units are pending (lie-build\n"
            "                          --resume or --into goes on from it); never waits\n"
            "                          for the constructor.  SIGINT and SIGTERM quit as Q\n"
            "      --allow-external-uris  let the glTF reference files outside its folder\n"
            "      --stats[=json]      at exit: frames, fps while moving, update times, pending\n"
            "      --stats-file FILE   the --stats=json record to FILE, not stderr\n"
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
            "E and Shift+E exposure, Ctrl+Z undo, Ctrl+Y redo, P prints the camera as a lie-render --camera spec,\n"
            "Ctrl+S saves the cache, O toggles the overlay, Q or Escape quits.\n"
            "\n"
            "Script commands: frames N, orbit YAW PITCH, dolly F, select NODE (a name, or\n"
            "'#N' quoted: an unquoted # starts a comment), pick X Y,\n"
            "drag DX DY DZ, rotate AX AY AZ DEG, set-material FIELDS, set-emission FIELDS\n"
            "(FIELDS as in edit files: base-color: [r, g, b], roughness: r, strength: s),\n"
            "remove (the selection), undo, redo, wait (until no unit is pending),\n"
            "wait-at-most S (as wait, S seconds at most), wait-units N (until N units have\n"
            "landed, or none is pending), pause and resume (units stop\n"
            "landing in between), redraw N (the full frame N times more, each timed),\n"
            "screenshot FILE.png (of what has landed), quit.\n",
            prog, 512, 512, LIE_LIGHT_SAMPLES_DEFAULT, LIE_MAX_DEPTH_DEFAULT);
}

#define usage_error(...) lie_usage_error(prog, __VA_ARGS__)

enum {
    OPT_LIGHT_SAMPLES = 256, OPT_MAX_DEPTH, OPT_CAMERA, OPT_CTOR_THREADS, OPT_SCRIPT, OPT_RECORD,
    OPT_SAVE, OPT_EXPOSURE, OPT_VIEW_SIZE
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
    {"exposure", required_argument, NULL, OPT_EXPOSURE},
    {"view-size", required_argument, NULL, OPT_VIEW_SIZE},
    {NULL, 0, NULL, 0},
};

/* ---- statistics and overlay ---------------------------------------------------- */

/* What the renderer's images say: images per second over the time spent
 * rendering them (every level: the renderer's rate), the full frames
 * before and after the constructor caught up with the view (none pending
 * at the frame's end, no unit landing during it). */
typedef struct frame_summary {
    double fps, first_full_ms, before_ms, after_ms;
    int n_before, n_after;
} frame_summary;

static void summarise(const view_frame_time *t, size_t n, frame_summary *f)
{
    memset(f, 0, sizeof *f);
    double busy = 0.0;
    for (size_t i = 0; i < n; i++) {
        busy += t[i].ms;
        if (t[i].level != 2)
            continue;
        if (f->first_full_ms == 0.0)
            f->first_full_ms = t[i].ms;
        if (t[i].pending == 0 && t[i].clean) {
            f->after_ms += t[i].ms;
            f->n_after++;
        } else {
            f->before_ms += t[i].ms;
            f->n_before++;
        }
    }
    f->fps = busy > 0.0 ? 1e3 * (double)n / busy : 0.0;
    f->before_ms = f->n_before ? f->before_ms / f->n_before : 0.0;
    f->after_ms = f->n_after ? f->after_ms / f->n_after : 0.0;
}

static void print_ctor_json(FILE *fp, session *S)
{
    lie_ctor *c = view_world_ctor(S->w);
    if (!c)
        return;
    lie_ctor_stats cs;
    lie_ctor_get_stats(c, &cs);
    fprintf(fp,
            ",\"units\":%llu,\"units_pending\":%llu,\"units_built\":%llu,\"nodes_built\":%llu,\"views\":%d,"
            "\"units_over_time\":[",
            (unsigned long long)cs.units, (unsigned long long)cs.units_pending, (unsigned long long)cs.units_built,
            (unsigned long long)cs.nodes_built, cs.views);
    for (size_t i = 0; i < cs.n_samples; i++)
        fprintf(fp, "%s[%.3f,%llu]", i ? "," : "", cs.samples[i].seconds, (unsigned long long)cs.samples[i].units);
    fprintf(fp, "]");
}

static lie_status print_stats(session *S, const view_frame_time *times, size_t n_times, const lie_cli *cli,
                              lie_error *err)
{
    int n;
    const double *ms = view_world_update_ms(S->w, &n);
    frame_summary fs;
    summarise(times, n_times, &fs);
    /* fps_mean: real frames, as the window showed them while the view moved:
     * each loop that put a new image on screen, over the wall time from
     * the change that started the motion (the renderer's own rate over its
     * busy time is render_fps: coarse levels of a still view counted there
     * made thousands of "frames" a second) */
    double fps = S->moving_seconds > 0.0 ? (double)S->moving_frames / S->moving_seconds : 0.0;
    if (cli->stats == 2) {
        lie_stats_json js;
        FILE *fp = lie_stats_json_begin(&js, prog, NULL);
        if (!fp)
            return lie_stats_json_end(cli, &js, err);
        fprintf(fp, ",\"frames\":%llu,\"moving_frames\":%llu,\"moving_seconds\":%.6f,\"fps_mean\":%.3f,"
                    "\"render_fps\":%.3f,",
                (unsigned long long)S->frames, (unsigned long long)S->moving_frames, S->moving_seconds, fps, fs.fps);
        fprintf(fp, "\"first_frame_ms\":%.3f,\"full_frame_first_ms\":%.3f,\"full_frames_before\":%d,"
                        "\"full_frame_before_ms\":%.3f,\"full_frames_after\":%d,\"full_frame_after_ms\":%.3f,"
                        "\"full_frames\":[",
                S->first_image_ms, fs.first_full_ms, fs.n_before, fs.before_ms, fs.n_after, fs.after_ms);
        int k = 0;
        for (size_t i = 0; i < n_times; i++)
            if (times[i].level == 2)
                fprintf(fp, "%s[%.3f,%.3f,%lld]", k++ ? "," : "", times[i].end - S->start_t, times[i].ms,
                        (long long)times[i].pending);
        fprintf(fp, "]");
        print_ctor_json(fp, S);
        fprintf(fp, ",\"update_ms\":[");
        for (int i = 0; i < n; i++)
            fprintf(fp, "%s%.3f", i ? "," : "", ms[i]);
        fprintf(fp, "],\"edit_first_frame_ms\":[");
        for (int i = 0; i < S->n_first; i++)
            fprintf(fp, "%s%.3f", i ? "," : "", S->first_ms[i]);
        fprintf(fp, "],\"catchup_ms\":[");
        for (int i = 0; i < S->n_catchup; i++)
            fprintf(fp, "%s%.3f", i ? "," : "", S->catchup_ms[i]);
        fprintf(fp, "],\"refine_ms\":[");
        for (int i = 0; i < S->n_refine; i++)
            fprintf(fp, "%s%.3f", i ? "," : "", S->refine_ms[i]);
        fprintf(fp, "],\"pending_max\":%lld,\"exposure\":%.6f,\"exposure_mode\":\"%s\",\"camera\":",
                (long long)view_world_pending_max(S->w), (double)S->exposure_shown, S->ro.exposure_auto ? "auto" : "fixed");
        lie_json_string(fp, S->spec);
        fprintf(fp, "}\n");
        return lie_stats_json_end(cli, &js, err);
    } else {
        double sum = 0.0, mx = 0.0;
        for (int i = 0; i < n; i++) {
            sum += ms[i];
            mx = ms[i] > mx ? ms[i] : mx;
        }
        fprintf(stderr, "%s: first image %.0f ms; full frames %.1f ms first, %.1f ms before the constructor caught "
                        "up (%d), %.1f ms after (%d)\n",
                prog, S->first_image_ms, fs.first_full_ms, fs.before_ms, fs.n_before, fs.after_ms, fs.n_after);
        fprintf(stderr,
                "%s: %llu frames, %.1f fps while the view moved (%llu frames), %.1f images a second rendering\n"
                "  %d edits, update %.1f ms mean, %.1f ms max; at most %lld units pending\n"
                "  camera %s\n",
                prog, (unsigned long long)S->frames, fps, (unsigned long long)S->moving_frames, fs.fps, n,
                n ? sum / n : 0.0, mx, (long long)view_world_pending_max(S->w), S->spec);
    }
    return LIE_OK;
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

/* The options into the session and the world's options: -1 to go on, or
 * the exit status. */
static int parse_options(session *S, view_world_options *wo, lie_cli *cli, const char **camera,
                         const char **script_path, int argc, char **argv)
{
    long v;
    int c;
    while ((c = lie_cli_next(cli, argc, argv, "s:", long_opts)) > 0) {
        switch (c) {
        case 's':
            if (!lie_parse_size(optarg, 16384, &S->ro.width, &S->ro.height))
                return usage_error("--size: expected WxH, got '%s'", optarg);
            break;
        case OPT_LIGHT_SAMPLES:
            if (!lie_cli_long(cli, 0, 1000000, &v))
                return cli->status;
            S->ro.light_samples = (int)v;
            break;
        case OPT_MAX_DEPTH:
            if (!lie_cli_long(cli, 0, 64, &v))
                return cli->status;
            S->ro.max_depth = (int)v;
            break;
        case OPT_CTOR_THREADS:
            if (!lie_cli_long(cli, 1, 4096, &v))
                return cli->status;
            wo->threads = (int)v;
            break;
        case OPT_CAMERA: *camera = optarg; break;
        case OPT_SCRIPT: *script_path = optarg; break;
        case OPT_RECORD: wo->record = optarg; break;
        case OPT_SAVE: S->save = optarg; break;
        case OPT_EXPOSURE:
            S->ro.exposure_auto = strcmp(optarg, "auto") == 0;
            if (!S->ro.exposure_auto && !lie_parse_float(optarg, -64.0f, 64.0f, &S->ro.exposure))
                return usage_error("--exposure: expected a number of stops or auto, got '%s'", optarg);
            break;
        case OPT_VIEW_SIZE:
            if (!lie_parse_size(optarg, 16384, &wo->view_width, &wo->view_height))
                return usage_error("--view-size: expected WxH, got '%s'", optarg);
            break;
        }
    }
    if (c == LIE_CLI_EXIT)
        return cli->status;
    wo->so.allow_external_uris = cli->external;
    wo->so.threads = cli->threads; /* --threads: the textures are decoded on them too */
    S->ro.threads = cli->threads;
    S->quiet = cli->quiet;
    return -1;
}

/* The display first: without one there is nothing to do.  SDL would fall
 * back to an invisible offscreen driver (and let libwayland print about a
 * missing runtime dir): ask only for the display there is, unless
 * SDL_VIDEODRIVER names one.  0, or 1 after the error line. */
static int open_display(void)
{
    const char *drv = getenv("SDL_VIDEODRIVER");
    if (!drv || !*drv) {
        const char *x11 = getenv("DISPLAY"), *wl = getenv("WAYLAND_DISPLAY");
        if (!(x11 && *x11) && !(wl && *wl)) {
            fprintf(stderr, "%s: cannot open a window: no display (DISPLAY and WAYLAND_DISPLAY are not set)\n", prog);
            return 1;
        }
        SDL_SetHint(SDL_HINT_VIDEODRIVER, x11 && *x11 ? "x11" : "wayland");
    }
    if (SDL_Init(SDL_INIT_VIDEO) != 0) {
        fprintf(stderr, "%s: cannot open a window: no display (%s)\n", prog, SDL_GetError());
        return 1;
    }
    return 0;
}

/* The window, and the image rendered and the one shown (with the overlay). */
typedef struct window {
    SDL_Window *win;
    SDL_Renderer *ren;
    SDL_Texture *tex;
    uint32_t *image, *shown;
} window;

/* 0, or 1 after the error line. */
static int window_open(window *W, const char *input, int width, int height)
{
    char title[256];
    snprintf(title, sizeof title, "lie-view: %s", input);
    W->win = SDL_CreateWindow(title, SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED, width, height,
                              SDL_WINDOW_SHOWN);
    /* no GPU needed: SDL's software renderer and a streaming texture */
    W->ren = W->win ? SDL_CreateRenderer(W->win, -1, SDL_RENDERER_SOFTWARE) : NULL;
    W->tex = W->ren ? SDL_CreateTexture(W->ren, SDL_PIXELFORMAT_ARGB8888, SDL_TEXTUREACCESS_STREAMING, width, height)
                    : NULL;
    W->image = calloc((size_t)width * (size_t)height, sizeof *W->image);
    W->shown = calloc((size_t)width * (size_t)height, sizeof *W->shown);
    if (!W->tex || !W->image || !W->shown) {
        fprintf(stderr, "%s: cannot open a window: %s\n", prog, !W->tex ? SDL_GetError() : "out of memory");
        return 1;
    }
    return 0;
}

static void window_close(window *W)
{
    free(W->image);
    free(W->shown);
    if (W->tex)
        SDL_DestroyTexture(W->tex);
    if (W->ren)
        SDL_DestroyRenderer(W->ren);
    if (W->win)
        SDL_DestroyWindow(W->win);
}

/* The node under a pixel (and the point hit, when p is not NULL). */
static int node_at(session *S, int x, int y, lie_vec3 *p)
{
    view_world_read_lock(S->w);
    int node = view_node_under(view_world_scene(S->w), view_world_rt(S->w), &S->cam, S->ro.width, S->ro.height,
                               (float)x + 0.5f, (float)y + 0.5f, p);
    view_world_read_unlock(S->w);
    return node;
}

/* A button pressed: drag the selection, or orbit (left), or pan. */
static void mouse_down(session *S, drag_state *D, const SDL_MouseButtonEvent *b)
{
    memset(D, 0, sizeof *D);
    D->active = b->button;
    D->axis = -1;
    D->x0 = D->lastx = b->x;
    D->y0 = D->lasty = b->y;
    if (b->button != SDL_BUTTON_LEFT) {
        D->panning = 1;
        return;
    }
    lie_vec3 p;
    int node = node_at(S, b->x, b->y, &p);
    if (node >= 0 && node == S->sel) {
        D->dragging = 1;
        D->depth = lie_v3_dot(lie_v3_sub(p, S->cam.eye), lie_v3_norm(S->cam.forward));
    } else {
        D->orbiting = 1;
    }
}

static void mouse_motion(session *S, drag_state *D, const SDL_MouseMotionEvent *m)
{
    int dx = m->x - D->lastx, dy = m->y - D->lasty;
    D->lastx = m->x;
    D->lasty = m->y;
    if (abs(m->x - D->x0) + abs(m->y - D->y0) > 3)
        D->moved = 1;
    if (!D->moved)
        return;
    SDL_Keymod mod = SDL_GetModState();
    if (D->orbiting) {
        view_orbit_rotate(&S->orbit, -0.4f * (float)dx, 0.4f * (float)dy);
    } else if (D->panning) {
        view_orbit_pan(&S->orbit, (float)dx / (float)S->ro.height, (float)dy / (float)S->ro.height);
    } else if (D->dragging && (mod & KMOD_CTRL)) {
        D->pending_yaw += 0.5f * (float)dx;
        D->pending_pitch += 0.5f * (float)dy;
    } else if (D->dragging) {
        /* the camera-facing plane through the grabbed point */
        float h = 2.0f * D->depth * tanf(0.5f * S->cam.yfov);
        float k = h / (float)S->ro.height;
        lie_vec3 d = lie_v3_add(lie_v3_scale(session_view_axis(&S->cam, 0), (float)dx * k),
                                lie_v3_scale(session_view_axis(&S->cam, 1), -(float)dy * k));
        if ((mod & KMOD_SHIFT) && D->axis < 0) {
            float a[3] = {fabsf(d.x), fabsf(d.y), fabsf(d.z)};
            D->axis = a[0] >= a[1] && a[0] >= a[2] ? 0 : a[1] >= a[2] ? 1 : 2;
        }
        D->pending = lie_v3_add(D->pending, d);
    }
}

/* The window's events since the last loop. */
static void handle_events(session *S, drag_state *D, int *quit)
{
    SDL_Event ev;
    while (SDL_PollEvent(&ev)) {
        if (ev.type == SDL_QUIT) {
            *quit = 1;
        } else if (ev.type == SDL_KEYDOWN && ev.key.keysym.sym == SDLK_e) {
            /* exposure, a stop a press (Shift: darker), from the one shown
             * (auto exposure's, which it ends) */
            S->ro.exposure = view_render_exposure(S->r) + ((ev.key.keysym.mod & KMOD_SHIFT) ? -1.0f : 1.0f);
            S->ro.exposure_auto = 0;
            view_render_set_exposure(S->r, S->ro.exposure);
        } else if (ev.type == SDL_KEYDOWN) {
            session_key(S, &ev.key, quit);
        } else if (ev.type == SDL_MOUSEBUTTONDOWN) {
            mouse_down(S, D, &ev.button);
        } else if (ev.type == SDL_MOUSEMOTION && D->active) {
            mouse_motion(S, D, &ev.motion);
        } else if (ev.type == SDL_MOUSEBUTTONUP && D->active) {
            if (D->dragging)
                session_flush_drag(S, D);
            else if (D->orbiting && !D->moved) /* a click selects */
                session_select(S, node_at(S, ev.button.x, ev.button.y, NULL));
            memset(D, 0, sizeof *D);
        } else if (ev.type == SDL_MOUSEWHEEL) {
            view_orbit_dolly(&S->orbit, 0.1f * (float)ev.wheel.y);
        }
    }
}

/* The latencies and frame rates --stats reports, after a fetch that found
 * `images` whole images, the last of world version image_version. */
static void count_frames(session *S, uint64_t images, uint64_t image_version, int idle)
{
    if (S->await_version && image_version >= S->await_version) {
        session_push_ms(&S->first_ms, &S->n_first, 1e3 * (lie_time_now() - S->await_t0));
        S->await_version = 0;
    }
    if (S->refining && idle) {
        /* the full --light-samples image of the view since it stopped */
        session_push_ms(&S->refine_ms, &S->n_refine, 1e3 * (lie_time_now() - S->last_change_t));
        S->refining = 0;
    }
    if (S->catching_up && !view_world_busy(S->w)) {
        session_push_ms(&S->catchup_ms, &S->n_catchup, 1e3 * (lie_time_now() - S->last_edit_end));
        S->catching_up = 0;
    }
    if (images > S->last_images) {
        /* a whole image (a level) is on screen: a frame; while the camera
         * moves, fps counts the time from the previous moving frame, or
         * from the change that started the motion */
        double now = lie_time_now();
        S->frames += images - S->last_images;
        S->fps_window_frames += (int)(images - S->last_images);
        S->last_images = images;
        int moving = S->shown_cam_gen != S->cam_gen;
        if (moving) {
            S->moving_frames++;
            S->moving_seconds += now - (S->prev_moving ? S->last_present : S->change_t);
        }
        S->prev_moving = moving;
        S->shown_cam_gen = S->cam_gen;
        S->last_present = now;
    }
    double now = lie_time_now();
    if (now - S->fps_window_start >= 0.5) {
        S->fps = (float)S->fps_window_frames / (float)(now - S->fps_window_start);
        S->fps_window_frames = 0;
        S->fps_window_start = now;
    }
}

/* The constructor builds for the camera once it has been still a quarter
 * of a second (and for the first, once the first image is on screen): each such camera is a view of
 * the cache it builds (lie-build --view), what it sees first in the queue. */
static void look(session *S)
{
    double now = lie_time_now();
    if (S->first_image_ms < 0.0)
        return; /* the first image first: sampling the view would take the cores from it */
    if (S->looked_set && memcmp(&S->looked, &S->cam, sizeof S->cam) == 0) {
        S->cam_change_t = now;
        return;
    }
    if (S->looked_set && now - S->cam_change_t < 0.25)
        return;
    S->looked = S->cam;
    S->looked_set = 1;
    S->cam_change_t = now;
    view_world_look(S->w, &S->cam);
}

/* One turn of the loop after the events: the drag's edits, the script,
 * the camera, the newest image on screen. */
static void loop_step(session *S, drag_state *D, script_run *R, window *W, int *quit)
{
    /* while dragging, an edit every 40 ms at most: each is a phase 1 of
     * the update over every edit since its last commit */
    if (D->dragging && lie_time_now() - D->last_flush >= 0.04) {
        session_flush_drag(S, D);
        D->last_flush = lie_time_now();
    }
    uint64_t images, image_version, px;
    int idle;
    if (R->sc && !*quit) {
        view_render_fetch(S->r, NULL, &images, &px, &idle, &image_version);
        if (session_script_step(S, R, images, idle))
            *quit = 1;
    }
    session_camera_update(S);
    view_render_request(S->r, &S->cam, S->mode, S->sel);
    view_render_fetch(S->r, W->image, &images, &S->level_pixels, &idle, &image_version);
    count_frames(S, images, image_version, idle);
    memcpy(W->shown, W->image, sizeof *W->shown * (size_t)S->ro.width * (size_t)S->ro.height);
    if (S->overlay)
        draw_overlay(S, W->shown);
    SDL_UpdateTexture(W->tex, NULL, W->shown, S->ro.width * (int)sizeof *W->shown);
    SDL_RenderCopy(W->ren, W->tex, NULL, NULL);
    SDL_RenderPresent(W->ren);
    /* the time to the first frame: from the start of main to the present
     * of the first whole image, of any level (the coarsest, first) */
    if (images > 0 && S->first_image_ms < 0.0)
        S->first_image_ms = 1e3 * (lie_time_now() - S->start_t);
    look(S);
}

/* The world opened, the start camera set: 0, or 1 after the error line. */
static int open_world(session *S, const view_world_options *wo, const char *input, const char *camera)
{
    lie_error err;
    lie_error_clear(&err);
    if (view_world_open(input, wo, &S->w, &err) != LIE_OK)
        return fail_line(&err);
    const lie_scene *scene = view_world_scene(S->w);
    if (!S->quiet)
        lie_print_scene_warnings(prog, scene, input);
    lie_camera start;
    if (lie_camera_parse(scene, camera, &start, &err) != LIE_OK) {
        if (!err.file[0])
            snprintf(err.file, sizeof err.file, "%s", input);
        return fail_line(&err);
    }
    view_orbit_from_camera(&S->orbit, &start, scene);
    session_camera_update(S);
    S->shown_cam_gen = S->cam_gen; /* the first view is not a motion */
    S->refining = 0;
    return 0;
}

/* The outputs (--record, --save, the script's screenshots) before the
 * window opens: none may be an input (the cache, the scene's files, the
 * script), and --record and --save not the same file; --save may replace
 * the cache it started from. */
static int claim_outputs(session *S, const view_world_options *wo, const char *input, const script_run *R)
{
    lie_error err;
    lie_error_clear(&err);
    lie_status st = lie_file_set_note(S->files, input, &err);
    if (st == LIE_OK && R->path)
        st = lie_file_set_note(S->files, R->path, &err);
    if (st == LIE_OK && wo->record)
        st = lie_file_set_claim(S->files, wo->record, NULL, &err);
    if (st == LIE_OK && S->save)
        st = lie_file_set_claim(S->files, S->save, input, &err);
    for (int i = 0; st == LIE_OK && R->sc && i < R->sc->n; i++)
        if (R->sc->cmds[i].kind == VIEW_CMD_SCREENSHOT)
            st = lie_file_set_check(S->files, R->sc->cmds[i].arg, &err);
    return st == LIE_OK ? 0 : fail_line(&err);
}

/* At exit: the script's error, the record, --save, --stats. */
static int finish(session *S, const script_run *R, const lie_cli *cli, int rc)
{
    lie_error err;
    lie_error_clear(&err);
    if (R->failed)
        rc = fail_line(&R->err);
    size_t n_times = 0;
    view_frame_time *times = S->r ? view_render_times(S->r, &n_times) : NULL;
    S->exposure_shown = S->r ? view_render_exposure(S->r) : S->ro.exposure;
    view_render_stop(S->r);
    S->r = NULL;
    if (rc == 0 && view_world_write_record(S->w, &err) != LIE_OK)
        rc = fail_line(&err);
    if (rc == 0 && S->save && view_world_save(S->w, S->save, &err) != LIE_OK)
        rc = fail_line(&err);
    if (rc == 0 && cli->stats && print_stats(S, times, n_times, cli, &err) != LIE_OK)
        rc = fail_line(&err);
    free(times);
    if (R->paused)
        view_world_release(S->w);
    return rc;
}

/* SIGINT and SIGTERM end the session as Q does (the record, --save and
 * --stats are written); a second one ends it at once. */
static volatile sig_atomic_t quit_signal;

static void on_quit_signal(int sig)
{
    if (quit_signal) {
        signal(sig, SIG_DFL);
        raise(sig);
        return;
    }
    quit_signal = sig;
}

static void quit_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sigemptyset(&sa.sa_mask);
    sa.sa_handler = on_quit_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

int main(int argc, char **argv)
{
    session S;
    memset(&S, 0, sizeof S);
    S.ro.width = S.ro.height = 512;
    S.ro.light_samples = LIE_LIGHT_SAMPLES_DEFAULT;
    S.ro.max_depth = LIE_MAX_DEPTH_DEFAULT;
    S.overlay = 1;
    S.sel = -1;
    S.start_t = lie_time_now();
    S.first_image_ms = -1.0;
    view_world_options wo;
    memset(&wo, 0, sizeof wo);
    wo.so = lie_scene_options_default();
    wo.so.files = S.files = lie_file_set_create(LIE_FILES_NAMES);
    wo.threads = 0; /* the constructor's: a thread a core, as rst-update */
    wo.view_width = wo.view_height = 512;
    wo.max_depth = S.ro.max_depth;
    const char *camera = NULL, *script_path = NULL;
    lie_cli cli = {.tool = prog, .usage = usage, .missing = "missing input cache or scene",
                   .takes = LIE_CLI_THREADS | LIE_CLI_EXTERNAL | LIE_CLI_STATS};
    int rc = parse_options(&S, &wo, &cli, &camera, &script_path, argc, argv);
    if (rc >= 0) {
        lie_file_set_destroy(S.files);
        return rc;
    }
    lie_error err;
    script_run R;
    memset(&R, 0, sizeof R);
    R.path = script_path;
    if (script_path && view_script_read(script_path, &R.sc, &err) != LIE_OK) {
        lie_file_set_destroy(S.files);
        return fail_line(&err);
    }
    wo.max_depth = S.ro.max_depth; /* the views' mirrors are the frames' */
    if (open_display() != 0) {
        view_script_destroy(R.sc);
        lie_file_set_destroy(S.files);
        return 1;
    }
    /* after SDL_Init, which installs its own handlers for them */
    quit_handlers();
    window W;
    memset(&W, 0, sizeof W);
    rc = S.files ? open_world(&S, &wo, cli.operand, camera) : 1;
    if (rc == 0)
        rc = claim_outputs(&S, &wo, cli.operand, &R);
    if (rc == 0) {
        rc = window_open(&W, cli.operand, S.ro.width, S.ro.height);
        if (rc == 0 && view_render_start(S.w, &S.ro, &S.r, &err) != LIE_OK)
            rc = fail_line(&err);
        drag_state D;
        memset(&D, 0, sizeof D);
        int quit = rc != 0;
        S.fps_window_start = lie_time_now();
        while (!quit) {
            double loop_start = lie_time_now();
            handle_events(&S, &D, &quit);
            if (quit_signal)
                quit = 1;
            loop_step(&S, &D, &R, &W, &quit);
            /* about 120 loops a second: input stays quick, the renderer keeps the cores */
            double spent = lie_time_now() - loop_start;
            if (spent < 0.008)
                SDL_Delay((Uint32)((0.008 - spent) * 1000.0) + 1);
        }
        rc = finish(&S, &R, &cli, rc);
    }
    free(S.first_ms);
    free(S.catchup_ms);
    free(S.refine_ms);
    window_close(&W);
    view_world_close(S.w);
    view_script_destroy(R.sc);
    lie_file_set_destroy(S.files);
    SDL_Quit();
    return rc;
}
