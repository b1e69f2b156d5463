/* SPDX-License-Identifier: Apache-2.0 */
/* Inputs and outputs that respect what is there.
 *
 * Inputs: opened non-blocking (a FIFO or a device cannot hang the open),
 * checked with fstat (only regular files, or "-" for stdin) and read within
 * a stated size limit.
 *
 * Outputs: a temporary file in the target's directory, fsync, rename
 * (CONTRIBUTING.md, Files).  A symlink is followed to its target and the target is
 * replaced atomically in its own folder; an existing non-regular file (a
 * character device such as /dev/null, a FIFO) is written in place.  A group
 * holds finished temporaries until every output of a run is complete, then
 * renames them all.  Temporaries still open are unlinked on SIGINT, SIGTERM
 * and SIGHUP by a handler that then re-raises the signal, unless a commit is
 * renaming: the signal then waits for the last rename, so a group is all in
 * place or none of it; SIGKILL cannot be caught, so lie_tmp_clean removes
 * stale ones of our naming when asked.  A replaced file keeps its mode,
 * owner and group; "do not replace" is decided by the rename itself
 * (renameat2's RENAME_NOREPLACE, or link and unlink where the file system
 * lacks it), never by a test made earlier. */
#include "core/core.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* ---- the temporaries a signal must remove ------------------------------
 * Process-wide by nature (a signal handler has no context pointer): the one
 * piece of mutable global state in the library.  Slots are claimed with an
 * atomic exchange; the handler reads only slots marked live and calls only
 * async-signal-safe functions (unlink, signal, raise). */

enum { TMP_SLOTS = 64, SLOT_FREE = 0, SLOT_FILLING = 1, SLOT_LIVE = 2 };
static char tmp_paths[TMP_SLOTS][4096];
static atomic_int tmp_state[TMP_SLOTS];
static pthread_once_t tmp_once = PTHREAD_ONCE_INIT;
static const int tmp_signals[] = {SIGINT, SIGTERM, SIGHUP};
/* The commits renaming now (>= 0), or -1 once a signal is ending the
 * process.  A signal during a commit is left in `tmp_deferred` for the last
 * commit to finish to act on; a commit that finds the process ending does
 * not start.  One atomic word decides which comes first, whatever thread
 * the signal lands on. */
static atomic_int tmp_committing;
static atomic_int tmp_deferred;

/* Remove every live temporary and end the process by `sig`'s default action
 * (async-signal-safe calls only). */
static void tmp_die(int sig)
{
    for (int i = 0; i < TMP_SLOTS; i++)
        if (atomic_load(&tmp_state[i]) == SLOT_LIVE)
            unlink(tmp_paths[i]);
    signal(sig, SIG_DFL);
    sigset_t one;
    sigemptyset(&one);
    sigaddset(&one, sig);
    pthread_sigmask(SIG_UNBLOCK, &one, NULL);
    raise(sig); /* from the handler: delivered with the default action once it returns */
}

static void tmp_on_signal(int sig)
{
    int saved = errno;
    for (;;) {
        int c = atomic_load(&tmp_committing);
        if (c > 0) { /* the commit in progress finishes, then acts on it */
            int none = 0;
            atomic_compare_exchange_strong(&tmp_deferred, &none, sig);
            errno = saved;
            return;
        }
        if (c < 0 || atomic_compare_exchange_weak(&tmp_committing, &c, -1))
            break;
    }
    errno = saved;
    tmp_die(sig);
}

/* Enter a commit's renames: 0, or -1 when a signal is already ending the
 * process (its handler is removing the temporaries). */
static int commit_enter(void)
{
    for (;;) {
        int c = atomic_load(&tmp_committing);
        if (c < 0)
            return -1;
        if (atomic_compare_exchange_weak(&tmp_committing, &c, c + 1))
            return 0;
    }
}

/* Leave it; the last commit out acts on a signal that came meanwhile. */
static void commit_leave(void)
{
    for (;;) {
        int c = atomic_load(&tmp_committing);
        int next = c == 1 && atomic_load(&tmp_deferred) ? -1 : c - 1;
        if (atomic_compare_exchange_weak(&tmp_committing, &c, next)) {
            if (next < 0)
                tmp_die(atomic_load(&tmp_deferred));
            return;
        }
    }
}

/* Installed only where the signal still has its default action: a program
 * that handles or ignores a signal itself keeps its choice. */
