/* SPDX-License-Identifier: Apache-2.0 */
/* Progressive rendering: a thread renders the current request coarse first
 * (a quarter of the resolution and a tenth of the light samples, then half
 * and a quarter), then the full image with every light sample, each level
 * in bands of rows drawn over the one before, so the window shows whatever
 * is ready and never waits on a whole frame.  A new request (the camera
 * moved, an edit, a constructor step) abandons the level at the next band.
 * Each band is whole rows of tiles rendered by lie_render_tiles on all
 * workers, so the full level is the very image lie-render makes.
 *
 * Units the constructor lands (§4.3.1) do not make a frame stale: a
 * unit not yet landed is answered by Embree, so the image is the same,
 * only slower.  A view that moves uses every unit landed by its next
 * band.  A still view is already at full quality; its full frame is
 * rendered again over the one shown (no coarse levels) once the
 * constructor has caught up with the view (landed_due): the same picture,
 * in the time the cache gives.  Before that a redraw would only take the
 * cores from the constructor: redrawing on every landing kept both cores
 * rendering the same picture while the constructor's threads waited for
 * them, and one redraw when half had landed made a drag's catch-up on
 * scifi_hallway a tenth longer (docs/measurements.md).  A full
 * frame during which no unit landed is *clean*: the frame lie-render
 * makes from a cache of what had landed; screenshots hold the constructor
 * and take one. */
#include "view.h"

#include <stdlib.h>
#include <string.h>

#define LEVELS 3
#define BAND_TILE_ROWS 1 /* 16 pixel rows a band: an edit waits on one band at most */

struct view_render {
    view_world *w;
    view_render_options o;
    lie_lights *lights; /* the render thread's, for the world's scene as it is (lie_lights_fit) */
    lie_lights *quick;  /* the coarse levels' while the first are prepared (lie_lights_create_untextured) */
    /* the scene's first lights, prepared beside the first images (m) */
    pthread_t lights_tid;
    int lights_started, lights_done;
    lie_lights *first_lights;
    pthread_t tid;
    int started;
    pthread_mutex_t m;
    pthread_cond_t cv;        /* a request arrived, or a level finished */
    /* the request (m) */
    lie_camera cam;
    int mode, sel, quit;
    uint64_t gen, version_seen; /* version_seen: the world's, at the last request */
    /* what is shown (m) */
    uint32_t *display;
    int dirty;
    uint64_t images, level_pixels;
    uint64_t full_gen, full_version; /* the request and world version `full` shows, 0: none */
    uint64_t done_gen, done_version; /* every level of these is finished: idle */
    uint64_t image_version;          /* the world version of the last image finished */
    uint64_t force, full_force;      /* full frames asked for again (view_render_again), and shown */
    int full_clean;                  /* no unit landed while `full` was rendered */
    view_frame_time *times;          /* every full frame's time */
    size_t n_times, cap_times;
    lie_frame *full;
    float auto_ev;                   /* --exposure auto: the last finished image's (m) */
    /* the render thread's own: a frame per level and view mode (the modes'
     * AOV layers are what lie_render_tiles fills) */
    lie_frame *level[LEVELS][3];
    uint8_t *sel_mask;
};

static const int level_div[LEVELS] = {4, 2, 1};
static const int level_ls_div[LEVELS] = {10, 4, 1};

static uint32_t pack(const float c[3], int srgb, float scale)
{
    uint32_t p = 0xff000000u;
    for (int k = 0; k < 3; k++) {
        /* the shaded view is exposed as lie-render --exposure exposes a PNG */
        float v = srgb ? lie_image_srgb_encode(c[k] * scale) : (c[k] < 0.0f ? 0.0f : c[k] > 1.0f ? 1.0f : c[k]);
        p |= (uint32_t)(v * 255.0f + 0.5f) << (16 - 8 * k);
    }
    return p;
}

/* Draw rows [y0, y1) of a level into the display, each level pixel a
 * div x div block; selected pixels tinted, their outline orange. */
