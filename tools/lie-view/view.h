/* SPDX-License-Identifier: Apache-2.0 */
/* lie-view: the paper's interactive loop (§3): navigate, move objects and
 * see correct soft shadows at once, while an asynchronous constructor
 * (§4.3.1) catches up with the edits (§5).
 *
 * Threads: the SDL thread (events, overlay, present), one progressive
 * renderer (progressive.c, which renders on lie_render_tiles' workers)
 * and the constructor (world.c).  The world lock is taken for reading by
 * the renderer per band and by picking, for writing by edits and by the
 * constructor when it swaps recomputed units in. */
#ifndef LIE_VIEW_H
#define LIE_VIEW_H

#include "common/cli.h"
#include "lie.h"

#include <pthread.h>
#include <stdatomic.h>

extern const char *view_prog;

/* ---- camera (camera.c) ---------------------------------------------- */

/* An orbit camera about a target, world up +y; angles in degrees.  What is
 * rendered is always the camera its --camera spec parses to, so a printed
 * spec reproduces the frame bit for bit in lie-render. */
typedef struct view_orbit {
    lie_vec3 target;
    float yaw, pitch, dist, fov;
} view_orbit;

void view_orbit_from_camera(view_orbit *o, const lie_camera *c, const lie_scene *s);
lie_vec3 view_orbit_eye(const view_orbit *o);
void view_orbit_rotate(view_orbit *o, float dyaw, float dpitch);
void view_orbit_dolly(view_orbit *o, float f);          /* toward the target by the fraction f */
void view_orbit_pan(view_orbit *o, float dx, float dy); /* in view heights at the target */
void view_orbit_fly(view_orbit *o, float fwd, float right, float up); /* eye and target, world units */
void view_orbit_frame(view_orbit *o, lie_box3 b);       /* F: target the box, fit it in view */
/* "eye=X,Y,Z,target=X,Y,Z,up=0,1,0,fov=DEG" (%.9g: floats round-trip). */
void view_orbit_spec(const view_orbit *o, char *buf, size_t size);

/* A worker thread (the renderer's, the constructor) that waits on cv under
 * m and ends when *quit is set: set it, wake the thread and join it. */
void view_thread_quit(pthread_mutex_t *m, pthread_cond_t *cv, int *quit, pthread_t tid);

/* ---- the world: scene, cache, edits, constructor (world.c) ----------- */

typedef struct view_world view_world;

typedef struct view_world_options {
    int threads;           /* constructor threads (0: one a core) */
    int view_width, view_height, max_depth; /* how the constructor samples views (lie-build --view-size) */
    const char *record;    /* --record EDITS.yaml, or NULL */
    lie_scene_options so;
} view_world_options;

lie_status view_world_open(const char *input, const view_world_options *opt, view_world **out, lie_error *err);
void view_world_close(view_world *w);

/* Readers (renderer, picking) hold the read lock while they use these. */
void view_world_read_lock(view_world *w);
void view_world_read_unlock(view_world *w);
const lie_scene *view_world_scene(const view_world *w);
const lie_rt *view_world_rt(const view_world *w);
const lie_vis_oracle *view_world_oracle(const view_world *w); /* NULL without a cache */
/* The renderer, before a band (read lock held): the oracle follows the lists landed. */
void view_world_sync_oracle(view_world *w);
/* Changes whenever the constructor lands units (0 without one): frames
 * stay right, and get faster when rendered again. */
uint64_t view_world_units_version(const view_world *w);
/* Stop units landing until the release (screenshots, pause); returns at once
 * (a unit in progress is dropped; a whole cache's update step in progress
 * ends first). */
void view_world_hold(view_world *w);
void view_world_release(view_world *w);
/* The camera now: the constructor builds what it sees first. */
void view_world_look(view_world *w, const lie_camera *cam);
/* The constructor, or NULL (a whole cache: lib/update). */
lie_ctor *view_world_ctor(const view_world *w);
/* Changes on every edit and every constructor step: frames older than it are stale. */
uint64_t view_world_version(const view_world *w);
int64_t view_world_pending(const view_world *w);   /* units not yet rebuilt */
uint64_t view_world_units_built(const view_world *w); /* units the constructor has landed (0 without one) */
int view_world_busy(const view_world *w);          /* units pending, or the update not yet committed */
int64_t view_world_pending_max(const view_world *w);
double view_world_last_update_ms(const view_world *w);
int view_world_has_cache(const view_world *w);

/* An empty edit for view_world_edit, named as the session's record. */
lie_edit *view_world_new_edit(const view_world *w);
/* An edit (lib/edit): applied at once, recorded, and undoable as a group;
 * join: part of the last group (the steps of one drag undo together). */
lie_status view_world_edit(view_world *w, const lie_edit *e, int join, lie_error *err);
lie_status view_world_undo(view_world *w, int *done, lie_error *err);
lie_status view_world_redo(view_world *w, int *done, lie_error *err);
/* update_ms of every edit applied so far (for --stats=json). */
const double *view_world_update_ms(const view_world *w, int *n);
/* Block until no unit is pending. */
void view_world_wait(view_world *w);
/* Write the cache (the edit log gains the session's edits as one entry
 * named as --record, so rst-update CACHE EDITS.yaml gives the same bytes). */
