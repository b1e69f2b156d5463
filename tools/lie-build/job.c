/* SPDX-License-Identifier: Apache-2.0 */
/* lie-build's steps (tools/lie-build/job.h): the library does the work,
 * these put its calls in order and keep what they make in the job. */
#include "job.h"
#include "dist.h"

#include <stdlib.h>
#include <string.h>

/* --partial: the first SIGINT, SIGTERM or SIGHUP asks the build to stop
 * (lie_build_control.stop); a second one aborts at once, as without
 * --partial.  The write that follows is the library's: its handler removes
 * the temporary and re-raises (lib/core/file.c), so the cache on disk is
 * the whole partial cache or nothing. */
volatile sig_atomic_t job_stop_signal;
static const int stop_signals[3] = {SIGINT, SIGTERM, SIGHUP};

static void on_stop(int sig)
{
    if (job_stop_signal) {
        signal(sig, SIG_DFL);
        raise(sig); /* delivered with the default action once the handler returns */
        return;
    }
    job_stop_signal = sig;
}

/* Install on_stop where a signal has its default action (a signal the
 * caller ignores, as nohup does SIGHUP, stays ignored), or put the default
 * back. */
static void stop_handlers(int on, int installed[3])
{
    for (int i = 0; i < 3; i++) {
        struct sigaction old, sa;
        memset(&sa, 0, sizeof sa);
        sigemptyset(&sa.sa_mask);
        if (on) {
            installed[i] = sigaction(stop_signals[i], NULL, &old) == 0 && old.sa_handler == SIG_DFL &&
                           !(old.sa_flags & SA_SIGINFO);
            if (!installed[i])
                continue;
            sa.sa_handler = on_stop;
            for (int j = 0; j < 3; j++)
                sigaddset(&sa.sa_mask, stop_signals[j]);
        } else {
            if (!installed[i])
                continue;
            sa.sa_handler = SIG_DFL;
        }
        sigaction(stop_signals[i], &sa, NULL);
    }
}

const char *job_signal_name(int sig)
{
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "a signal";
}

/* --edit: read, parse and apply each edit file in order (a resumed build's
 * log must hold the same texts); edit_log[i].name is set, text and size
 * are filled. */
static lie_status apply_edits(lie_scene *scene, const lie_scene_options *so, lie_cache_edit *edit_log, int n,
                              const lie_cache *resume, lie_error *err)
{
    for (int i = 0; i < n; i++)
        edit_log[i].text = NULL;
    if (resume && resume->n_edits != n)
        return lie_error_set(err, LIE_ERR_ARG, scene->path, "the partial cache was built with %d edit files, not %d",
                             resume->n_edits, n);
    for (int i = 0; i < n; i++) {
        lie_cache_edit *ed = &edit_log[i];
        lie_edit *e = NULL;
        if (lie_file_set_read(so->files, ed->name, LIE_READ_MAX_TEXT, &ed->text, &ed->size, err) != LIE_OK ||
            lie_edit_parse(ed->text, ed->size, ed->name, &e, err) != LIE_OK ||
            lie_edit_apply(scene, e, so, NULL, err) != LIE_OK) {
            lie_edit_destroy(e);
            return err->status;
        }
        lie_edit_destroy(e);
        if (resume && (resume->edits[i].size != ed->size || memcmp(resume->edits[i].text, ed->text, ed->size)))
            return lie_error_set(err, LIE_ERR_ARG, ed->name, "differs from edit %d of the partial cache", i);
    }
    return LIE_OK;
}

static void free_edits(lie_cache_edit *edit_log, int n)
{
    for (int i = 0; i < n; i++)
        free(edit_log[i].text);
}

/* A resumed build's views must be the partial cache's. */
static int same_views(const lie_cache_views *a, const lie_cache_views *b)
{
    if (a->n_cams != b->n_cams || (a->n_cams && (a->width != b->width || a->height != b->height ||
                                                 a->max_depth != b->max_depth)))
        return 0;
    for (int i = 0; i < a->n_cams; i++) {
        lie_camera x = a->cams[i], y = b->cams[i];
        x.name = y.name = NULL;
        if (memcmp(&x, &y, sizeof x) != 0)
            return 0;
    }
    return 1;
}

/* The cameras of the --view options and the frames of --path, appended to
 * *cams (the cache's views first, with --into). */
