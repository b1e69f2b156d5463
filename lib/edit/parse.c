/* SPDX-License-Identifier: Apache-2.0 */
/* Reading edit files (formats/edit.md) with libyaml's document API, which
 * keeps a line and column for every node: each error names file:line:col
 * and the key. */
#include "edit/edit.h"

#include "core/yaml_doc.h"

#include <stdlib.h>
#include <string.h>

static lie_status get_string(lie_yaml *p, const yaml_node_t *n, const char *key, char **out)
{
    const char *s = lie_yaml_scalar(n);
    if (!s || !*s)
        return lie_yaml_error(p, n, key, "expected a name");
    free(*out);
    *out = strdup(s);
    return *out ? LIE_OK : lie_error_set(p->err, LIE_ERR_NOMEM, p->name, "out of memory");
}

/* A transform: 16 numbers (column-major), or {translation, rotation, scale}. */
static lie_status get_transform(lie_yaml *p, const yaml_node_t *n, const char *key, double m[16])
{
    if (n->type == YAML_SEQUENCE_NODE)
        return lie_yaml_numbers(p, n, key, m, 16);
    if (n->type != YAML_MAPPING_NODE)
        return lie_yaml_error(p, n, key, "expected 16 numbers or a mapping of translation, rotation, scale");
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, sc[3] = {1, 1, 1};
    for (yaml_node_pair_t *pr = n->data.mapping.pairs.start; pr < n->data.mapping.pairs.top; pr++) {
        yaml_node_t *kn = yaml_document_get_node(&p->doc, pr->key), *vn = yaml_document_get_node(&p->doc, pr->value);
        const char *k = lie_yaml_scalar(kn);
        char sub[96];
        snprintf(sub, sizeof sub, "%s.%s", key, k ? k : "?");
        lie_status st;
        if (!k || !vn)
            return lie_yaml_error(p, n, key, "keys must be plain names");
        if (strcmp(k, "translation") == 0)
            st = lie_yaml_numbers(p, vn, sub, t, 3);
        else if (strcmp(k, "rotation") == 0)
            st = lie_yaml_numbers(p, vn, sub, q, 4);
        else if (strcmp(k, "scale") == 0)
            st = lie_yaml_numbers(p, vn, sub, sc, 3);
        else
            return lie_yaml_error(p, kn, sub, "unknown key (expected translation, rotation or scale)");
        if (st != LIE_OK)
            return st;
    }
    if (!(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] > 0.0))
        return lie_yaml_error(p, n, key, "rotation is a zero quaternion");
    lie_mat4 r = lie_mat4_from_trs(t, q, sc);
    memcpy(m, r.m, sizeof r.m);
    return LIE_OK;
}

typedef struct field {
    const char *name;
    int seen;
    const yaml_node_t *key, *value;
} field;

/* Collect an operation's fields; unknown keys are errors. */
static lie_status collect(lie_yaml *p, const yaml_node_t *map, const char *op, field *f, int nf)
{
    if (map->type != YAML_MAPPING_NODE)
        return lie_yaml_error(p, map, op, "expected a mapping of the operation's fields");
    for (yaml_node_pair_t *pr = map->data.mapping.pairs.start; pr < map->data.mapping.pairs.top; pr++) {
        yaml_node_t *kn = yaml_document_get_node(&p->doc, pr->key), *vn = yaml_document_get_node(&p->doc, pr->value);
        const char *k = lie_yaml_scalar(kn);
        if (!k || !vn)
            return lie_yaml_error(p, map, op, "keys must be plain names");
        int found = 0;
        for (int i = 0; i < nf; i++)
            if (strcmp(f[i].name, k) == 0) {
                char sub[96];
                snprintf(sub, sizeof sub, "%s.%s", op, k);
                if (f[i].seen)
                    return lie_yaml_error(p, kn, sub, "given twice");
                f[i].seen = 1;
                f[i].key = kn;
                f[i].value = vn;
                found = 1;
            }
        if (!found) {
            char sub[96], what[256];
            snprintf(sub, sizeof sub, "%s.%s", op, k);
            int n = snprintf(what, sizeof what, "unknown key (expected");
            for (int i = 0; i < nf && n < (int)sizeof what; i++)
                n += snprintf(what + n, sizeof what - (size_t)n, "%s %s", i ? "," : "", f[i].name);
            snprintf(what + (n < (int)sizeof what ? n : (int)sizeof what - 1), sizeof what - (size_t)(n < (int)sizeof what ? n : (int)sizeof what - 1), ")");
            return lie_yaml_error(p, kn, sub, what);
        }
    }
    return LIE_OK;
}

