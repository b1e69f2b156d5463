/* SPDX-License-Identifier: Apache-2.0 */
/* lib/cache: the versioned cache file (.lie) that lie-build writes and the
 * other tools read.  Byte layout: formats/lie-cache.md.
 *
 * A cache records the scene by path and content hash (never a copy), every
 * build parameter, the edit log (empty after lie-build; rst-update appends),
 * a summary of the emitters, and the local illumination environments.  The
 * same scene and parameters always give the same bytes. */
#ifndef LIE_CACHE_H
#define LIE_CACHE_H

#include "core/core.h"
#include "export/export.h"
#include "lie/lie.h"
#include "scene/scene.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

#define LIE_CACHE_VERSION 7u
/* ROOTS entries from version 6 that name no node: the unit is one lone
 * leaf (lie_pnode_lone), unlit or none, which the reader shares. */
#define LIE_CACHE_ROOT_LONE_UNLIT 0xFFFFFFFFu
#define LIE_CACHE_ROOT_LONE_NONE 0xFFFFFFFEu
/* Caches of earlier versions hold units built by earlier rules (their
 * sampling hashed emitter indices, their shaft tolerances read the scene's
 * extent; formats/lie-cache.md, Versions): they still render, but an update
 * or a resumed build would mix their units with units of the present rules,
 * which no fresh build gives.  lie_cache_rules_old says which. */
#define LIE_CACHE_RULES_VERSION 5u
/* optional_flags bit: an interrupted lie-build (env->partial); a reader
 * that ignores it still renders correctly, as the unbuilt units are class
 * none (formats/lie-cache.md) */
#define LIE_CACHE_OPT_PARTIAL 1u

/* What the cache knows of each emitter, to check it against a scene. */
typedef struct lie_cache_emitter {
    uint32_t type;       /* lie_emitter_type */
    int32_t node;        /* glTF node index */
    uint32_t first_tri, n_tris;
    uint32_t n_clusters; /* its clusters (lie_cluster); 1 in versions 1 to 3 */
    uint32_t partition;  /* lie_scene_cluster_digest; 0 for one cluster */
} lie_cache_emitter;

/* One applied edit: the edit file's name as given and its full text
 * (`size` bytes; a decoded cache adds a terminating 0 not counted in size). */
typedef struct lie_cache_edit {
    char *name;
    unsigned char *text;
    size_t size;
} lie_cache_edit;

/* The views a cache was built for: cameras sampled through a width x
 * height image, 2 x 2 rays a pixel, through up to max_depth mirrors. */
typedef struct lie_cache_views {
    lie_camera *cams;        /* owned; names are not kept (NULL) */
    int n_cams;
    int width, height, max_depth;
} lie_cache_views;

typedef struct lie_cache {
    char *scene_path;        /* as given to lie-build */
    uint64_t scene_hash;     /* content hash of the scene as loaded from the file */
    uint64_t state_hash;     /* content hash after the edit log (what env was built for) */
    uint32_t n_tris;
    lie_cache_emitter *emitters;
    int n_emitters;
    lie_cache_edit *edits;
    int n_edits;
    lie_env *env;            /* owned; env->params are the build parameters */
    /* lie-build --view/--path: the views the units were built for (§4.3.1),
     * which an update samples again to keep their decisions (none: every
     * unit was built, as fine as its lists need) */
    lie_cache_views views;
    uint32_t version;        /* the format version it was read from; 0: made in memory (current rules) */
} lie_cache;

/* Whether the cache's units were built by rules older than this library's
 * (read from a file older than LIE_CACHE_RULES_VERSION). */
int lie_cache_rules_old(const lie_cache *c);

/* Free everything the cache owns (env included); NULL is fine. */
void lie_cache_destroy(lie_cache *c);

/* Serialise to a malloc'd buffer (caller frees).  A cache that a reader
 * would reject (inconsistent counts, bad parameters, a malformed env) is
 * refused with LIE_ERR_ARG, so whatever encodes also decodes. */
lie_status lie_cache_encode(const lie_cache *c, unsigned char **data, size_t *size, lie_error *err);
/* Encode and write atomically (temporary file, fsync, rename); "-" = stdout.
 * *bytes (may be NULL) receives the size written. */
lie_status lie_cache_write(const char *path, const lie_cache *c, size_t *bytes, lie_error *err);
/* Write the cache and, when scene_out is not NULL, scene `s` as glTF there
 * (lie_gltf_export_group with scene_opt, NULL: the defaults): every file is
 * complete on disk before any is renamed into place, so a failure (a full
 * disk, say) leaves all or none. */