static lie_status gather_views(const lie_scene *scene, const char *input, const char *const *views, int n_views,
                               const lie_camera_path *cpath, lie_cache_views *v, lie_error *err)
{
    lie_status st = LIE_OK;
    int n_new = n_views + (cpath ? cpath->n_frames : 0);
    lie_camera *cams = st == LIE_OK ? realloc(v->cams, sizeof *cams * ((size_t)(v->n_cams + n_new) + 1)) : NULL;
    if (st == LIE_OK && !cams)
        st = lie_error_set(err, LIE_ERR_NOMEM, input, "out of memory");
    if (cams)
        v->cams = cams;
    for (int i = 0; st == LIE_OK && i < n_views; i++) {
        st = lie_camera_parse(scene, views[i], &cams[v->n_cams], err);
        if (st != LIE_OK && !err->file[0])
            snprintf(err->file, sizeof err->file, "%s", input);
        cams[v->n_cams].name = NULL; /* caches keep the geometry, not the name */
        if (st == LIE_OK)
            v->n_cams++;
    }
    for (int i = 0; st == LIE_OK && cpath && i < cpath->n_frames; i++) {
        cams[v->n_cams] = lie_camera_path_frame(cpath, i);
        cams[v->n_cams++].name = NULL;
    }
    return st;
}


void job_init(build_job *j)
{
    memset(j, 0, sizeof *j);
    j->bp = lie_build_params_default();
    j->so = lie_scene_options_default();
    j->view_w = j->view_h = 512;
    lie_error_clear(&j->err);
}

/* A cache whose units follow older build rules (lie_cache_rules_old) cannot
 * be completed: its units and new ones would not be one build's. */
#define OLD_RULES "made by an older lie (format version before 5), whose units a new build would not reproduce: build it afresh"

/* --into: the cache to add views to, its scene and parameters. */
static lie_status load_into(build_job *j)
{
    lie_error *err = &j->err;
    if (lie_cache_read(j->into, &j->old, err) != LIE_OK ||
        lie_cache_load_scene(j->old, j->into, j->input, &j->so, &j->scene, err) != LIE_OK ||
        (j->path_file && lie_camera_path_read(j->path_file, &j->cpath, err) != LIE_OK))
        return err->status;
    const lie_cache_views *ov = &j->old->views;
    if (lie_cache_rules_old(j->old))
        return lie_error_set(err, LIE_ERR_ARG, j->into, "%s", OLD_RULES);
    if (!ov->n_cams)
        return lie_error_set(err, LIE_ERR_ARG, j->into, "built for the whole scene, not for views: nothing to add");
    if (j->size_given && (j->view_w != ov->width || j->view_h != ov->height))
        return lie_error_set(err, LIE_ERR_ARG, j->into, "built for views of %dx%d, not %dx%d", ov->width,
                             ov->height, j->view_w, j->view_h);
    j->bp = j->old->env->params;
    j->cv.width = ov->width;
    j->cv.height = ov->height;
    j->cv.max_depth = ov->max_depth;
    j->input = j->old->scene_path;
    return LIE_OK;
}

lie_status job_load(build_job *j)
{
    j->cv = (lie_cache_views){NULL, 0, j->view_w, j->view_h, LIE_MAX_DEPTH_DEFAULT};
    if (!(j->files = lie_file_set_create(LIE_FILES_NAMES)))
        return lie_error_set(&j->err, LIE_ERR_NOMEM, j->input, "out of memory");
    j->so.files = j->files;
    const char *cache_in = j->resume_file ? j->resume_file : j->into;
    if (cache_in && lie_file_set_note(j->files, cache_in, &j->err) != LIE_OK)
        return j->err.status;
    if (j->resume_file) { /* the partial cache's parameters, this run's threads and node cap */
        if (lie_cache_read(j->resume_file, &j->resume, &j->err) != LIE_OK)
            return j->err.status;
        if (lie_cache_rules_old(j->resume))
            return lie_error_set(&j->err, LIE_ERR_ARG, j->resume_file, "%s", OLD_RULES);
        int threads = j->bp.threads;
        uint64_t max_nodes = j->bp.max_nodes;
        j->bp = j->resume->env->params;
        j->bp.threads = threads;
        j->bp.max_nodes = max_nodes;
    }
    lie_status st = j->into ? load_into(j)
                            : build_load_inputs(j->input, j->path_file, &j->so, &j->scene, &j->cpath, &j->err);
    if (st != LIE_OK)
        return st;
    j->loaded_hash = j->scene->hash;
    st = apply_edits(j->scene, &j->so, j->edit_log, j->n_edits, j->resume, &j->err);
    if (st == LIE_OK && j->path_file)
        st = lie_file_set_note(j->files, j->path_file, &j->err);
    if (st == LIE_OK && j->output)
        st = lie_file_set_claim(j->files, j->output, cache_in, &j->err);
    return st;
}