/* set-weights: {node, weights: [w0, w1, ...]} (glTF 2.0 §3.7.2.2 morph weights). */
static lie_status parse_set_weights(lie_yaml *p, const yaml_node_t *vn, const char *opk, lie_edit_op *op)
{
    field f[] = {{"node", 0, 0, 0}, {"weights", 0, 0, 0}};
    lie_status st = collect(p, vn, opk, f, 2);
    if (st != LIE_OK)
        return st;
    if (!f[0].seen || !f[1].seen)
        return lie_yaml_error(p, vn, f[0].seen ? "set-weights.weights" : "set-weights.node", "missing");
    op->kind = LIE_EDIT_SET_WEIGHTS;
    if ((st = get_string(p, f[0].value, "set-weights.node", &op->node)) != LIE_OK)
        return st;
    const yaml_node_t *w = f[1].value;
    if (w->type != YAML_SEQUENCE_NODE || w->data.sequence.items.top == w->data.sequence.items.start)
        return lie_yaml_error(p, w, "set-weights.weights", "expected a sequence of one or more numbers");
    int n = (int)(w->data.sequence.items.top - w->data.sequence.items.start);
    if (n > 65536)
        return lie_yaml_error(p, w, "set-weights.weights", "more than 65536 weights");
    op->weights = calloc((size_t)n, sizeof *op->weights);
    if (!op->weights)
        return lie_error_set(p->err, LIE_ERR_NOMEM, p->name, "out of memory");
    op->n_weights = n;
    for (int i = 0; i < n; i++) {
        yaml_node_t *it = yaml_document_get_node(&p->doc, w->data.sequence.items.start[i]);
        if (!it)
            return lie_yaml_error(p, w, "set-weights.weights", "malformed sequence");
        if ((st = lie_yaml_number(p, it, "set-weights.weights", &op->weights[i])) != LIE_OK)
            return st;
    }
    return LIE_OK;
}

/* set-light: {node, color, intensity, range, inner-cone, outer-cone}
 * (KHR_lights_punctual; cone angles in degrees). */
static lie_status parse_set_light(lie_yaml *p, const yaml_node_t *vn, const char *opk, lie_edit_op *op)
{
    field f[] = {{"node", 0, 0, 0},  {"color", 0, 0, 0},      {"intensity", 0, 0, 0},
                 {"range", 0, 0, 0}, {"inner-cone", 0, 0, 0}, {"outer-cone", 0, 0, 0}};
    lie_status st = collect(p, vn, opk, f, 6);
    if (st != LIE_OK)
        return st;
    if (!f[0].seen)
        return lie_yaml_error(p, vn, "set-light.node", "missing");
    if (!f[1].seen && !f[2].seen && !f[3].seen && !f[4].seen && !f[5].seen)
        return lie_yaml_error(p, vn, opk, "needs at least one of color, intensity, range, inner-cone, outer-cone");
    op->kind = LIE_EDIT_SET_LIGHT;
    if ((st = get_string(p, f[0].value, "set-light.node", &op->node)) != LIE_OK)
        return st;
    double c[3], x;
    if (f[1].seen) {
        if ((st = lie_yaml_numbers(p, f[1].value, "set-light.color", c, 3)) != LIE_OK)
            return st;
        for (int k = 0; k < 3; k++) {
            if (!(c[k] >= 0.0 && c[k] <= 1e9))
                return lie_yaml_error(p, f[1].value, "set-light.color", "components must be in [0, 1e9]");
            op->color[k] = (float)c[k];
        }
        op->has |= LIE_EDIT_HAS_COLOR;
    }
    static const struct {
        const char *key;
        double lo, hi;
        unsigned bit;
    } num[4] = {{"set-light.intensity", 0.0, 1e12, LIE_EDIT_HAS_INTENSITY},
                {"set-light.range", 0.0, 1e12, LIE_EDIT_HAS_RANGE},
                {"set-light.inner-cone", 0.0, 90.0, LIE_EDIT_HAS_INNER},
                {"set-light.outer-cone", 0.0, 90.0, LIE_EDIT_HAS_OUTER}};
    float *dst[4] = {&op->intensity, &op->range, &op->inner_deg, &op->outer_deg};
    for (int i = 0; i < 4; i++) {
        if (!f[2 + i].seen)
            continue;
        if ((st = lie_yaml_number(p, f[2 + i].value, num[i].key, &x)) != LIE_OK)
            return st;
        if (!(x >= num[i].lo && x <= num[i].hi)) {
            char what[64];
            snprintf(what, sizeof what, "must be in [%g, %g]", num[i].lo, num[i].hi);
            return lie_yaml_error(p, f[2 + i].value, num[i].key, what);
        }
        *dst[i] = (float)x;
        op->has |= num[i].bit;
    }
    return LIE_OK;
}

