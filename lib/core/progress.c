/* Progress bars on a terminal only (CONTRIBUTING.md, Tools). */
#include "core/core.h"

#include <unistd.h>

void lie_progress_begin(lie_progress *p, FILE *stream, const char *label, int enabled)
{
    p->stream = stream;
    p->label = label;
    p->last = 0.0;
    p->active = enabled && stream && isatty(fileno(stream));
}

void lie_progress_update(lie_progress *p, size_t done, size_t total)
{
    if (!p->active || total == 0)
        return;
    double now = lie_time_now();
    if (done < total && now - p->last < 0.25)
        return;
    p->last = now;
    int width = 40;
    int fill = (int)((double)done / (double)total * width);
    fprintf(p->stream, "\r%s [", p->label ? p->label : "");
    for (int i = 0; i < width; i++)
        fputc(i < fill ? '#' : ' ', p->stream);
    fprintf(p->stream, "] %3d%%", (int)(100.0 * (double)done / (double)total));
    fflush(p->stream);
}

void lie_progress_end(lie_progress *p)
{
    if (p->active) {
        fputs("\r\033[K", p->stream);
        fflush(p->stream);
    }
    p->active = 0;
}

void lie_progress_cb(void *pctx, size_t done, size_t total)
{
    lie_progress_update(pctx, done, total);
}
