/* SPDX-License-Identifier: Apache-2.0 */
/* Writing edits (formats/edit.md) with libyaml's emitter: one line per
 * operation, `- KIND: {FIELD: VALUE, ...}`, fields in the order of
 * formats/edit.md, only those the operation holds.  Numbers read back as
 * the values they were written from: a float field (colours, metallic,
 * roughness, emission, light fields) with nine significant digits; a
 * double (move, rotate, scale, weights) with nine when those read back as
 * the same double, else seventeen; a matrix always with seventeen, the form
 * lie-view's undo records have always had. */
#include "edit/internal.h"

#include <yaml.h>

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

typedef struct out_buf {
    unsigned char *data;
    size_t size, cap;
} out_buf;

static int on_write(void *user, unsigned char *buffer, size_t size)
{
    out_buf *b = user;
    if (size > SIZE_MAX - b->size - 1 || !LIE_GROW(b->data, b->cap, b->size + size + 1))
        return 0;
    memcpy(b->data + b->size, buffer, size);
    b->size += size;
    b->data[b->size] = 0;
    return 1;
}

typedef struct writer {
    yaml_emitter_t em;
    int failed;
} writer;

static void emit(writer *w, yaml_event_t *ev, int made)
{
    if (w->failed)
        return;
    if (!made || !yaml_emitter_emit(&w->em, ev))
        w->failed = 1;
}

static void scalar(writer *w, const char *s, yaml_scalar_style_t style)
{
    yaml_event_t ev;
    emit(w, &ev,
         yaml_scalar_event_initialize(&ev, NULL, NULL, (yaml_char_t *)s, (int)strlen(s), 1, 1, style));
}

/* A name (node, file, as): plain when it can be, else quoted ('#3'). */
static void name(writer *w, const char *key, const char *value)
{
    scalar(w, key, YAML_PLAIN_SCALAR_STYLE);
    scalar(w, value ? value : "", YAML_ANY_SCALAR_STYLE);
}

typedef enum number_form { FLOAT_DIGITS, DOUBLE_DIGITS, EXACT_DIGITS } number_form;

static void number(writer *w, double x, number_form form)
{
    char buf[40];
    if (form == FLOAT_DIGITS) {
        snprintf(buf, sizeof buf, "%.9g", x);
    } else {
        snprintf(buf, sizeof buf, "%.9g", x);
        if (form == EXACT_DIGITS || strtod(buf, NULL) != x)
            snprintf(buf, sizeof buf, "%.17g", x);
    }
    scalar(w, buf, YAML_PLAIN_SCALAR_STYLE);
}

static void flow(writer *w, int mapping, int start)
{
    yaml_event_t ev;
    if (mapping)
        emit(w, &ev, start ? yaml_mapping_start_event_initialize(&ev, NULL, NULL, 1, YAML_FLOW_MAPPING_STYLE)
                           : yaml_mapping_end_event_initialize(&ev));
    else
        emit(w, &ev, start ? yaml_sequence_start_event_initialize(&ev, NULL, NULL, 1, YAML_FLOW_SEQUENCE_STYLE)
                           : yaml_sequence_end_event_initialize(&ev));
}

/* KEY: [x0, x1, ...] of doubles, or of floats when f is given */
static void numbers(writer *w, const char *key, const double *d, const float *f, int n, number_form form)
{
    scalar(w, key, YAML_PLAIN_SCALAR_STYLE);
    flow(w, 0, 1);
    for (int i = 0; i < n; i++)
        number(w, f ? (double)f[i] : d[i], form);
    flow(w, 0, 0);
}

static void one(writer *w, const char *key, double x, number_form form)
{
    scalar(w, key, YAML_PLAIN_SCALAR_STYLE);
    number(w, x, form);
}

/* The optional float fields of set-material, set-emission and set-light,
 * in the order formats/edit.md lists them; an operation's `has` holds the
 * bits of its own kind only. */
static const struct {
    unsigned bit;
    const char *key;
    size_t offset;
    int n;
} float_field[] = {
    {LIE_EDIT_HAS_BASE_COLOR, "base-color", offsetof(lie_edit_op, base_color), 3},
    {LIE_EDIT_HAS_METALLIC, "metallic", offsetof(lie_edit_op, metallic), 1},
    {LIE_EDIT_HAS_ROUGHNESS, "roughness", offsetof(lie_edit_op, roughness), 1},
    {LIE_EDIT_HAS_EMISSIVE, "emissive", offsetof(lie_edit_op, emissive), 3},
    {LIE_EDIT_HAS_STRENGTH, "strength", offsetof(lie_edit_op, strength), 1},
    {LIE_EDIT_HAS_COLOR, "color", offsetof(lie_edit_op, color), 3},
    {LIE_EDIT_HAS_INTENSITY, "intensity", offsetof(lie_edit_op, intensity), 1},
    {LIE_EDIT_HAS_RANGE, "range", offsetof(lie_edit_op, range), 1},
    {LIE_EDIT_HAS_INNER, "inner-cone", offsetof(lie_edit_op, inner_deg), 1},
    {LIE_EDIT_HAS_OUTER, "outer-cone", offsetof(lie_edit_op, outer_deg), 1},
};

static void float_fields(writer *w, const lie_edit_op *op)
{
    for (size_t i = 0; i < sizeof float_field / sizeof float_field[0]; i++) {
        if (!(op->has & float_field[i].bit))
            continue;
        const float *f = (const float *)(const void *)((const char *)op + float_field[i].offset);
        if (float_field[i].n == 3)
            numbers(w, float_field[i].key, NULL, f, 3, FLOAT_DIGITS);
        else
            one(w, float_field[i].key, *f, FLOAT_DIGITS);
    }
}

