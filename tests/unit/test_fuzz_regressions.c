/* SPDX-License-Identifier: Apache-2.0 */
/* Every input under tests/fuzz/regressions/TARGET/ (crashes the fuzzers
 * found, kept once fixed) replayed through the same checks as its fuzz
 * target, so that `make test`, and its ASan + UBSan run, keep them fixed.
 * The fuzz targets are compiled in here with their entry points renamed. */
#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#define LIE_FUZZ_ENTRY fuzz_cache_one
#include "../fuzz/fuzz_cache.c"
#undef LIE_FUZZ_ENTRY
#define LIE_FUZZ_ENTRY fuzz_edit_one
#include "../fuzz/fuzz_edit.c"
#undef LIE_FUZZ_ENTRY
#define LIE_FUZZ_ENTRY fuzz_campath_one
#include "../fuzz/fuzz_campath.c"
#undef LIE_FUZZ_ENTRY
#define LIE_FUZZ_ENTRY fuzz_gltf_one
#include "../fuzz/fuzz_gltf.c"
#undef LIE_FUZZ_ENTRY

#define REGRESSIONS TEST_SCENES "/../fuzz/regressions"

typedef int (*fuzz_fn)(const unsigned char *data, size_t size);

static int name_cmp(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* Feed every file of regressions/<target>/ to fn, in name order; returns how many. */
static int replay(const char *target, fuzz_fn fn)
{
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/%s", REGRESSIONS, target);
    DIR *d = opendir(dir);
    if (!d)
        return 0; /* no regressions yet */
    char **names = NULL;
    size_t n = 0;
    for (struct dirent *de; (de = readdir(d));) {
        if (de->d_name[0] == '.')
            continue;
        names = realloc(names, (n + 1) * sizeof *names);
        assert_non_null(names);
        names[n] = strdup(de->d_name);
        assert_non_null(names[n]);
        n++;
    }
    closedir(d);
    if (n)
        qsort(names, n, sizeof *names, name_cmp);
    for (size_t i = 0; i < n; i++) {
        char path[2048];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        unsigned char *data = NULL;
        size_t size = 0;
        lie_error err;
        if (lie_read_file(path, &data, &size, &err) != LIE_OK)
            fail_msg("%s: cannot read", path);
        /* A regression that comes back aborts or trips a sanitizer here. */
        print_message("replaying %s/%s (%zu bytes)\n", target, names[i], size);
        fn(data, size);
        free(data);
        free(names[i]);
    }
    free(names);
    return (int)n;
}

static void test_fuzz_regressions_cache_rejected_or_round_trip(void **state)
{
    (void)state;
    replay("cache", fuzz_cache_one);
}

static void test_fuzz_regressions_edit_parse_and_apply(void **state)
{
    (void)state;
    replay("edit", fuzz_edit_one);
}

static void test_fuzz_regressions_campath_parse_and_frames(void **state)
{
    (void)state;
    assert_true(replay("campath", fuzz_campath_one) >= 1);
}

static void test_fuzz_regressions_gltf_import(void **state)
{
    (void)state;
    replay("gltf", fuzz_gltf_one);
}

/* The targets themselves on a few ordinary inputs, so that a broken target
 * (not just a broken reader) shows here too. */
static void test_fuzz_targets_accept_ordinary_inputs(void **state)
{
    (void)state;
    static const char edit[] = "- move: {node: TallBlock, by: [0.5, 0, 0]}\n- remove: {node: ShortBlock}\n";
    static const char path[] = "keys:\n  - {eye: [0, 1, 5], target: [0, 1, 0], frames: 3}\n"
                               "  - {eye: [5, 1, 0], target: [0, 1, 0]}\n";
    fuzz_edit_one((const unsigned char *)edit, strlen(edit));
    fuzz_campath_one((const unsigned char *)path, strlen(path));
    unsigned char *data = NULL;
    size_t size = 0;
    lie_error err;
    assert_int_equal(lie_read_file(TEST_SCENES "/cornell.gltf", &data, &size, &err), LIE_OK);
    fuzz_gltf_one(data, size);
    free(data);
    static const unsigned char junk[64] = "LIECACHE";
    fuzz_cache_one(junk, sizeof junk);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fuzz_regressions_cache_rejected_or_round_trip),
        cmocka_unit_test(test_fuzz_regressions_edit_parse_and_apply),
        cmocka_unit_test(test_fuzz_regressions_campath_parse_and_frames),
        cmocka_unit_test(test_fuzz_regressions_gltf_import),
        cmocka_unit_test(test_fuzz_targets_accept_ordinary_inputs),
    };
    return cmocka_run_group_tests_name("fuzz_regressions", tests, NULL, NULL);
}
