/* SPDX-License-Identifier: Apache-2.0 */
/* A parallel-for over POSIX threads.  Items are handed out in order (or in
 * a caller's order: the costliest first, so that no long item starts last
 * and leaves the other workers idle) from an atomic counter; callers write
 * only to per-item slots, so results never depend on the schedule
 * (CONTRIBUTING.md, Determinism). */
#include "core/core.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

int lie_cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

double lie_time_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double lie_cpu_time(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0)
        return 0.0;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct job {
    size_t n, total; /* items; their summed weight */
    atomic_size_t next, done;
    const uint32_t *weight;
    const uint32_t *order; /* the k-th item handed out is order[k] (NULL: k) */
    atomic_flag reporting; /* one progress call at a time */
    lie_parallel_fn fn;
    void *ctx;
    lie_progress_fn progress;
    void *pctx;
} job;

typedef struct worker_arg {
    job *j;
    int id;
    double cpu, end; /* the worker's CPU seconds in the loop; when it ran out of items */
} worker_arg;

static double thread_cpu_now(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0)
        return 0.0;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void *worker_main(void *p)
{
    worker_arg *w = p;
    job *j = w->j;
    double cpu0 = thread_cpu_now();
    for (;;) {
        size_t k = atomic_fetch_add(&j->next, 1);
        if (k >= j->n)
            break;
        size_t i = j->order ? j->order[k] : k;
        j->fn(j->ctx, i, w->id);
        size_t wi = j->weight ? j->weight[i] : 1;
        atomic_fetch_add(&j->done, wi);
        /* any worker reports, so a long item on one worker does not stall
         * the bar; done is summed over all of them, and read inside the
         * flag: a count taken before it could be older than the one the
         * previous holder reported, and the bar would go back */
        if (j->progress && !atomic_flag_test_and_set(&j->reporting)) {
            j->progress(j->pctx, atomic_load(&j->done), j->total);
            atomic_flag_clear(&j->reporting);
        }
    }
    w->cpu = thread_cpu_now() - cpu0;
    w->end = lie_time_now();
    return NULL;
}

lie_status lie_parallel_for(size_t n, int threads, lie_parallel_fn fn, void *ctx,
                            lie_progress_fn progress, void *pctx)
{
    return lie_parallel_for_weighted(n, threads, fn, ctx, NULL, progress, pctx);
}

lie_status lie_parallel_for_weighted(size_t n, int threads, lie_parallel_fn fn, void *ctx,
                                     const uint32_t *weight, lie_progress_fn progress, void *pctx)
{
    return lie_parallel_for_ordered(n, threads, fn, ctx, NULL, weight, progress, pctx, NULL);
}

lie_status lie_parallel_for_ordered(size_t n, int threads, lie_parallel_fn fn, void *ctx, const uint32_t *order,
                                    const uint32_t *weight, lie_progress_fn progress, void *pctx,
                                    lie_parallel_report *report)
{
    double t_start = lie_time_now();
    if (threads <= 0)
        threads = lie_cpu_count();
    if ((size_t)threads > n)
        threads = n > 0 ? (int)n : 1;
    job j;
    j.n = n;
    j.weight = weight;
    j.order = order;
    j.total = n;
    if (weight) {
        j.total = 0;
        for (size_t i = 0; i < n; i++)
            j.total += weight[i];
    }
    atomic_flag_clear(&j.reporting);
    if (progress)
        progress(pctx, 0, j.total); /* the start: the bar's clock */
    atomic_init(&j.next, 0);
    atomic_init(&j.done, 0);
    j.fn = fn;
    j.ctx = ctx;
    j.progress = progress;
    j.pctx = pctx;
    worker_arg *args = calloc((size_t)threads, sizeof *args);
    pthread_t *tids = calloc((size_t)threads, sizeof *tids);
    if (!args || !tids) {
        free(args);
        free(tids);
        return LIE_ERR_NOMEM;
    }
    int started = 1;
    for (int t = 0; t < threads; t++) {
        args[t].j = &j;
        args[t].id = t;
    }
    for (int t = 1; t < threads; t++) {
        if (pthread_create(&tids[t], NULL, worker_main, &args[t]) != 0)
            break; /* fewer workers: same result, only slower */
        started++;
    }
    worker_main(&args[0]);
    for (int t = 1; t < started; t++)
        pthread_join(tids[t], NULL);
    if (progress && n > 0)
        progress(pctx, j.total, j.total); /* the end, which a skipped call may have missed */
    if (report) {
        memset(report, 0, sizeof *report);
        report->workers = started;
        report->wall = lie_time_now() - t_start;
        double first_idle = 0.0;
        for (int t = 0; t < started; t++) {
            report->cpu_sum += args[t].cpu;
            if (args[t].cpu > report->cpu_max)
                report->cpu_max = args[t].cpu;
            if (t == 0 || args[t].end < first_idle)
                first_idle = args[t].end;
        }
        report->tail = started > 1 ? lie_time_now() - first_idle : 0.0;
    }
    free(args);
    free(tids);
    return LIE_OK;
}