static const char *kind_name(lie_edit_kind k)
{
    static const char *const names[] = {"move",   "move",         "rotate",       "scale",
                                        "set-transform", "remove", "add",  "set-material",
                                        "set-emission",  "set-weights", "set-light", "restore"};
    return (unsigned)k < sizeof names / sizeof names[0] ? names[k] : "?";
}

static void write_op(writer *w, const lie_edit_op *op)
{
    yaml_event_t ev;
    emit(w, &ev, yaml_mapping_start_event_initialize(&ev, NULL, NULL, 1, YAML_BLOCK_MAPPING_STYLE));
    scalar(w, kind_name(op->kind), YAML_PLAIN_SCALAR_STYLE);
    flow(w, 1, 1);
    if (op->kind == LIE_EDIT_ADD)
        name(w, "file", op->file);
    name(w, "node", op->node);
    switch (op->kind) {
    case LIE_EDIT_MOVE_BY:
    case LIE_EDIT_MOVE_TO:
        numbers(w, op->kind == LIE_EDIT_MOVE_BY ? "by" : "to", op->v, NULL, 3, DOUBLE_DIGITS);
        break;
    case LIE_EDIT_ROTATE:
        numbers(w, "axis", op->v, NULL, 3, DOUBLE_DIGITS);
        one(w, "degrees", op->degrees, DOUBLE_DIGITS);
        break;
    case LIE_EDIT_SCALE:
        numbers(w, "by", op->v, NULL, 3, DOUBLE_DIGITS);
        break;
    case LIE_EDIT_SET_TRANSFORM:
        numbers(w, "matrix", op->matrix, NULL, 16, EXACT_DIGITS);
        break;
    case LIE_EDIT_REMOVE:
    case LIE_EDIT_RESTORE:
        break;
    case LIE_EDIT_ADD:
        name(w, "as", op->as);
        if (op->has & LIE_EDIT_HAS_TRANSFORM)
            numbers(w, "transform", op->matrix, NULL, 16, EXACT_DIGITS);
        break;
    case LIE_EDIT_SET_MATERIAL:
    case LIE_EDIT_SET_EMISSION:
        if (op->has & LIE_EDIT_HAS_PRIMITIVE)
            one(w, "primitive", op->primitive, DOUBLE_DIGITS); /* an integer: written as one */
        float_fields(w, op);
        break;
    case LIE_EDIT_SET_LIGHT:
        float_fields(w, op);
        break;
    case LIE_EDIT_SET_WEIGHTS:
        numbers(w, "weights", op->weights, NULL, op->n_weights, DOUBLE_DIGITS);
        break;
    }
    flow(w, 1, 0);
    emit(w, &ev, yaml_mapping_end_event_initialize(&ev));
}

lie_status lie_edit_write_ops(const lie_edit_op *ops, int n_ops, const char *name_for_errors, unsigned char **text,
                              size_t *size, lie_error *err)
{
    *text = NULL;
    *size = 0;
    out_buf b = {calloc(1, 1), 0, 1};
    if (!b.data)
        return lie_error_set(err, LIE_ERR_NOMEM, name_for_errors, "out of memory");
    if (n_ops == 0) { /* no operation: an empty file (a sequence would be "[]") */
        *text = b.data;
        return LIE_OK;
    }
    writer w;
    memset(&w, 0, sizeof w);
    if (!yaml_emitter_initialize(&w.em)) {
        free(b.data);
        return lie_error_set(err, LIE_ERR_NOMEM, name_for_errors, "out of memory");
    }
    yaml_emitter_set_output(&w.em, on_write, &b);
    yaml_emitter_set_width(&w.em, -1); /* one line per operation, however long */
    yaml_emitter_set_unicode(&w.em, 1);
    yaml_event_t ev;
    emit(&w, &ev, yaml_stream_start_event_initialize(&ev, YAML_UTF8_ENCODING));
    emit(&w, &ev, yaml_document_start_event_initialize(&ev, NULL, NULL, NULL, 1));
    emit(&w, &ev, yaml_sequence_start_event_initialize(&ev, NULL, NULL, 1, YAML_BLOCK_SEQUENCE_STYLE));
    for (int i = 0; i < n_ops; i++)
        write_op(&w, &ops[i]);
    emit(&w, &ev, yaml_sequence_end_event_initialize(&ev));
    emit(&w, &ev, yaml_document_end_event_initialize(&ev, 1));
    emit(&w, &ev, yaml_stream_end_event_initialize(&ev));
    const char *problem = w.em.problem;
    yaml_emitter_delete(&w.em);
    if (w.failed) {
        free(b.data);
        return lie_error_set(err, problem ? LIE_ERR_ARG : LIE_ERR_NOMEM, name_for_errors, "cannot write the edit: %s",
                             problem ? problem : "out of memory");
    }
    *text = b.data;
    *size = b.size;
    return LIE_OK;
}

lie_status lie_edit_write(const lie_edit *e, unsigned char **text, size_t *size, lie_error *err)
{
    return lie_edit_write_ops(e->ops, e->n_ops, e->name, text, size, err);
}

lie_status lie_edit_text(const lie_edit *e, unsigned char **text, size_t *size, lie_error *err)
{
    if (!e->text)
        return lie_edit_write(e, text, size, err);
    *text = malloc(e->size + 1);
    if (!*text)
        return lie_error_set(err, LIE_ERR_NOMEM, e->name, "out of memory");
    memcpy(*text, e->text, e->size);
    (*text)[e->size] = 0;
    *size = e->size;
    return LIE_OK;
}
