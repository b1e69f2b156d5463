/* SPDX-License-Identifier: Apache-2.0 */
/* lib/core: status codes and error messages, small vector math, deterministic
 * hashing and sampling, a parallel-for over worker threads, timers, progress
 * bars and atomic file output.  Everything else in lib/ stands on this. */
#ifndef LIE_CORE_H
#define LIE_CORE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

/* ---- status and errors (CONTRIBUTING.md, Errors) ---------------------- */

typedef enum lie_status {
    LIE_OK = 0,
    LIE_ERR_IO = -1,          /* a file could not be opened, read or written */
    LIE_ERR_FORMAT = -2,      /* the input is malformed */
    LIE_ERR_NOMEM = -3,       /* allocation failed */
    LIE_ERR_ARG = -4,         /* a caller passed a bad argument or option */
    LIE_ERR_RT = -5,          /* the ray tracing back end (Embree) failed */
    LIE_ERR_UNSUPPORTED = -6, /* valid input that this version cannot handle */
    LIE_ERR_LIMIT = -7,       /* input claims sizes beyond the resource limits */
    LIE_ERR_NOT_FOUND = -8    /* a named thing (camera, node) does not exist */
} lie_status;

/* A message for the user.  `file` is the input it concerns (may be empty),
 * `line`/`col` are 1-based positions in a text input or 0. */
typedef struct lie_error {
    lie_status status;
    int line, col;
    char file[1024];
    char msg[1024];
} lie_error;

/* Short name of a status ("I/O error", ...). */
const char *lie_status_str(lie_status s);

/* Fill `err` (may be NULL) and return `status`.  `file` may be NULL. */
lie_status lie_error_set(lie_error *err, lie_status status, const char *file,
                         const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
lie_status lie_error_set_at(lie_error *err, lie_status status, const char *file,
                            int line, int col, const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));
void lie_error_clear(lie_error *err);

/* Format `err` as one line "file:line:col: msg" (the parts that apply),
 * without the tool prefix or newline. */
void lie_error_format(const lie_error *err, char *buf, size_t size);

/* ---- vectors and boxes ------------------------------------------------ */

typedef struct lie_vec3 {
    float x, y, z;
} lie_vec3;

typedef struct lie_box3 {
    lie_vec3 lo, hi;
} lie_box3;

