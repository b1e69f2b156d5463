/* SPDX-License-Identifier: Apache-2.0 */
/* Status codes and one-line error messages (CONTRIBUTING.md, Errors and Tools). */
#include "core/core.h"

#include <stdarg.h>
#include <string.h>

const char *lie_status_str(lie_status s)
{
    switch (s) {
    case LIE_OK: return "success";
    case LIE_ERR_IO: return "I/O error";
    case LIE_ERR_FORMAT: return "malformed input";
    case LIE_ERR_NOMEM: return "out of memory";
    case LIE_ERR_ARG: return "bad argument";
    case LIE_ERR_RT: return "ray tracing back end failed";
    case LIE_ERR_UNSUPPORTED: return "unsupported";
    case LIE_ERR_LIMIT: return "beyond resource limits";
    case LIE_ERR_NOT_FOUND: return "not found";
    }
    return "unknown error";
}

/* Messages are single lines that reach a terminal: a path read from a cache,
 * a node name or a third-party message may hold a newline or an escape
 * sequence, so control bytes are written as escapes, the way git quotes a
 * path (\n, \t, \033, ...).  Valid UTF-8 passes; C1 controls (U+0080 to
 * U+009F) and bytes that are not UTF-8 become \ooo. */
static size_t utf8_len(const unsigned char *s)
{
    unsigned c = s[0];
    size_t n = c >= 0xf0 && c <= 0xf4 ? 4 : c >= 0xe0 ? 3 : c >= 0xc2 && c < 0xe0 ? 2 : 0;
    if (c >= 0xf5)
        return 0;
    for (size_t i = 1; i < n; i++)
        if ((s[i] & 0xc0) != 0x80)
            return 0;
    if (n == 2 && c == 0xc2 && s[1] < 0xa0)
        return 0; /* C1 control */
    if (n == 3 && ((c == 0xe0 && s[1] < 0xa0) || (c == 0xed && s[1] >= 0xa0)))
        return 0; /* overlong, surrogate */
    if (n == 4 && ((c == 0xf0 && s[1] < 0x90) || (c == 0xf4 && s[1] >= 0x90)))
        return 0;
    return n;
}

void lie_escape_controls(char *out, size_t size, const char *s)
{
    if (size == 0)
        return;
    size_t o = 0;
    const unsigned char *p = (const unsigned char *)s;
    while (*p) {
        char tmp[8];
        size_t len, adv = 1;
        const char *piece = (const char *)p;
        unsigned c = *p;
        if (c >= 0x20 && c < 0x7f) {
            len = 1;
        } else if (c >= 0x80 && (len = utf8_len(p)) > 0) {
            adv = len;
        } else {
            const char *named = c == '\n' ? "\\n" : c == '\t' ? "\\t" : c == '\r' ? "\\r" : NULL;
            if (named)
                len = (size_t)snprintf(tmp, sizeof tmp, "%s", named);
            else
                len = (size_t)snprintf(tmp, sizeof tmp, "\\%03o", c);
            piece = tmp;
        }
        if (o + len >= size)
            break;
        memcpy(out + o, piece, len);
        o += len;
        p += adv;
    }
    out[o] = 0;
}

static void escape_in_place(char *s, size_t size)
{
    char buf[2048];
    lie_escape_controls(buf, sizeof buf < size ? sizeof buf : size, s);
    memcpy(s, buf, strlen(buf) + 1);
}

static lie_status set_v(lie_error *err, lie_status status, const char *file, int line, int col,
                        const char *fmt, va_list ap)
{
    if (!err)
        return status;
    err->status = status;
    err->line = line;
    err->col = col;
    snprintf(err->file, sizeof err->file, "%s", file ? file : "");
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    escape_in_place(err->file, sizeof err->file);
    escape_in_place(err->msg, sizeof err->msg);
    return status;
}

lie_status lie_error_set(lie_error *err, lie_status status, const char *file, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    set_v(err, status, file, 0, 0, fmt, ap);
    va_end(ap);
    return status;
}

lie_status lie_error_set_at(lie_error *err, lie_status status, const char *file, int line, int col,
                            const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    set_v(err, status, file, line, col, fmt, ap);
    va_end(ap);
    return status;
}

void lie_error_clear(lie_error *err)
{
    if (err)
        memset(err, 0, sizeof *err);
}

/* Escapes again (a no-op on what set_v wrote) for errors filled by hand. */
void lie_error_format(const lie_error *err, char *buf, size_t size)
{
    char file[2048], msg[2048];
    lie_escape_controls(file, sizeof file, err->file);
    lie_escape_controls(msg, sizeof msg, err->msg[0] ? err->msg : lie_status_str(err->status));
    if (file[0] && err->line > 0)
        snprintf(buf, size, "%s:%d:%d: %s", file, err->line, err->col, msg);
    else if (file[0])
        snprintf(buf, size, "%s: %s", file, msg);
    else
        snprintf(buf, size, "%s", msg);
}