static void tmp_install(void)
{
    for (size_t i = 0; i < sizeof tmp_signals / sizeof *tmp_signals; i++) {
        struct sigaction old, sa;
        if (sigaction(tmp_signals[i], NULL, &old) != 0 || old.sa_handler != SIG_DFL ||
            (old.sa_flags & SA_SIGINFO))
            continue;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = tmp_on_signal;
        sigemptyset(&sa.sa_mask);
        for (size_t j = 0; j < sizeof tmp_signals / sizeof *tmp_signals; j++)
            sigaddset(&sa.sa_mask, tmp_signals[j]);
        sigaction(tmp_signals[i], &sa, NULL);
    }
}

/* Returns the slot, or -1 when all are taken (the file is then not removed
 * on a signal, which is all that is lost). */
static int tmp_register(const char *path)
{
    pthread_once(&tmp_once, tmp_install);
    for (int i = 0; i < TMP_SLOTS; i++) {
        int expect = SLOT_FREE;
        if (atomic_compare_exchange_strong(&tmp_state[i], &expect, SLOT_FILLING)) {
            snprintf(tmp_paths[i], sizeof tmp_paths[i], "%s", path);
            atomic_store(&tmp_state[i], SLOT_LIVE);
            return i;
        }
    }
    return -1;
}

static void tmp_release(int slot)
{
    if (slot >= 0 && slot < TMP_SLOTS)
        atomic_store(&tmp_state[slot], SLOT_FREE);
}

/* ---- outputs ------------------------------------------------------------ */

struct lie_atomic_group {
    size_t n, cap;
    struct pending {
        char *tmp, *target;
        int slot, no_replace;
    } *files;
};

lie_atomic_group *lie_atomic_group_create(void) { return calloc(1, sizeof(lie_atomic_group)); }

void lie_atomic_group_destroy(lie_atomic_group *g)
{
    if (!g)
        return;
    for (size_t i = 0; i < g->n; i++) {
        unlink(g->files[i].tmp);
        tmp_release(g->files[i].slot);
        free(g->files[i].tmp);
        free(g->files[i].target);
    }
    free(g->files);
    free(g);
}

/* rename(tmp, target), or with no_replace the same only while target does
 * not exist, decided atomically by the kernel: renameat2's
 * RENAME_NOREPLACE, or on a file system without it link (which fails on an
 * existing name) then unlink.  0, or -1 with errno (EEXIST: it exists). */
static int put_in_place(const char *tmp, const char *target, int no_replace)
{
    if (!no_replace)
        return rename(tmp, target);
    if (renameat2(AT_FDCWD, tmp, AT_FDCWD, target, RENAME_NOREPLACE) == 0)
        return 0;
    if (errno != EINVAL && errno != ENOSYS)
        return -1;
    if (link(tmp, target) != 0)
        return -1;
    unlink(tmp);
    return 0;
}

static lie_status place_error(lie_error *err, const char *target, int e)
{
    if (e == EEXIST)
        return lie_error_set(err, LIE_ERR_IO, target, "exists (it appeared while writing; not replaced)");
    return lie_error_set(err, LIE_ERR_IO, target, "cannot rename into place: %s", strerror(e));
}

/* Renames in two passes: first the files that must not replace anything,
 * which can fail because a file appeared (those already placed are taken
 * back), then the replacing ones, in commit order, which fail only on an I/O
 * error of the folder itself.  Signals wait for the end (commit_enter). */
lie_status lie_atomic_group_commit(lie_atomic_group *g, lie_error *err)
{
    if (g->n == 0)
        return LIE_OK;
    if (commit_enter() != 0)
        return lie_error_set(err, LIE_ERR_IO, g->files[0].target, "not renamed into place: interrupted by a signal");
    lie_status st = LIE_OK;
    for (size_t i = 0; i < g->n; i++) {
        struct pending *p = &g->files[i];
        if (!p->no_replace)
            continue;
        if (put_in_place(p->tmp, p->target, 1) != 0) {
            st = place_error(err, p->target, errno);
            for (size_t k = 0; k < i; k++) /* take back the new files placed */
                if (g->files[k].no_replace)
                    rename(g->files[k].target, g->files[k].tmp);
            break;
        }
    }
    for (size_t i = 0; st == LIE_OK && i < g->n; i++) {
        struct pending *p = &g->files[i];
        if (!p->no_replace && rename(p->tmp, p->target) != 0)
            st = place_error(err, p->target, errno);
        else
            p->no_replace = -1; /* in place */
    }
    commit_leave();
    /* what was not renamed stays for lie_atomic_group_destroy to remove */
    size_t kept = 0;
    for (size_t i = 0; i < g->n; i++) {
        struct pending *p = &g->files[i];
        if (p->no_replace == -1) {
            tmp_release(p->slot);
            free(p->tmp);
            free(p->target);
        } else {
            g->files[kept++] = *p;
        }
    }
    g->n = kept;
    return st;
}