static void blit(view_render *r, const lie_frame *f, int div, int mode, int y0, int y1)
{
    const float *src = f->rgb;
    int srgb = 1;
    if (mode != VIEW_MODE_SHADE) {
        const lie_aov *a = lie_frame_find_aov(f, mode == VIEW_MODE_COMPLEXITY ? "complexity" : "patch");
        if (a) {
            src = a->data;
            srgb = 0;
        }
    }
    int W = r->o.width, H = r->o.height, lw = f->width;
    const uint8_t *m = r->sel_mask;
    float scale = exp2f(r->o.exposure_auto ? r->auto_ev : r->o.exposure);
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < lw; x++) {
            size_t i = (size_t)y * (size_t)lw + (size_t)x;
            uint32_t p = pack(src + 3 * i, srgb, scale);
            if (m && m[i]) {
                int edge = x == 0 || !m[i - 1] || x + 1 == lw || !m[i + 1] || y == 0 || !m[i - (size_t)lw];
                if (edge)
                    p = 0xffff9020u;
                else
                    p = 0xff000000u | (((p >> 1) & 0x7f7f7f) + 0x402808);
            }
            for (int dy = 0; dy < div && y * div + dy < H; dy++)
                for (int dx = 0; dx < div && x * div + dx < W; dx++)
                    r->display[(size_t)(y * div + dy) * (size_t)W + (size_t)(x * div + dx)] = p;
        }
}

/* The selection mask of rows [y0, y1): pixel centres whose first hit
 * belongs to the selected subtree. */
static void mask_rows(view_render *r, const lie_scene *s, const lie_rt *rt, const lie_camera *cam, int lw, int lh,
                      const uint8_t *in, int y0, int y1)
{
    lie_view v = lie_view_make(cam, lw, lh);
    lie_vec3 org[8], dir[8];
    lie_hit hits[8];
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < lw; x += 8) {
            int n = lw - x < 8 ? lw - x : 8;
            for (int i = 0; i < n; i++)
                lie_view_ray(&v, (float)(x + i) + 0.5f, (float)y + 0.5f, lw, lh, &org[i], &dir[i]);
            lie_rt_intersect8(rt, org, dir, n, 1, hits);
            for (int i = 0; i < n; i++) {
                uint32_t t = hits[i].tri;
                r->sel_mask[(size_t)y * (size_t)lw + (size_t)(x + i)] =
                    t != LIE_NO_HIT && t < s->n_tris && in[s->instances[s->tri_instance[t]].node];
            }
        }
}

/* Whether units landed since the shown full frame (units_seen) make it
 * worth rendering again (see the top of this file). */
static int landed_due(view_render *r, uint64_t units_seen)
{
    return view_world_units_version(r->w) != units_seen && view_world_pending(r->w) == 0;
}

/* A full frame's time, kept for --stats (m held). */
static void note_time(view_render *r, int level, double t0, double t1, int clean)
{
    if (r->n_times == r->cap_times) {
        size_t cap = r->cap_times ? 2 * r->cap_times : 64;
        view_frame_time *t = realloc(r->times, sizeof *t * cap);
        if (!t)
            return;
        r->times = t;
        r->cap_times = cap;
    }
    view_frame_time *t = &r->times[r->n_times++];
    t->end = t1;
    t->ms = 1e3 * (t1 - t0);
    t->clean = clean;
    t->level = level;
    t->pending = view_world_pending(r->w);
}

/* The options lights are prepared with: the full level's, whose frames
 * must be lie-render's. */
static lie_render_options lights_options(const view_render *r)
{
    lie_render_options o = lie_render_options_default();
    o.light_samples = r->o.light_samples;
    o.max_depth = r->o.max_depth;
    o.threads = r->o.threads;
    return o;
}

/* The first lights, beside the first images: the textured emitters'
 * distributions read every texel of their textures (bedroom_corner's
 * lamp: 0.1 to 0.2 s), which the first coarse images need not wait for. */