lie_status lie_cache_write_with_scene(const char *path, const lie_cache *c, const lie_scene *s,
                                      const char *scene_out, const lie_gltf_export_options *scene_opt,
                                      size_t *bytes, lie_error *err);

/* Writing a cache unit by unit, as a build makes them, holding 4 bytes a
 * unit and one unit's tree (lib/cache/cache.c): open with the cache's
 * fields (c->env gives the parameters and counts, its trees are not read),
 * give every unit in unit order, close.  The file is written atomically at
 * close, byte for byte what lie_cache_write gives the same cache with env's
 * partial flag `partial`; until then nothing is at `path` (spills are
 * unlinked temporaries).  "-" is stdout. */
typedef struct lie_cache_stream lie_cache_stream;
lie_status lie_cache_stream_open(const char *path, const lie_cache *c, lie_cache_stream **out, lie_error *err);
/* The next unit: its tree from node `root` of `nodes` (children and lists
 * index nodes and pool), or root a ROOTS tag (LIE_CACHE_ROOT_LONE_*). */
lie_status lie_cache_stream_unit(lie_cache_stream *s, const lie_pnode *nodes, const uint32_t *pool, uint32_t root,
                                 lie_error *err);
/* The nodes and list entries written so far. */
uint64_t lie_cache_stream_nodes(const lie_cache_stream *s);
uint64_t lie_cache_stream_pool(const lie_cache_stream *s);
/* Write the file (once every unit was given) and free s, whatever happens. */
lie_status lie_cache_stream_close(lie_cache_stream *s, int partial, size_t *bytes, lie_error *err);
/* Free s, writing nothing; NULL is fine. */
void lie_cache_stream_abort(lie_cache_stream *s);

/* Parse and validate a whole cache held in memory: magic, version, section
 * table, every size and offset, every checksum, then the structure (tree
 * links, classes, list ranges, triangle indices) — before trusting a byte.
 * `name` is used in messages.  On success *out is owned by the caller. */
lie_status lie_cache_decode(const unsigned char *data, size_t size, const char *name, lie_cache **out,
                            lie_error *err);
/* Read a file ("-" = stdin) and decode it. */
lie_status lie_cache_read(const char *path, lie_cache **out, lie_error *err);

/* Section table of a valid encoding, for `lie-inspect summary`. */
typedef struct lie_cache_section {
    uint32_t id;
    char name[16];
    uint64_t offset, size;
} lie_cache_section;
#define LIE_CACHE_MAX_SECTIONS 32
lie_status lie_cache_sections(const unsigned char *data, size_t size, const char *name,
                              lie_cache_section *out, int *n, lie_error *err);

/* Record the names of edits first .. n_edits - 1 of the log (given relative
 * to the working directory) relative to the folder of cache_path, the file
 * the cache is about to be written to, so that their `add` files resolve
 * from the cache's folder wherever it is loaded from, as its scene does.
 * Absolute names, names whose folder does not exist, and "-" (stdout) stay
 * as they are. */
void lie_cache_log_relative_to(lie_cache *c, int first, const char *cache_path);
/* A log read from the cache at from_path, to be written to to_path: the
 * names of edits 0 .. n - 1 recorded relative (absolute ones stay) are
 * resolved as lie_cache_load_scene resolves them from here (as recorded,
 * or relative to from_path's folder) and recorded relative to to_path's
 * folder instead, so that their `add` files resolve from the new cache's
 * folder as rst-update's log does (lie_cache_log_relative_to).  `files`:
 * as lie_scene_options.files (NULL: the file system).  LIE_ERR_NOMEM, or a
 * logged edit that does not parse. */
lie_status lie_cache_log_move(lie_cache *c, int n, const char *from_path, const char *to_path,
                              const lie_file_set *files, lie_error *err);
/* Load the scene the cache describes: its glTF file (`override`, or the
 * recorded path as given, or that path relative to the cache's folder),
 * checked against scene_hash, with the edit log replayed and the result
 * checked against state_hash.  A logged edit's `add` files resolve the
 * same way: relative to its recorded name's folder as given, or else with
 * that name taken relative to the cache's folder.  `cache_path` (may be
 * NULL) names the cache in messages. */
lie_status lie_cache_load_scene(const lie_cache *c, const char *cache_path, const char *override,
                                const lie_scene_options *so, lie_scene **out, lie_error *err);

/* Record scene s's state in c: its triangle count, the emitter summary and
 * the state hash (lie-build and lib/update make every cache's this way).
 * c->emitters is reallocated; the rest of c is left alone. */
lie_status lie_cache_set_state(lie_cache *c, const lie_scene *s, lie_error *err);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