/* Follow symlinks from `path` to the file they name, which may not exist yet
 * (a dangling link names the file to create).  At most 40 links, as the
 * kernel allows; the result is the last name reached.  As the kernel's
 * protected_symlinks does for open(), a link in a sticky world-writable
 * folder (/tmp) is followed only if it belongs to us or to the folder's
 * owner: otherwise another user could aim our output at any file.  Returns
 * 0, or -1 for such a link. */
static int resolve_links(const char *path, char *out, size_t size)
{
    snprintf(out, size, "%s", path);
    for (int hops = 0; hops < 40; hops++) {
        struct stat st, dir;
        if (lstat(out, &st) != 0 || !S_ISLNK(st.st_mode))
            return 0;
        char *slash = strrchr(out, '/');
        int dirlen = slash ? (int)(slash - out + 1) : 0;
        char dname[4096];
        snprintf(dname, sizeof dname, "%.*s", dirlen ? dirlen : 1, dirlen ? out : ".");
        if (stat(dname, &dir) == 0 && (dir.st_mode & S_ISVTX) && (dir.st_mode & S_IWOTH) &&
            st.st_uid != geteuid() && st.st_uid != dir.st_uid)
            return -1;
        char link[4096];
        ssize_t n = readlink(out, link, sizeof link - 1);
        if (n <= 0)
            return 0;
        link[n] = 0;
        if (link[0] == '/') {
            snprintf(out, size, "%s", link);
        } else {
            char joined[8192];
            snprintf(joined, sizeof joined, "%.*s%s", dirlen, out, link);
            if (strlen(joined) >= size)
                return 0;
            snprintf(out, size, "%s", joined);
        }
    }
    return 0;
}

