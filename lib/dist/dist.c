/* SPDX-License-Identifier: Apache-2.0 */
/* The tools' MPI layer (lib/dist/dist.h).
 * Size: one job, the MPI layer: start, broadcast, the setup check and the work
 * sharing share the communicator state. */
#include "common/cli.h" /* lie_report_error: lib/dist is linked into tools only */
#include "dist/dist.h"
#include "lie.h"

#include <link.h> /* dl_iterate_phdr: the build ID */
#include <mpi.h>
#include <pthread.h>
#include <time.h>
#include <sys/stat.h>
#include <sys/resource.h>
#include <stdlib.h>
#include <string.h>

static struct {
    int active;        /* MPI initialised */
    int rank, size;
    int checked;       /* lie_dist_check passed: errors now travel in lie_dist_run's messages */
    int serialized;    /* MPI may be called from another thread than the main one */
    uint64_t bcast_bytes, bcast_files;
    int argc;          /* the command line (main's argv, borrowed): every rank must share it */
    char **argv;
    /* the last lie_dist_run, for statistics (rank 0) */
    lie_dist_rank_stats *per_rank;
    size_t n_items;
    double service_cpu;
} dist = {0, 0, 1, 0, 0, 0, 0, 0, NULL, NULL, 0, 0.0};

enum { TAG_REQ = 1, TAG_RES, TAG_ERR, TAG_ITEM };
#define ITEM_DONE (-1)
#define ITEM_ABORT (-2)
#define REQUESTS_OPEN 2 /* per worker: one item in hand, one on its way */
#define MSG_MAX 1400

#ifdef __SANITIZE_ADDRESS__
#include <dlfcn.h>
/* LeakSanitizer reports what Open MPI's plugins keep to the end
 * (tests/lsan-mpi.supp suppresses it by module); a plugin unloaded before
 * the report would be an unnamed module no suppression can match, so in
 * sanitizer builds every loaded Open MPI plugin is made resident. */
static int keep_plugin(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size;
    (void)data;
    if (info->dlpi_name && strstr(info->dlpi_name, "/openmpi/"))
        dlopen(info->dlpi_name, RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);
    return 0;
}
static void keep_plugins(void) { dl_iterate_phdr(keep_plugin, NULL); }
#else
static void keep_plugins(void) {}
#endif

static void finish(void)
{
    int fin = 0;
    MPI_Finalized(&fin);
    if (!fin) {
        keep_plugins();
        MPI_Finalize();
    }
}

