/* SPDX-License-Identifier: Apache-2.0 */
/* Progress bars on a terminal only (CONTRIBUTING.md, Tools). */
#include "core/core.h"

#include <unistd.h>

void lie_progress_begin(lie_progress *p, FILE *stream, const char *label, int enabled)
{
    p->stream = stream;
    p->label = label;
    p->unit = NULL;
    p->last = 0.0;
    p->start = lie_time_now();
    p->active = enabled && stream && isatty(fileno(stream));
    if (p->active) { /* something shows from the start, before any item is done */
        fprintf(stream, "\r%s ...\033[K", label ? label : "");
        fflush(stream);
    }
}

/* "12.3 s", "4 min 05 s", "1 h 02 min" */
static void put_duration(FILE *fp, double t)
{
    if (!(t >= 0.0) || t > 1e7)
        fputs("?", fp);
    else if (t < 60.0)
        fprintf(fp, "%.1f s", t);
    else if (t < 3600.0)
        fprintf(fp, "%d min %02d s", (int)(t / 60.0), (int)t % 60);
    else
        fprintf(fp, "%d h %02d min", (int)(t / 3600.0), (int)(t / 60.0) % 60);
}

void lie_progress_update(lie_progress *p, size_t done, size_t total)
{
    if (!p->active || total == 0)
        return;
    double now = lie_time_now();
    if (done == 0) { /* the work starts: rate and ETA count from here */
        p->start = now;
        p->last = 0.0;
    }
    if (done < total && now - p->last < 0.25)
        return;
    p->last = now;
    if (done > total)
        done = total;
    int width = 30;
    double frac = (double)done / (double)total, elapsed = now - p->start;
    int fill = (int)(frac * width);
    fprintf(p->stream, "\r%s [", p->label ? p->label : "");
    for (int i = 0; i < width; i++)
        fputc(i < fill ? '#' : ' ', p->stream);
    fprintf(p->stream, "] %3d%% ", (int)(100.0 * frac));
    put_duration(p->stream, elapsed);
    if (elapsed > 0.0 && done > 0) {
        if (p->unit)
            fprintf(p->stream, ", %.4g %s/s", (double)done / elapsed, p->unit);
        else
            fprintf(p->stream, ", %.3g%%/s", 100.0 * frac / elapsed);
        fputs(", ETA ", p->stream);
        put_duration(p->stream, elapsed * (1.0 - frac) / frac);
    }
    fputs("\033[K", p->stream); /* clear what a longer line left */
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
