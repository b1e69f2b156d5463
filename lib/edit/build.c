/* SPDX-License-Identifier: Apache-2.0 */
/* Building edits as data: an empty edit, one constructor per operation,
 * and appending.  An appended operation goes through the writer and the
 * parser (write.c, parse.c), so an edit built here passes exactly the
 * checks an edit file does, and holds exactly what its written form reads
 * back as. */
#include "edit/internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

lie_edit *lie_edit_create(const char *name)
{
    lie_edit *e = calloc(1, sizeof *e);
    if (!e || !(e->name = strdup(name ? name : ""))) {
        free(e);
        return NULL;
    }
    return e;
}

double lie_edit_float_value(float f)
{
    char buf[32];
    snprintf(buf, sizeof buf, "%.9g", (double)f);
    return strtod(buf, NULL);
}

static lie_edit_op op_on(lie_edit_kind kind, const char *node)
{
    lie_edit_op op;
    memset(&op, 0, sizeof op);
    op.kind = kind;
    op.node = (char *)node;
    return op;
}

static lie_edit_op op_v(lie_edit_kind kind, const char *node, double x, double y, double z)
{
    lie_edit_op op = op_on(kind, node);
    op.v[0] = x;
    op.v[1] = y;
    op.v[2] = z;
    return op;
}

lie_edit_op lie_edit_op_move_by(const char *node, double x, double y, double z)
{
    return op_v(LIE_EDIT_MOVE_BY, node, x, y, z);
}

lie_edit_op lie_edit_op_move_to(const char *node, double x, double y, double z)
{
    return op_v(LIE_EDIT_MOVE_TO, node, x, y, z);
}

lie_edit_op lie_edit_op_rotate(const char *node, double ax, double ay, double az, double degrees)
{
    lie_edit_op op = op_v(LIE_EDIT_ROTATE, node, ax, ay, az);
    op.degrees = degrees;
    return op;
}

lie_edit_op lie_edit_op_scale(const char *node, double x, double y, double z)
{
    return op_v(LIE_EDIT_SCALE, node, x, y, z);
}

lie_edit_op lie_edit_op_set_transform(const char *node, const double matrix[16])
{
    lie_edit_op op = op_on(LIE_EDIT_SET_TRANSFORM, node);
    memcpy(op.matrix, matrix, sizeof op.matrix);
    return op;
}

lie_edit_op lie_edit_op_remove(const char *node) { return op_on(LIE_EDIT_REMOVE, node); }

lie_edit_op lie_edit_op_restore(const char *node) { return op_on(LIE_EDIT_RESTORE, node); }

lie_edit_op lie_edit_op_add(const char *file, const char *node, const char *as, const double *matrix)
{
    lie_edit_op op = op_on(LIE_EDIT_ADD, node);
    op.file = (char *)file;
    op.as = (char *)as;
    if (matrix) {
        memcpy(op.matrix, matrix, sizeof op.matrix);
        op.has |= LIE_EDIT_HAS_TRANSFORM;
    }
    return op;
}

lie_edit_op lie_edit_op_set_material(const char *node, unsigned has, const float base_color[3], float metallic,
                                     float roughness)
{
    lie_edit_op op = op_on(LIE_EDIT_SET_MATERIAL, node);
    op.has = has & (LIE_EDIT_HAS_BASE_COLOR | LIE_EDIT_HAS_METALLIC | LIE_EDIT_HAS_ROUGHNESS);
    if ((has & LIE_EDIT_HAS_BASE_COLOR) && base_color)
        memcpy(op.base_color, base_color, sizeof op.base_color);
    op.metallic = metallic;
    op.roughness = roughness;
    return op;
}

lie_edit_op lie_edit_op_set_emission(const char *node, unsigned has, const float emissive[3], float strength)
{
    lie_edit_op op = op_on(LIE_EDIT_SET_EMISSION, node);
    op.has = has & (LIE_EDIT_HAS_EMISSIVE | LIE_EDIT_HAS_STRENGTH);
    if ((has & LIE_EDIT_HAS_EMISSIVE) && emissive)
        memcpy(op.emissive, emissive, sizeof op.emissive);
    op.strength = strength;
    return op;
}

lie_edit_op lie_edit_op_set_weights(const char *node, const double *weights, int n_weights)
{
    lie_edit_op op = op_on(LIE_EDIT_SET_WEIGHTS, node);
    op.weights = (double *)weights;
    op.n_weights = n_weights;
    return op;
}

lie_edit_op lie_edit_op_set_light(const char *node, unsigned has, const float color[3], float intensity, float range,
                                  float inner_deg, float outer_deg)
{
    lie_edit_op op = op_on(LIE_EDIT_SET_LIGHT, node);
    op.has = has & (LIE_EDIT_HAS_COLOR | LIE_EDIT_HAS_INTENSITY | LIE_EDIT_HAS_RANGE | LIE_EDIT_HAS_INNER |
                    LIE_EDIT_HAS_OUTER);
    if ((has & LIE_EDIT_HAS_COLOR) && color)
        memcpy(op.color, color, sizeof op.color);
    op.intensity = intensity;
    op.range = range;
    op.inner_deg = inner_deg;
    op.outer_deg = outer_deg;
    return op;
}

lie_status lie_edit_append(lie_edit *e, const lie_edit_op *op, lie_error *err)
{
    if (!e || !op)
        return lie_error_set(err, LIE_ERR_ARG, e ? e->name : NULL, "lie_edit_append: NULL edit or operation");
    /* a node (and for add a file and a name) the writer can hold */
    if (!op->node || !*op->node || (op->kind == LIE_EDIT_ADD && (!op->file || !*op->file || !op->as || !*op->as)))
        return lie_error_set(err, LIE_ERR_ARG, e->name, "lie_edit_append: the operation needs a %s",
                             !op->node || !*op->node ? "node" : op->file && *op->file ? "new name (as)" : "file");
    unsigned char *text = NULL;
    size_t size = 0;
    lie_status st = lie_edit_write_ops(op, 1, e->name, &text, &size, err);
    if (st != LIE_OK)
        return st;
    lie_edit *one = NULL;
    lie_error sub;
    lie_error_clear(&sub);
    st = lie_edit_parse(text, size, e->name, &one, &sub);
    free(text);
    if (st != LIE_OK) /* the parser's message, without the written line's position */
        return lie_error_set(err, st, e->name, "%s", sub.msg);
    lie_edit_op *ops = realloc(e->ops, sizeof *ops * ((size_t)e->n_ops + 1));
    if (!ops) {
        lie_edit_destroy(one);
        return lie_error_set(err, LIE_ERR_NOMEM, e->name, "out of memory");
    }
    e->ops = ops;
    e->ops[e->n_ops] = one->ops[0];
    e->ops[e->n_ops].line = e->ops[e->n_ops].col = 0;
    e->n_ops++;
    one->n_ops = 0; /* its strings now belong to e */
    lie_edit_destroy(one);
    /* the edit is no longer the text it was parsed from */
    free(e->text);
    e->text = NULL;
    e->size = 0;
    return LIE_OK;
}