static void *lights_main(void *arg)
{
    view_render *r = arg;
    lie_render_options o = lights_options(r);
    lie_lights *l = NULL;
    lie_error err;
    view_world_read_lock(r->w);
    if (lie_lights_create(view_world_scene(r->w), &o, &l, &err) != LIE_OK)
        l = NULL; /* the render thread prepares its own */
    view_world_read_unlock(r->w);
    pthread_mutex_lock(&r->m);
    r->first_lights = l;
    r->lights_done = 1;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->m);
    return NULL;
}

/* Before the full level (no lock held): the first lights done.  A band
 * must not wait for them: it holds the world's read lock, which an edit
 * waiting to write would keep the lights thread from taking. */
static void wait_first_lights(view_render *r)
{
    pthread_mutex_lock(&r->m);
    while (r->lights_started && !r->lights_done)
        pthread_cond_wait(&r->cv, &r->m);
    pthread_mutex_unlock(&r->m);
}

/* The lights a band of level lv uses (the world's read lock held): the
 * scene's as it is, prepared with the full level's options; while the
 * first are still being prepared, the coarse levels use the untextured
 * ones.  NULL: each band prepares its own (out of memory). */
static const lie_lights *band_lights(view_render *r, const lie_scene *s, int lv)
{
    if (lie_lights_fit(r->lights, s))
        return r->lights;
    pthread_mutex_lock(&r->m);
    int done = !r->lights_started || r->lights_done;
    lie_lights *first = r->first_lights;
    r->first_lights = NULL;
    pthread_mutex_unlock(&r->m);
    if (first) {
        lie_lights_destroy(r->lights);
        r->lights = first;
        if (lie_lights_fit(r->lights, s))
            return r->lights;
    }
    lie_render_options o = lights_options(r);
    lie_error err;
    if (!done && lv < LEVELS - 1) {
        if (!lie_lights_fit(r->quick, s)) {
            /* with the finer coarse level's samples: the closed forms
             * only where a coarse level uses them (scifi_hallway's 632
             * convex pieces are not made twice at 32 light samples) */
            int n = r->o.light_samples / level_ls_div[LEVELS - 2];
            o.light_samples = n > 0 ? n : 1;
            lie_lights_destroy(r->quick);
            if (lie_lights_create_untextured(s, &o, &r->quick, &err) != LIE_OK)
                r->quick = NULL;
        }
        return r->quick;
    }
    /* the scene changed (an edit): prepared here, once per scene state */
    lie_lights_destroy(r->lights);
    if (lie_lights_create(s, &o, &r->lights, &err) != LIE_OK)
        r->lights = NULL;
    return r->lights;
}

/* The render thread: pick the level to draw (coarse while the view moves,
 * then finer), draw it band by band, publish each band.  One piece: the
 * generations it compares (camera, world version, units, forced redraws)
 * decide together what is drawn next. */