int lie_dist_start(int *argc, char ***argv)
{
    if (dist.active)
        return dist.size;
    if (!getenv("OMPI_COMM_WORLD_SIZE") && !getenv("PMIX_RANK"))
        return 1;
    int provided = 0;
    /* one thread at a time: rank 0's service thread during lie_dist_run,
     * the main thread otherwise; render and build threads never call MPI */
    if (MPI_Init_thread(argc, argv, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS)
        return 1;
    keep_plugins();
    dist.serialized = provided >= MPI_THREAD_SERIALIZED;
    MPI_Comm_rank(MPI_COMM_WORLD, &dist.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &dist.size);
    dist.argc = *argc;
    dist.argv = *argv;
    dist.active = 1;
    atexit(finish);
    return dist.size;
}

int lie_dist_rank(void) { return dist.rank; }
int lie_dist_size(void) { return dist.size; }
uint64_t lie_dist_bytes_broadcast(void) { return dist.bcast_bytes; }
uint64_t lie_dist_files_broadcast(void) { return dist.bcast_files; }

uint64_t lie_dist_bytes_gathered(void)
{
    uint64_t n = 0;
    for (int r = 0; dist.per_rank && r < dist.size; r++)
        n += dist.per_rank[r].bytes;
    return n;
}

/* MPI counts are ints: large buffers go in pieces. */
#define PIECE (1 << 30)

static void bcast_bytes(unsigned char *p, size_t n)
{
    for (size_t off = 0; off < n; off += PIECE) {
        size_t k = n - off < PIECE ? n - off : PIECE;
        MPI_Bcast(p + off, (int)k, MPI_BYTE, 0, MPI_COMM_WORLD);
    }
}

void lie_dist_bcast(void *data, size_t size)
{
    if (dist.active)
        bcast_bytes(data, size);
}

lie_status lie_dist_load(const lie_scene_options *so, lie_dist_load_fn load, void *ctx, lie_error *err)
{
    if (!dist.active || dist.size == 1)
        return load(ctx, so, err);
    lie_scene_options o = *so;
    lie_file_set *set = NULL;
    unsigned char *packed = NULL;
    size_t size = 0;
    uint64_t head[3] = {0, 0, 0}; /* status, packed size, files */
    lie_status st = LIE_OK;
    if (dist.rank == 0) {
        set = lie_file_set_create(LIE_FILES_RECORD);
        st = set ? LIE_OK : lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
        o.files = set;
        if (st == LIE_OK)
            st = load(ctx, &o, err);
        if (st == LIE_OK)
            st = lie_file_set_pack(set, &packed, &size, err);
        if (st == LIE_OK) /* the caller's record of the run's inputs (lie_file_set_claim) */
            st = lie_file_set_note_all(so->files, set, err);
        head[0] = (uint64_t)(int64_t)st;
        head[1] = size;
        head[2] = lie_file_set_count(set);
        lie_file_set_destroy(set);
        set = NULL;
    }
    MPI_Bcast(head, 3, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    lie_status st0 = (lie_status)(int64_t)head[0];
    if (st0 != LIE_OK) { /* rank 0's own error is the one reported (lie_dist_fail) */
        free(packed);
        return dist.rank == 0 ? st : lie_error_set(err, st0, NULL, "rank 0 could not load its inputs");
    }
    /* every rank allocates, so an out-of-memory rank still takes part */
    if (dist.rank != 0)
        packed = malloc((size_t)head[1] + 1);
    int ok = packed != NULL, all = 0;
    MPI_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (!all) {
        free(packed);
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory for the %llu bytes of the inputs%s",
                             (unsigned long long)head[1], ok ? " on another rank" : "");
    }
    bcast_bytes(packed, (size_t)head[1]);
    dist.bcast_bytes += head[1] * (uint64_t)(dist.size - 1);
    dist.bcast_files += head[2];
    if (dist.rank != 0) {
        st = lie_file_set_unpack(packed, (size_t)head[1], &set, err);
        o.files = set;
        if (st == LIE_OK)
            st = load(ctx, &o, err);
        lie_file_set_destroy(set);
    }
    free(packed);
    return st;
}

/* ---- the check all ranks end their setup with --------------------------- */

typedef struct rank_report {
    int64_t status;
    uint64_t exe_hash, scene_hash, state_hash;
    char version[32];
    char msg[MSG_MAX];
} rank_report;

/* The executable's GNU build ID (ld --build-id: a hash of its contents
 * the linker writes into a note), read from memory: the first object
 * dl_iterate_phdr reports is the executable. */
static int build_id(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size;
    uint64_t *h = data;
    for (int i = 0; i < info->dlpi_phnum; i++) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[i];
        if (ph->p_type != PT_NOTE)
            continue;
        const unsigned char *p = (const unsigned char *)(info->dlpi_addr + ph->p_vaddr), *end = p + ph->p_memsz;
        while ((size_t)(end - p) >= sizeof(ElfW(Nhdr))) {
            ElfW(Nhdr) n;
            memcpy(&n, p, sizeof n);
            size_t name_len = (n.n_namesz + 3u) & ~3u, desc_len = (n.n_descsz + 3u) & ~3u;
            const unsigned char *name = p + sizeof n, *desc = name + name_len;
            if (name_len > (size_t)(end - name) || desc_len > (size_t)(end - desc))
                break;
            if (n.n_type == NT_GNU_BUILD_ID && n.n_namesz == 4 && memcmp(name, "GNU", 4) == 0 && n.n_descsz) {
                *h = lie_hash_bytes(desc, n.n_descsz, 0x6c69652d62696400ull);
                return 1;
            }
            p = desc + desc_len;
        }
    }
    return 1;
}