lie_status view_world_save(view_world *w, const char *path, lie_error *err);
/* Write --record's file: every live edit, in order (atomically). */
lie_status view_world_write_record(view_world *w, lie_error *err);

/* Node helpers (call with the read lock held, or from the SDL thread,
 * which is the only writer). */
int view_node_under(const lie_scene *s, const lie_rt *rt, const lie_camera *cam, int width, int height, float x,
                    float y, lie_vec3 *hit_point);
lie_box3 view_node_bounds(const lie_scene *s, int node);
const char *view_node_name(const lie_scene *s, int node, char *buf, size_t size);
/* in[n] = 1 for node and its subtree (in has s->n_nodes entries). */
void view_node_subtree(const lie_scene *s, int node, uint8_t *in);

/* ---- progressive rendering (progressive.c) ---------------------------- */

enum { VIEW_MODE_SHADE = 0, VIEW_MODE_COMPLEXITY = 1, VIEW_MODE_PATCH = 2 };

typedef struct view_render view_render;

typedef struct view_render_options {
    int width, height, light_samples, max_depth, threads;
    float exposure;        /* stops, as lie-render --exposure */
    int exposure_auto;     /* --exposure auto: each image's own (lie_frame_auto_exposure), as lie-render's */
} view_render_options;

/* A full frame: when it ended (lie_time_now), how long it took, whether
 * no unit landed meanwhile, and the units pending at its end. */
typedef struct view_frame_time {
    double end, ms;
    int level;             /* 0 coarsest .. 2 full */
    int clean;
    int64_t pending;
} view_frame_time;

lie_status view_render_start(view_world *w, const view_render_options *opt, view_render **out, lie_error *err);
void view_render_stop(view_render *r);
/* What to show: the renderer restarts (coarse first) when any of these or
 * the world's version changes.  sel: node or -1. */
void view_render_request(view_render *r, const lie_camera *cam, int mode, int sel);
/* Copy the display image (ARGB8888, width x height) if it changed since the
 * last call; returns 1 then.  *level_pixels: pixels of the last image
 * finished; *images: images finished so far; *idle: every level of the
 * current request is finished; *image_version: the world version the last
 * finished image shows. */
int view_render_fetch(view_render *r, uint32_t *argb, uint64_t *images, uint64_t *level_pixels, int *idle,
                      uint64_t *image_version);
/* Hold the constructor, render the full frame of the current request from
 * what has landed, and write it as lie-render would (by extension, PNGs
 * with the exposure): one frame's wait, never the constructor's backlog. */
lie_status view_render_screenshot(view_render *r, const char *path, lie_error *err);
/* Render the full frame again (its time is measured: view_render_times). */
void view_render_again(view_render *r);
/* Full frames finished so far. */
uint64_t view_render_full_count(view_render *r);
/* The shaded view's exposure, in stops (auto exposure off). */
void view_render_set_exposure(view_render *r, float ev);
/* The exposure the shaded view is shown with now, in stops (auto's last). */
float view_render_exposure(view_render *r);
/* Every image finished so far, each level (a copy: free it). */
view_frame_time *view_render_times(view_render *r, size_t *n);

/* ---- overlay text (font.c) -------------------------------------------- */

/* Draw ASCII text with the built-in 5x7 font at scale `scale`, shadowed. */
void view_text(uint32_t *argb, int width, int height, int x, int y, int scale, uint32_t colour, const char *text);

/* ---- scripts (script.c) ----------------------------------------------- */

typedef enum view_cmd_kind {
    VIEW_CMD_FRAMES, VIEW_CMD_ORBIT, VIEW_CMD_DOLLY, VIEW_CMD_SELECT, VIEW_CMD_PICK, VIEW_CMD_DRAG,
    VIEW_CMD_ROTATE, VIEW_CMD_SET_MATERIAL, VIEW_CMD_SET_EMISSION, VIEW_CMD_UNDO, VIEW_CMD_REDO, VIEW_CMD_WAIT,
    VIEW_CMD_SCREENSHOT, VIEW_CMD_QUIT, VIEW_CMD_REMOVE, VIEW_CMD_PAUSE, VIEW_CMD_RESUME, VIEW_CMD_REDRAW,
    VIEW_CMD_WAIT_AT_MOST, VIEW_CMD_WAIT_UNITS
} view_cmd_kind;

typedef struct view_cmd {
    view_cmd_kind kind;
    int line;
    double v[4];
    char *arg;             /* node name, file, or the edit fields "{...}" minus "node" */
    lie_edit *fields;      /* set-material, set-emission: the operation, its node unset */
} view_cmd;

typedef struct view_script {
    view_cmd *cmds;
    int n;
} view_script;

/* Parse a script file: one command a line, '#' comments.  Errors name
 * file:line and the command. */
lie_status view_script_read(const char *path, view_script **out, lie_error *err);
void view_script_destroy(view_script *s);

#endif
