/* SPDX-License-Identifier: Apache-2.0 */
/* --script FILE: one command a line, '#' comments (see lie-view --help).
 * A '#' inside single or double quotes is not a comment, so a node is
 * selected by index as edit files name it, `select '#3'` (an unquoted #3
 * would be a comment).  Parsing checks everything it can, so a bad script
 * fails before a window opens. */
#include "view.h"

#include <ctype.h>
#include <stdlib.h>
#include <string.h>

static const struct {
    const char *name;
    view_cmd_kind kind;
    int n_numbers; /* -1: a word or the rest of the line */
} commands[] = {
    {"frames", VIEW_CMD_FRAMES, 1},      {"orbit", VIEW_CMD_ORBIT, 2},
    {"dolly", VIEW_CMD_DOLLY, 1},        {"select", VIEW_CMD_SELECT, -1},
    {"pick", VIEW_CMD_PICK, 2},          {"drag", VIEW_CMD_DRAG, 3},
    {"rotate", VIEW_CMD_ROTATE, 4},      {"set-material", VIEW_CMD_SET_MATERIAL, -1},
    {"set-emission", VIEW_CMD_SET_EMISSION, -1}, {"undo", VIEW_CMD_UNDO, 0},
    {"redo", VIEW_CMD_REDO, 0},          {"wait", VIEW_CMD_WAIT, 0},
    {"screenshot", VIEW_CMD_SCREENSHOT, -1}, {"quit", VIEW_CMD_QUIT, 0},
    {"remove", VIEW_CMD_REMOVE, 0},      {"pause", VIEW_CMD_PAUSE, 0},
    {"resume", VIEW_CMD_RESUME, 0},      {"redraw", VIEW_CMD_REDRAW, 1},
    {"wait-at-most", VIEW_CMD_WAIT_AT_MOST, 1}, {"wait-units", VIEW_CMD_WAIT_UNITS, 1},
};

void view_script_destroy(view_script *s)
{
    if (!s)
        return;
    for (int i = 0; i < s->n; i++) {
        free(s->cmds[i].arg);
        lie_edit_destroy(s->cmds[i].fields);
    }
    free(s->cmds);
    free(s);
}

static char *trim(char *p)
{
    while (isspace((unsigned char)*p))
        p++;
    size_t n = strlen(p);
    while (n > 0 && isspace((unsigned char)p[n - 1]))
        p[--n] = 0;
    return p;
}

/* set-material / set-emission fields, with or without braces: the
 * operation, parsed by lib/edit, its node set when the command runs. */
static lie_status parse_fields(const char *path, int line, const char *op, const char *fields, lie_edit **out,
                               lie_error *err)
{
    lie_error sub;
    lie_error_clear(&sub);
    if (lie_edit_parse_fields(op, fields, path, out, &sub) != LIE_OK)
        return lie_error_set_at(err, LIE_ERR_ARG, path, line, 1, "%s: %s", op, sub.msg);
    return LIE_OK;
}

lie_status view_script_read(const char *path, view_script **out, lie_error *err)
{
    *out = NULL;
    unsigned char *data = NULL;
    size_t size = 0;
    lie_status st = lie_read_file(path, &data, &size, err);
    if (st != LIE_OK)
        return st;
    view_script *s = calloc(1, sizeof *s);
    if (!s) {
        free(data);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    char *text = malloc(size + 1);
    if (!text) {
        free(data);
        free(s);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    memcpy(text, data, size);
    text[size] = 0;
    free(data);
    data = NULL;
    int line = 0;
    for (char *ln = text, *next; ln; ln = next) {
        char *nl = strchr(ln, '\n');
        next = nl ? nl + 1 : NULL;
        if (nl)
            *nl = 0;
        line++;
        /* a comment: '#' outside quotes */
        for (char *q = ln, quote = 0; *q; q++) {
            if (quote) {
                quote = *q == quote ? 0 : quote;
            } else if (*q == '\'' || *q == '"') {
                quote = *q;
            } else if (*q == '#') {
                *q = 0;
                break;
            }
        }
        char *p = trim(ln);
        if (!*p)
            continue;
        char *rest = p;
        while (*rest && !isspace((unsigned char)*rest))
            rest++;
        if (*rest)
            *rest++ = 0;
        rest = trim(rest);
        int k = -1;
        for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
            if (strcmp(p, commands[i].name) == 0)
                k = (int)i;
        if (k < 0) {
            st = lie_error_set_at(err, LIE_ERR_ARG, path, line, 1, "unknown command '%s'", p);
            break;
        }
        view_cmd c;
        memset(&c, 0, sizeof c);
        c.kind = commands[k].kind;
        c.line = line;
        int want = commands[k].n_numbers;
        if (want >= 0) {
            int got = 0;
            char *q = rest;
            while (*q && got < 4) {
                char *end;
                double v = strtod(q, &end);
                if (end == q || !isfinite(v))
                    break;
                c.v[got++] = v;
                q = trim(end);
            }
            if (got != want || *q) {
                st = lie_error_set_at(err, LIE_ERR_ARG, path, line, 1, "%s: expected %d number%s", p, want,
                                      want == 1 ? "" : "s");
                break;
            }
            if (((c.kind == VIEW_CMD_FRAMES || c.kind == VIEW_CMD_REDRAW) &&
                 (c.v[0] < 0 || c.v[0] > 1e6 || c.v[0] != (double)(long)c.v[0])) ||
                (c.kind == VIEW_CMD_REDRAW && c.v[0] < 1) || (c.kind == VIEW_CMD_WAIT_AT_MOST && !(c.v[0] >= 0)) ||
                (c.kind == VIEW_CMD_WAIT_UNITS && !(c.v[0] >= 0 && c.v[0] <= 1e18)) ||
                (c.kind == VIEW_CMD_DOLLY && !(c.v[0] < 1.0))) {
                st = lie_error_set_at(err, LIE_ERR_ARG, path, line, 1, "%s: value out of range", p);
                break;
            }
        } else {
            if (!*rest) {
                st = lie_error_set_at(err, LIE_ERR_ARG, path, line, 1, "%s: missing argument", p);
                break;
            }
            if (c.kind == VIEW_CMD_SET_MATERIAL || c.kind == VIEW_CMD_SET_EMISSION) {
                st = parse_fields(path, line, p, rest, &c.fields, err);
                if (st != LIE_OK)
                    break;
            }
            size_t len = strlen(rest);
            if (c.kind == VIEW_CMD_SELECT && len >= 2 && (rest[0] == '\'' || rest[0] == '"') && rest[len - 1] == rest[0]) {
                rest[len - 1] = 0; /* 'NAME': quoted as in edit files */
                rest++;
            }
            c.arg = strdup(rest);
            if (!c.arg) {
                lie_edit_destroy(c.fields);
                st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
                break;
            }
        }
        view_cmd *nc = realloc(s->cmds, sizeof *nc * ((size_t)s->n + 1));
        if (!nc) {
            free(c.arg);
            lie_edit_destroy(c.fields);
            st = lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
            break;
        }
        s->cmds = nc;
        s->cmds[s->n++] = c;
    }
    free(text);
    if (st != LIE_OK) {
        view_script_destroy(s);
        return st;
    }
    *out = s;
    return LIE_OK;
}
