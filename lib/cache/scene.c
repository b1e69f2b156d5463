/* SPDX-License-Identifier: Apache-2.0 */
/* The scene a cache was built for: its glTF file plus the edit log. */
#include "cache/cache.h"
#include "edit/edit.h"

#include <stdlib.h>
#include <string.h>

/* Whether every file the `add` operations of e load exists. */
static int adds_resolve(const lie_edit *e, const lie_file_set *files)
{
    char path[4096];
    for (int k = 0; k < e->n_ops; k++)
        if (e->ops[k].kind == LIE_EDIT_ADD &&
            (!lie_edit_add_path(e, &e->ops[k], path, sizeof path) || !lie_file_set_exists(files, path)))
            return 0;
    return 1;
}

/* A logged edit's `add` files are relative to its file's name as recorded
 * (lie_cache_log_relative_to makes it relative to the cache's folder).
 * Like the scene's path: as recorded when they resolve from here, else
 * from the cache's folder, so that a cache loads from any directory. */
static lie_status log_name(lie_edit *e, const char *cache_path, const lie_file_set *files, lie_error *err)
{
    const char *slash = strrchr(cache_path, '/');
    if (e->name[0] == '/' || !slash || adds_resolve(e, files))
        return LIE_OK;
    size_t n = (size_t)(slash - cache_path) + strlen(e->name) + 2;
    char *alt = malloc(n);
    if (!alt)
        return lie_error_set(err, LIE_ERR_NOMEM, cache_path, "out of memory");
    snprintf(alt, n, "%.*s/%s", (int)(slash - cache_path), cache_path, e->name);
    char *was = e->name;
    e->name = alt;
    if (adds_resolve(e, files)) {
        free(was);
        return LIE_OK;
    }
    e->name = was; /* from neither: the errors name them as recorded */
    free(alt);
    return LIE_OK;
}

void lie_cache_log_relative_to(lie_cache *c, int first, const char *cache_path)
{
    if (strcmp(cache_path, "-") == 0)
        return;
    for (int i = first < 0 ? 0 : first; i < c->n_edits; i++) {
        if (c->edits[i].name[0] == '/')
            continue;
        char *rel = lie_path_from_folder_of(c->edits[i].name, cache_path);
        if (!rel)
            continue; /* its folder does not resolve (a name, not a file): kept as given */
        free(c->edits[i].name);
        c->edits[i].name = rel;
    }
}

lie_status lie_cache_log_move(lie_cache *c, int n, const char *from_path, const char *to_path,
                              const lie_file_set *files, lie_error *err)
{
    if (strcmp(to_path, "-") == 0)
        return LIE_OK;
    for (int i = 0; i < n && i < c->n_edits; i++) {
        if (c->edits[i].name[0] == '/')
            continue;
        lie_edit *e = NULL;
        lie_status st = lie_edit_parse(c->edits[i].text, c->edits[i].size, c->edits[i].name, &e, err);
        if (st == LIE_OK)
            st = log_name(e, from_path, files, err);
        char *rel = st == LIE_OK ? lie_path_relative_to_folder_of(e->name, to_path) : NULL;
        lie_edit_destroy(e);
        if (st != LIE_OK)
            return st;
        if (rel) { /* else a folder that does not resolve: kept as recorded */
            free(c->edits[i].name);
            c->edits[i].name = rel;
        }
    }
    return LIE_OK;
}