static void *render_main(void *arg)
{
    view_render *r = arg;
    uint64_t done_gen = 0, done_version = 0, done_units = 0, done_force = 0;
    for (;;) {
        pthread_mutex_lock(&r->m);
        while (!r->quit && r->gen == done_gen && view_world_version(r->w) == done_version &&
               !landed_due(r, done_units) && r->force == done_force) {
            struct timespec ts;
            clock_gettime(CLOCK_REALTIME, &ts);
            ts.tv_nsec += 10 * 1000 * 1000; /* the world's version is polled */
            if (ts.tv_nsec >= 1000000000L) {
                ts.tv_sec++;
                ts.tv_nsec -= 1000000000L;
            }
            pthread_cond_timedwait(&r->cv, &r->m, &ts);
        }
        if (r->quit) {
            pthread_mutex_unlock(&r->m);
            break;
        }
        uint64_t gen = r->gen, force = r->force;
        lie_camera cam = r->cam;
        int mode = r->mode, sel = r->sel;
        /* only units landed (or a frame asked for again): the full level alone */
        int again = gen == done_gen && view_world_version(r->w) == done_version;
        pthread_mutex_unlock(&r->m);
        uint64_t version = view_world_version(r->w), units = view_world_units_version(r->w);
        int abandoned = 0;
        for (int lv = again ? LEVELS - 1 : 0; lv < LEVELS && !abandoned; lv++) {
            if (lv == LEVELS - 1)
                wait_first_lights(r);
            double t_level = lie_time_now();
            int div = level_div[lv];
            int lw = (r->o.width + div - 1) / div, lh = (r->o.height + div - 1) / div;
            lie_render_options ro = lie_render_options_default();
            ro.width = lw;
            ro.height = lh;
            ro.light_samples = r->o.light_samples / level_ls_div[lv] > 0 ? r->o.light_samples / level_ls_div[lv] : 1;
            ro.max_depth = r->o.max_depth;
            ro.threads = r->o.threads;
            if (r->o.light_samples == 0)
                ro.eye_only = 1;
            if (mode == VIEW_MODE_COMPLEXITY)
                ro.aovs = LIE_AOV_COMPLEXITY;
            else if (mode == VIEW_MODE_PATCH)
                ro.aovs = LIE_AOV_PATCH;
            if (mode != VIEW_MODE_SHADE)
                ro.eye_only = 1;
            lie_frame **fp = &r->level[lv][mode];
            if (!*fp) {
                lie_error ferr;
                if (lie_render_frame_create(view_world_scene(r->w), &ro, fp, &ferr) != LIE_OK) {
                    abandoned = 1;
                    break;
                }
            }
            lie_frame *f = *fp;
            size_t tiles_x = (size_t)((lw + LIE_TILE - 1) / LIE_TILE), n_tiles = lie_render_tile_count(lw, lh);
            for (size_t t0 = 0; t0 < n_tiles && !abandoned; t0 += BAND_TILE_ROWS * tiles_x) {
                size_t nt = n_tiles - t0 < BAND_TILE_ROWS * tiles_x ? n_tiles - t0 : BAND_TILE_ROWS * tiles_x;
                int y0 = (int)(t0 / tiles_x) * LIE_TILE;
                int y1 = y0 + BAND_TILE_ROWS * LIE_TILE < lh ? y0 + BAND_TILE_ROWS * LIE_TILE : lh;
                view_world_read_lock(r->w);
                view_world_sync_oracle(r->w);
                const lie_scene *s = view_world_scene(r->w);
                ro.lights = ro.eye_only ? NULL : band_lights(r, s, lv);
                ro.oracle = view_world_oracle(r->w);
                ro.visibility = ro.oracle ? LIE_VIS_LIE : LIE_VIS_FULL;
                lie_error err;
                lie_status st = view_world_version(r->w) != version || (mode != VIEW_MODE_SHADE && !ro.oracle)
                                    ? LIE_ERR_ARG
                                    : lie_render_tiles(s, view_world_rt(r->w), &cam, &ro, f, t0, nt, NULL, &err);
                uint8_t *in = sel >= 0 ? calloc((size_t)s->n_nodes + 1, 1) : NULL;
                if (st == LIE_OK && in) {
                    view_node_subtree(s, sel, in);
                    mask_rows(r, s, view_world_rt(r->w), &cam, lw, lh, in, y0, y1);
                }
                free(in);
                view_world_read_unlock(r->w);
                pthread_mutex_lock(&r->m);
                if (st != LIE_OK || r->gen != gen || r->quit) {
                    abandoned = 1;
                } else {
                    uint8_t *keep = r->sel_mask;
                    if (sel < 0)
                        r->sel_mask = NULL;
                    blit(r, f, div, mode, y0, y1);
                    r->sel_mask = keep;
                    r->dirty = 1;
                }
                pthread_mutex_unlock(&r->m);
            }
            if (abandoned)
                break;
            /* --exposure auto: the image's own exposure, as lie-render
             * gives its frame; the bands drawn with the last image's are
             * drawn again if it differs */
            lie_auto_exposure ae = {0.0f, LIE_EXPOSURE_KEY, 0.0, 0};
            if (r->o.exposure_auto && mode == VIEW_MODE_SHADE)
                ae = lie_frame_auto_exposure(f, LIE_EXPOSURE_KEY);
            pthread_mutex_lock(&r->m);
            if (r->o.exposure_auto && mode == VIEW_MODE_SHADE && ae.ev != r->auto_ev && r->gen == gen) {
                r->auto_ev = ae.ev;
                uint8_t *keep = r->sel_mask;
                if (sel < 0)
                    r->sel_mask = NULL;
                blit(r, f, div, mode, 0, lh);
                r->sel_mask = keep;
                r->dirty = 1;
            }
            r->images++;
            r->level_pixels = (uint64_t)lw * (uint64_t)lh;
            r->image_version = version;
            if (lv == LEVELS - 1 && mode == VIEW_MODE_SHADE) {
                lie_frame *t = r->full;
                r->full = f;
                r->level[lv][mode] = t;
                r->full_gen = gen;
                r->full_version = version;
                r->full_force = force;
                r->full_clean = view_world_units_version(r->w) == units;
            }
            double t_end = lie_time_now();
            note_time(r, lv, t_level, t_end, view_world_units_version(r->w) == units);
            pthread_cond_broadcast(&r->cv);
            pthread_mutex_unlock(&r->m);
        }
        if (!abandoned) {
            done_gen = gen;
            done_version = version;
            done_units = units;
            done_force = force;
            pthread_mutex_lock(&r->m);
            r->done_gen = gen;
            r->done_version = version;
            pthread_mutex_unlock(&r->m);
        }
    }
    return NULL;
}