/* `primitive: K`: one primitive of the node's own mesh (0-based); the
 * number is converted only once it is known to be an integer in range. */
static lie_status get_primitive(lie_yaml *p, const yaml_node_t *n, const char *key, lie_edit_op *op)
{
    double x = 0.0;
    lie_status st = lie_yaml_number(p, n, key, &x);
    if (st == LIE_OK && !(x >= 0.0 && x <= 65535.0 && x == floor(x)))
        return lie_yaml_error(p, n, key, "expected an integer in [0, 65535]");
    if (st == LIE_OK) {
        op->primitive = (int)x;
        op->has |= LIE_EDIT_HAS_PRIMITIVE;
    }
    return st;
}

static lie_status parse_op(lie_yaml *p, const yaml_node_t *item, int index, lie_edit_op *op)
{
    char key[64];
    snprintf(key, sizeof key, "[%d]", index);
    if (item->type != YAML_MAPPING_NODE || item->data.mapping.pairs.top - item->data.mapping.pairs.start != 1)
        return lie_yaml_error(p, item, key,
                    "expected one operation: move, rotate, scale, set-transform, remove, add, set-material, "
                    "set-emission, set-weights or set-light");
    yaml_node_pair_t *pr = item->data.mapping.pairs.start;
    yaml_node_t *kn = yaml_document_get_node(&p->doc, pr->key), *vn = yaml_document_get_node(&p->doc, pr->value);
    const char *name = lie_yaml_scalar(kn);
    if (!name || !vn)
        return lie_yaml_error(p, item, key, "malformed operation");
    op->line = (int)item->start_mark.line + 1;
    op->col = (int)item->start_mark.column + 1;
    char opk[64];
    snprintf(opk, sizeof opk, "%s", name);
    lie_status st = LIE_OK;
    if (strcmp(name, "move") == 0) {
        field f[] = {{"node", 0, 0, 0}, {"by", 0, 0, 0}, {"to", 0, 0, 0}};
        if ((st = collect(p, vn, opk, f, 3)) != LIE_OK)
            return st;
        if (f[1].seen == f[2].seen)
            return lie_yaml_error(p, vn, opk, "needs exactly one of by or to");
        op->kind = f[1].seen ? LIE_EDIT_MOVE_BY : LIE_EDIT_MOVE_TO;
        const field *v = f[1].seen ? &f[1] : &f[2];
        st = lie_yaml_numbers(p, v->value, f[1].seen ? "move.by" : "move.to", op->v, 3);
        if (st == LIE_OK && !f[0].seen)
            return lie_yaml_error(p, vn, "move.node", "missing");
        if (st == LIE_OK)
            st = get_string(p, f[0].value, "move.node", &op->node);
    } else if (strcmp(name, "rotate") == 0) {
        field f[] = {{"node", 0, 0, 0}, {"axis", 0, 0, 0}, {"degrees", 0, 0, 0}};
        if ((st = collect(p, vn, opk, f, 3)) != LIE_OK)
            return st;
        for (int i = 0; i < 3; i++)
            if (!f[i].seen) {
                char sub[64];
                snprintf(sub, sizeof sub, "rotate.%s", f[i].name);
                return lie_yaml_error(p, vn, sub, "missing");
            }
        op->kind = LIE_EDIT_ROTATE;
        st = get_string(p, f[0].value, "rotate.node", &op->node);
        if (st == LIE_OK)
            st = lie_yaml_numbers(p, f[1].value, "rotate.axis", op->v, 3);
        if (st == LIE_OK && !(op->v[0] * op->v[0] + op->v[1] * op->v[1] + op->v[2] * op->v[2] > 0.0))
            return lie_yaml_error(p, f[1].value, "rotate.axis", "must not be zero");
        if (st == LIE_OK)
            st = lie_yaml_number(p, f[2].value, "rotate.degrees", &op->degrees);
    } else if (strcmp(name, "scale") == 0) {
        field f[] = {{"node", 0, 0, 0}, {"by", 0, 0, 0}};
        if ((st = collect(p, vn, opk, f, 2)) != LIE_OK)
            return st;
        if (!f[0].seen || !f[1].seen)
            return lie_yaml_error(p, vn, f[0].seen ? "scale.by" : "scale.node", "missing");
        op->kind = LIE_EDIT_SCALE;
        st = get_string(p, f[0].value, "scale.node", &op->node);
        if (st == LIE_OK) {
            if (f[1].value->type == YAML_SEQUENCE_NODE) {
                st = lie_yaml_numbers(p, f[1].value, "scale.by", op->v, 3);
            } else {
                st = lie_yaml_number(p, f[1].value, "scale.by", &op->v[0]);
                op->v[1] = op->v[2] = op->v[0];
            }
        }
        if (st == LIE_OK && !(op->v[0] != 0.0 && op->v[1] != 0.0 && op->v[2] != 0.0))
            return lie_yaml_error(p, f[1].value, "scale.by", "a scale factor of 0 would collapse the object");
    } else if (strcmp(name, "set-transform") == 0) {
        field f[] = {{"node", 0, 0, 0}, {"matrix", 0, 0, 0}};
        if ((st = collect(p, vn, opk, f, 2)) != LIE_OK)
            return st;
        if (!f[0].seen || !f[1].seen)
            return lie_yaml_error(p, vn, f[0].seen ? "set-transform.matrix" : "set-transform.node", "missing");
        op->kind = LIE_EDIT_SET_TRANSFORM;
        st = get_string(p, f[0].value, "set-transform.node", &op->node);
        if (st == LIE_OK)
            st = lie_yaml_numbers(p, f[1].value, "set-transform.matrix", op->matrix, 16);
    } else if (strcmp(name, "remove") == 0 || strcmp(name, "restore") == 0) {
        /* {node}: remove, or restore (an undo of remove) */
        field f[] = {{"node", 0, 0, 0}};
        char nkey[16];
        snprintf(nkey, sizeof nkey, "%s.node", name);
        if ((st = collect(p, vn, opk, f, 1)) != LIE_OK)
            return st;
        if (!f[0].seen)
            return lie_yaml_error(p, vn, nkey, "missing");
        op->kind = strcmp(name, "remove") == 0 ? LIE_EDIT_REMOVE : LIE_EDIT_RESTORE;
        st = get_string(p, f[0].value, nkey, &op->node);
    } else if (strcmp(name, "add") == 0) {
        field f[] = {{"file", 0, 0, 0}, {"node", 0, 0, 0}, {"as", 0, 0, 0}, {"transform", 0, 0, 0}};
        if ((st = collect(p, vn, opk, f, 4)) != LIE_OK)
            return st;
        for (int i = 0; i < 3; i++)
            if (!f[i].seen) {
                char sub[64];
                snprintf(sub, sizeof sub, "add.%s", f[i].name);
                return lie_yaml_error(p, vn, sub, "missing");
            }
        op->kind = LIE_EDIT_ADD;
        st = get_string(p, f[0].value, "add.file", &op->file);
        if (st == LIE_OK)
            st = get_string(p, f[1].value, "add.node", &op->node);
        if (st == LIE_OK)
            st = get_string(p, f[2].value, "add.as", &op->as);
        if (st == LIE_OK && f[3].seen) {
            st = get_transform(p, f[3].value, "add.transform", op->matrix);
            op->has |= LIE_EDIT_HAS_TRANSFORM;
        }
    } else if (strcmp(name, "set-material") == 0) {
        field f[] = {{"node", 0, 0, 0},      {"base-color", 0, 0, 0}, {"metallic", 0, 0, 0},
                     {"roughness", 0, 0, 0}, {"primitive", 0, 0, 0}};
        if ((st = collect(p, vn, opk, f, 5)) != LIE_OK)
            return st;
        if (f[4].seen && (st = get_primitive(p, f[4].value, "set-material.primitive", op)) != LIE_OK)
            return st;
        if (!f[0].seen)
            return lie_yaml_error(p, vn, "set-material.node", "missing");
        if (!f[1].seen && !f[2].seen && !f[3].seen)
            return lie_yaml_error(p, vn, opk, "needs at least one of base-color, metallic, roughness");
        op->kind = LIE_EDIT_SET_MATERIAL;
        st = get_string(p, f[0].value, "set-material.node", &op->node);
        double c[3], x;
        if (st == LIE_OK && f[1].seen) {
            st = lie_yaml_numbers(p, f[1].value, "set-material.base-color", c, 3);
            for (int k = 0; st == LIE_OK && k < 3; k++) {
                if (!(c[k] >= 0.0 && c[k] <= 1.0))
                    return lie_yaml_error(p, f[1].value, "set-material.base-color", "components must be in [0, 1]");
                op->base_color[k] = (float)c[k];
            }
            op->has |= LIE_EDIT_HAS_BASE_COLOR;
        }
        if (st == LIE_OK && f[2].seen) {
            st = lie_yaml_number(p, f[2].value, "set-material.metallic", &x);
            if (st == LIE_OK && !(x >= 0.0 && x <= 1.0))
                return lie_yaml_error(p, f[2].value, "set-material.metallic", "must be in [0, 1]");
            op->metallic = (float)x;
            op->has |= LIE_EDIT_HAS_METALLIC;
        }
        if (st == LIE_OK && f[3].seen) {
            st = lie_yaml_number(p, f[3].value, "set-material.roughness", &x);
            if (st == LIE_OK && !(x >= 0.0 && x <= 1.0))
                return lie_yaml_error(p, f[3].value, "set-material.roughness", "must be in [0, 1]");
            op->roughness = (float)x;
            op->has |= LIE_EDIT_HAS_ROUGHNESS;
        }
    } else if (strcmp(name, "set-emission") == 0) {
        field f[] = {{"node", 0, 0, 0}, {"emissive", 0, 0, 0}, {"strength", 0, 0, 0}, {"primitive", 0, 0, 0}};
        if ((st = collect(p, vn, opk, f, 4)) != LIE_OK)
            return st;
        if (f[3].seen && (st = get_primitive(p, f[3].value, "set-emission.primitive", op)) != LIE_OK)
            return st;
        if (!f[0].seen)
            return lie_yaml_error(p, vn, "set-emission.node", "missing");
        if (!f[1].seen && !f[2].seen)
            return lie_yaml_error(p, vn, opk, "needs emissive, strength or both");
        op->kind = LIE_EDIT_SET_EMISSION;
        st = get_string(p, f[0].value, "set-emission.node", &op->node);
        double c[3], x;
        if (st == LIE_OK && f[1].seen) {
            st = lie_yaml_numbers(p, f[1].value, "set-emission.emissive", c, 3);
            for (int k = 0; st == LIE_OK && k < 3; k++) {
                if (!(c[k] >= 0.0 && c[k] <= 1.0))
                    return lie_yaml_error(p, f[1].value, "set-emission.emissive", "components must be in [0, 1]");
                op->emissive[k] = (float)c[k];
            }
            op->has |= LIE_EDIT_HAS_EMISSIVE;
        }
        if (st == LIE_OK && f[2].seen) {
            st = lie_yaml_number(p, f[2].value, "set-emission.strength", &x);
            if (st == LIE_OK && !(x >= 0.0 && x <= 1e9))
                return lie_yaml_error(p, f[2].value, "set-emission.strength", "must be in [0, 1e9]");
            op->strength = (float)x;
            op->has |= LIE_EDIT_HAS_STRENGTH;
        }
    } else if (strcmp(name, "set-weights") == 0) {
        st = parse_set_weights(p, vn, opk, op);
    } else if (strcmp(name, "set-light") == 0) {
        st = parse_set_light(p, vn, opk, op);
    } else {
        return lie_yaml_error(p, kn, opk,
                    "unknown operation (expected move, rotate, scale, set-transform, remove, add, set-material, "
                    "set-emission, set-weights or set-light)");
    }
    return st;
}

