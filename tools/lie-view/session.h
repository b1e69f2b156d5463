/* SPDX-License-Identifier: Apache-2.0 */
/* lie-view's session (tools/lie-view/session.c): the camera, the
 * selection, the edits a key, a drag or a script line makes, and the
 * statistics --stats prints.  The window loop is main.c's. */
#ifndef LIE_VIEW_SESSION_H
#define LIE_VIEW_SESSION_H

#include "view.h"

#include <SDL.h>

typedef struct session {
    lie_file_set *files; /* the session's inputs and outputs: no output may replace an input */
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
    double start_t;         /* the program started */
    double first_image_ms;  /* to the first image on screen (-1: none yet) */
    float exposure_shown;   /* at exit: the stops the view was shown with (--exposure auto: the last image's) */
    lie_camera looked;      /* the camera the constructor last built for */
    double cam_change_t;
    int looked_set;
} session;


typedef struct drag_state {
    int active, orbiting, dragging, panning, moved, join, axis;
    int x0, y0, lastx, lasty;
    float depth;            /* of the grabbed point along the view */
    lie_vec3 pending;       /* motion not yet applied */
    double last_flush;
    float pending_yaw, pending_pitch;
} drag_state;

typedef struct script_run {
    view_script *sc;
    const char *path;
    int next;
    int waiting;            /* 0 none, 1 frames, 2 pending, 3 full frames redrawn, 4 units landed */
    uint64_t until_images;
    uint64_t until_units;   /* wait-units */
    int paused;             /* the script holds the constructor */
    int redraws;            /* redraw: frames still to ask for */
    double deadline;        /* wait-at-most: when waiting ends anyway (0: never) */
    int failed;
    lie_error err;
} script_run;

/* Append ms to a growable array of latencies (dropped when out of memory). */
void session_push_ms(double **arr, int *n, double ms);
/* The camera is always what its spec parses to (so it prints exactly). */
void session_camera_update(session *S);
void session_select(session *S, int node);
/* The camera's right (which 0) or up (1) axis. */
lie_vec3 session_view_axis(const lie_camera *c, int which);
/* Apply a drag's pending motion and rotation as edits. */
void session_flush_drag(session *S, drag_state *d);
void session_key(session *S, const SDL_KeyboardEvent *k, int *quit);
/* Run commands until one has to wait; returns 1 when the script says quit. */
int session_script_step(session *S, script_run *R, uint64_t images, int idle);

#endif
