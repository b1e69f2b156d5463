/* SPDX-License-Identifier: Apache-2.0 */
/* lib/core's inputs, outputs and messages (docs/tools.md, "Hostile inputs
 * and outputs"): control bytes are
 * escaped, inputs are regular files within a limit, a group of outputs
 * appears together or not at all, stale temporaries are found by name. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "core/core.h"

static char dir[64];

static int setup(void **state)
{
    snprintf(dir, sizeof dir, "/tmp/lie-test-file.XXXXXX");
    return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state)
{
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static void path_in(char *out, size_t size, const char *name) { snprintf(out, size, "%s/%s", dir, name); }

static void test_escape_controls_like_git(void **state)
{
    char out[256];
    lie_escape_controls(out, sizeof out, "a\nb\tc\rd\033[31m\x07" "e");
    assert_string_equal(out, "a\\nb\\tc\\rd\\033[31m\\007e");
    lie_escape_controls(out, sizeof out, "Zo\xc3\xab \xe2\x82\xac \xf0\x9f\x98\x80"); /* UTF-8 passes */
    assert_string_equal(out, "Zo\xc3\xab \xe2\x82\xac \xf0\x9f\x98\x80");
    lie_escape_controls(out, sizeof out, "x\xc2\x9by\xffz\xc3"); /* C1 CSI, not UTF-8, a cut sequence */
    assert_string_equal(out, "x\\302\\233y\\377z\\303");
    lie_escape_controls(out, 5, "ab\ncd"); /* truncated to fit, */
    assert_string_equal(out, "ab\\n");
    lie_escape_controls(out, 4, "ab\ncd"); /* never inside an escape */
    assert_string_equal(out, "ab");
}

static void test_error_messages_are_escaped(void **state)
{
    lie_error err;
    lie_error_set(&err, LIE_ERR_FORMAT, "dir\n/x.gltf", "node '%s' not found", "A\033]0;t\007");
    char line[512];
    lie_error_format(&err, line, sizeof line);
    assert_string_equal(line, "dir\\n/x.gltf: node 'A\\033]0;t\\007' not found");
}

static void test_read_refuses_fifo_and_respects_limit(void **state)
{
    char fifo[128], big[128];
    path_in(fifo, sizeof fifo, "fifo");
    path_in(big, sizeof big, "big");
    assert_int_equal(mkfifo(fifo, 0600), 0);
    unsigned char *data;
    size_t size;
    lie_error err;
    assert_int_equal(lie_read_file(fifo, &data, &size, &err), LIE_ERR_IO); /* at once, no writer needed */
    assert_non_null(strstr(err.msg, "cannot read a FIFO"));
    assert_int_equal(lie_read_file(dir, &data, &size, &err), LIE_ERR_IO);
    assert_non_null(strstr(err.msg, "a directory"));
    FILE *fp = fopen(big, "wb");
    assert_non_null(fp);
    for (int i = 0; i < 100; i++)
        fputc('x', fp);
    fclose(fp);
    assert_int_equal(lie_read_file_max(big, 99, &data, &size, &err), LIE_ERR_LIMIT);
    assert_int_equal(lie_read_file_max(big, 100, &data, &size, &err), LIE_OK);
    assert_int_equal(size, 100);
    free(data);
}

static void write_text(lie_atomic_file *af, const char *text) { fputs(text, af->fp); }

static int file_is(const char *path, const char *text)
{
    char buf[64] = {0};
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return 0;
    size_t n = fread(buf, 1, sizeof buf - 1, fp);
    fclose(fp);
    return n == strlen(text) && memcmp(buf, text, n) == 0;
}

static void count_cb(void *ctx, const char *name, uint64_t bytes)
{
    (void)name;
    (void)bytes;
    ++*(int *)ctx;
}

static void test_group_commits_all_or_none(void **state)
{
    char a[128], b[128];
    path_in(a, sizeof a, "a.out");
    path_in(b, sizeof b, "b.out");
    lie_error err;
    /* abandoned: nothing appears, no temporary stays */
    lie_atomic_group *g = lie_atomic_group_create();
    lie_atomic_file fa, fb;
    assert_int_equal(lie_atomic_open_group(&fa, a, g, &err), LIE_OK);
    write_text(&fa, "A");
    assert_int_equal(lie_atomic_commit(&fa, &err), LIE_OK);
    assert_int_equal(access(a, F_OK), -1); /* complete, but not yet visible */
    lie_atomic_group_destroy(g);
    assert_int_equal(access(a, F_OK), -1);
    int n = 0;
    assert_int_equal(lie_tmp_clean(dir, 0, 1, count_cb, &n, &err), LIE_OK);
    assert_int_equal(n, 0); /* the temporary went with the group */
    /* committed: both appear */
    g = lie_atomic_group_create();
    assert_int_equal(lie_atomic_open_group(&fa, a, g, &err), LIE_OK);
    assert_int_equal(lie_atomic_open_group(&fb, b, g, &err), LIE_OK);
    write_text(&fa, "A");
    write_text(&fb, "B");
    assert_int_equal(lie_atomic_commit(&fa, &err), LIE_OK);
    assert_int_equal(lie_atomic_commit(&fb, &err), LIE_OK);
    assert_int_equal(lie_atomic_group_commit(g, &err), LIE_OK);
    lie_atomic_group_destroy(g);
    assert_true(file_is(a, "A"));
    assert_true(file_is(b, "B"));
}