/* --into: the old views' pixels, and the old views first in j->cv. */
static lie_status old_views(build_job *j)
{
    const lie_cache_views *ov = &j->old->views;
    j->cv.cams = malloc(sizeof *j->cv.cams * ((size_t)ov->n_cams + 1));
    if (!j->cv.cams)
        return lie_error_set(&j->err, LIE_ERR_NOMEM, j->into, "out of memory");
    memcpy(j->cv.cams, ov->cams, sizeof *j->cv.cams * (size_t)ov->n_cams);
    j->cv.n_cams = ov->n_cams;
    return lie_camera_pixels(j->scene, j->rt, j->cv.cams, j->cv.n_cams, j->cv.width, j->cv.height, j->cv.max_depth,
                             &j->old_px, &j->err);
}

lie_status job_views(build_job *j)
{
    lie_cache_views *cv = &j->cv;
    lie_status rc = j->into ? old_views(j) : LIE_OK;
    if (rc == LIE_OK && (j->n_views || j->path_file)) {
        int first_new = cv->n_cams;
        rc = gather_views(j->scene, j->input, j->views, j->n_views, j->cpath, cv, &j->err);
        if (rc == LIE_OK)
            rc = lie_camera_pixels(j->scene, j->rt, cv->cams + first_new, cv->n_cams - first_new, cv->width,
                                   cv->height, cv->max_depth, &j->px, &j->err);
        if (rc == LIE_OK && j->old_px) { /* the old views' pixels and the new: all the views' */
            lie_pixels *added = j->px;
            j->px = NULL;
            rc = lie_pixels_merge(j->old_px, added, &j->px, &j->err);
            lie_pixels_destroy(added);
        }
    }
    lie_camera_path_destroy(j->cpath);
    j->cpath = NULL;
    if (rc == LIE_OK && j->resume && !same_views(&j->resume->views, cv))
        rc = lie_error_set(&j->err, LIE_ERR_ARG, j->resume_file,
                           "was built for other views (--view, --path, --view-size)");
    if (rc == LIE_OK)
        rc = lie_dist_check(j->scene->hash, j->scene->hash, &j->err);
    return rc;
}

/* The cache's fields around its env: provenance, edit log, state, views
 * (j->head, j->log), made once. */
static lie_status job_head(build_job *j)
{
    if (j->have_head)
        return LIE_OK;
    lie_cache *cache = &j->head;
    memset(cache, 0, sizeof *cache);
    cache->scene_path = (char *)j->input;
    cache->scene_hash = j->old ? j->old->scene_hash : j->loaded_hash;
    if (j->old) { /* the edit log goes on */
        cache->edits = j->old->edits;
        cache->n_edits = j->old->n_edits;
    } else {
        cache->edits = j->edit_log;
        cache->n_edits = j->n_edits;
    }
    /* --edit's names (command-line arguments) relative to the cache's folder,
     * where their `add` files resolve from (lie_cache_log_relative_to) */
    if (!j->old && j->n_edits) {
        j->log = calloc((size_t)j->n_edits, sizeof *j->log);
        if (!j->log)
            return lie_error_set(&j->err, LIE_ERR_NOMEM, j->output, "out of memory");
        for (int i = 0; i < j->n_edits; i++) {
            j->log[i] = j->edit_log[i];
            j->log[i].name = strdup(j->edit_log[i].name);
            if (!j->log[i].name)
                j->log[i].name = j->edit_log[i].name; /* kept as given */
        }
        cache->edits = j->log;
        lie_cache_log_relative_to(cache, 0, j->output);
    }
    cache->views = j->cv;
    j->have_head = 1;
    return lie_cache_set_state(cache, j->scene, &j->err);
}

static lie_status stream_unit(void *ctx, const lie_pnode *nodes, const uint32_t *pool, uint32_t root)
{
    build_job *j = ctx;
    return lie_cache_stream_unit(j->stream, nodes, pool, root, &j->stream_err);
}