lie_status lie_cache_load_scene(const lie_cache *c, const char *cache_path, const char *override,
                                const lie_scene_options *so, lie_scene **out, lie_error *err)
{
    *out = NULL;
    const char *path = override ? override : c->scene_path;
    if (!override && strcmp(path, "-") == 0)
        return lie_error_set(err, LIE_ERR_ARG, cache_path,
                             "the cache was built from a scene read from stdin: name its file (--scene)");
    char alt[4096];
    /* a relative path that does not resolve from here: try it relative to
     * the cache's folder (caches travel with their scenes) */
    lie_file_set *files = so ? so->files : NULL; /* files read by another process, if any */
    if (!override && c->scene_path[0] != '/' && !lie_file_set_exists(files, path) && cache_path) {
        const char *slash = strrchr(cache_path, '/');
        if (slash && (size_t)(slash - cache_path) + strlen(path) + 2 < sizeof alt) {
            snprintf(alt, sizeof alt, "%.*s/%s", (int)(slash - cache_path), cache_path, path);
            if (lie_file_set_exists(files, alt))
                path = alt;
        }
    }
    /* the partition the cache was built with (lie-build --emitter-clusters):
     * its largest cluster count reproduces it, as lib/scene/cluster.c
     * splits greedily, the same cuts in the same order for any larger cap */
    lie_scene_options kso = so ? *so : lie_scene_options_default();
    for (int e = 0; e < c->n_emitters; e++)
        if ((int)c->emitters[e].n_clusters > kso.emitter_clusters && c->emitters[e].n_clusters <= LIE_CLUSTER_MAX &&
            (!so || so->emitter_clusters == 0))
            kso.emitter_clusters = (int)c->emitters[e].n_clusters;
    lie_scene *s = NULL;
    lie_status st = lie_scene_load(path, &kso, &s, err);
    if (st != LIE_OK)
        return st;
    if (s->hash != c->scene_hash) {
        lie_error_set(err, LIE_ERR_FORMAT, cache_path,
                      "scene %s has content hash %016llx, the cache was built for %016llx", path,
                      (unsigned long long)s->hash, (unsigned long long)c->scene_hash);
        lie_scene_destroy(s);
        return LIE_ERR_FORMAT;
    }
    for (int i = 0; i < c->n_edits; i++) {
        lie_edit *e = NULL;
        st = lie_edit_parse(c->edits[i].text, c->edits[i].size, c->edits[i].name, &e, err);
        if (st == LIE_OK && cache_path)
            st = log_name(e, cache_path, files, err);
        if (st == LIE_OK)
            st = lie_edit_apply(s, e, so, NULL, err);
        lie_edit_destroy(e);
        if (st != LIE_OK) {
            lie_scene_destroy(s);
            return st;
        }
    }
    if (s->hash != c->state_hash) {
        lie_error_set(err, LIE_ERR_FORMAT, cache_path,
                      "the scene after the edit log has content hash %016llx, the cache expects %016llx",
                      (unsigned long long)s->hash, (unsigned long long)c->state_hash);
        lie_scene_destroy(s);
        return LIE_ERR_FORMAT;
    }
    if (s->n_tris != c->n_tris || s->n_emitters != c->n_emitters) {
        lie_error_set(err, LIE_ERR_FORMAT, cache_path, "the scene has %u triangles and %d emitters, the cache %u and %d",
                      s->n_tris, s->n_emitters, c->n_tris, c->n_emitters);
        lie_scene_destroy(s);
        return LIE_ERR_FORMAT;
    }
    for (int e = 0; e < s->n_emitters; e++) {
        uint32_t dig = lie_scene_cluster_digest(s, e);
        if ((uint32_t)s->emitters[e].n_clusters != c->emitters[e].n_clusters || dig != c->emitters[e].partition) {
            lie_error_set(err, LIE_ERR_FORMAT, cache_path,
                          "emitter %d: the cache splits it into %u clusters (digest %08x), this lie-build into %d "
                          "(%08x): rebuild the cache",
                          e, c->emitters[e].n_clusters, c->emitters[e].partition, s->emitters[e].n_clusters, dig);
            lie_scene_destroy(s);
            return LIE_ERR_FORMAT;
        }
    }
    *out = s;
    return LIE_OK;
}

lie_status lie_cache_set_state(lie_cache *c, const lie_scene *s, lie_error *err)
{
    lie_cache_emitter *em = realloc(c->emitters, sizeof *em * ((size_t)s->n_emitters + 1));
    if (!em)
        return lie_error_set(err, LIE_ERR_NOMEM, s->path, "out of memory");
    c->emitters = em;
    c->n_emitters = s->n_emitters;
    for (int e = 0; e < s->n_emitters; e++) {
        em[e].type = (uint32_t)s->emitters[e].type;
        em[e].node = s->emitters[e].node;
        em[e].first_tri = s->emitters[e].first_tri;
        em[e].n_tris = s->emitters[e].n_tris;
        em[e].n_clusters = (uint32_t)s->emitters[e].n_clusters;
        em[e].partition = lie_scene_cluster_digest(s, e);
    }
    c->n_tris = s->n_tris;
    c->state_hash = s->hash;
    return LIE_OK;
}