lie_status lie_atomic_open_flags(lie_atomic_file *af, const char *path, lie_atomic_group *group, unsigned flags,
                                 lie_error *err)
{
    memset(af, 0, sizeof *af);
    af->slot = -1;
    af->group = group;
    af->no_replace = (flags & LIE_ATOMIC_NO_REPLACE) != 0;
    if (strcmp(path, "-") == 0) {
        af->fp = stdout;
        af->is_stdout = 1;
        snprintf(af->path, sizeof af->path, "-");
        return LIE_OK;
    }
    if (strlen(path) + 16 >= sizeof af->tmp)
        return lie_error_set(err, LIE_ERR_ARG, path, "path too long");
    snprintf(af->path, sizeof af->path, "%s", path);
    if (resolve_links(path, af->target, sizeof af->target) != 0)
        return lie_error_set(err, LIE_ERR_IO, path,
                             "cannot write: a symlink of another user in a sticky world-writable folder");
    if (strlen(af->target) + 16 >= sizeof af->tmp)
        return lie_error_set(err, LIE_ERR_ARG, path, "the path a symlink names is too long");

    struct stat st;
    int exists = stat(af->target, &st) == 0;
    if (af->no_replace && (exists || lstat(af->target, &st) == 0)) /* a dangling link too */
        return lie_error_set(err, LIE_ERR_IO, path, "exists (not replaced)");
    if (exists && S_ISDIR(st.st_mode))
        return lie_error_set(err, LIE_ERR_IO, path, "cannot write: is a directory");
    if (exists && !S_ISREG(st.st_mode)) {
        /* a device or FIFO: replacing it with a regular file would destroy
         * it (think /dev/null as root), so write into it as a shell would */
        int fd = open(af->target, O_WRONLY | O_NOCTTY | O_CLOEXEC);
        if (fd < 0)
            return lie_error_set(err, LIE_ERR_IO, path, "cannot open: %s", strerror(errno));
        af->fp = fdopen(fd, "wb");
        if (!af->fp) {
            int e = errno;
            close(fd);
            return lie_error_set(err, LIE_ERR_IO, path, "cannot open: %s", strerror(e));
        }
        af->in_place = 1;
        return LIE_OK;
    }

    /* The temporary lives next to the target so rename() is atomic. */
    const char *slash = strrchr(af->target, '/');
    size_t dirlen = slash ? (size_t)(slash - af->target + 1) : 0, len = strlen(af->target);
    /* "DIR/.NAME.tmpXXXXXX": the length was checked above */
    memcpy(af->tmp, af->target, dirlen);
    af->tmp[dirlen] = '.';
    memcpy(af->tmp + dirlen + 1, af->target + dirlen, len - dirlen);
    memcpy(af->tmp + len + 1, ".tmpXXXXXX", sizeof ".tmpXXXXXX");
    /* signals between mkstemp and the registration would leave the file */
    sigset_t block, old;
    sigemptyset(&block);
    for (size_t i = 0; i < sizeof tmp_signals / sizeof *tmp_signals; i++)
        sigaddset(&block, tmp_signals[i]);
    pthread_sigmask(SIG_BLOCK, &block, &old);
    int fd = mkostemp(af->tmp, O_CLOEXEC);
    int e = errno;
    if (fd >= 0)
        af->slot = tmp_register(af->tmp);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    if (fd < 0) {
        af->tmp[0] = 0;
        return lie_error_set(err, LIE_ERR_IO, path, "cannot create: %s", strerror(e));
    }
    /* mkstemp makes 0600 and gives the file our owner: a replaced file keeps
     * its owner and group (chown first: it clears set-id bits) and its mode,
     * a new one gets the usual umask-derived mode.  Where we may not give it
     * the old owner (not root, another user's file in a folder we may
     * write), we refuse rather than take the file from its owner. */
    if (exists && (st.st_uid != geteuid() || st.st_gid != getegid()) &&
        fchown(fd, st.st_uid != geteuid() ? st.st_uid : (uid_t)-1, st.st_gid != getegid() ? st.st_gid : (gid_t)-1) !=
            0) {
        e = errno;
        close(fd);
        lie_atomic_abort(af);
        return lie_error_set(err, LIE_ERR_IO, path, "cannot replace it keeping its owner (uid %u, gid %u): %s",
                             (unsigned)st.st_uid, (unsigned)st.st_gid, strerror(e));
    }
    mode_t um = umask(0);
    umask(um);
    fchmod(fd, exists ? (st.st_mode & 07777) : (0666 & ~um));
    af->fp = fdopen(fd, "wb");
    if (!af->fp) {
        e = errno;
        close(fd);
        lie_atomic_abort(af);
        return lie_error_set(err, LIE_ERR_IO, path, "cannot create: %s", strerror(e));
    }
    return LIE_OK;
}

lie_status lie_atomic_open_group(lie_atomic_file *af, const char *path, lie_atomic_group *group, lie_error *err)
{
    return lie_atomic_open_flags(af, path, group, 0, err);
}

lie_status lie_atomic_open(lie_atomic_file *af, const char *path, lie_error *err)
{
    return lie_atomic_open_flags(af, path, NULL, 0, err);
}

lie_status lie_atomic_commit(lie_atomic_file *af, lie_error *err)
{
    if (af->is_stdout) {
        if (fflush(stdout) != 0 || ferror(stdout))
            return lie_error_set(err, LIE_ERR_IO, "-", "write failed: %s", strerror(errno));
        af->fp = NULL;
        return LIE_OK;
    }
    int bad = ferror(af->fp) || fflush(af->fp) != 0 || (!af->in_place && fsync(fileno(af->fp)) != 0);
    int e = errno;
    if (fclose(af->fp) != 0 && !bad) {
        bad = 1;
        e = errno;
    }
    af->fp = NULL;
    if (bad) {
        lie_atomic_abort(af);
        return lie_error_set(err, LIE_ERR_IO, af->path, "write failed: %s", strerror(e ? e : EIO));
    }
    if (af->in_place)
        return LIE_OK;
    if (af->group) {
        lie_atomic_group *g = af->group;
        if (g->n == g->cap) {
            size_t cap = g->cap ? g->cap * 2 : 4;
            struct pending *nf = realloc(g->files, cap * sizeof *nf);
            if (!nf) {
                lie_atomic_abort(af);
                return lie_error_set(err, LIE_ERR_NOMEM, af->path, "out of memory");
            }
            g->files = nf;
            g->cap = cap;
        }
        struct pending p = {strdup(af->tmp), strdup(af->target), af->slot, af->no_replace};
        if (!p.tmp || !p.target) {
            free(p.tmp);
            free(p.target);
            lie_atomic_abort(af);
            return lie_error_set(err, LIE_ERR_NOMEM, af->path, "out of memory");
        }
        g->files[g->n++] = p;
        af->tmp[0] = 0;
        af->slot = -1;
        return LIE_OK;
    }
    if (commit_enter() != 0) {
        lie_atomic_abort(af);
        return lie_error_set(err, LIE_ERR_IO, af->path, "not renamed into place: interrupted by a signal");
    }
    int placed = put_in_place(af->tmp, af->target, af->no_replace);
    e = errno;
    commit_leave();
    if (placed != 0) {
        lie_atomic_abort(af);
        return place_error(err, af->path, e);
    }
    tmp_release(af->slot);
    af->slot = -1;
    af->tmp[0] = 0;
    return LIE_OK;
}

