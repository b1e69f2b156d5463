/* Whole-file reads and atomic writes: a temporary file in the target's
 * directory, fsync, rename (STYLE.md 15). */
#include "core/core.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

lie_status lie_atomic_open(lie_atomic_file *af, const char *path, lie_error *err)
{
    memset(af, 0, sizeof *af);
    if (strcmp(path, "-") == 0) {
        af->fp = stdout;
        af->is_stdout = 1;
        snprintf(af->path, sizeof af->path, "-");
        return LIE_OK;
    }
    if (strlen(path) + 16 >= sizeof af->tmp)
        return lie_error_set(err, LIE_ERR_ARG, path, "path too long");
    snprintf(af->path, sizeof af->path, "%s", path);
    /* The temporary lives next to the target so rename() is atomic. */
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash ? (size_t)(slash - path + 1) : 0;
    snprintf(af->tmp, sizeof af->tmp, "%.*s.%s.tmpXXXXXX", (int)dirlen, path,
             slash ? slash + 1 : path);
    int fd = mkstemp(af->tmp);
    if (fd < 0)
        return lie_error_set(err, LIE_ERR_IO, path, "cannot create: %s", strerror(errno));
    /* mkstemp makes 0600; outputs should get the usual umask-derived mode. */
    mode_t um = umask(0);
    umask(um);
    fchmod(fd, 0666 & ~um);
    af->fp = fdopen(fd, "wb");
    if (!af->fp) {
        int e = errno;
        close(fd);
        unlink(af->tmp);
        return lie_error_set(err, LIE_ERR_IO, path, "cannot create: %s", strerror(e));
    }
    return LIE_OK;
}

lie_status lie_atomic_commit(lie_atomic_file *af, lie_error *err)
{
    if (af->is_stdout) {
        if (fflush(stdout) != 0 || ferror(stdout))
            return lie_error_set(err, LIE_ERR_IO, "-", "write failed: %s", strerror(errno));
        af->fp = NULL;
        return LIE_OK;
    }
    int bad = ferror(af->fp) || fflush(af->fp) != 0 || fsync(fileno(af->fp)) != 0;
    int e = errno;
    if (fclose(af->fp) != 0 && !bad) {
        bad = 1;
        e = errno;
    }
    af->fp = NULL;
    if (bad) {
        unlink(af->tmp);
        return lie_error_set(err, LIE_ERR_IO, af->path, "write failed: %s", strerror(e ? e : EIO));
    }
    if (rename(af->tmp, af->path) != 0) {
        e = errno;
        unlink(af->tmp);
        return lie_error_set(err, LIE_ERR_IO, af->path, "cannot rename into place: %s", strerror(e));
    }
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
}

lie_status lie_read_file(const char *path, unsigned char **data, size_t *size, lie_error *err)
{
    *data = NULL;
    *size = 0;
    FILE *fp = strcmp(path, "-") == 0 ? stdin : fopen(path, "rb");
    if (!fp)
        return lie_error_set(err, LIE_ERR_IO, path, "cannot open: %s", strerror(errno));
    size_t cap = 1 << 16, n = 0;
    unsigned char *buf = malloc(cap);
    if (!buf) {
        if (fp != stdin)
            fclose(fp);
        return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
    }
    for (;;) {
        if (n == cap) {
            unsigned char *nb = cap > SIZE_MAX / 2 ? NULL : realloc(buf, cap * 2);
            if (!nb) {
                free(buf);
                if (fp != stdin)
                    fclose(fp);
                return lie_error_set(err, LIE_ERR_NOMEM, path, "out of memory");
            }
            buf = nb;
            cap *= 2;
        }
        size_t got = fread(buf + n, 1, cap - n, fp);
        n += got;
        if (got == 0)
            break;
    }
    int bad = ferror(fp);
    int e = errno;
    if (fp != stdin)
        fclose(fp);
    if (bad) {
        free(buf);
        return lie_error_set(err, LIE_ERR_IO, path, "read failed: %s", strerror(e));
    }
    *data = buf;
    *size = n;
    return LIE_OK;
}
