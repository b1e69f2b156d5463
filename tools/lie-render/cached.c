/* SPDX-License-Identifier: Apache-2.0 */
/* lie-render SCENE --path PATH.yaml --cache C.lie: lie-build --path and
 * lie-render in one run that builds as it goes.  The cache is built for the
 * path's frames as views, as lie-build --path builds it; before a frame is
 * rendered, the units of the triangles its view sees are built (a unit is
 * the same whenever it is built: lib/lie/lie.h), and any unit the render
 * still met unbuilt (a triangle the view's sampling missed) is built and
 * the frame rendered again, so every frame is the one lie-render makes
 * from the whole cache.  The cache is written after each frame that built
 * something: a run stopped anywhere goes on from it (a partial cache, as
 * lie-build --resume would take). */
#include "cached.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The cache so far, on disk. */
static lie_status save(cached_run *cr, lie_ctor *c, lie_error *err)
{
    lie_cache prov;
    memset(&prov, 0, sizeof prov);
    prov.scene_path = (char *)cr->scene_file;
    prov.scene_hash = cr->scene->hash;
    lie_cache *cache = NULL;
    lie_status st = lie_ctor_cache(c, &prov, &cache, err);
    if (st == LIE_OK)
        st = lie_cache_write(cr->cache_file, cache, NULL, err);
    lie_cache_destroy(cache);
    return st;
}

/* An existing cache must be this run's: the scene, the path's frames as views. */
static lie_status check_cache(const cached_run *cr, const lie_cache *c, const lie_camera *cams, int n,
                              lie_error *err)
{
    const lie_cache_views *v = &c->views;
    int same = c->scene_hash == cr->scene->hash && c->n_edits == 0 && v->n_cams == n &&
               v->width == cr->view_width && v->height == cr->view_height && v->max_depth == cr->ro->max_depth;
    for (int i = 0; same && i < n; i++) {
        lie_camera a = v->cams[i], b = cams[i];
        a.name = b.name = NULL;
        same = memcmp(&a, &b, sizeof a) == 0;
    }
    if (!same)
        return lie_error_set(err, LIE_ERR_ARG, cr->cache_file,
                             "was built for another scene or other views (--path, --view-size, --max-depth)");
    return LIE_OK;
}

lie_status cached_render(cached_run *cr, frame_out *fo, const int *todo, int n_todo, lie_render_stats *rs,
                         double *t_render, double *t_write, int *rendered, lie_error *err)
{
    const lie_camera_path *cp = cr->cpath;
    lie_camera *cams = malloc(sizeof *cams * ((size_t)cp->n_frames + 1));
    uint8_t *met = calloc((size_t)cr->scene->n_tris + 1, 1);
    lie_cache *old = NULL;
    lie_ctor *c = NULL;
    lie_env_shadows *lv = NULL;
    lie_status st = cams && met ? LIE_OK : lie_error_set(err, LIE_ERR_NOMEM, cr->cache_file, "out of memory");
    for (int i = 0; st == LIE_OK && i < cp->n_frames; i++) {
        cams[i] = lie_camera_path_frame(cp, i);
        cams[i].name = NULL;
    }
    struct stat sb;
    if (st == LIE_OK && stat(cr->cache_file, &sb) == 0) {
        st = lie_cache_read(cr->cache_file, &old, err);
        if (st == LIE_OK)
            st = check_cache(cr, old, cams, cp->n_frames, err);
    }
    if (st == LIE_OK) {
        lie_ctor_options co = lie_ctor_options_default();
        co.manual = 1;
        co.view_width = cr->view_width;
        co.view_height = cr->view_height;
        co.max_depth = cr->ro->max_depth;
        co.views = cams;
        co.n_views = cp->n_frames;
        st = lie_ctor_create(cr->scene, cr->rt, &co, old, &c, err);
    }
    if (st == LIE_OK)
        st = lie_env_shadows_create(cr->scene, lie_ctor_env(c), &lv, err);
    if (st == LIE_OK) {
        lie_env_shadows_record_unbuilt(lv, met);
        cr->ro->oracle = lie_env_shadows_oracle(lv);
        cr->ro->visibility = LIE_VIS_LIE;
    }
    for (int k = 0; k < n_todo && st == LIE_OK; k++) {
        int fi = todo[k];
        double ta = lie_time_now();
        uint64_t built = 0, more = 0;
        lie_frame *frame = NULL;
        lie_render_stats fs;
        st = lie_ctor_build(c, NULL, &cams[fi], cr->ro->threads, &built, err);
        for (int pass = 0; st == LIE_OK; pass++) {
            lie_env_shadows_grow(lv, lie_ctor_longest(c));
            memset(met, 0, cr->scene->n_tris);
            lie_frame_destroy(frame);
            frame = NULL;
            st = lie_render(cr->scene, cr->rt, &cams[fi], cr->ro, &frame, &fs, err);
            /* the units the render met unbuilt that a build for the views
             * holds: built, and the frame again (a few thin triangles) */
            if (st == LIE_OK)
                st = lie_ctor_build(c, met, NULL, cr->ro->threads, &more, err);
            if (st != LIE_OK || more == 0)
                break;
            built += more;
            cr->rerenders++;
        }
        cr->units_built += built;
        if (st == LIE_OK && built)
            st = save(cr, c, err);
        double tb = lie_time_now();
        if (st == LIE_OK) {
            (*rendered)++;
            lie_render_stats_add(rs, &fs);
            st = write_frame(fo, fi, &cams[fi], frame, NULL, err);
        }
        lie_frame_destroy(frame);
        *t_render += tb - ta;
        *t_write += lie_time_now() - tb;
    }
    /* The whole path rendered: what is still pending (units a partial cache
     * left whose triangles no frame rendered here met) is built, so the
     * cache is lie-build --path's whole. */
    if (st == LIE_OK && cr->whole) {
        uint64_t built = 0;
        memset(met, 1, cr->scene->n_tris);
        st = lie_ctor_build(c, met, NULL, cr->ro->threads, &built, err);
        if (st == LIE_OK && built)
            st = save(cr, c, err);
        cr->units_built += built;
    }
    cr->ro->oracle = NULL;
    lie_env_shadows_destroy(lv);
    lie_ctor_destroy(c);
    lie_cache_destroy(old);
    free(met);
    free(cams);
    return st;
}