/* A whole build writes its units to the cache as they are made, so that
 * it holds one unit per thread and the roots, not them all with the
 * assembled env and the file's bytes (a view build keeps its env: --stats
 * sets it against the views' pixels). */
static lie_status open_stream(build_job *j, lie_build_control *ctl)
{
    if (j->px || j->into)
        return LIE_OK;
    lie_env desc;
    memset(&desc, 0, sizeof desc);
    desc.n_tris = j->scene->n_tris; /* what the build's env will say (its trees aside) */
    desc.n_clusters = j->scene->n_clusters;
    desc.params = j->bp;
    desc.params.threads = 0;
    desc.scene_hash = j->scene->hash;
    lie_status st = job_head(j);
    if (st != LIE_OK)
        return st;
    j->head.env = &desc;
    st = lie_cache_stream_open(j->output, &j->head, &j->stream, &j->err);
    j->head.env = NULL;
    if (st != LIE_OK)
        return st;
    lie_error_clear(&j->stream_err);
    ctl->sink = stream_unit;
    ctl->sink_ctx = j;
    return LIE_OK;
}

/* One process's build, stopped by a signal under --partial. */
static lie_status build_here(build_job *j, lie_progress *progress)
{
    lie_build_control ctl;
    memset(&ctl, 0, sizeof ctl);
    if (open_stream(j, &ctl) != LIE_OK)
        return j->err.status;
    ctl.pixels = j->px;
    ctl.progress = progress;
    ctl.resume = j->resume ? j->resume->env : NULL;
    ctl.stop = j->partial ? &job_stop_signal : NULL;
    ctl.audit_complex = j->audit_complex && !j->bp.complex_predict;
    int handlers[3] = {0, 0, 0};
    if (j->partial)
        stop_handlers(1, handlers);
    lie_status rc = lie_env_build_with(j->scene, j->rt, &j->bp, &ctl, &j->env, &j->st, &j->err);
    if (j->partial)
        stop_handlers(0, handlers); /* from here a signal aborts; the write's handler cleans up */
    if (rc != LIE_OK && j->stream && j->stream_err.status != LIE_OK)
        j->err = j->stream_err; /* the file's error, not the build's echo of it */
    if (rc == LIE_OK && j->stream) { /* what the file holds, for --stats */
        j->env->n_nodes = (uint32_t)lie_cache_stream_nodes(j->stream);
        j->env->n_pool = (uint32_t)lie_cache_stream_pool(j->stream);
    }
    return rc;
}

lie_status job_build(build_job *j, lie_progress *progress)
{
    lie_status rc;
    if (j->into) {
        j->env = j->old->env;
        j->old->env = NULL;
        rc = lie_env_add_views(j->env, j->scene, j->rt, j->old_px, j->px, j->bp.threads, &j->st, &j->as, &j->err);
    } else if (lie_dist_size() > 1) {
        rc = build_dist(j->scene, j->rt, &j->bp, j->px, &j->env, &j->st, &j->err);
    } else {
        rc = build_here(j, progress);
    }
    lie_cache_destroy(j->resume);
    j->resume = NULL;
    lie_pixels_destroy(j->old_px);
    j->old_px = NULL;
    return rc;
}

lie_status job_write(build_job *j)
{
    if (j->stream) {
        lie_cache_stream *s = j->stream;
        j->stream = NULL;
        return lie_cache_stream_close(s, j->env->partial, &j->bytes, &j->err);
    }
    lie_status rc = job_head(j);
    if (rc != LIE_OK)
        return rc;
    j->head.env = j->env;
    rc = lie_cache_write(j->output, &j->head, &j->bytes, &j->err);
    j->head.env = NULL;
    return rc;
}

void job_free(build_job *j)
{
    lie_cache_stream_abort(j->stream);
    for (int i = 0; j->log && i < j->n_edits; i++)
        if (j->log[i].name != j->edit_log[i].name)
            free(j->log[i].name);
    free(j->log);
    free(j->head.emitters);
    free_edits(j->edit_log, j->n_edits);
    lie_cache_destroy(j->resume);
    lie_camera_path_destroy(j->cpath);
    lie_pixels_destroy(j->px);
    lie_pixels_destroy(j->old_px);
    free(j->cv.cams);
    lie_env_destroy(j->env);
    lie_cache_destroy(j->old);
    lie_rt_destroy(j->rt);
    lie_scene_destroy(j->scene);
    lie_file_set_destroy(j->files);
    memset(j, 0, sizeof *j);
}
