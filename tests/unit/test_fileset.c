/* SPDX-License-Identifier: Apache-2.0 */
/* lib/core file sets (fileset.c) and loading a scene from one: what lib/dist
 * broadcasts under mpirun.  A scene recorded on one load loads again from
 * the set alone, with the same content hash, and the URI policy still
 * holds. */
#include <limits.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "fixtures.h"
#include "scene/scene.h"

#define SCENES TEST_SCENES "/"
#define FIXTURES TEST_SCENES "/../data/gltf/"

static void test_fileset_pack_unpack_round_trip(void **state)
{
    lie_error err;
    lie_file_set *a = lie_file_set_create(LIE_FILES_RECORD);
    assert_non_null(a);
    assert_int_equal(lie_file_set_add(a, "x.gltf", "{}", 2, &err), LIE_OK);
    assert_int_equal(lie_file_set_add(a, "dir/empty.bin", "", 0, &err), LIE_OK);
    assert_int_equal(lie_file_set_add(a, "x.gltf", "changed", 7, &err), LIE_OK); /* the first bytes stay */
    assert_int_equal(lie_file_set_count(a), 2);
    assert_int_equal(lie_file_set_bytes(a), 2);
    unsigned char *d = NULL;
    size_t n = 0;
    assert_int_equal(lie_file_set_pack(a, &d, &n, &err), LIE_OK);
    lie_file_set *b = NULL;
    assert_int_equal(lie_file_set_unpack(d, n, &b, &err), LIE_OK);
    assert_int_equal(lie_file_set_get_mode(b), LIE_FILES_ONLY);
    size_t k;
    const unsigned char *x = lie_file_set_find(b, "x.gltf", &k);
    assert_non_null(x);
    assert_int_equal(k, 2);
    assert_memory_equal(x, "{}", 2);
    assert_non_null(lie_file_set_find(b, "dir/empty.bin", &k));
    assert_int_equal(k, 0);
    /* every truncation and a trailing byte are refused */
    for (size_t cut = 0; cut < n; cut++) {
        lie_file_set *c = NULL;
        assert_int_not_equal(lie_file_set_unpack(d, cut, &c, &err), LIE_OK);
        assert_null(c);
    }
    unsigned char *longer = malloc(n + 1);
    assert_non_null(longer);
    memcpy(longer, d, n);
    longer[n] = 0;
    lie_file_set *c = NULL;
    assert_int_equal(lie_file_set_unpack(longer, n + 1, &c, &err), LIE_ERR_FORMAT);
    free(longer);
    /* a NUL inside a path (found by tests/fuzz/fuzz_fileset.c): refused, not cut short */
    unsigned char nul[16 + 16 + 3] = {'L', 'I', 'E', 'F', 'I', 'L', 'E', 'S', 1};
    nul[16] = 3;
    memcpy(nul + 32, "a\0b", 3);
    assert_int_equal(lie_file_set_unpack(nul, sizeof nul, &c, &err), LIE_ERR_FORMAT);
    assert_non_null(strstr(err.msg, "NUL"));
    assert_null(c);
    free(d);
    lie_file_set_destroy(b);
    lie_file_set_destroy(a);
}

static void test_fileset_only_mode_reads_nothing_else(void **state)
{
    lie_error err;
    lie_file_set *only = NULL;
    unsigned char packed[16] = {'L', 'I', 'E', 'F', 'I', 'L', 'E', 'S'};
    assert_int_equal(lie_file_set_unpack(packed, sizeof packed, &only, &err), LIE_OK);
    unsigned char *d = NULL;
    size_t n = 0;
    /* a file that exists on disk is still not read */
    assert_int_equal(lie_file_set_read(only, SCENES "cornell.gltf", LIE_READ_MAX_TEXT, &d, &n, &err), LIE_ERR_IO);
    assert_null(d);
    assert_non_null(strstr(err.msg, LIE_FILE_SET_MISSING));
    assert_false(lie_file_set_exists(only, SCENES "cornell.gltf"));
    assert_true(lie_file_set_exists(NULL, SCENES "cornell.gltf"));
    lie_file_set_destroy(only);
}

/* Load path recording its files; load again from the packed set alone. */
static void expect_load_from_memory(const char *path, int n_files)
{
    lie_error err;
    lie_scene_options so = lie_scene_options_default();
    so.files = lie_file_set_create(LIE_FILES_RECORD);
    assert_non_null(so.files);
    lie_scene *a = NULL, *b = NULL;
    assert_int_equal(lie_scene_load(path, &so, &a, &err), LIE_OK);
    assert_int_equal(lie_file_set_count(so.files), n_files);
    unsigned char *d = NULL;
    size_t n = 0;
    assert_int_equal(lie_file_set_pack(so.files, &d, &n, &err), LIE_OK);
    lie_file_set_destroy(so.files);
    assert_int_equal(lie_file_set_unpack(d, n, &so.files, &err), LIE_OK);
    free(d);
    assert_int_equal(lie_scene_load(path, &so, &b, &err), LIE_OK);
    assert_true(a->hash == b->hash);
    assert_int_equal(a->n_textures, b->n_textures);
    for (int t = 0; t < a->n_textures; t++)
        assert_texels_equal(&a->textures[t], &b->textures[t]);
    lie_file_set_destroy(so.files);
    lie_scene_destroy(b);
    lie_scene_destroy(a);
}