void lie_atomic_abort(lie_atomic_file *af)
{
    if (af->is_stdout) {
        af->fp = NULL;
        return;
    }
    if (af->fp) {
        fclose(af->fp);
        af->fp = NULL;
    }
    if (af->tmp[0])
        unlink(af->tmp);
    af->tmp[0] = 0;
    tmp_release(af->slot);
    af->slot = -1;
}

/* ".NAME.tmpXXXXXX", as lie_atomic_open names its temporaries (mkstemp's
 * six characters are letters and digits). */
static int is_our_tmp(const char *name)
{
    size_t n = strlen(name);
    if (n < 1 + 1 + 4 + 6 || name[0] != '.')
        return 0;
    const char *x = name + n - 6;
    if (memcmp(x - 4, ".tmp", 4) != 0)
        return 0;
    for (int i = 0; i < 6; i++)
        if (!((x[i] >= 'a' && x[i] <= 'z') || (x[i] >= 'A' && x[i] <= 'Z') || (x[i] >= '0' && x[i] <= '9')))
            return 0;
    return 1;
}

lie_status lie_tmp_clean(const char *dir, double min_age, int dry_run, lie_tmp_clean_fn fn, void *ctx,
                         lie_error *err)
{
    DIR *d = opendir(dir);
    if (!d)
        return lie_error_set(err, LIE_ERR_IO, dir, "cannot open directory: %s", strerror(errno));
    int dfd = dirfd(d);
    time_t now = time(NULL);
    lie_status st = LIE_OK;
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        if (!is_our_tmp(de->d_name))
            continue;
        struct stat sb;
        /* regular files of ours only: never a symlink, never another user's */
        if (fstatat(dfd, de->d_name, &sb, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(sb.st_mode) ||
            sb.st_uid != geteuid() || difftime(now, sb.st_mtime) < min_age)
            continue;
        if (!dry_run && unlinkat(dfd, de->d_name, 0) != 0 && errno != ENOENT) {
            st = lie_error_set(err, LIE_ERR_IO, dir, "cannot remove %s: %s", de->d_name, strerror(errno));
            break;
        }
        if (fn)
            fn(ctx, de->d_name, (uint64_t)sb.st_size);
    }
    closedir(d);
    return st;
}

/* ---- inputs ------------------------------------------------------------- */

static const char *kind_of(mode_t m)
{
    if (S_ISDIR(m))
        return "a directory";
    if (S_ISFIFO(m))
        return "a FIFO";
    if (S_ISCHR(m))
        return "a character device";
    if (S_ISBLK(m))
        return "a block device";
    if (S_ISSOCK(m))
        return "a socket";
    return "not a regular file";
}

lie_status lie_input_open(const char *path, uint64_t max, int *fdp, uint64_t *sizep, lie_error *err)
{
    *fdp = -1;
    *sizep = 0;
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (fd < 0)
        return lie_error_set(err, LIE_ERR_IO, path, "cannot open: %s", strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return lie_error_set(err, LIE_ERR_IO, path, "cannot open: %s", strerror(e));
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return lie_error_set(err, LIE_ERR_IO, path, "cannot read %s: only regular files (or - for stdin)",
                             kind_of(st.st_mode));
    }
    if ((uint64_t)st.st_size > max) {
        close(fd);
        return lie_error_set(err, LIE_ERR_LIMIT, path, "file is %llu bytes, beyond the limit of %llu",
                             (unsigned long long)st.st_size, (unsigned long long)max);
    }
    int fl = fcntl(fd, F_GETFL);
    if (fl >= 0)
        fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
    *fdp = fd;
    *sizep = (uint64_t)st.st_size;
    return LIE_OK;
}

