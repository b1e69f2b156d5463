/* SPDX-License-Identifier: Apache-2.0 */
/* lib/edit: scene edit files (formats/edit.md), read with libyaml, and
 * their application to a scene's document.
 *
 * An edit file is a YAML sequence of operations applied in order.  Nodes
 * are named by their glTF name (which must be unique) or "#index".  Every
 * error carries file, line and column and names the key. */
#ifndef LIE_EDIT_H
#define LIE_EDIT_H

#include "core/core.h"
#include "scene/scene.h"

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

typedef enum lie_edit_kind {
    LIE_EDIT_MOVE_BY = 0,
    LIE_EDIT_MOVE_TO = 1,
    LIE_EDIT_ROTATE = 2,
    LIE_EDIT_SCALE = 3,
    LIE_EDIT_SET_TRANSFORM = 4,
    LIE_EDIT_REMOVE = 5,
    LIE_EDIT_ADD = 6,
    LIE_EDIT_SET_MATERIAL = 7,
    LIE_EDIT_SET_EMISSION = 8,
    LIE_EDIT_SET_WEIGHTS = 9,
    LIE_EDIT_SET_LIGHT = 10,
    LIE_EDIT_RESTORE = 11   /* undo a remove: the node and its subtree come back as they were */
} lie_edit_kind;

/* Which optional fields of set-material / set-emission were given. */
enum {
    LIE_EDIT_HAS_BASE_COLOR = 1 << 0,
    LIE_EDIT_HAS_METALLIC = 1 << 1,
    LIE_EDIT_HAS_ROUGHNESS = 1 << 2,
    LIE_EDIT_HAS_EMISSIVE = 1 << 3,
    LIE_EDIT_HAS_STRENGTH = 1 << 4,
    LIE_EDIT_HAS_COLOR = 1 << 5,     /* set-light */
    LIE_EDIT_HAS_INTENSITY = 1 << 6,
    LIE_EDIT_HAS_RANGE = 1 << 7,
    LIE_EDIT_HAS_TRANSFORM = 1 << 8, /* add */
    LIE_EDIT_HAS_INNER = 1 << 9,
    LIE_EDIT_HAS_OUTER = 1 << 10,
    LIE_EDIT_HAS_PRIMITIVE = 1 << 11 /* set-material, set-emission: one primitive of the node's mesh */
};

typedef struct lie_edit_op {
    lie_edit_kind kind;
    int line, col;         /* where the operation starts, for messages */
    char *node;            /* the node named (for add: the node in `file`) */
    double v[3];           /* move by/to, rotate axis, scale factors */
    double degrees;        /* rotate */
    double matrix[16];     /* set-transform, add's transform (column-major) */
    char *file;            /* add: the glTF file, relative to the edit file */
    char *as;              /* add: the new node's name */
    unsigned has;          /* LIE_EDIT_HAS_* */
    float base_color[3], metallic, roughness, emissive[3], strength;
    int primitive;         /* with LIE_EDIT_HAS_PRIMITIVE: the primitive of the node's own mesh */
    double *weights;       /* set-weights: n_weights morph weights */
    int n_weights;
    float color[3], intensity, range, inner_deg, outer_deg; /* set-light */
} lie_edit_op;

typedef struct lie_edit {
    char *name;            /* the edit file's name as given */
    lie_edit_op *ops;
    int n_ops;
    /* The text it was parsed from (size bytes and a NUL), which a cache's
     * edit log keeps as it was; NULL for an edit built by the constructors
     * below, or appended to since. */
    unsigned char *text;
    size_t size;
} lie_edit;

/* Parse an edit file held in memory; `name` is used in messages and to
 * resolve `add` files.  On success *out is owned by the caller. */
lie_status lie_edit_parse(const unsigned char *text, size_t size, const char *name, lie_edit **out,
                          lie_error *err);
void lie_edit_destroy(lie_edit *e);
/* The file an `add` operation loads: op->file relative to the folder of
 * the edit file's name, or op->file itself when absolute or when the name
 * has no folder.  0 when it does not fit in `cap` bytes. */
int lie_edit_add_path(const lie_edit *e, const lie_edit_op *op, char *path, size_t cap);

/* ---- edits as data (build.c, write.c, inverse.c) -------------------------- */

/* One operation of `kind` ("set-material", ...) from its fields as a
 * program's user gives them, the YAML of formats/edit.md without the node
 * ("base-color: [0.8, 0.2, 0.1], roughness: 0.5"; braces optional): a
 * one-operation edit whose node is NULL, for the caller to set before
 * lie_edit_append.  Errors are the parser's. */
lie_status lie_edit_parse_fields(const char *kind, const char *fields, const char *name, lie_edit **out,
                                 lie_error *err);

/* An empty edit named `name` (messages, and the folder `add` files are
 * relative to); NULL when out of memory. */