lie_status view_render_start(view_world *w, const view_render_options *opt, view_render **out, lie_error *err)
{
    *out = NULL;
    view_render *r = calloc(1, sizeof *r);
    if (!r)
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    r->w = w;
    r->o = *opt;
    r->sel = -1;
    pthread_mutex_init(&r->m, NULL);
    pthread_cond_init(&r->cv, NULL);
    size_t n = (size_t)opt->width * (size_t)opt->height;
    r->display = calloc(n, sizeof *r->display);
    r->sel_mask = calloc(n, 1);
    /* r->full: the first full frame rendered (a frame lie_render_frame_create
     * made, with the coverage --exposure auto leaves the background out by) */
    if (!r->display || !r->sel_mask) {
        view_render_stop(r);
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory for %dx%d frames", opt->width, opt->height);
    }
    if (opt->light_samples > 0) {
        /* off the first image's path (lights_main); without the thread, the
         * render thread prepares them */
        r->lights_started = pthread_create(&r->lights_tid, NULL, lights_main, r) == 0;
    }
    if (pthread_create(&r->tid, NULL, render_main, r) != 0) {
        view_render_stop(r);
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "cannot start the render thread");
    }
    r->started = 1;
    *out = r;
    return LIE_OK;
}

void view_render_stop(view_render *r)
{
    if (!r)
        return;
    if (r->started) {
        view_thread_quit(&r->m, &r->cv, &r->quit, r->tid);
    }
    if (r->lights_started)
        pthread_join(r->lights_tid, NULL);
    lie_lights_destroy(r->first_lights);
    lie_lights_destroy(r->quick);
    for (int lv = 0; lv < LEVELS; lv++)
        for (int m = 0; m < 3; m++)
            lie_frame_destroy(r->level[lv][m]);
    lie_frame_destroy(r->full);
    lie_lights_destroy(r->lights);
    free(r->times);
    free(r->display);
    free(r->sel_mask);
    pthread_mutex_destroy(&r->m);
    pthread_cond_destroy(&r->cv);
    free(r);
}

void view_render_request(view_render *r, const lie_camera *cam, int mode, int sel)
{
    pthread_mutex_lock(&r->m);
    if (r->gen == 0 || memcmp(cam, &r->cam, sizeof *cam) != 0 || mode != r->mode || sel != r->sel) {
        r->cam = *cam;
        r->mode = mode;
        r->sel = sel;
        r->gen++;
        pthread_cond_broadcast(&r->cv);
    }
    uint64_t v = view_world_version(r->w);
    if (v != r->version_seen) {
        r->version_seen = v; /* an edit: wake the renderer now rather than at its next poll */
        pthread_cond_broadcast(&r->cv);
    }
    pthread_mutex_unlock(&r->m);
}

