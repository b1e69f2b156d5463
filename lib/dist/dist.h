/* SPDX-License-Identifier: Apache-2.0 */
/* lib/dist: the tools' layer over MPI (Open MPI), for lie-render and
 * lie-build started by mpirun.  It is not part of liblie.a: the Makefile
 * builds it into its own archive, linked into those two tools only, so the
 * library stays MPI-free and works through plain entry points
 * (lie_render_tiles, lie_env_build_range, lie_env_join).
 *
 * Without mpirun nothing here touches MPI: lie_dist_start sees none of
 * Open MPI's launch variables and leaves the process a single rank.
 *
 * Failures never hang the job.  Up to lie_dist_check every rank runs the
 * same collective calls in the same order; a rank that fails still enters
 * them with its error (lie_dist_fail), so all ranks learn of it and rank 0
 * reports the first failing rank's error.  After the check, work goes
 * through lie_dist_run, whose ranks report errors in their messages.  A
 * rank that dies (killed, crashed) is mpirun's to notice: it ends the job.
 *
 * One process-wide state (rank, size, phase): MPI's own is process-wide. */
#ifndef LIE_DIST_H
#define LIE_DIST_H

#include "core/core.h"
#include "scene/scene.h"

#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Initialise MPI if mpirun (Open MPI's OMPI_COMM_WORLD_SIZE or PMIx's
 * PMIX_RANK) started this process; MPI_Finalize then runs at exit.
 * Returns the number of ranks (1 without mpirun).  Call once, after option
 * parsing, before reading inputs. */
int lie_dist_start(int *argc, char ***argv);
int lie_dist_rank(void);
int lie_dist_size(void);

/* Load inputs once (the scene with every buffer and image it references,
 * a cache, a camera path): load(ctx, so) runs on rank 0 with so->files
 * recording every file it reads (lie_file_set, lib/core); the files are
 * broadcast, and load runs on the other ranks from them alone, so only
 * rank 0 needs the files ("-", a pipe, works too).  A rank that fails
 * still returns here with its error (for lie_dist_fail); the other ranks
 * fail with "rank 0 could not load it".  Without mpirun: load(ctx, so). */
typedef lie_status (*lie_dist_load_fn)(void *ctx, const lie_scene_options *so, lie_error *err);
lie_status lie_dist_load(const lie_scene_options *so, lie_dist_load_fn load, void *ctx, lie_error *err);

/* Rank 0's size bytes at data on every rank (without mpirun: nothing). */
void lie_dist_bcast(void *data, size_t size);

/* Every rank's setup ends here: ranks compare their binary (a hash of the
 * executable), version and scene and cache hashes with rank 0's.  Returns
 * LIE_OK on every rank when all agree; otherwise an error on every rank, on
 * rank 0 naming the rank and what differs. */
lie_status lie_dist_check(uint64_t scene_hash, uint64_t state_hash, lie_error *err);

/* A tool's exit on error `err`.  Without mpirun: print "prog: err" and
 * return code.  Before lie_dist_check: take part in its exchange with the
 * error, so rank 0 prints the first failing rank's error as
 * "prog: rank R: err" and every rank returns code.  After it: rank 0 prints
 * (the error names the rank), other ranks stay silent. */
int lie_dist_fail(const char *prog, const lie_error *err, int code);

/* ---- dynamic work sharing ----------------------------------------------- */

typedef struct lie_dist_buf {
    unsigned char *data;
    size_t size, cap;
} lie_dist_buf;
/* Append n bytes (a NULL src leaves them uninitialised); the pointer to
 * them, or NULL when out of memory. */
void *lie_dist_buf_add(lie_dist_buf *b, const void *src, size_t n);
void lie_dist_buf_free(lie_dist_buf *b);

/* n_items items handed out dynamically (self-scheduling: a rank that
 * finishes early takes more; each worker keeps two requests open so it
 * never waits for rank 0, which works on items too).  run() computes an
 * item on any rank into out (cleared before); take() consumes it on rank 0,
 * in the order results arrive.  Items are given out in index order. */
typedef struct lie_dist_work {
    size_t n_items;
    void *ctx;
    lie_status (*run)(void *ctx, size_t item, lie_dist_buf *out, lie_error *err);
    lie_status (*take)(void *ctx, size_t item, int rank, const unsigned char *data, size_t size, lie_error *err);
    uint64_t (*units)(void *ctx, size_t item); /* tiles or build units in an item, for statistics */
} lie_dist_work;

typedef struct lie_dist_rank_stats {
    uint64_t items;
    uint64_t units;     /* tiles, build units */
    double seconds;     /* in run() */
    uint64_t bytes;     /* results sent to rank 0 */
} lie_dist_rank_stats;

/* Run the work on every rank.  Returns the first error (on rank 0 naming
 * the rank) on every rank; a worker that failed gets its own error, the
 * others "stopped: another rank failed". */
lie_status lie_dist_run(const lie_dist_work *w, lie_error *err);

/* Bytes broadcast by lie_dist_load; results
 * gathered by the last lie_dist_run (rank 0).  Files broadcast by
 * lie_dist_load. */
uint64_t lie_dist_bytes_broadcast(void);
uint64_t lie_dist_files_broadcast(void);
uint64_t lie_dist_bytes_gathered(void);

/* Rank 0, after lie_dist_run: per-rank items, units (unit_name: "tiles",
 * "units"), seconds in run() and bytes sent, and the bytes broadcast and
 * gathered, as JSON members (,"ranks":[...],...) or human lines.  Nothing
 * without mpirun. */
void lie_dist_stats_print(FILE *fp, const char *unit_name, int json);

#ifdef __cplusplus
}
#endif
#endif