/* This binary: ranks running different builds would not give one
 * process's bytes.  Its build ID and its file's size where it has an ID
 * (a file changed after linking, as a test's appended byte, differs in
 * size); otherwise a hash of the file, which reads all of it (16 MB, 12 ms
 * a rank here, a tenth of a rank's setup). */
static uint64_t exe_hash(void)
{
    uint64_t h = 0;
    struct stat sb;
    dl_iterate_phdr(build_id, &h);
    if (h && stat("/proc/self/exe", &sb) == 0)
        return lie_hash_bytes(&sb.st_size, sizeof sb.st_size, h);
    unsigned char *d = NULL;
    size_t n = 0;
    lie_error e;
    if (lie_read_file("/proc/self/exe", &d, &n, &e) != LIE_OK)
        return 0;
    h = lie_hash_bytes(d, n, 0x6c69652d65786500ull);
    free(d);
    return h;
}

static void format_error(const lie_error *err, char *out, size_t cap)
{
    lie_error_format(err, out, cap);
}

static int is_option(const char *a) { return a[0] == '-' && a[1] && !strchr(a, '='); }

/* Argument i of a command line of n with its option ("--size 32x24"),
 * or "nothing" past its end. */
static void describe_arg(char *const *args, int n, int i, char *out, size_t cap)
{
    if (i >= n)
        snprintf(out, cap, "nothing");
    else if (i > 0 && args[i][0] != '-' && is_option(args[i - 1]))
        snprintf(out, cap, "%.200s %.200s", args[i - 1], args[i]);
    else if (i + 1 < n && is_option(args[i]) && args[i + 1][0] != '-')
        snprintf(out, cap, "%.200s %.200s", args[i], args[i + 1]);
    else
        snprintf(out, cap, "%.400s", args[i]);
}

/* Ranks started with other options (mpirun's MPMD form, A : B) would each
 * compute their share of another image or cache, and the output would mix
 * them: rank 0 broadcasts its command line (argv[1..]) and every rank
 * compares its own.  why: "" when they are the same, else the first
 * argument that differs, with its option. */
