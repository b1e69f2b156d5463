/* Status codes and one-line error messages (STYLE.md 3, 12). */
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

/* Messages are single lines: newlines from third-party strings become spaces. */
static void flatten_line(char *s)
{
    for (; *s; s++)
        if (*s == '\n' || *s == '\r' || *s == '\t')
            *s = ' ';
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
    flatten_line(err->msg);
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

void lie_error_format(const lie_error *err, char *buf, size_t size)
{
    const char *msg = err->msg[0] ? err->msg : lie_status_str(err->status);
    if (err->file[0] && err->line > 0)
        snprintf(buf, size, "%s:%d:%d: %s", err->file, err->line, err->col, msg);
    else if (err->file[0])
        snprintf(buf, size, "%s: %s", err->file, msg);
    else
        snprintf(buf, size, "%s", msg);
}