void lie_edit_destroy(lie_edit *e)
{
    if (!e)
        return;
    for (int i = 0; i < e->n_ops; i++) {
        free(e->ops[i].node);
        free(e->ops[i].file);
        free(e->ops[i].as);
        free(e->ops[i].weights);
    }
    free(e->ops);
    free(e->name);
    free(e->text);
    free(e);
}

lie_status lie_edit_parse(const unsigned char *text, size_t size, const char *name, lie_edit **out, lie_error *err)
{
    *out = NULL;
    lie_yaml p;
    lie_status lst = lie_yaml_load(&p, text, size, name, err);
    if (lst != LIE_OK)
        return lst;
    lie_status st = LIE_OK;
    lie_edit *e = calloc(1, sizeof *e);
    if (!e || !(e->name = strdup(name)) || !(e->text = malloc(size + 1))) {
        if (e)
            free(e->name);
        free(e);
        lie_yaml_free(&p);
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    }
    memcpy(e->text, text, size);
    e->text[size] = 0;
    e->size = size;
    yaml_node_t *root = yaml_document_get_root_node(&p.doc);
    if (root) {
        if (root->type != YAML_SEQUENCE_NODE) {
            st = lie_yaml_error(&p, root, "document", "expected a sequence of operations (lines starting with '- ')");
        } else {
            int n = (int)(root->data.sequence.items.top - root->data.sequence.items.start);
            e->ops = calloc((size_t)n + 1, sizeof *e->ops);
            if (!e->ops)
                st = lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
            for (int i = 0; st == LIE_OK && i < n; i++) {
                yaml_node_t *it = yaml_document_get_node(&p.doc, root->data.sequence.items.start[i]);
                if (!it) {
                    st = lie_yaml_error(&p, root, "document", "malformed sequence");
                    break;
                }
                e->n_ops = i + 1;
                st = parse_op(&p, it, i, &e->ops[i]);
            }
        }
    }
    lie_yaml_free(&p);
    if (st != LIE_OK) {
        lie_edit_destroy(e);
        return st;
    }
    *out = e;
    return LIE_OK;
}

lie_status lie_edit_parse_fields(const char *kind, const char *fields, const char *name, lie_edit **out, lie_error *err)
{
    *out = NULL;
    size_t n = strlen(fields);
    if (n >= 2 && fields[0] == '{' && fields[n - 1] == '}') { /* braces are optional */
        fields++;
        n -= 2;
    }
    /* the operation with a stand-in node, which the caller replaces */
    char *text = malloc(strlen(kind) + n + 32);
    if (!text)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    int len = sprintf(text, "- %s: {node: x, %.*s}\n", kind, (int)n, fields);
    lie_edit *e = NULL;
    lie_status st = lie_edit_parse((const unsigned char *)text, (size_t)len, name, &e, err);
    free(text);
    if (st == LIE_OK && e->n_ops != 1) {
        lie_edit_destroy(e);
        return lie_error_set(err, LIE_ERR_FORMAT, name, "%s: expected the fields of one operation", kind);
    }
    if (st != LIE_OK)
        return st;
    free(e->ops[0].node);
    e->ops[0].node = NULL;
    e->ops[0].line = e->ops[0].col = 0;
    free(e->text); /* not a file's text */
    e->text = NULL;
    e->size = 0;
    *out = e;
    return LIE_OK;
}