static void test_scene_loads_from_the_files_another_load_read(void **state)
{
    expect_load_from_memory(SCENES "museum2.gltf", 3);        /* .gltf, .bin, the floor's PNG */
    expect_load_from_memory(FIXTURES "inside_dotdot.gltf", 3); /* "sub/../external.bin" and an escaped URI */
}

static void test_scene_from_memory_keeps_the_uri_policy(void **state)
{
    /* a set holding the file a URI names does not let the URI leave the
     * scene's folder: the policy runs before the set is asked */
    lie_error err;
    lie_scene_options so = lie_scene_options_default();
    so.files = lie_file_set_create(LIE_FILES_RECORD);
    assert_non_null(so.files);
    unsigned char *d = NULL;
    size_t n = 0;
    assert_int_equal(lie_read_file(FIXTURES "external.bin", &d, &n, &err), LIE_OK);
    assert_int_equal(lie_file_set_add(so.files, FIXTURES "escape/../external.bin", d, n, &err), LIE_OK);
    free(d);
    lie_scene *s = NULL;
    lie_error_clear(&err);
    assert_int_equal(lie_scene_load(FIXTURES "escape/escape.gltf", &so, &s, &err), LIE_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "leaves the scene's folder"));
    assert_null(s);
    lie_file_set_destroy(so.files);
}


/* A run's outputs: never an input (by name, through a symlink, a hard link
 * or ".."), never another output (even one not there yet); the input an
 * output updates in place, "-" and devices pass. */
static void test_outputs_may_be_no_input_and_no_other_output(void **state)
{
    char dir[] = "/tmp/lie-test-claim.XXXXXX";
    assert_non_null(mkdtemp(dir));
    char in[256], lnk[256], hard[256], out[256], dotdot[256], sub[256];
    snprintf(in, sizeof in, "%s/in.lie", dir);
    snprintf(lnk, sizeof lnk, "%s/link.png", dir);
    snprintf(hard, sizeof hard, "%s/hard.png", dir);
    snprintf(out, sizeof out, "%s/out.png", dir);
    snprintf(sub, sizeof sub, "%s/sub", dir);
    snprintf(dotdot, sizeof dotdot, "%s/sub/../out.png", dir);
    FILE *fp = fopen(in, "w");
    assert_non_null(fp);
    fputs("x", fp);
    fclose(fp);
    assert_int_equal(symlink(in, lnk), 0);
    assert_int_equal(link(in, hard), 0);
    assert_int_equal(mkdir(sub, 0700), 0);
    lie_error err;
    lie_file_set *set = lie_file_set_create(LIE_FILES_NAMES);
    assert_int_equal(lie_file_set_note(set, in, &err), LIE_OK);
    assert_int_equal(lie_file_set_claim(set, in, NULL, &err), LIE_ERR_ARG);
    assert_non_null(strstr(err.msg, "is also the input"));
    assert_int_equal(lie_file_set_claim(set, lnk, NULL, &err), LIE_ERR_ARG);
    assert_int_equal(lie_file_set_claim(set, hard, NULL, &err), LIE_ERR_ARG);
    assert_int_equal(lie_file_set_check(set, hard, &err), LIE_ERR_ARG);
    assert_int_equal(lie_file_set_claim(set, out, NULL, &err), LIE_OK); /* not there yet */
    assert_int_equal(lie_file_set_claim(set, out, NULL, &err), LIE_ERR_ARG);
    assert_non_null(strstr(err.msg, "is also the output"));
    assert_int_equal(lie_file_set_claim(set, dotdot, NULL, &err), LIE_ERR_ARG);
    assert_int_equal(lie_file_set_check(set, dotdot, &err), LIE_ERR_ARG);
    assert_int_equal(lie_file_set_claim(set, in, in, &err), LIE_OK); /* an update in place */
    assert_int_equal(lie_file_set_claim(set, "-", NULL, &err), LIE_OK);
    assert_int_equal(lie_file_set_claim(set, "-", NULL, &err), LIE_OK);
    assert_int_equal(lie_file_set_claim(set, "/dev/null", NULL, &err), LIE_OK);
    assert_int_equal(lie_file_set_claim(set, "/dev/null", NULL, &err), LIE_OK);
    assert_int_equal(lie_file_set_claim(NULL, in, NULL, &err), LIE_OK); /* no set: no check */
    lie_file_set_destroy(set);
    /* a scene's load names its buffers: none may be an output */
    set = lie_file_set_create(LIE_FILES_NAMES);
    lie_scene_options so = lie_scene_options_default();
    so.files = set;
    lie_scene *s = NULL;
    assert_int_equal(lie_scene_load(SCENES "cornell.gltf", &so, &s, &err), LIE_OK);
    assert_int_equal(lie_file_set_bytes(set), 0); /* names, not bytes */
    assert_int_equal(lie_file_set_claim(set, SCENES "cornell.bin", NULL, &err), LIE_ERR_ARG);
    assert_int_equal(lie_file_set_claim(set, SCENES "../scenes/cornell.gltf", NULL, &err), LIE_ERR_ARG);
    lie_scene_destroy(s);
    lie_file_set_destroy(set);
    unlink(lnk);
    unlink(hard);
    unlink(in);
    rmdir(sub);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fileset_pack_unpack_round_trip),
        cmocka_unit_test(test_fileset_only_mode_reads_nothing_else),
        cmocka_unit_test(test_scene_loads_from_the_files_another_load_read),
        cmocka_unit_test(test_scene_from_memory_keeps_the_uri_policy),
        cmocka_unit_test(test_outputs_may_be_no_input_and_no_other_output),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