static inline lie_vec3 lie_v3(float x, float y, float z) { lie_vec3 r = {x, y, z}; return r; }
static inline lie_vec3 lie_v3_add(lie_vec3 a, lie_vec3 b) { return lie_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline lie_vec3 lie_v3_sub(lie_vec3 a, lie_vec3 b) { return lie_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline lie_vec3 lie_v3_scale(lie_vec3 a, float s) { return lie_v3(a.x * s, a.y * s, a.z * s); }
/* max and min that compile to one instruction (fmaxf/fminf are library
 * calls on x86 for their NaN rules).  A NaN `a` gives b. */
static inline float lie_maxf(float a, float b) { return a > b ? a : b; }
static inline float lie_minf(float a, float b) { return a < b ? a : b; }
/* fminf and fmaxf to the bit, inline: glibc's results for every input
 * (the other argument where one is NaN, b where they compare equal, as
 * between 0 and -0), where the same results must come out as before. */
static inline float lie_fminf(float a, float b) { return a < b || b != b ? a : b; }
static inline float lie_fmaxf(float a, float b) { return a > b || b != b ? a : b; }
/* The largest float below 1 (1 - 2^-24): where a sample coordinate is
 * clamped into [0, 1). */
#define LIE_BELOW_ONE 0x1.fffffep-1f
/* The largest coordinate magnitude of v (NaN coordinates count as 0). */
static inline float lie_v3_maxabs(lie_vec3 v)
{
    return lie_maxf(fabsf(v.x), lie_maxf(fabsf(v.y), lie_maxf(fabsf(v.z), 0.0f)));
}

static inline float lie_v3_dot(lie_vec3 a, lie_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline lie_vec3 lie_v3_cross(lie_vec3 a, lie_vec3 b)
{
    return lie_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float lie_v3_len(lie_vec3 a) { return sqrtf(lie_v3_dot(a, a)); }
static inline lie_vec3 lie_v3_norm(lie_vec3 a)
{
    float l = lie_v3_len(a);
    return l > 0.0f ? lie_v3_scale(a, 1.0f / l) : lie_v3(0.0f, 0.0f, 0.0f);
}
/* (ternaries, not fminf/fmaxf: those are library calls when NaNs must be honoured) */
static inline lie_vec3 lie_v3_min(lie_vec3 a, lie_vec3 b)
{
    return lie_v3(a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z);
}
static inline lie_vec3 lie_v3_max(lie_vec3 a, lie_vec3 b)
{
    return lie_v3(a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z);
}
static inline lie_box3 lie_box3_empty(void)
{
    lie_box3 b = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    return b;
}
static inline void lie_box3_grow(lie_box3 *b, lie_vec3 p)
{
    b->lo = lie_v3_min(b->lo, p);
    b->hi = lie_v3_max(b->hi, p);
}
static inline int lie_box3_is_empty(const lie_box3 *b) { return !(b->lo.x <= b->hi.x); }
/* The coordinate range.  Every world-space position of a scene (a vertex,
 * a light) lies within +-LIE_COORD_MAX, every camera's eye and target within
 * +-LIE_CAMERA_COORD_MAX; scenes, edits, cameras and camera paths are
 * checked where they enter the library (lie_scene_flatten, lie_camera_check),
 * and the viewer clamps its navigation to them.  Why these: Embree works in
 * single precision and stops (an assertion, exit 134) on rays and bounds past
 * about 1.8e18 (its FLT_LARGE); the library multiplies up to three
 * coordinates (areas, plane offsets, determinants), which stay finite in
 * float (3.4e38) below 1e12; a camera may stand a hundred scene sizes away
 * (the default camera of a scene that fills the range stands at 4.5e12). */
#define LIE_COORD_MAX 1e12f
#define LIE_CAMERA_COORD_MAX 1e14f
/* Every coordinate of v within +-max (NaN is not). */
static inline int lie_v3_within(lie_vec3 v, float max)
{
    return fabsf(v.x) <= max && fabsf(v.y) <= max && fabsf(v.z) <= max;
}
/* A sphere around n points, as x, y, z, r: their box's centre and the
 * farthest point's distance, enlarged so rounding never leaves a point out
 * (culling tests may trust it). */
void lie_bound_sphere(const lie_vec3 *p, uint32_t n, float sphere[4]);

/* Orthonormal basis around unit vector n (Duff et al. 2017, branchless). */
void lie_onb(lie_vec3 n, lie_vec3 *t, lie_vec3 *b);

/* 4x4 matrices in double, column-major as glTF stores them: m[col*4+row]. */
typedef struct lie_mat4 {
    double m[16];
} lie_mat4;

lie_mat4 lie_mat4_identity(void);
lie_mat4 lie_mat4_mul(const lie_mat4 *a, const lie_mat4 *b);
/* T * R * S from glTF translation, rotation quaternion (x, y, z, w), scale. */
lie_mat4 lie_mat4_from_trs(const double t[3], const double q[4], const double s[3]);
lie_vec3 lie_mat4_point(const lie_mat4 *m, lie_vec3 p);
lie_vec3 lie_mat4_vector(const lie_mat4 *m, lie_vec3 v);
/* Normal transform: inverse transpose of the upper 3x3 (not normalised). */
lie_vec3 lie_mat4_normal(const lie_mat4 *m, lie_vec3 n);
/* Inverse of an affine transform; returns 0 (and the identity) if singular. */
int lie_mat4_inverse(const lie_mat4 *m, lie_mat4 *out);
/* Rotation by `radians` about unit `axis` (Rodrigues). */
lie_mat4 lie_mat4_rotation(const double axis[3], double radians);
lie_mat4 lie_mat4_translation(double x, double y, double z);
/* Determinant of the upper 3x3 (negative: the transform mirrors). */
double lie_mat4_det3(const lie_mat4 *m);

/* ---- deterministic hashing and sampling (CONTRIBUTING.md, Determinism) - */

/* XXH3-64 of a byte range with a seed. */
uint64_t lie_hash_bytes(const void *data, size_t size, uint64_t seed);
/* Hash of a few 64-bit identities (triangle, path, emitter, sample, pixel...). */
uint64_t lie_hash_u64x4(uint64_t a, uint64_t b, uint64_t c, uint64_t d);
/* Uniform float in [0, 1) from the top 24 bits of a hash. */
static inline float lie_hash_to_unit(uint64_t h) { return (float)(h >> 40) * (1.0f / 16777216.0f); }

/* Van der Corput radical inverse in base 2 (Hammersley's second axis). */
static inline float lie_radical_inverse2(uint32_t i)
{
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return (float)(i >> 8) * (1.0f / 16777216.0f);
}

/* Streaming hash state for content hashes (XXH3-64). */
typedef struct lie_hasher lie_hasher;
lie_hasher *lie_hasher_create(uint64_t seed);
void lie_hasher_update(lie_hasher *h, const void *data, size_t size);
uint64_t lie_hasher_digest(const lie_hasher *h);
void lie_hasher_destroy(lie_hasher *h);

/* Uniform point on a triangle from (u1, u2) in [0,1)^2, as barycentrics
 * (b1, b2) of vertices 1 and 2 (Heitz 2019's low-distortion map would do
 * too; the square-root map keeps strata contiguous). */
void lie_sample_triangle(float u1, float u2, float *b1, float *b2);

/* ---- growable arrays -------------------------------------------------- */

/* Make the heap array *arr (a pointer to any object pointer; capacity *cap
 * elements of `size` bytes) hold at least `need` elements: the capacity
 * doubles from at least 8, so appends cost O(1) amortised.  Returns 1, or 0
 * when out of memory (then *arr and *cap are unchanged). */
int lie_grow(void *arr, size_t *cap, size_t need, size_t size);
/* The same for an array `a` with a size_t capacity `cap`; the common case
 * (room already) costs one compare. */
#define LIE_GROW(a, cap, need) ((size_t)(need) <= (cap) || lie_grow(&(a), &(cap), (need), sizeof *(a)))
/* Append v to array a of n elements (LIE_GROW); 1, or 0 when out of memory. */
#define LIE_PUSH(a, n, cap, v) (LIE_GROW(a, cap, (size_t)(n) + 1) ? ((a)[(n)++] = (v), 1) : 0)

/* Release p and reset it to NULL: a struct's array freed so that the
 * struct can be filled again (or freed again) safely. */
#define LIE_FREE(p)                                                                                                   \
    do {                                                                                                              \
        free(p);                                                                                                      \
        (p) = NULL;                                                                                                   \
    } while (0)

/* ---- threads ---------------------------------------------------------- */

/* Number of online CPUs (at least 1). */
int lie_cpu_count(void);

/* Calls fn(ctx, item, worker) for every item in [0, n) on `threads` workers
 * (0 = all cores), items handed out in order from a shared counter.  fn must
 * write only to slots owned by `item`, so the result does not depend on the
 * schedule.  `progress` (may be NULL) is called by whichever worker finishes
 * an item (one call at a time; a worker that finds another reporting skips
 * its call), with the number of items all workers finished so far, and
 * once with 0 before any item starts and once with the total after the last. */
typedef void (*lie_parallel_fn)(void *ctx, size_t item, int worker);
typedef void (*lie_progress_fn)(void *pctx, size_t done, size_t total);
lie_status lie_parallel_for(size_t n, int threads, lie_parallel_fn fn, void *ctx,
                            lie_progress_fn progress, void *pctx);
/* The same with a weight per item (its expected work; NULL: 1 each):
 * progress gets the summed weight of the items finished and the total. */
lie_status lie_parallel_for_weighted(size_t n, int threads, lie_parallel_fn fn, void *ctx,
                                     const uint32_t *weight, lie_progress_fn progress, void *pctx);
/* What a parallel-for spent: per-worker CPU seconds (the thread's own clock,
 * so other processes on the machine do not count) summed and at most, and
 * the wall seconds from the first worker out of items to the end (the tail
 * of the schedule, where cores idle). */
typedef struct lie_parallel_report {
    int workers;
    double wall, cpu_sum, cpu_max, tail;
} lie_parallel_report;
/* The same, handing out item order[k] k-th (a permutation of [0, n); NULL:
 * in order), for example the costliest first; report may be NULL. */
lie_status lie_parallel_for_ordered(size_t n, int threads, lie_parallel_fn fn, void *ctx, const uint32_t *order,
                                    const uint32_t *weight, lie_progress_fn progress, void *pctx,
                                    lie_parallel_report *report);

/* ---- time and progress ------------------------------------------------ */

double lie_time_now(void); /* seconds, monotonic */
double lie_cpu_time(void); /* the process's CPU seconds, user and system, over all threads */

/* A progress bar on `stream` if it is a terminal and `enabled`, redrawn at
 * most a few times a second, with the elapsed time, the rate (in `unit`s
 * per second when a unit is set, else percent) and the time left at that
 * rate, counted from the last update with done = 0 (lie_parallel_for makes
 * one as it starts).  label may hold "frame N/M" for paths. */
typedef struct lie_progress {
    FILE *stream;
    int active;
    double last;
    const char *label;
    const char *unit;  /* what done and total count ("tiles"), or NULL */
    double start;      /* lie_time_now() at begin */
} lie_progress;
void lie_progress_begin(lie_progress *p, FILE *stream, const char *label, int enabled);
void lie_progress_update(lie_progress *p, size_t done, size_t total);
void lie_progress_end(lie_progress *p);
/* Adapter for lie_parallel_for: pctx is a lie_progress. */
void lie_progress_cb(void *pctx, size_t done, size_t total);

/* ---- atomic output (CONTRIBUTING.md, Files) --------------------------- */

/* Writes go to a temporary file in the target's directory; commit fsyncs
 * and renames it over the target, abort removes it.  Path "-" writes
 * straight to stdout (commit flushes).  A symlink is followed and its target
 * replaced in the target's folder; an existing device or FIFO is written in
 * place, without a temporary.  Temporaries are removed on SIGINT, SIGTERM
 * and SIGHUP (where those still have their default action: a handler is
 * installed on first use, unlinks, then re-raises); a signal that comes while
 * a commit renames waits until the commit is done.  SIGKILL leaves them, see
 * lie_tmp_clean.  A replaced file keeps its mode, owner and group; when
 * the owner cannot be kept (another user's file, and we are not root) the
 * open fails.  Owns the FILE. */
typedef struct lie_atomic_group lie_atomic_group;
typedef struct lie_atomic_file {
    FILE *fp;
    char path[4096];   /* as given, for messages */
    char target[4096]; /* the file replaced: path with symlinks followed */
    char tmp[4096];
    int is_stdout, in_place, slot, no_replace;
    lie_atomic_group *group;
} lie_atomic_file;
lie_status lie_atomic_open(lie_atomic_file *af, const char *path, lie_error *err);
/* LIE_ATOMIC_NO_REPLACE: create the file, never replace one: the open fails
 * with "exists" when the target exists, and the commit (renameat2's
 * RENAME_NOREPLACE, or link and unlink) fails the same way, replacing
 * nothing, when one appeared meanwhile.  `group` may be NULL. */
enum { LIE_ATOMIC_NO_REPLACE = 1 };
lie_status lie_atomic_open_flags(lie_atomic_file *af, const char *path, lie_atomic_group *group, unsigned flags,
                                 lie_error *err);
lie_status lie_atomic_commit(lie_atomic_file *af, lie_error *err);
void lie_atomic_abort(lie_atomic_file *af);

/* All outputs of one run visible together or none: a file opened into a
 * group is, on commit, complete and fsynced but left as its temporary;
 * lie_atomic_group_commit renames them all: first those opened
 * LIE_ATOMIC_NO_REPLACE (when one finds its name taken, those placed are
 * taken back and nothing is replaced), then the others in commit order (a
 * rename failing part way, which needs an I/O error on the folder itself,
 * leaves the earlier ones in place).  SIGINT, SIGTERM and SIGHUP wait for
 * the end of the renames.  Destroy removes temporaries not renamed; accepts
 * NULL. */
lie_atomic_group *lie_atomic_group_create(void);
lie_status lie_atomic_open_group(lie_atomic_file *af, const char *path, lie_atomic_group *group, lie_error *err);
lie_status lie_atomic_group_commit(lie_atomic_group *g, lie_error *err);
void lie_atomic_group_destroy(lie_atomic_group *g);

/* Remove the stale temporaries lie_atomic_open leaves when a process is
 * killed (".NAME.tmpXXXXXX"): regular files of this user in `dir` not
 * modified for `min_age` seconds; `fn` (may be NULL) is told each name. */
typedef void (*lie_tmp_clean_fn)(void *ctx, const char *name, uint64_t bytes);
lie_status lie_tmp_clean(const char *dir, double min_age, int dry_run, lie_tmp_clean_fn fn, void *ctx,
                         lie_error *err);

/* ---- inputs ------------------------------------------------------------- */

/* Size limits of inputs: caches, EXR images (the default), glTF files and
 * their buffers and images (4 GiB - 1: a GLB's length is 32-bit), YAML edit
 * files and camera paths. */
#define LIE_READ_MAX_DEFAULT (UINT64_C(16) << 30)
#define LIE_READ_MAX_GLTF (UINT64_C(0xFFFFFFFF) - 1)
#define LIE_READ_MAX_TEXT (UINT64_C(64) << 20)

/* Open an input: non-blocking, so a FIFO or device cannot hang the open,
 * then fstat: only a regular file of at most `max` bytes.  The descriptor
 * (blocking again, close-on-exec) is the caller's. */
lie_status lie_input_open(const char *path, uint64_t max, int *fd, uint64_t *size, lie_error *err);
/* Read fd to its end into a malloc'd buffer, failing beyond `max` bytes;
 * `hint` is the expected size (0: unknown).  `name` is for messages. */
lie_status lie_read_fd(int fd, const char *name, uint64_t max, uint64_t hint, unsigned char **data, size_t *size,
                       lie_error *err);
/* Read a whole input ("-" = stdin) into a malloc'd buffer; *size set.
 * lie_read_file allows LIE_READ_MAX_DEFAULT bytes. */
lie_status lie_read_file_max(const char *path, uint64_t max, unsigned char **data, size_t *size, lie_error *err);
lie_status lie_read_file(const char *path, unsigned char **data, size_t *size, lie_error *err);
/* `path` (relative to the working directory) written relative to the
 * folder of file `other` instead, so that it names the same file from
 * there: a malloc'd string, or NULL when either folder cannot be resolved
 * (realpath) or memory runs out.  An absolute path comes back as it is. */
char *lie_path_from_folder_of(const char *path, const char *other);
/* The same for an absolute `path` too: the relative path that names it
 * from the folder of `other`. */
char *lie_path_relative_to_folder_of(const char *path, const char *other);

/* ---- file sets: inputs held in memory (fileset.c) ------------------------
 * The files a load read (a scene with its buffers and images, a cache, a
 * camera path), each under the path it was opened by, so that another
 * process can repeat the load from memory: lib/dist reads them on rank 0
 * and broadcasts them under mpirun.  A reader given a set
 * (lie_scene_options.files) takes a file from it when the set holds its
 * path; otherwise LIE_FILES_RECORD reads the file system (with all the
 * reader's checks) and adds what it read, LIE_FILES_ONLY fails with
 * "cannot open: " LIE_FILE_SET_MISSING.  A NULL set means the file system.
 * Not thread-safe: one load at a time. */
typedef enum {
    LIE_FILES_RECORD,
    LIE_FILES_ONLY,
    LIE_FILES_NAMES /* like RECORD, but only the names and identities of the files read are kept, not
                     * their bytes: a run's inputs, for lie_file_set_claim */
} lie_file_set_mode;
typedef struct lie_file_set lie_file_set;
#define LIE_FILE_SET_MISSING "not among the files read by the first process"
/* NULL when out of memory; destroy accepts NULL. */
lie_file_set *lie_file_set_create(lie_file_set_mode mode);
void lie_file_set_destroy(lie_file_set *set);
lie_file_set_mode lie_file_set_get_mode(const lie_file_set *set);
size_t lie_file_set_count(const lie_file_set *set);
uint64_t lie_file_set_bytes(const lie_file_set *set);
/* The bytes held for path, or NULL; owned by the set. */
const unsigned char *lie_file_set_find(const lie_file_set *set, const char *path, size_t *size);
/* Add a copy of data under path; a path held already keeps its bytes. */
lie_status lie_file_set_add(lie_file_set *set, const char *path, const void *data, size_t size, lie_error *err);
/* lie_read_file_max through the set (see above); *data is the caller's. */
lie_status lie_file_set_read(lie_file_set *set, const char *path, uint64_t max, unsigned char **data, size_t *size,
                             lie_error *err);
/* Could path be read: held, or (not LIE_FILES_ONLY) it exists on disk. */
int lie_file_set_exists(const lie_file_set *set, const char *path);
/* A run's inputs and outputs (CONTRIBUTING.md, Files): an output must be
 * neither an input nor another output of the run.  lie_file_set_note adds
 * an input read outside the set (its identity: device and inode); _note_all
 * adds every input of `from`.  lie_file_set_claim checks an output about to
 * be written against every input and every output claimed before, as the
 * same file (device and inode) or, for one not there yet, the same resolved
 * path, and claims it; "-", devices and FIFOs always pass.  `replaces`
 * (may be NULL) names the one input this output is the new version of (a
 * cache updated in place), which it may replace.  The error: "OUT: is also
 * the input IN: refusing to write over it".  set NULL: nothing is checked. */
lie_status lie_file_set_note(lie_file_set *set, const char *path, lie_error *err);
lie_status lie_file_set_note_all(lie_file_set *set, const lie_file_set *from, lie_error *err);
lie_status lie_file_set_claim(lie_file_set *set, const char *path, const char *replaces, lie_error *err);
/* The same check, without claiming: for the many outputs of a pattern
 * (frame_%04d.exr), distinct by construction. */
lie_status lie_file_set_check(lie_file_set *set, const char *path, lie_error *err);
/* The set as one malloc'd buffer, and back (the result is LIE_FILES_ONLY;
 * every length is checked). */
lie_status lie_file_set_pack(const lie_file_set *set, unsigned char **data, size_t *size, lie_error *err);
lie_status lie_file_set_unpack(const unsigned char *data, size_t size, lie_file_set **out, lie_error *err);

/* Escape control bytes (C0, DEL, C1) and invalid UTF-8 in s for a one-line
 * message, as git quotes paths: \n \t \r \033 ...  Writes at most size bytes
 * with a terminating NUL. */
void lie_escape_controls(char *out, size_t size, const char *s);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