lie_status lie_read_fd(int fd, const char *name, uint64_t max, uint64_t hint, unsigned char **data, size_t *size,
                       lie_error *err)
{
    *data = NULL;
    *size = 0;
    if (max > SIZE_MAX - 1)
        max = SIZE_MAX - 1;
    /* a regular file's size is known; the loop still reads to the end, as
     * files can grow, but never beyond max */
    size_t cap = hint > 0 && hint <= max ? (size_t)hint + 1 : 1 << 16, n = 0;
    unsigned char *buf = malloc(cap);
    if (!buf)
        return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
    for (;;) {
        if (n == cap) {
            size_t ncap = cap > SIZE_MAX / 2 ? SIZE_MAX : cap * 2;
            if (ncap > max + 1)
                ncap = (size_t)max + 1;
            unsigned char *nb = ncap > cap ? realloc(buf, ncap) : NULL;
            if (!nb) {
                free(buf);
                return lie_error_set(err, LIE_ERR_NOMEM, name, "out of memory");
            }
            buf = nb;
            cap = ncap;
        }
        ssize_t got = read(fd, buf + n, cap - n);
        if (got < 0) {
            if (errno == EINTR)
                continue;
            int e = errno;
            free(buf);
            return lie_error_set(err, LIE_ERR_IO, name, "read failed: %s", strerror(e));
        }
        if (got == 0)
            break;
        n += (size_t)got;
        if (n > max) {
            free(buf);
            return lie_error_set(err, LIE_ERR_LIMIT, name, "input is larger than the limit of %llu bytes",
                                 (unsigned long long)max);
        }
    }
    *data = buf;
    *size = n;
    return LIE_OK;
}

lie_status lie_read_file_max(const char *path, uint64_t max, unsigned char **data, size_t *size, lie_error *err)
{
    *data = NULL;
    *size = 0;
    if (strcmp(path, "-") == 0)
        return lie_read_fd(STDIN_FILENO, path, max, 0, data, size, err);
    int fd;
    uint64_t fsize;
    lie_status st = lie_input_open(path, max, &fd, &fsize, err);
    if (st != LIE_OK)
        return st;
    st = lie_read_fd(fd, path, max, fsize, data, size, err);
    close(fd);
    return st;
}

lie_status lie_read_file(const char *path, unsigned char **data, size_t *size, lie_error *err)
{
    return lie_read_file_max(path, LIE_READ_MAX_DEFAULT, data, size, err);
}

/* The folder part of `path` resolved to an absolute path without links, or
 * NULL. */
static char *real_folder(const char *path)
{
    const char *slash = strrchr(path, '/');
    char *dir = slash ? strndup(path, slash == path ? 1 : (size_t)(slash - path)) : strdup(".");
    char *real = dir ? realpath(dir, NULL) : NULL;
    free(dir);
    return real;
}

char *lie_path_from_folder_of(const char *path, const char *other)
{
    return path[0] == '/' ? strdup(path) : lie_path_relative_to_folder_of(path, other);
}

char *lie_path_relative_to_folder_of(const char *path, const char *other)
{
    char *from = real_folder(other), *to = real_folder(path);
    char *out = NULL;
    if (from && to) {
        /* the components the two folders share, then one ".." for each of
         * `from`'s others, then the rest of `to`, then the file's name */
        size_t common = 0;
        for (size_t i = 0;; i++) {
            int end_f = from[i] == 0 || from[i] == '/', end_t = to[i] == 0 || to[i] == '/';
            if (end_f && end_t)
                common = i;
            if (from[i] != to[i] || !from[i])
                break;
        }
        size_t ups = 0;
        for (const char *c = from + common; strcmp(from, "/") != 0 && *c; c++)
            ups += *c == '/';
        const char *rest = to + common + (to[common] == '/');
        const char *slash = strrchr(path, '/');
        const char *base = slash ? slash + 1 : path;
        size_t cap = 3 * ups + strlen(rest) + strlen(base) + 3;
        out = malloc(cap);
        if (out) {
            size_t n = 0;
            for (size_t k = 0; k < ups; k++)
                n += (size_t)snprintf(out + n, cap - n, "../");
            if (*rest)
                n += (size_t)snprintf(out + n, cap - n, "%s/", rest);
            snprintf(out + n, cap - n, "%s", base);
        }
    }
    free(from);
    free(to);
    return out;
}
