/* SPDX-License-Identifier: Apache-2.0 */
/* lie-inspect: what its commands share (one command per file). */
#ifndef LIE_INSPECT_H
#define LIE_INSPECT_H

#include "common/cli.h"
#include "lie.h"

extern const char *const inspect_prog;

/* diff: differences listed without --all */
#define INSPECT_DIFF_SHOWN 20

typedef struct inspect_options {
    const char *scene;   /* verify, image: --scene */
    const char *output;  /* image: -o */
    const char *camera;  /* image: --camera */
    int json, quiet, external, all, strict;
    int emitter;         /* image: --emitter, -1 = all */
    int width, height, threads;
    int min_age, dry_run; /* clean */
} inspect_options;

/* clean: temporaries younger than this (seconds) may belong to a live run */
#define INSPECT_CLEAN_MIN_AGE 60

/* Print "lie-inspect: FILE: message" from err; return `code`. */
int inspect_fail(const lie_error *err, int code);
/* Report a failed write to stdout; 0 if stdout is fine, else 1. */
int inspect_stdout_check(void);

/* A JSON string literal; bytes that are not UTF-8 become U+FFFD. */
void inspect_json_string(FILE *fp, const char *s);
/* A string on one line of text: control bytes and backslashes escaped. */
void inspect_text_string(FILE *fp, const char *s);
/* The shortest %g form that reads back as the same float. */
void inspect_fmt_float(float f, char *buf, size_t size);
const char *inspect_emitter_type_name(uint32_t t);
const char *inspect_mode_name(lie_blocker_mode m);

/* A cache read whole: the bytes (for the section table) and the decoded cache. */
typedef struct inspect_cache {
    unsigned char *data;
    size_t size;
    lie_cache *cache;
} inspect_cache;
lie_status inspect_load(const char *path, inspect_cache *l, lie_error *err);
void inspect_unload(inspect_cache *l);

/* Patch paths ordered as their digit strings: a patch before its children. */
int inspect_path_cmp(lie_patch_path a, lie_patch_path b);

/* Visit every node of unit (tri, e) in pre-order with its patch path. */
typedef void (*inspect_node_fn)(void *ctx, uint32_t tri, int e, lie_patch_path path, uint32_t node);
void inspect_walk(const lie_env *env, uint32_t node, uint32_t tri, int e, lie_patch_path path, inspect_node_fn fn,
                  void *ctx);

/* The dump format's fields of one node after its patch name:
 * "CLASS QUALITY COUNT[ : B1 B2 ...]" (the blocker list of a partial leaf). */
void inspect_print_node(FILE *fp, const lie_env *env, const lie_pnode *n);
/* The same as JSON members: "class":..,"quality":..,"count":..[,"blockers":[..]] */
void inspect_json_node(FILE *fp, const lie_env *env, const lie_pnode *n);

int inspect_verify(const char *path, const inspect_options *o);
int inspect_summary(const char *path, const inspect_options *o);
int inspect_dump(const char *path, const inspect_options *o);
int inspect_patch(const char *path, const char *patch, const inspect_options *o);
int inspect_diff(const char *a, const char *b, const inspect_options *o);
int inspect_image(const char *path, const inspect_options *o);
int inspect_clean(const char *dir, const inspect_options *o);

#endif