static void compare_args(char *why, size_t cap)
{
    uint64_t n = 0;
    for (int i = 1; dist.rank == 0 && i < dist.argc; i++)
        n += strlen(dist.argv[i]) + 1;
    MPI_Bcast(&n, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    char *buf = malloc(n + 1);
    char **theirs = calloc(n + 1, sizeof *theirs);
    if (!buf || !theirs)
        MPI_Abort(MPI_COMM_WORLD, 1); /* a command line's size: nothing else can go on */
    for (int i = 1, k = 0; dist.rank == 0 && i < dist.argc; i++) {
        size_t len = strlen(dist.argv[i]) + 1;
        memcpy(buf + k, dist.argv[i], len);
        k += (int)len;
    }
    bcast_bytes((unsigned char *)buf, n);
    int m = 0;
    for (size_t k = 0; k < n; k += strlen(buf + k) + 1)
        theirs[m++] = buf + k;
    char *const *mine = dist.argv + 1;
    int nm = dist.argc - 1, i = 0;
    while (i < nm && i < m && strcmp(mine[i], theirs[i]) == 0)
        i++;
    why[0] = 0;
    if (i < nm || i < m) {
        char a[512], b[512];
        describe_arg(mine, nm, i, a, sizeof a);
        describe_arg(theirs, m, i, b, sizeof b);
        snprintf(why, cap, "started with %s where rank 0 has %s: every rank must be given the same options", a,
                 b);
    }
    free(buf);
    free(theirs);
}

/* Gather every rank's report on rank 0, decide, broadcast the verdict;
 * on failure rank 0's err names the rank. */
static lie_status exchange(const rank_report *report, lie_error *err)
{
    rank_report copy = *report, *mine = &copy;
    char why[MSG_MAX];
    compare_args(why, sizeof why);
    if (mine->status == LIE_OK && why[0]) {
        mine->status = LIE_ERR_ARG;
        snprintf(mine->msg, sizeof mine->msg, "%s", why);
    }
    rank_report *all = NULL;
    if (dist.rank == 0 && !(all = calloc((size_t)dist.size, sizeof *all)))
        MPI_Abort(MPI_COMM_WORLD, 1); /* a few kilobytes per rank: nothing else can go on */
    MPI_Gather(mine, (int)sizeof *mine, MPI_BYTE, all, (int)sizeof *mine, MPI_BYTE, 0, MPI_COMM_WORLD);
    char verdict[MSG_MAX + 64] = "";
    if (dist.rank == 0) {
        for (int r = 0; all && r < dist.size && !verdict[0]; r++)
            if (all[r].status != LIE_OK)
                snprintf(verdict, sizeof verdict, "rank %d: %s", r, all[r].msg);
        for (int r = 1; all && r < dist.size && !verdict[0]; r++) {
            const rank_report *a = &all[0], *b = &all[r];
            if (strcmp(a->version, b->version) != 0)
                snprintf(verdict, sizeof verdict, "rank %d: version %s differs from rank 0's %s", r, b->version,
                         a->version);
            else if (a->exe_hash != b->exe_hash || !a->exe_hash)
                snprintf(verdict, sizeof verdict,
                         "rank %d: runs a different binary from rank 0's (executable hash %016llx, rank 0 "
                         "%016llx): refused, the output would not be one process's",
                         r, (unsigned long long)b->exe_hash, (unsigned long long)a->exe_hash);
            else if (a->scene_hash != b->scene_hash || a->state_hash != b->state_hash)
                snprintf(verdict, sizeof verdict,
                         "rank %d: scene or cache hash %016llx/%016llx differs from rank 0's %016llx/%016llx", r,
                         (unsigned long long)b->scene_hash, (unsigned long long)b->state_hash,
                         (unsigned long long)a->scene_hash, (unsigned long long)a->state_hash);
        }
        free(all);
    }
    MPI_Bcast(verdict, (int)sizeof verdict, MPI_CHAR, 0, MPI_COMM_WORLD);
    if (!verdict[0])
        return LIE_OK;
    if (report->status != LIE_OK && dist.rank != 0)
        return (lie_status)report->status; /* err holds this rank's own error */
    lie_error_clear(err);
    return lie_error_set(err, mine->status != LIE_OK ? (lie_status)mine->status : LIE_ERR_ARG, NULL, "%s",
                         verdict);
}

static void report_init(rank_report *r, lie_status st, const lie_error *err)
{
    memset(r, 0, sizeof *r);
    r->status = st;
    snprintf(r->version, sizeof r->version, "%s", LIE_VERSION);
    if (st != LIE_OK)
        format_error(err, r->msg, sizeof r->msg);
}

lie_status lie_dist_check(uint64_t scene_hash, uint64_t state_hash, lie_error *err)
{
    if (!dist.active)
        return LIE_OK;
    rank_report r;
    report_init(&r, LIE_OK, NULL);
    r.exe_hash = exe_hash();
    r.scene_hash = scene_hash;
    r.state_hash = state_hash;
    lie_status st = exchange(&r, err);
    dist.checked = 1; /* from here on errors travel in lie_dist_run's messages */
    return st;
}

int lie_dist_fail(const char *prog, const lie_error *err, int code)
{
    if (!dist.active)
        return lie_report_error(prog, err, code);
    lie_error e = *err;
    if (!dist.checked) {
        rank_report r;
        report_init(&r, err->status ? err->status : LIE_ERR_IO, err);
        exchange(&r, &e);
        dist.checked = 1;
    }
    if (dist.rank == 0)
        lie_report_error(prog, &e, code);
    return code;
}

/* ---- dynamic work sharing ----------------------------------------------- */

void *lie_dist_buf_add(lie_dist_buf *b, const void *src, size_t n)
{
    if (b->size + n > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->size + n)
            cap *= 2;
        unsigned char *d = realloc(b->data, cap);
        if (!d)
            return NULL;
        b->data = d;
        b->cap = cap;
    }
    void *p = b->data + b->size;
    if (src && n)
        memcpy(p, src, n);
    b->size += n;
    return p;
}