lie_edit *lie_edit_create(const char *name);

/* One operation of each kind, ready for lie_edit_append.  Nothing is
 * allocated: the strings and arrays are the caller's, and append copies
 * them.  `has` says which optional fields are given (LIE_EDIT_HAS_*). */
lie_edit_op lie_edit_op_move_by(const char *node, double x, double y, double z);
lie_edit_op lie_edit_op_move_to(const char *node, double x, double y, double z);
lie_edit_op lie_edit_op_rotate(const char *node, double ax, double ay, double az, double degrees);
lie_edit_op lie_edit_op_scale(const char *node, double x, double y, double z);
lie_edit_op lie_edit_op_set_transform(const char *node, const double matrix[16]);
lie_edit_op lie_edit_op_remove(const char *node);
lie_edit_op lie_edit_op_restore(const char *node);
/* matrix NULL: the node keeps its world transform from `file` */
lie_edit_op lie_edit_op_add(const char *file, const char *node, const char *as, const double *matrix);
lie_edit_op lie_edit_op_set_material(const char *node, unsigned has, const float base_color[3], float metallic,
                                     float roughness);
lie_edit_op lie_edit_op_set_emission(const char *node, unsigned has, const float emissive[3], float strength);
lie_edit_op lie_edit_op_set_weights(const char *node, const double *weights, int n_weights);
lie_edit_op lie_edit_op_set_light(const char *node, unsigned has, const float color[3], float intensity, float range,
                                  float inner_deg, float outer_deg);

/* Append a copy of op to e, checked as an edit file's operation is (the
 * parser's message on a bad value; LIE_ERR_ARG without a node).  e drops
 * the text it was parsed from.  On an error e is unchanged. */
lie_status lie_edit_append(lie_edit *e, const lie_edit_op *op, lie_error *err);

/* A float (a viewer's motion, say) as an edit's double: the value of its
 * nine significant digits, which is what the edit's written form holds and
 * reads back as. */
double lie_edit_float_value(float f);

/* Write e as an edit file (formats/edit.md): one `- KIND: {...}` line per
 * operation, through libyaml's emitter; no operation gives an empty text.
 * Parsing the text gives back e's operations, value for value.  *text
 * (size bytes and a NUL) is the caller's to free. */
lie_status lie_edit_write(const lie_edit *e, unsigned char **text, size_t *size, lie_error *err);
/* What a cache's edit log keeps for e: the text it was parsed from, else
 * its written form.  *text is the caller's to free. */
lie_status lie_edit_text(const lie_edit *e, unsigned char **text, size_t *size, lie_error *err);

/* The edit that restores what applying e to s (as it is now, before e)
 * changes: a node's local transform, the first material of each mesh node
 * of a subtree (colour, metallic, roughness, emission), a removal
 * (restore), a restoration (remove), a node's morph weights, a light's
 * fields.  Operations naming no node of s are left out (applying e fails
 * on them).  LIE_ERR_UNSUPPORTED when e adds an object: formats/edit.md has
 * no operation taking it out again.  *out is the caller's. */
lie_status lie_edit_inverse(const lie_scene *s, const lie_edit *e, lie_edit **out, lie_error *err);

/* What an application changed, for lib/update.  Material and emission
 * changes are not listed: they move no blocker list (formats/edit.md). */
typedef struct lie_edit_effect {
    int *nodes;            /* nodes whose world transform, geometry or presence changed */
    int n_nodes;
} lie_edit_effect;
void lie_edit_effect_free(lie_edit_effect *fx);

/* Apply the operations to s's document in order, then re-flatten s.
 * An operation that cannot change what it names (set-emission or
 * set-material on a subtree without meshes, set-light on a node without a
 * punctual light, set-weights on a mesh without morph targets, a transform
 * of a subtree that holds nothing a transform moves) is an error: no edit
 * is silently ignored.  An edit of a skin's joint counts as an edit of
 * every node that skin deforms (fx->nodes).  A set-transform or set-weights
 * to the values a node already has changes nothing and touches nothing.
 * Removed nodes keep their triangle slots as empty (zero-area) triangles
 * and added objects take new slots after all others, so the global
 * triangle indices of untouched objects never change.  `fx` (may be NULL)
 * collects the nodes touched.  On error s may be partly edited. */
lie_status lie_edit_apply(lie_scene *s, const lie_edit *e, const lie_scene_options *opt,
                          lie_edit_effect *fx, lie_error *err);

/* Whether a transform of `node` changes anything: its subtree holds an
 * unskinned mesh, a light, a camera or a skin's joint. */
int lie_edit_transform_matters(const lie_scene *s, int node);

/* Find a node by name or "#index"; a missing or ambiguous name is an error. */
lie_status lie_edit_find_node(const lie_scene *s, const char *name, int *node, const char *file, int line,
                              int col, lie_error *err);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
