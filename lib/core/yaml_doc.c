/* SPDX-License-Identifier: Apache-2.0 */
/* YAML documents with positions for messages (see yaml_doc.h). */
#include "core/yaml_doc.h"

#include <stdlib.h>
#include <string.h>

/* libyaml keeps a "simple key" per flow level and checks them all at every
 * token, so deep flow nesting costs time quadratic in the depth (100k levels,
 * 200 KB, take a minute); its loader also recurses.  Tokens are scanned
 * first and nesting past LIE_YAML_MAX_DEPTH refused before the depth grows:
 * the scan stops at the first token too deep, while the stacks are small. */
static lie_status check_depth(const unsigned char *text, size_t size, const char *name, lie_error *err)
{
    yaml_parser_t parser;
    if (!yaml_parser_initialize(&parser))
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    yaml_parser_set_input_string(&parser, text, size);
    lie_status st = LIE_OK;
    int depth = 0;
    for (;;) {
        yaml_token_t tok;
        if (!yaml_parser_scan(&parser, &tok))
            break; /* a syntax error: the loader reports it with its position */
        yaml_token_type_t t = tok.type;
        yaml_mark_t at = tok.start_mark;
        yaml_token_delete(&tok);
        if (t == YAML_STREAM_END_TOKEN)
            break;
        if (t == YAML_FLOW_SEQUENCE_START_TOKEN || t == YAML_FLOW_MAPPING_START_TOKEN ||
            t == YAML_BLOCK_SEQUENCE_START_TOKEN || t == YAML_BLOCK_MAPPING_START_TOKEN) {
            if (++depth > LIE_YAML_MAX_DEPTH) {
                st = lie_error_set_at(err, LIE_ERR_LIMIT, name, (int)at.line + 1, (int)at.column + 1,
                                      "YAML nested deeper than %d levels", LIE_YAML_MAX_DEPTH);
                break;
            }
        } else if (t == YAML_FLOW_SEQUENCE_END_TOKEN || t == YAML_FLOW_MAPPING_END_TOKEN ||
                   t == YAML_BLOCK_END_TOKEN) {
            depth--;
        }
    }
    yaml_parser_delete(&parser);
    return st;
}

lie_status lie_yaml_load(lie_yaml *y, const unsigned char *text, size_t size, const char *name, lie_error *err)
{
    memset(y, 0, sizeof *y);
    y->name = name;
    y->err = err;
    lie_status st = check_depth(text, size, name, err);
    if (st != LIE_OK)
        return st;
    yaml_parser_t parser;
    if (!yaml_parser_initialize(&parser))
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    yaml_parser_set_input_string(&parser, text, size);
    if (!yaml_parser_load(&parser, &y->doc)) {
        st = lie_error_set_at(err, LIE_ERR_FORMAT, name, (int)parser.problem_mark.line + 1,
                              (int)parser.problem_mark.column + 1, "YAML: %s",
                              parser.problem ? parser.problem : "syntax error");
        yaml_parser_delete(&parser);
        return st;
    }
    /* One document per file: what follows a "---" would otherwise be
     * dropped unread, even when it is invalid. */
    yaml_document_t next;
    if (!yaml_parser_load(&parser, &next)) {
        st = lie_error_set_at(err, LIE_ERR_FORMAT, name, (int)parser.problem_mark.line + 1,
                              (int)parser.problem_mark.column + 1, "YAML: %s",
                              parser.problem ? parser.problem : "syntax error");
    } else {
        if (yaml_document_get_root_node(&next))
            st = lie_error_set_at(err, LIE_ERR_FORMAT, name, (int)next.start_mark.line + 1,
                                  (int)next.start_mark.column + 1,
                                  "a second YAML document: a file holds one (remove the '---' or '...')");
        yaml_document_delete(&next);
    }
    yaml_parser_delete(&parser);
    if (st != LIE_OK) {
        yaml_document_delete(&y->doc);
        memset(&y->doc, 0, sizeof y->doc);
    }
    return st;
}

void lie_yaml_free(lie_yaml *y) { yaml_document_delete(&y->doc); }

lie_status lie_yaml_error(lie_yaml *y, const yaml_node_t *n, const char *key, const char *what)
{
    return lie_error_set_at(y->err, LIE_ERR_FORMAT, y->name, (int)n->start_mark.line + 1,
                            (int)n->start_mark.column + 1, "%s: %s", key, what);
}

const char *lie_yaml_scalar(const yaml_node_t *n)
{
    return n && n->type == YAML_SCALAR_NODE ? (const char *)n->data.scalar.value : NULL;
}

lie_status lie_yaml_number(lie_yaml *y, const yaml_node_t *n, const char *key, double *out)
{
    const char *s = lie_yaml_scalar(n);
    if (!s || n->data.scalar.style != YAML_PLAIN_SCALAR_STYLE)
        return lie_yaml_error(y, n, key, "expected a number");
    char *end;
    double v = strtod(s, &end);
    if (!*s || *end || !isfinite(v) || strpbrk(s, "xXnNiI"))
        return lie_yaml_error(y, n, key, "expected a number");
    *out = v;
    return LIE_OK;
}

lie_status lie_yaml_numbers(lie_yaml *y, const yaml_node_t *n, const char *key, double *out, int count)
{
    if (n->type != YAML_SEQUENCE_NODE || n->data.sequence.items.top - n->data.sequence.items.start != count) {
        char what[64];
        snprintf(what, sizeof what, "expected a sequence of %d numbers", count);
        return lie_yaml_error(y, n, key, what);
    }
    for (int i = 0; i < count; i++) {
        yaml_node_t *it = yaml_document_get_node(&y->doc, n->data.sequence.items.start[i]);
        if (!it)
            return lie_yaml_error(y, n, key, "malformed sequence");
        lie_status st = lie_yaml_number(y, it, key, &out[i]);
        if (st != LIE_OK)
            return st;
    }
    return LIE_OK;
}