int view_render_fetch(view_render *r, uint32_t *argb, uint64_t *images, uint64_t *level_pixels, int *idle,
                      uint64_t *image_version)
{
    pthread_mutex_lock(&r->m);
    *image_version = r->image_version;
    *idle = r->done_gen == r->gen && r->done_version == view_world_version(r->w);
    int d = argb ? r->dirty : 0; /* NULL: only the counters */
    if (d)
        memcpy(argb, r->display, sizeof *argb * (size_t)r->o.width * (size_t)r->o.height);
    if (argb)
        r->dirty = 0;
    *images = r->images;
    *level_pixels = r->level_pixels;
    pthread_mutex_unlock(&r->m);
    return d;
}

uint64_t view_render_full_count(view_render *r)
{
    pthread_mutex_lock(&r->m);
    uint64_t n = 0;
    for (size_t i = 0; i < r->n_times; i++)
        n += r->times[i].level == LEVELS - 1;
    pthread_mutex_unlock(&r->m);
    return n;
}

void view_render_set_exposure(view_render *r, float ev)
{
    pthread_mutex_lock(&r->m);
    r->o.exposure = ev;
    r->o.exposure_auto = 0;
    r->force++; /* the full frame again, exposed anew */
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->m);
}

float view_render_exposure(view_render *r)
{
    pthread_mutex_lock(&r->m);
    float ev = r->o.exposure_auto ? r->auto_ev : r->o.exposure;
    pthread_mutex_unlock(&r->m);
    return ev;
}

void view_render_again(view_render *r)
{
    pthread_mutex_lock(&r->m);
    r->force++;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->m);
}

view_frame_time *view_render_times(view_render *r, size_t *n)
{
    pthread_mutex_lock(&r->m);
    view_frame_time *t = malloc(sizeof *t * (r->n_times + 1));
    *n = t ? r->n_times : 0;
    if (t && r->n_times)
        memcpy(t, r->times, sizeof *t * r->n_times);
    pthread_mutex_unlock(&r->m);
    return t;
}

lie_status view_render_screenshot(view_render *r, const char *path, lie_error *err)
{
    /* Units stop landing (the one in progress is dropped, never the backlog
     * waited for) and a full frame is rendered from what has landed: the
     * frame lie-render makes from the cache --save would write now. */
    view_world_hold(r->w);
    view_render_again(r);
    pthread_mutex_lock(&r->m);
    uint64_t force = r->force;
    while (!(r->full_gen == r->gen && r->full_version == view_world_version(r->w) && r->full_force >= force &&
             r->full_clean && r->mode == VIEW_MODE_SHADE)) {
        if (r->mode != VIEW_MODE_SHADE) {
            pthread_mutex_unlock(&r->m);
            view_world_release(r->w);
            return lie_error_set(err, LIE_ERR_ARG, path, "screenshots are of the shaded view");
        }
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += 10 * 1000 * 1000;
        if (ts.tv_nsec >= 1000000000L) {
            ts.tv_sec++;
            ts.tv_nsec -= 1000000000L;
        }
        pthread_cond_timedwait(&r->cv, &r->m, &ts);
    }
    /* the frame stays ours while m is held */
    lie_frame_options fo;
    memset(&fo, 0, sizeof fo);
    fo.png.exposure = r->o.exposure;
    /* --exposure auto: the frame's own, said in the file as lie-render says it */
    char text[160];
    lie_png_text png_text = {"lie.exposure", text};
    if (r->o.exposure_auto) {
        lie_auto_exposure ae = lie_frame_auto_exposure(r->full, LIE_EXPOSURE_KEY);
        fo.png.exposure = ae.ev;
        lie_auto_exposure_text(&ae, text, sizeof text);
        fo.png.text = &png_text;
        fo.png.n_text = 1;
    }
    lie_status st = lie_frame_write(path, r->full, &fo, err);
    pthread_mutex_unlock(&r->m);
    view_world_release(r->w);
    return st;
}
