/* SPDX-License-Identifier: Apache-2.0 */
/* lie-build's run, step by step (tools/lie-build/job.c): what the command
 * line asks for, what is loaded and made, released by job_free.  main
 * (tools/lie-build/main.c) parses into it and calls the steps in order;
 * each returns LIE_OK or fills j->err. */
#ifndef LIE_BUILD_JOB_H
#define LIE_BUILD_JOB_H

#include "lie.h"

#include <signal.h>

#define JOB_MAX_VIEWS 64
#define JOB_MAX_EDITS 64

typedef struct build_job {
    /* the command line */
    lie_build_params bp;
    lie_scene_options so;
    const char *input, *output, *into, *path_file, *resume_file;
    const char *views[JOB_MAX_VIEWS];
    int n_views;
    lie_cache_edit edit_log[JOB_MAX_EDITS]; /* --edit: names, then the texts read */
    int n_edits;
    int view_w, view_h, size_given, params_given, partial;
    int audit_complex; /* --complex-predict audit: count what the prediction would name */
    /* what the run loads and makes */
    lie_cache *old, *resume; /* --into's cache, --resume's partial cache */
    lie_scene *scene;
    uint64_t loaded_hash; /* the scene's hash before --edit */
    lie_camera_path *cpath;
    lie_rt *rt;
    lie_cache_views cv;     /* the views the cache is built for */
    lie_pixels *px, *old_px; /* their pixels; with --into, the old views' alone */
    lie_env *env;           /* streamed: its counts and flags, no trees */
    /* a whole build in one process writes its units as they are made
     * (lie_cache_stream): the cache's fields around them, kept until the
     * stream is closed */
    lie_cache_stream *stream;
    lie_cache head;
    lie_cache_edit *log;
    int have_head;
    lie_error stream_err;
    lie_build_stats st;
    lie_add_stats as;
    size_t bytes;
    lie_file_set *files; /* the run's inputs and output (lie_file_set_claim) */
    lie_error err;
} build_job;

/* The defaults, nothing loaded. */
void job_init(build_job *j);
/* --resume's and --into's caches, the scene (and --path), the edits; then
 * the output is claimed: it may replace --resume's or --into's cache, no
 * other input. */
lie_status job_load(build_job *j);
/* The views' cameras and pixels (all the views' with --into), checked
 * against a resumed build's and across ranks. */
lie_status job_views(build_job *j);
/* The environments: added to --into's, shared out under mpirun, or built
 * here (stopping at a signal with --partial). */
lie_status job_build(build_job *j, lie_progress *progress);
/* The cache: its provenance, state and views around j->env, written. */
lie_status job_write(build_job *j);
void job_free(build_job *j);

/* --partial: the signal that stopped the build (0: none), and its name. */
extern volatile sig_atomic_t job_stop_signal;
const char *job_signal_name(int sig);

/* --stats (tools/lie-build/stats.c): times are load, bvh, build, write. */
struct lie_cli;
/* --stats (text on stderr) or --stats=json (stderr or --stats-file; an error in j->err). */
lie_status job_print_stats(const struct lie_cli *cli, build_job *j, double cpu_build, const double t[4]);

#endif