static void put_file(const char *path, const char *text)
{
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    fputs(text, fp);
    fclose(fp);
}

static int count_tmps(void)
{
    int n = 0;
    lie_error err;
    assert_int_equal(lie_tmp_clean(dir, 0, 1, count_cb, &n, &err), LIE_OK);
    return n;
}

/* "Do not replace" is the rename's own test: a file that appears between
 * the open and the commit is not replaced, alone or in a group, and a group
 * then places nothing (not even its replacing files). */
static void test_no_replace_is_decided_by_the_rename(void **state)
{
    char a[128], b[128], c[128];
    path_in(a, sizeof a, "a.out");
    path_in(b, sizeof b, "b.out");
    path_in(c, sizeof c, "c.out");
    lie_error err;
    lie_atomic_file fa, fb, fc;
    /* alone: exists at the open, appears before the commit */
    put_file(a, "theirs");
    assert_int_equal(lie_atomic_open_flags(&fa, a, NULL, LIE_ATOMIC_NO_REPLACE, &err), LIE_ERR_IO);
    assert_non_null(strstr(err.msg, "exists"));
    assert_int_equal(lie_atomic_open_flags(&fb, b, NULL, LIE_ATOMIC_NO_REPLACE, &err), LIE_OK);
    write_text(&fb, "ours");
    put_file(b, "theirs");
    assert_int_equal(lie_atomic_commit(&fb, &err), LIE_ERR_IO);
    assert_non_null(strstr(err.msg, "exists"));
    assert_true(file_is(b, "theirs"));
    assert_int_equal(count_tmps(), 0);
    /* a group of one replacing file and two new ones, one of which appears */
    unlink(b);
    put_file(c, "old");
    lie_atomic_group *g = lie_atomic_group_create();
    assert_int_equal(lie_atomic_open_flags(&fc, c, g, 0, &err), LIE_OK);
    unlink(a);
    assert_int_equal(lie_atomic_open_flags(&fa, a, g, LIE_ATOMIC_NO_REPLACE, &err), LIE_OK);
    assert_int_equal(lie_atomic_open_flags(&fb, b, g, LIE_ATOMIC_NO_REPLACE, &err), LIE_OK);
    write_text(&fa, "A");
    write_text(&fb, "B");
    write_text(&fc, "C");
    assert_int_equal(lie_atomic_commit(&fc, &err), LIE_OK);
    assert_int_equal(lie_atomic_commit(&fa, &err), LIE_OK);
    assert_int_equal(lie_atomic_commit(&fb, &err), LIE_OK);
    put_file(b, "theirs");
    assert_int_equal(lie_atomic_group_commit(g, &err), LIE_ERR_IO);
    lie_atomic_group_destroy(g);
    assert_int_equal(access(a, F_OK), -1); /* placed, then taken back */
    assert_true(file_is(b, "theirs"));
    assert_true(file_is(c, "old"));
    assert_int_equal(count_tmps(), 0);
}

/* A replaced file keeps its owner, group and mode: as root, a file of
 * another user (65534, "nobody") stays theirs and readable by them. */
static void test_replaced_file_keeps_owner_and_mode(void **state)
{
    char a[128];
    path_in(a, sizeof a, "a.out");
    put_file(a, "old");
    assert_int_equal(chmod(a, 0640), 0);
    uid_t uid = geteuid() == 0 ? 65534 : geteuid();
    gid_t gid = geteuid() == 0 ? 65534 : getegid();
    assert_int_equal(chown(a, uid, gid), 0);
    lie_error err;
    lie_atomic_file fa;
    assert_int_equal(lie_atomic_open(&fa, a, &err), LIE_OK);
    write_text(&fa, "new");
    assert_int_equal(lie_atomic_commit(&fa, &err), LIE_OK);
    struct stat st;
    assert_int_equal(stat(a, &st), 0);
    assert_true(file_is(a, "new"));
    assert_int_equal(st.st_uid, uid);
    assert_int_equal(st.st_gid, gid);
    assert_int_equal(st.st_mode & 07777, 0640);
}

/* SIGTERM at any moment of a group's commit leaves all of its files old or
 * all new: a child commits a group of 24 replacing files and is killed a
 * random few microseconds after it says it starts, 60 times. */