void lie_dist_buf_free(lie_dist_buf *b)
{
    free(b->data);
    memset(b, 0, sizeof *b);
}

/* A result's header: the item and the seconds run() took. */
typedef struct res_head {
    int64_t item;
    double seconds;
} res_head;

static void send_bytes(const void *p, size_t n, int dest, int tag)
{
    /* results beyond 2 GiB would need pieces; a tile range or a unit range
     * is far below (the callers keep items small) */
    MPI_Send(p, (int)n, MPI_BYTE, dest, tag, MPI_COMM_WORLD);
}

static lie_status run_item(const lie_dist_work *w, size_t item, lie_dist_buf *b, double *secs, lie_error *err)
{
    b->size = 0;
    res_head h = {(int64_t)item, 0.0};
    if (!lie_dist_buf_add(b, &h, sizeof h))
        return lie_error_set(err, LIE_ERR_NOMEM, NULL, "out of memory");
    double t0 = lie_time_now();
    lie_status st = w->run(w->ctx, item, b, err);
    *secs = lie_time_now() - t0;
    memcpy(&((res_head *)(void *)b->data)->seconds, secs, sizeof *secs);
    return st;
}

static lie_status worker(const lie_dist_work *w, lie_error *err)
{
    lie_dist_buf b = {0};
    lie_status first = LIE_OK;
    int open = 0, aborted = 0;
    for (; open < REQUESTS_OPEN; open++)
        MPI_Send(NULL, 0, MPI_BYTE, 0, TAG_REQ, MPI_COMM_WORLD);
    while (open > 0) {
        int64_t item;
        MPI_Recv(&item, 1, MPI_INT64_T, 0, TAG_ITEM, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        open--;
        if (item < 0) {
            aborted |= item == ITEM_ABORT;
            continue;
        }
        if (first != LIE_OK) {
            /* an item already on its way when this rank failed: answered,
             * so that rank 0 does not wait for it */
            static const char skip[] = "skipped after an earlier error";
            MPI_Send(skip, (int)sizeof skip, MPI_CHAR, 0, TAG_ERR, MPI_COMM_WORLD);
            open++;
            continue;
        }
        double secs = 0.0;
        lie_error e;
        lie_error_clear(&e);
        lie_status st = run_item(w, (size_t)item, &b, &secs, &e);
        if (st == LIE_OK) {
            send_bytes(b.data, b.size, 0, TAG_RES);
        } else {
            char msg[MSG_MAX];
            lie_error_format(&e, msg, sizeof msg);
            MPI_Send(msg, (int)strlen(msg) + 1, MPI_CHAR, 0, TAG_ERR, MPI_COMM_WORLD);
            first = st;
            *err = e;
        }
        open++;
    }
    lie_dist_buf_free(&b);
    if (first == LIE_OK && aborted)
        return lie_error_set(err, LIE_ERR_IO, NULL, "stopped: another rank failed");
    return first;
}

typedef struct peer {
    int credits;       /* requests not yet answered */
    int assigned;      /* items out, results not yet in */
    int ended;         /* a terminal answer was sent */
} peer;

/* Rank 0 runs two threads during lie_dist_run: the main thread computes
 * items like any worker, and a service thread, the only one calling MPI
 * then (MPI_THREAD_SERIALIZED), answers requests and takes results as they
 * come, so that no worker waits for rank 0 to finish an item of its own.
 * `mu` guards next, failed, err and the local result slot; take() runs on
 * the service thread outside the lock. */
typedef struct master {
    const lie_dist_work *w;
    peer *peers;
    size_t next;
    lie_status failed;
    lie_error *err;
    lie_dist_rank_stats *per_rank;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    /* the main thread's last result, waiting for the service thread */
    int slot_full, main_done;
    size_t slot_item;
    lie_status slot_st;
    lie_error slot_err;
    lie_dist_buf *slot_buf;
    double slot_secs;
    double service_cpu; /* the service thread's CPU seconds */
} master;

static void fail_once(master *m, lie_status st, int rank, const char *msg)
{
    if (m->failed != LIE_OK)
        return;
    m->failed = st;
    lie_error_clear(m->err);
    lie_error_set(m->err, st, NULL, "rank %d: %s", rank, msg);
}

static void fail_locked(master *m, lie_status st, int rank, const lie_error *e)
{
    char msg[MSG_MAX];
    lie_error_format(e, msg, sizeof msg);
    pthread_mutex_lock(&m->mu);
    fail_once(m, st, rank, msg);
    pthread_mutex_unlock(&m->mu);
}

static void count(master *m, int rank, size_t item, double secs, uint64_t bytes)
{
    m->per_rank[rank].items++;
    m->per_rank[rank].seconds += secs;
    m->per_rank[rank].bytes += bytes;
    if (m->w->units)
        m->per_rank[rank].units += m->w->units(m->w->ctx, item);
}

static void handle(master *m, const MPI_Status *ps)
{
    int n = 0, src = ps->MPI_SOURCE, tag = ps->MPI_TAG;
    MPI_Get_count(ps, MPI_BYTE, &n);
    unsigned char *buf = malloc((size_t)n + 1);
    if (!buf) /* a message cannot be left unreceived without stalling its sender */
        MPI_Abort(MPI_COMM_WORLD, 1);
    MPI_Recv(buf, n, MPI_BYTE, src, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    peer *p = &m->peers[src];
    p->credits++;
    if (tag == TAG_RES && (size_t)n >= sizeof(res_head)) {
        res_head h;
        memcpy(&h, buf, sizeof h);
        p->assigned--;
        count(m, src, (size_t)h.item, h.seconds, (uint64_t)n);
        pthread_mutex_lock(&m->mu);
        int ok = m->failed == LIE_OK;
        pthread_mutex_unlock(&m->mu);
        if (ok) {
            lie_error e;
            lie_error_clear(&e);
            lie_status st = m->w->take(m->w->ctx, (size_t)h.item, src, buf + sizeof h, (size_t)n - sizeof h, &e);
            if (st != LIE_OK)
                fail_locked(m, st, 0, &e);
        }
    } else if (tag == TAG_ERR) {
        p->assigned--;
        buf[n] = 0;
        pthread_mutex_lock(&m->mu);
        fail_once(m, LIE_ERR_IO, src, (const char *)buf);
        pthread_mutex_unlock(&m->mu);
    }
    free(buf);
}

/* Answer every open request: the next item, or the end. */
static void answer(master *m)
{
    pthread_mutex_lock(&m->mu);
    for (int r = 1; r < dist.size; r++) {
        peer *p = &m->peers[r];
        while (p->credits > 0) {
            int64_t item;
            if (m->failed == LIE_OK && m->next < m->w->n_items) {
                item = (int64_t)m->next++;
                p->assigned++;
            } else {
                item = m->failed == LIE_OK ? ITEM_DONE : ITEM_ABORT;
                p->ended = 1;
            }
            MPI_Send(&item, 1, MPI_INT64_T, r, TAG_ITEM, MPI_COMM_WORLD);
            p->credits--;
        }
    }
    pthread_mutex_unlock(&m->mu);
}

static int workers_done(const master *m)
{
    for (int r = 1; r < dist.size; r++)
        if (!m->peers[r].ended || m->peers[r].assigned || m->peers[r].credits)
            return 0;
    return 1;
}

/* The main thread's result, if one waits: taken here, outside the lock. */
static int take_local(master *m)
{
    pthread_mutex_lock(&m->mu);
    int full = m->slot_full, ok = m->failed == LIE_OK;
    pthread_mutex_unlock(&m->mu);
    if (!full)
        return 0;
    lie_status st = m->slot_st;
    lie_error e = m->slot_err;
    const lie_dist_buf *b = m->slot_buf;
    if (st == LIE_OK && ok)
        st = m->w->take(m->w->ctx, m->slot_item, 0, b->data + sizeof(res_head), b->size - sizeof(res_head), &e);
    count(m, 0, m->slot_item, m->slot_secs, 0);
    if (st != LIE_OK)
        fail_locked(m, st, 0, &e);
    pthread_mutex_lock(&m->mu);
    m->slot_full = 0;
    pthread_cond_broadcast(&m->cv);
    pthread_mutex_unlock(&m->mu);
    return 1;
}

/* The service thread's wait between polls when nothing came: from
 * IDLE_MIN, doubling up to IDLE_MAX while nothing comes.  Open MPI's
 * blocking calls spin, and a fixed 0.1 ms sleep between polls cost the
 * service thread 0.12 CPU s in a 13-frame path on 2 ranks that took 1.8 s
 * (a fourteenth of a core, taken from the ranks' work on a machine whose
 * cores they fill); backing off, 0.04-0.05 s, most of it take()'s work.
 * A worker keeps two requests open, so it has its next item while its
 * request waits; the main thread's results wake the thread at once (cv). */
#define IDLE_MIN_NS 50000L
#define IDLE_MAX_NS 2000000L

static void idle_wait(master *m, long ns)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    ts.tv_nsec += ns;
    if (ts.tv_nsec >= 1000000000L) {
        ts.tv_sec++;
        ts.tv_nsec -= 1000000000L;
    }
    pthread_mutex_lock(&m->mu);
    if (!m->slot_full)
        pthread_cond_timedwait(&m->cv, &m->mu, &ts);
    pthread_mutex_unlock(&m->mu);
}

static void *service(void *arg)
{
    master *m = arg;
    long idle = IDLE_MIN_NS;
    for (;;) {
        int busy = 0, flag = 1;
        MPI_Status ps;
        while (flag) { /* what has arrived */
            MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &ps);
            if (flag) {
                handle(m, &ps);
                busy = 1;
            }
        }
        answer(m);
        busy |= take_local(m);
        pthread_mutex_lock(&m->mu);
        int done = m->main_done && !m->slot_full && workers_done(m);
        pthread_mutex_unlock(&m->mu);
        if (done) {
            struct rusage ru; /* for --stats: what rank 0's checking costs */
            if (getrusage(RUSAGE_THREAD, &ru) == 0)
                m->service_cpu = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
                                 (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
            return NULL;
        }
        if (busy) {
            idle = IDLE_MIN_NS;
        } else {
            idle_wait(m, idle);
            idle = idle * 2 < IDLE_MAX_NS ? idle * 2 : IDLE_MAX_NS;
        }
    }
}

static lie_status leader(const lie_dist_work *w, lie_dist_rank_stats *per_rank, lie_error *err)
{
    master m;
    memset(&m, 0, sizeof m);
    m.w = w;
    m.err = err;
    m.peers = calloc((size_t)dist.size, sizeof *m.peers);
    m.per_rank = calloc((size_t)dist.size, sizeof *m.per_rank);
    if (!m.peers || !m.per_rank)
        MPI_Abort(MPI_COMM_WORLD, 1); /* a few bytes per rank: nothing else can go on */
    pthread_mutex_init(&m.mu, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC); /* idle_wait's deadline */
    pthread_cond_init(&m.cv, &ca);
    pthread_condattr_destroy(&ca);
    pthread_t th;
    int threaded = dist.serialized && pthread_create(&th, NULL, service, &m) == 0;
    lie_dist_buf b[2] = {{0}, {0}};
    for (int k = 0;; k ^= 1) {
        pthread_mutex_lock(&m.mu);
        int more = m.failed == LIE_OK && m.next < w->n_items;
        size_t item = more ? m.next++ : 0;
        pthread_mutex_unlock(&m.mu);
        if (!more)
            break;
        double secs = 0.0;
        lie_error e;
        lie_error_clear(&e);
        lie_status st = run_item(w, item, &b[k], &secs, &e);
        pthread_mutex_lock(&m.mu);
        while (m.slot_full) /* the previous result still waits to be taken */
            pthread_cond_wait(&m.cv, &m.mu);
        m.slot_full = 1;
        pthread_cond_broadcast(&m.cv); /* the service thread takes it at once */
        m.slot_item = item;
        m.slot_st = st;
        m.slot_err = e;
        m.slot_buf = &b[k];
        m.slot_secs = secs;
        pthread_mutex_unlock(&m.mu);
        if (!threaded)
            take_local(&m);
    }
    pthread_mutex_lock(&m.mu);
    m.main_done = 1;
    pthread_cond_broadcast(&m.cv);
    pthread_mutex_unlock(&m.mu);
    if (threaded)
        pthread_join(th, NULL);
    else
        service(&m);
    lie_dist_buf_free(&b[0]);
    lie_dist_buf_free(&b[1]);
    if (per_rank)
        memcpy(per_rank, m.per_rank, sizeof *per_rank * (size_t)dist.size);
    dist.service_cpu = m.service_cpu;
    pthread_mutex_destroy(&m.mu);
    pthread_cond_destroy(&m.cv);
    free(m.peers);
    free(m.per_rank);
    return m.failed;
}

static lie_status run_all(const lie_dist_work *w, lie_dist_rank_stats *per_rank, lie_error *err)
{
    if (!dist.active || dist.size == 1) {
        /* one rank: the same items, in order, here */
        lie_dist_buf b = {0};
        lie_status st = LIE_OK;
        lie_dist_rank_stats rs = {0, 0, 0.0, 0};
        for (size_t i = 0; st == LIE_OK && i < w->n_items; i++) {
            double secs = 0.0;
            st = run_item(w, i, &b, &secs, err);
            if (st == LIE_OK)
                st = w->take(w->ctx, i, 0, b.data + sizeof(res_head), b.size - sizeof(res_head), err);
            rs.items++;
            rs.seconds += secs;
            if (w->units)
                rs.units += w->units(w->ctx, i);
        }
        lie_dist_buf_free(&b);
        if (per_rank)
            per_rank[0] = rs;
        return st;
    }
    return dist.rank == 0 ? leader(w, per_rank, err) : worker(w, err);
}

void lie_dist_stats_print(FILE *fp, const char *unit_name, int json)
{
    const lie_dist_rank_stats *pr = dist.per_rank;
    if (!dist.active || !pr)
        return;
    uint64_t gathered = lie_dist_bytes_gathered();
    if (json) {
        fprintf(fp, ",\"ranks\":[");
        for (int r = 0; r < dist.size; r++)
            fprintf(fp, "%s{\"rank\":%d,\"items\":%llu,\"%s\":%llu,\"seconds\":%.6f,\"bytes_sent\":%llu}", r ? "," : "",
                    r, (unsigned long long)pr[r].items, unit_name, (unsigned long long)pr[r].units, pr[r].seconds,
                    (unsigned long long)pr[r].bytes);
        fprintf(fp,
                "],\"items\":%zu,\"files_broadcast\":%llu,\"bytes_broadcast\":%llu,\"bytes_gathered\":%llu,"
                "\"seconds_cpu_service\":%.6f",
                dist.n_items, (unsigned long long)dist.bcast_files, (unsigned long long)dist.bcast_bytes,
                (unsigned long long)gathered, dist.service_cpu);
        return;
    }
    fprintf(fp, "  %d ranks, %zu items; %llu files (%llu bytes) broadcast, %llu bytes gathered; rank 0's service "
                "thread %.3f CPU s\n", dist.size, dist.n_items, (unsigned long long)dist.bcast_files,
            (unsigned long long)dist.bcast_bytes, (unsigned long long)gathered, dist.service_cpu);
    for (int r = 0; r < dist.size; r++)
        fprintf(fp, "  rank %d: %llu %s in %llu items, %.3f s, %llu bytes sent\n", r, (unsigned long long)pr[r].units,
                unit_name, (unsigned long long)pr[r].items, pr[r].seconds, (unsigned long long)pr[r].bytes);
}

lie_status lie_dist_run(const lie_dist_work *w, lie_error *err)
{
    free(dist.per_rank);
    dist.per_rank = calloc((size_t)dist.size, sizeof *dist.per_rank);
    dist.n_items = w->n_items;
    return run_all(w, dist.per_rank, err);
}