static void test_group_commit_is_whole_under_sigterm(void **state)
{
    enum { FILES = 24, RUNS = 60 };
    char names[FILES][128];
    for (int i = 0; i < FILES; i++) {
        char n[32];
        snprintf(n, sizeof n, "f%02d.out", i);
        path_in(names[i], sizeof names[i], n);
    }
    int mixed = 0;
    for (int run = 0; run < RUNS; run++) {
        for (int i = 0; i < FILES; i++)
            put_file(names[i], "old");
        int pfd[2];
        assert_int_equal(pipe(pfd), 0);
        pid_t pid = fork();
        assert_true(pid >= 0);
        if (pid == 0) {
            close(pfd[0]);
            lie_error err;
            lie_atomic_group *g = lie_atomic_group_create();
            lie_atomic_file f;
            for (int i = 0; i < FILES; i++) {
                if (lie_atomic_open_group(&f, names[i], g, &err) != LIE_OK)
                    _exit(3);
                write_text(&f, "new");
                if (lie_atomic_commit(&f, &err) != LIE_OK)
                    _exit(3);
            }
            (void)!write(pfd[1], "x", 1);
            lie_status st = lie_atomic_group_commit(g, &err);
            lie_atomic_group_destroy(g);
            _exit(st == LIE_OK ? 0 : 4);
        }
        close(pfd[1]);
        char x;
        assert_int_equal(read(pfd[0], &x, 1), 1);
        close(pfd[0]);
        struct timespec ts = {0, (run % 12) * 15000L};
        nanosleep(&ts, NULL);
        kill(pid, SIGTERM);
        int status;
        assert_int_equal(waitpid(pid, &status, 0), pid);
        assert_true(WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 0));
        int n_new = 0;
        for (int i = 0; i < FILES; i++)
            n_new += file_is(names[i], "new");
        if (n_new != 0 && n_new != FILES)
            mixed++;
        assert_int_equal(count_tmps(), 0);
    }
    assert_int_equal(mixed, 0);
}

static void test_tmp_clean_finds_our_names_only(void **state)
{
    const char *names[] = {".x.lie.tmpAb12Cd", ".y.exr.tmp000000", ".z.tmp", "w.lie.tmpAb12Cd", ".v.lie.tmpAb_2Cd"};
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
        char p[128];
        path_in(p, sizeof p, names[i]);
        FILE *fp = fopen(p, "wb");
        assert_non_null(fp);
        fclose(fp);
    }
    lie_error err;
    int n = 0;
    assert_int_equal(lie_tmp_clean(dir, 0, 1, count_cb, &n, &err), LIE_OK);
    assert_int_equal(n, 2);
    n = 0;
    assert_int_equal(lie_tmp_clean(dir, 3600, 0, count_cb, &n, &err), LIE_OK);
    assert_int_equal(n, 0); /* all younger than an hour */
    assert_int_equal(lie_tmp_clean(dir, 0, 0, count_cb, &n, &err), LIE_OK);
    assert_int_equal(n, 2);
    char p[128];
    path_in(p, sizeof p, ".x.lie.tmpAb12Cd");
    assert_int_equal(access(p, F_OK), -1);
    path_in(p, sizeof p, ".z.tmp");
    assert_int_equal(access(p, F_OK), 0);
}

static void expect_path(const char *path, const char *other, const char *want)
{
    char *got = lie_path_from_folder_of(path, other);
    if (!want) {
        assert_null(got);
        return;
    }
    assert_non_null(got);
    assert_string_equal(got, want);
    free(got);
}

/* A path given from the working directory, rewritten from another file's
 * folder (a cache's edit log, lib/cache): the same file from there. */
static void test_path_from_another_folder_names_the_same_file(void **state)
{
    char here[4096], p[128];
    assert_non_null(getcwd(here, sizeof here));
    const char *dirs[] = {"a", "a/b", "c"};
    for (int i = 0; i < 3; i++) {
        path_in(p, sizeof p, dirs[i]);
        assert_int_equal(mkdir(p, 0755), 0);
    }
    assert_int_equal(chdir(dir), 0);
    expect_path("a/b/e.yaml", "c/u.lie", "../a/b/e.yaml");
    expect_path("a/e.yaml", "a/b/u.lie", "../e.yaml");
    expect_path("a/b/e.yaml", "a/u.lie", "b/e.yaml");
    expect_path("e.yaml", "u.lie", "e.yaml");
    expect_path("./a/../c/e.yaml", "c/u.lie", "e.yaml");
    expect_path("/x/e.yaml", "c/u.lie", "/x/e.yaml");
    expect_path("nosuch/e.yaml", "u.lie", NULL);
    expect_path("e.yaml", "nosuch/u.lie", NULL);
    assert_int_equal(chdir(here), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_escape_controls_like_git),
        cmocka_unit_test(test_error_messages_are_escaped),
        cmocka_unit_test_setup_teardown(test_read_refuses_fifo_and_respects_limit, setup, teardown),
        cmocka_unit_test_setup_teardown(test_group_commits_all_or_none, setup, teardown),
        cmocka_unit_test_setup_teardown(test_tmp_clean_finds_our_names_only, setup, teardown),
        cmocka_unit_test_setup_teardown(test_path_from_another_folder_names_the_same_file, setup, teardown),
        cmocka_unit_test_setup_teardown(test_no_replace_is_decided_by_the_rename, setup, teardown),
        cmocka_unit_test_setup_teardown(test_replaced_file_keeps_owner_and_mode, setup, teardown),
        cmocka_unit_test_setup_teardown(test_group_commit_is_whole_under_sigterm, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
