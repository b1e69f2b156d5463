/* SPDX-License-Identifier: Apache-2.0 */
/* lib/image: frames, sRGB curves, EXR and PNG writers and the EXR reader.
 * Size: long as one file per module is (CONTRIBUTING.md, Tests): each writer
 * and the reader have their own group of tests below. */
#include <fcntl.h>
#include <ftw.h>
#include <math.h>
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

#include <OpenEXR/openexr.h>
#include <png.h>

#include "image/image.h"

/* ---- helpers ------------------------------------------------------------- */

static char g_dir[256];

static const char *tmp_path(const char *name)
{
    static char buf[4][512];
    static int next;
    char *p = buf[next++ & 3];
    snprintf(p, sizeof buf[0], "%s/%s", g_dir, name);
    return p;
}

static int rm_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb;
    (void)flag;
    (void)ftw;
    return remove(path);
}

static int group_setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/lie-test-image-XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int group_teardown(void **state)
{
    (void)state;
    return nftw(g_dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
}

static unsigned char *slurp(const char *path, size_t *size)
{
    unsigned char *data = NULL;
    lie_error err;
    assert_int_equal(lie_read_file(path, &data, size, &err), LIE_OK);
    return data;
}

/* The two files hold the same bytes. */
static void assert_files_equal(const char *p1, const char *p2)
{
    size_t n1, n2;
    unsigned char *d1 = slurp(p1, &n1), *d2 = slurp(p2, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(d1, d2, n1);
    free(d1);
    free(d2);
}

static void spit(const char *path, const void *data, size_t size)
{
    /* A fresh file: truncating one makes ext4 flush it to disk first. */
    unlink(path);
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    assert_int_equal(fwrite(data, 1, size, fp), size);
    assert_int_equal(fclose(fp), 0);
}

static float bits_to_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* A 7x5 frame whose every sample differs, including awkward floats. */
static lie_frame *make_test_frame(void)
{
    lie_frame *f = lie_frame_create(7, 5);
    assert_non_null(f);
    static const char *const one[1] = {"R"};
    static const char *const xyz[3] = {"X", "Y", "Z"};
    float *cx = lie_frame_add_aov(f, "complexity", 1, one);
    float *nrm = lie_frame_add_aov(f, "normal", 3, xyz);
    assert_non_null(cx);
    assert_non_null(nrm);
    for (int i = 0; i < 7 * 5 * 3; i++)
        f->rgb[i] = (float)i * 0.37f - 3.0f;
    for (int i = 0; i < 7 * 5; i++)
        cx[i] = (float)(i * i);
    for (int i = 0; i < 7 * 5 * 3; i++)
        nrm[i] = sinf((float)i);
    /* Values that must survive bit for bit. */
    f->rgb[0] = -0.0f;
    f->rgb[1] = bits_to_float(0x00000001u); /* smallest denormal */
    f->rgb[2] = INFINITY;
    f->rgb[3] = -INFINITY;
    f->rgb[4] = bits_to_float(0x7fc01234u); /* NaN with a payload */
    f->rgb[5] = 3.4028235e38f;
    return f;
}

static void assert_frames_identical(const lie_frame *a, const lie_frame *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    size_t n = (size_t)a->width * (size_t)a->height;
    assert_memory_equal(a->rgb, b->rgb, n * 3 * sizeof(float));
    assert_int_equal(a->n_aovs, b->n_aovs);
    for (int i = 0; i < a->n_aovs; i++) {
        const lie_aov *x = &a->aovs[i];
        const lie_aov *y = lie_frame_find_aov(b, x->name);
        assert_non_null(y);
        assert_int_equal(x->n_channels, y->n_channels);
        for (int c = 0; c < x->n_channels; c++)
            assert_string_equal(x->channel[c], y->channel[c]);
        assert_memory_equal(x->data, y->data, n * (size_t)x->n_channels * sizeof(float));
    }
}

/* ---- frames ------------------------------------------------------------ */

static void test_frame_create_zeroes_rgb(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(3, 2);
    assert_non_null(f);
    assert_int_equal(f->width, 3);
    assert_int_equal(f->height, 2);
    assert_int_equal(f->n_aovs, 0);
    for (int i = 0; i < 3 * 2 * 3; i++)
        assert_true(f->rgb[i] == 0.0f);
    lie_frame_destroy(f);
    assert_null(lie_frame_create(0, 2));
    assert_null(lie_frame_create(2, -1));
}

static void test_frame_add_aov_zeroes_data_and_copies_names(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(4, 3);
    char name[16] = "depth", ch[8] = "Z";
    const char *names[1] = {ch};
    float *d = lie_frame_add_aov(f, name, 1, names);
    assert_non_null(d);
    /* The frame keeps its own copies of the names. */
    strcpy(name, "xxxxx");
    strcpy(ch, "Q");
    const lie_aov *a = lie_frame_find_aov(f, "depth");
    assert_non_null(a);
    assert_ptr_equal(a->data, d);
    assert_string_equal(a->channel[0], "Z");
    assert_int_equal(a->n_channels, 1);
    for (int i = 0; i < 12; i++)
        assert_true(d[i] == 0.0f);
    static const char *const rgba[4] = {"R", "G", "B", "A"};
    assert_non_null(lie_frame_add_aov(f, "color", 4, rgba));
    assert_int_equal(f->n_aovs, 2);
    /* Growing the array must keep earlier layers intact. */
    assert_ptr_equal(lie_frame_find_aov(f, "depth")->data, d);
    assert_null(lie_frame_find_aov(f, "missing"));
    lie_frame_destroy(f);
}

static void test_frame_add_aov_rejects_bad_layers(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(2, 2);
    static const char *const five[5] = {"a", "b", "c", "d", "e"};
    static const char *const dup[2] = {"X", "X"};
    static const char *const longch[1] = {"toolongname"};
    static const char *const empty[1] = {""};
    assert_null(lie_frame_add_aov(f, "a", 5, five));
    assert_null(lie_frame_add_aov(f, "a", 0, five));
    assert_null(lie_frame_add_aov(f, "a", 2, dup));
    assert_null(lie_frame_add_aov(f, "a", 1, longch));
    assert_null(lie_frame_add_aov(f, "a", 1, empty));
    assert_null(lie_frame_add_aov(f, "a", 1, NULL));
    assert_null(lie_frame_add_aov(f, "a_name_that_is_longer_than_31_chars", 1, five));
    assert_non_null(lie_frame_add_aov(f, "a", 1, five));
    assert_null(lie_frame_add_aov(f, "a", 1, five)); /* duplicate layer */
    assert_int_equal(f->n_aovs, 1);
    lie_frame_destroy(f);
}

static void test_frame_destroy_accepts_null(void **state)
{
    (void)state;
    lie_frame_destroy(NULL);
}

/* ---- sRGB -------------------------------------------------------------- */

static void test_srgb_curves_are_monotone(void **state)
{
    (void)state;
    /* Every float in [0, 1] would take too long; every 97th bit pattern
     * covers the whole range, and a dense sweep covers the knee. */
    float prev_e = 0.0f, prev_d = 0.0f;
    for (uint32_t u = 0; u <= 0x3f800000u; u += 97) {
        float x = bits_to_float(u);
        float e = lie_image_srgb_encode(x), d = lie_image_srgb_decode(x);
        assert_true(e >= prev_e);
        assert_true(d >= prev_d);
        prev_e = e;
        prev_d = d;
    }
    for (float x = 0.0030f, prev = 0.0f; x < 0.0032f; x = nextafterf(x, 1.0f)) {
        float e = lie_image_srgb_encode(x);
        assert_true(e >= prev);
        prev = e;
    }
    for (float x = 0.0400f, prev = 0.0f; x < 0.0410f; x = nextafterf(x, 1.0f)) {
        float d = lie_image_srgb_decode(x);
        assert_true(d >= prev);
        prev = d;
    }
}

static void test_srgb_curves_invert_each_other(void **state)
{
    (void)state;
    for (int i = 0; i <= 100000; i++) {
        float x = (float)i / 100000.0f;
        assert_true(fabsf(lie_image_srgb_decode(lie_image_srgb_encode(x)) - x) <= 1e-6f);
        assert_true(fabsf(lie_image_srgb_encode(lie_image_srgb_decode(x)) - x) <= 1e-6f);
    }
}

static void test_srgb_curves_clamp_to_unit_range(void **state)
{
    (void)state;
    assert_true(lie_image_srgb_encode(0.0f) == 0.0f);
    assert_true(lie_image_srgb_encode(1.0f) == 1.0f);
    assert_true(lie_image_srgb_encode(-1.0f) == 0.0f);
    assert_true(lie_image_srgb_encode(7.0f) == 1.0f);
    assert_true(lie_image_srgb_encode(NAN) == 0.0f);
    assert_true(lie_image_srgb_decode(NAN) == 0.0f);
    assert_true(lie_image_srgb_decode(2.0f) == 1.0f);
    /* IEC 61966-2-1 reference points. */
    assert_true(fabsf(lie_image_srgb_encode(0.5f) - 0.735357f) < 1e-6f);
    assert_true(fabsf(lie_image_srgb_encode(0.001f) - 0.01292f) < 1e-7f);
    assert_true(fabsf(lie_image_srgb_decode(0.5f) - 0.214041f) < 1e-6f);
}

/* ---- EXR --------------------------------------------------------------- */

static void test_exr_round_trip_is_bit_exact(void **state)
{
    (void)state;
    lie_frame *f = make_test_frame();
    lie_error err;
    const char *path = tmp_path("round.exr");
    assert_int_equal(lie_exr_write(path, f, NULL, &err), LIE_OK);
    lie_frame *g = NULL;
    assert_int_equal(lie_exr_read(path, &g, &err), LIE_OK);
    assert_non_null(g);
    assert_frames_identical(f, g);
    /* Layers come back in channel-list order: complexity before normal. */
    assert_string_equal(g->aovs[0].name, "complexity");
    assert_string_equal(g->aovs[1].name, "normal");
    lie_frame_destroy(f);
    lie_frame_destroy(g);
}

/* Options are per call: each compression round-trips exactly, and a call's
 * choice does not leak into the next (the default stays zip). */
static void test_exr_options_are_per_call(void **state)
{
    (void)state;
    lie_frame *f = make_test_frame();
    lie_error err;
    static const char *const names[] = {"zip", "zips", "piz", "rle", "none"};
    for (int k = 0; k < 5; k++) {
        lie_exr_compression c = LIE_EXR_NONE;
        assert_true(lie_exr_compression_parse(names[k], &c));
        assert_int_equal((int)c, k);
        const char *path = tmp_path("comp.exr");
        lie_exr_options o = {.compression = c, .threads = 1 + k % 2};
        assert_int_equal(lie_exr_write(path, f, &o, &err), LIE_OK);
        lie_frame *g = NULL;
        assert_int_equal(lie_exr_read(path, &g, &err), LIE_OK);
        assert_frames_identical(f, g);
        lie_frame_destroy(g);
    }
    lie_exr_compression c = LIE_EXR_RLE;
    assert_false(lie_exr_compression_parse("zip2", &c));
    assert_false(lie_exr_compression_parse(NULL, &c));
    assert_int_equal((int)c, LIE_EXR_RLE);
    const char *p1 = tmp_path("dflt1.exr"), *p2 = tmp_path("dflt2.exr");
    lie_exr_options zeroed = {0};
    assert_int_equal(lie_exr_write(p1, f, NULL, &err), LIE_OK);
    assert_int_equal(lie_exr_write(p2, f, &zeroed, &err), LIE_OK);
    assert_files_equal(p1, p2);
    lie_exr_options bad = {.compression = (lie_exr_compression)9};
    assert_int_equal(lie_exr_write(p1, f, &bad, &err), LIE_ERR_ARG);
    lie_frame_destroy(f);
}

static void test_exr_round_trip_many_chunks(void **state)
{
    (void)state;
    /* ZIP packs 16 lines a chunk: 37 lines make a partial last chunk. */
    lie_frame *f = lie_frame_create(33, 37);
    static const char *const z[1] = {"Z"};
    float *d = lie_frame_add_aov(f, "depth", 1, z);
    for (int i = 0; i < 33 * 37 * 3; i++)
        f->rgb[i] = (float)(i % 251) / 7.0f;
    for (int i = 0; i < 33 * 37; i++)
        d[i] = (float)i;
    lie_error err;
    const char *path = tmp_path("chunks.exr");
    assert_int_equal(lie_exr_write(path, f, NULL, &err), LIE_OK);
    lie_frame *g = NULL;
    assert_int_equal(lie_exr_read(path, &g, &err), LIE_OK);
    assert_frames_identical(f, g);
    lie_frame_destroy(f);
    lie_frame_destroy(g);
}

static void test_exr_layer_channels_read_back_in_rgba_order(void **state)
{
    (void)state;
    /* The channel list is sorted (B, G, R); the reader restores R, G, B. */
    lie_frame *f = lie_frame_create(2, 2);
    static const char *const rgb[3] = {"R", "G", "B"};
    float *c = lie_frame_add_aov(f, "albedo", 3, rgb);
    for (int i = 0; i < 12; i++)
        c[i] = (float)i;
    lie_error err;
    const char *path = tmp_path("rgba.exr");
    assert_int_equal(lie_exr_write(path, f, NULL, &err), LIE_OK);
    lie_frame *g = NULL;
    assert_int_equal(lie_exr_read(path, &g, &err), LIE_OK);
    const lie_aov *a = lie_frame_find_aov(g, "albedo");
    assert_non_null(a);
    assert_string_equal(a->channel[0], "R");
    assert_string_equal(a->channel[1], "G");
    assert_string_equal(a->channel[2], "B");
    assert_memory_equal(a->data, c, 12 * sizeof(float));
    lie_frame_destroy(f);
    lie_frame_destroy(g);
}

static void test_exr_long_channel_names_round_trip(void **state)
{
    (void)state;
    /* 31 + 1 + 7 bytes: beyond EXR's short-name limit. */
    lie_frame *f = lie_frame_create(3, 1);
    static const char *const ch[1] = {"channel"};
    const char *layer = "a_layer_name_of_31_characters__";
    float *d = lie_frame_add_aov(f, layer, 1, ch);
    assert_non_null(d);
    d[1] = 42.0f;
    lie_error err;
    const char *path = tmp_path("long.exr");
    assert_int_equal(lie_exr_write(path, f, NULL, &err), LIE_OK);
    lie_frame *g = NULL;
    assert_int_equal(lie_exr_read(path, &g, &err), LIE_OK);
    assert_frames_identical(f, g);
    lie_frame_destroy(f);
    lie_frame_destroy(g);
}

static void test_exr_default_layer_is_written_without_prefix(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(2, 1);
    static const char *const az[2] = {"A", "Z"};
    float *d = lie_frame_add_aov(f, "", 2, az);
    assert_non_null(d);
    d[0] = 1.0f;
    d[3] = 2.0f;
    lie_error err;
    const char *path = tmp_path("default.exr");
    assert_int_equal(lie_exr_write(path, f, NULL, &err), LIE_OK);

    exr_context_t ctx;
    assert_int_equal(exr_start_read(&ctx, path, NULL), EXR_ERR_SUCCESS);
    const exr_attr_chlist_t *cl;
    assert_int_equal(exr_get_channels(ctx, 0, &cl), EXR_ERR_SUCCESS);
    assert_int_equal(cl->num_channels, 5);
    static const char *const want[5] = {"A", "B", "G", "R", "Z"};
    for (int i = 0; i < 5; i++) {
        assert_string_equal(cl->entries[i].name.str, want[i]);
        assert_int_equal(cl->entries[i].pixel_type, EXR_PIXEL_FLOAT);
    }
    exr_compression_t comp;
    assert_int_equal(exr_get_compression(ctx, 0, &comp), EXR_ERR_SUCCESS);
    assert_int_equal(comp, EXR_COMPRESSION_ZIP);
    exr_finish(&ctx);

    lie_frame *g = NULL;
    assert_int_equal(lie_exr_read(path, &g, &err), LIE_OK);
    assert_frames_identical(f, g);
    lie_frame_destroy(f);
    lie_frame_destroy(g);
}

static void test_exr_write_rejects_duplicate_channels(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(2, 1);
    static const char *const r[1] = {"R"};
    assert_non_null(lie_frame_add_aov(f, "", 1, r)); /* clashes with RGB's "R" */
    lie_error err;
    const char *path = tmp_path("dup.exr");
    assert_int_equal(lie_exr_write(path, f, NULL, &err), LIE_ERR_ARG);
    assert_int_equal(access(path, F_OK), -1);
    lie_frame_destroy(f);
}

static void test_exr_attributes_round_trip(void **state)
{
    (void)state;
    lie_frame *f = make_test_frame();
    lie_attr attrs[5];
    memset(attrs, 0, sizeof attrs);
    attrs[0].name = "lie:scene";
    attrs[0].type = LIE_ATTR_STRING;
    attrs[0].s = "museum1.gltf";
    attrs[1].name = "lie:exposure";
    attrs[1].type = LIE_ATTR_FLOAT;
    attrs[1].f = 1.5f;
    attrs[2].name = "lie:samples";
    attrs[2].type = LIE_ATTR_INT;
    attrs[2].i = -64;
    attrs[3].name = "lie:eye";
    attrs[3].type = LIE_ATTR_V3F;
    attrs[3].v[0] = 1.0f;
    attrs[3].v[1] = -2.0f;
    attrs[3].v[2] = 3.5f;
    attrs[4].name = "worldToCamera";
    attrs[4].type = LIE_ATTR_M44F;
    for (int i = 0; i < 16; i++)
        attrs[4].v[i] = (float)i + 0.25f;
    lie_error err;
    const char *path = tmp_path("attrs.exr");
    assert_int_equal(lie_exr_write(path, f, &(lie_exr_options){.attrs = attrs, .n_attrs = 5}, &err), LIE_OK);

    char buf[64];
    assert_int_equal(lie_exr_read_string_attr(path, "lie:scene", buf, sizeof buf, &err), LIE_OK);
    assert_string_equal(buf, "museum1.gltf");

    exr_context_t ctx;
    assert_int_equal(exr_start_read(&ctx, path, NULL), EXR_ERR_SUCCESS);
    float fv;
    int32_t iv;
    exr_attr_v3f_t v3;
    exr_attr_m44f_t m;
    assert_int_equal(exr_attr_get_float(ctx, 0, "lie:exposure", &fv), EXR_ERR_SUCCESS);
    assert_true(fv == 1.5f);
    assert_int_equal(exr_attr_get_int(ctx, 0, "lie:samples", &iv), EXR_ERR_SUCCESS);
    assert_int_equal(iv, -64);
    assert_int_equal(exr_attr_get_v3f(ctx, 0, "lie:eye", &v3), EXR_ERR_SUCCESS);
    assert_true(v3.x == 1.0f && v3.y == -2.0f && v3.z == 3.5f);
    assert_int_equal(exr_attr_get_m44f(ctx, 0, "worldToCamera", &m), EXR_ERR_SUCCESS);
    assert_memory_equal(m.m, attrs[4].v, sizeof m.m);
    exr_finish(&ctx);

    /* The pixels are unaffected by the extra header. */
    lie_frame *g = NULL;
    assert_int_equal(lie_exr_read(path, &g, &err), LIE_OK);
    assert_frames_identical(f, g);
    lie_frame_destroy(f);
    lie_frame_destroy(g);
}

static void test_exr_read_string_attr_reports_missing_wrong_type_and_short_buffer(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(1, 1);
    lie_attr attrs[2];
    memset(attrs, 0, sizeof attrs);
    attrs[0].name = "note";
    attrs[0].type = LIE_ATTR_STRING;
    attrs[0].s = "twelve chars";
    attrs[1].name = "count";
    attrs[1].type = LIE_ATTR_INT;
    attrs[1].i = 3;
    lie_error err;
    const char *path = tmp_path("note.exr");
    assert_int_equal(lie_exr_write(path, f, &(lie_exr_options){.attrs = attrs, .n_attrs = 2}, &err), LIE_OK);
    char buf[13];
    assert_int_equal(lie_exr_read_string_attr(path, "nope", buf, sizeof buf, &err),
                     LIE_ERR_NOT_FOUND);
    assert_int_equal(lie_exr_read_string_attr(path, "count", buf, sizeof buf, &err),
                     LIE_ERR_FORMAT);
    assert_int_equal(lie_exr_read_string_attr(path, "note", buf, 12, &err), LIE_ERR_LIMIT);
    assert_int_equal(lie_exr_read_string_attr(path, "note", buf, 13, &err), LIE_OK);
    assert_string_equal(buf, "twelve chars");
    assert_int_equal(lie_exr_read_string_attr(tmp_path("absent.exr"), "note", buf, 13, &err),
                     LIE_ERR_IO);
    lie_frame_destroy(f);
}

static void test_exr_write_rejects_clashing_attribute(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(1, 1);
    lie_attr a;
    memset(&a, 0, sizeof a);
    a.name = "compression"; /* a required attribute of another type */
    a.type = LIE_ATTR_STRING;
    a.s = "none";
    lie_error err;
    const char *path = tmp_path("clash.exr");
    assert_int_equal(lie_exr_write(path, f, &(lie_exr_options){.attrs = &a, .n_attrs = 1}, &err), LIE_ERR_ARG);
    assert_non_null(strstr(err.msg, "compression"));
    assert_int_equal(access(path, F_OK), -1);
    lie_frame_destroy(f);
}

static void test_exr_write_is_deterministic(void **state)
{
    (void)state;
    lie_frame *f = make_test_frame();
    lie_attr a;
    memset(&a, 0, sizeof a);
    a.name = "lie:scene";
    a.type = LIE_ATTR_STRING;
    a.s = "x";
    lie_error err;
    const char *p1 = tmp_path("det1.exr"), *p2 = tmp_path("det2.exr");
    assert_int_equal(lie_exr_write(p1, f, &(lie_exr_options){.attrs = &a, .n_attrs = 1}, &err), LIE_OK);
    sleep(1); /* a timestamp, if any crept in, would now differ */
    assert_int_equal(lie_exr_write(p2, f, &(lie_exr_options){.attrs = &a, .n_attrs = 1}, &err), LIE_OK);
    size_t n1, n2;
    unsigned char *d1 = slurp(p1, &n1), *d2 = slurp(p2, &n2);
    assert_int_equal(n1, n2);
    assert_memory_equal(d1, d2, n1);
    /* OpenEXR magic and version 2, single-part scanline. */
    assert_true(n1 > 8);
    assert_memory_equal(d1, "\x76\x2f\x31\x01", 4);
    assert_int_equal(d1[4], 2);
    free(d1);
    free(d2);
    lie_frame_destroy(f);
}

/* Chunks are compressed on worker threads and written in order: a frame
 * of many chunks (the last one short) gives the same bytes for any thread
 * count and reads back bit for bit. */
static void test_exr_chunks_compressed_in_parallel_same_bytes(void **state)
{
    (void)state;
    const int w = 37, h = 203;
    lie_frame *f = lie_frame_create(w, h);
    assert_non_null(f);
    static const char *const one[1] = {"R"};
    float *cx = lie_frame_add_aov(f, "complexity", 1, one);
    assert_non_null(cx);
    for (int i = 0; i < w * h * 3; i++)
        f->rgb[i] = sinf((float)i * 0.01f) * (float)(i % 97);
    for (int i = 0; i < w * h; i++)
        cx[i] = (float)(i % 13);
    lie_error err;
    const char *p[3] = {tmp_path("par1.exr"), tmp_path("par2.exr"), tmp_path("par0.exr")};
    const int threads[3] = {1, 2, 0};
    for (int k = 0; k < 3; k++) {
        lie_exr_options o = {.threads = threads[k]};
        assert_int_equal(lie_exr_write(p[k], f, &o, &err), LIE_OK);
    }
    size_t n[3];
    unsigned char *d[3];
    for (int k = 0; k < 3; k++)
        d[k] = slurp(p[k], &n[k]);
    for (int k = 1; k < 3; k++) {
        assert_int_equal(n[k], n[0]);
        assert_memory_equal(d[k], d[0], n[0]);
    }
    lie_frame *g = NULL;
    assert_int_equal(lie_exr_read(p[1], &g, &err), LIE_OK);
    assert_int_equal(g->width, w);
    assert_int_equal(g->height, h);
    assert_memory_equal(g->rgb, f->rgb, sizeof(float) * 3 * (size_t)w * (size_t)h);
    assert_int_equal(g->n_aovs, 1);
    assert_memory_equal(g->aovs[0].data, cx, sizeof(float) * (size_t)w * (size_t)h);
    for (int k = 0; k < 3; k++)
        free(d[k]);
    lie_frame_destroy(g);
    lie_frame_destroy(f);
}

/* Chunks compressed apart (lie_exr_encode_chunks: another rank's band of
 * rows, only those rows valid in its frame) and written with opt.chunks
 * give lie_exr_write's bytes, for every compression, with half colour and
 * attributes, when some chunks are given and the rest compressed here; a
 * range outside the image is refused. */
static void test_exr_chunks_encoded_apart_same_bytes(void **state)
{
    (void)state;
    const int w = 29, h = 77;
    lie_frame *f = lie_frame_create(w, h);
    assert_non_null(f);
    static const char *const xyz[3] = {"X", "Y", "Z"};
    float *nrm = lie_frame_add_aov(f, "normal", 3, xyz);
    assert_non_null(nrm);
    for (int i = 0; i < w * h * 3; i++) {
        f->rgb[i] = cosf((float)i * 0.013f) * (float)(i % 31);
        nrm[i] = (float)(i % 7) - 3.0f;
    }
    lie_attr attrs[1] = {{.name = "note", .type = LIE_ATTR_STRING, .s = "made apart"}};
    lie_error err;
    for (int c = 0; c <= LIE_EXR_NONE; c++) {
        for (int half = 0; half < 2; half++) {
            lie_exr_options o = {.attrs = attrs, .n_attrs = 1, .compression = (lie_exr_compression)c, .threads = 2,
                                 .half = half};
            const char *pa = tmp_path("whole.exr"), *pb = tmp_path("apart.exr");
            assert_int_equal(lie_exr_write(pa, f, &o, &err), LIE_OK);
            int lines = lie_exr_chunk_lines((lie_exr_compression)c), n = (h + lines - 1) / lines;
            assert_true(lines == 1 || lines == 16 || lines == 32);
            lie_exr_chunk *ch = calloc((size_t)n, sizeof *ch);
            assert_non_null(ch);
            /* each band from a frame holding its own rows only */
            for (int first = 0; first < n; first += 2) {
                int count = n - first < 2 ? n - first : 2;
                lie_frame *band = lie_frame_create(w, h);
                float *bn = lie_frame_add_aov(band, "normal", 3, xyz);
                assert_non_null(bn);
                size_t y0 = (size_t)first * (size_t)lines, y1 = y0 + (size_t)count * (size_t)lines;
                if (y1 > (size_t)h)
                    y1 = (size_t)h;
                memcpy(band->rgb + y0 * (size_t)w * 3, f->rgb + y0 * (size_t)w * 3,
                       (y1 - y0) * (size_t)w * 3 * sizeof(float));
                memcpy(bn + y0 * (size_t)w * 3, nrm + y0 * (size_t)w * 3, (y1 - y0) * (size_t)w * 3 * sizeof(float));
                lie_exr_options bo = {.compression = (lie_exr_compression)c, .threads = 1, .half = half};
                assert_int_equal(lie_exr_encode_chunks(band, &bo, first, count, ch + first, &err), LIE_OK);
                lie_frame_destroy(band);
            }
            o.chunks = ch;
            assert_int_equal(lie_exr_write(pb, f, &o, &err), LIE_OK);
            assert_files_equal(pa, pb);
            /* some given, the others compressed by the writer */
            for (int k = 1; k < n; k += 2) {
                free(ch[k].data);
                ch[k].data = NULL;
            }
            assert_int_equal(lie_exr_write(pb, f, &o, &err), LIE_OK);
            assert_files_equal(pa, pb);
            for (int k = 0; k < n; k++)
                free(ch[k].data);
            lie_exr_chunk bad[2];
            assert_int_equal(lie_exr_encode_chunks(f, &o, n - 1, 2, bad, &err), LIE_ERR_ARG);
            free(ch);
        }
    }
    assert_int_equal(lie_exr_chunk_lines((lie_exr_compression)99), 0);
    lie_frame_destroy(f);
}

static void test_exr_write_to_missing_directory_fails_with_io_error(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(2, 2);
    lie_error err;
    assert_int_equal(lie_exr_write(tmp_path("no/such/dir/out.exr"), f, NULL, &err),
                     LIE_ERR_IO);
    assert_int_equal(err.status, LIE_ERR_IO);
    assert_true(err.msg[0] != 0);
    lie_frame_destroy(f);
}

static void test_exr_write_below_a_regular_file_fails_with_io_error(void **state)
{
    (void)state;
    /* A path whose "directory" is a regular file: refused for every user,
     * root included (ENOTDIR), and nothing is created. */
    char file[512];
    snprintf(file, sizeof file, "%s", tmp_path("plainfile"));
    FILE *fp = fopen(file, "wb");
    assert_non_null(fp);
    fclose(fp);
    char target[600];
    snprintf(target, sizeof target, "%s/out.exr", file);
    lie_frame *f = lie_frame_create(2, 2);
    lie_error err;
    assert_int_equal(lie_exr_write(target, f, NULL, &err), LIE_ERR_IO);
    struct stat st;
    assert_int_equal(stat(file, &st), 0);
    assert_int_equal(st.st_size, 0);
    lie_frame_destroy(f);
}

/* Renaming over a directory fails after the temporary was written: the
 * temporary must be gone and the directory untouched. */
static void test_exr_write_that_cannot_be_renamed_leaves_no_temp_file(void **state)
{
    (void)state;
    char dir[512];
    snprintf(dir, sizeof dir, "%s", tmp_path("blocked"));
    assert_int_equal(mkdir(dir, 0755), 0);
    char target[600];
    snprintf(target, sizeof target, "%s/out.exr", dir);
    assert_int_equal(mkdir(target, 0755), 0);
    lie_frame *f = make_test_frame();
    lie_error err;
    assert_int_equal(lie_exr_write(target, f, NULL, &err), LIE_ERR_IO);
    assert_int_equal(lie_png_write(target, f, NULL, &err), LIE_ERR_IO);
    struct stat st;
    assert_int_equal(stat(target, &st), 0);
    assert_true(S_ISDIR(st.st_mode));
    /* Only the blocking directory is left. */
    int fd = open(dir, O_RDONLY | O_DIRECTORY);
    assert_true(fd >= 0);
    close(fd);
    char cmd[700];
    snprintf(cmd, sizeof cmd, "test \"$(ls -A '%s')\" = out.exr", dir);
    assert_int_equal(system(cmd), 0);
    lie_frame_destroy(f);
}

static void test_exr_read_rejects_every_truncation(void **state)
{
    (void)state;
    lie_frame *f = make_test_frame();
    lie_error err;
    const char *path = tmp_path("full.exr"), *cut = tmp_path("cut.exr");
    assert_int_equal(lie_exr_write(path, f, NULL, &err), LIE_OK);
    size_t n;
    unsigned char *d = slurp(path, &n);
    for (size_t len = 0; len < n; len++) {
        spit(cut, d, len);
        lie_frame *g = (lie_frame *)&g; /* must be reset to NULL */
        lie_status st = lie_exr_read(cut, &g, &err);
        assert_true(st == LIE_ERR_FORMAT || st == LIE_ERR_LIMIT);
        assert_null(g);
        assert_true(err.msg[0] != 0);
        assert_null(strchr(err.msg, '\n'));
    }
    free(d);
    lie_frame_destroy(f);
}

static void test_exr_read_rejects_garbage(void **state)
{
    (void)state;
    lie_error err;
    lie_frame *g = NULL;
    const char *path = tmp_path("garbage.exr");
    unsigned char junk[4096];
    for (size_t i = 0; i < sizeof junk; i++)
        junk[i] = (unsigned char)(i * 131 + 7);
    spit(path, junk, sizeof junk);
    assert_int_equal(lie_exr_read(path, &g, &err), LIE_ERR_FORMAT);
    assert_null(g);
    /* The right magic followed by garbage. */
    memcpy(junk, "\x76\x2f\x31\x01\x02\x00\x00\x00", 8);
    spit(path, junk, sizeof junk);
    assert_int_equal(lie_exr_read(path, &g, &err), LIE_ERR_FORMAT);
    assert_null(g);
    assert_int_equal(lie_exr_read(tmp_path("absent.exr"), &g, &err), LIE_ERR_IO);
    assert_null(g);
    char buf[16];
    assert_int_equal(lie_exr_read_string_attr(path, "x", buf, sizeof buf, &err), LIE_ERR_FORMAT);
}

static void test_exr_read_survives_every_single_byte_corruption(void **state)
{
    (void)state;
    lie_frame *f = make_test_frame();
    lie_error err;
    const char *path = tmp_path("good.exr"), *bad = tmp_path("flip.exr");
    assert_int_equal(lie_exr_write(path, f, NULL, &err), LIE_OK);
    size_t n;
    unsigned char *d = slurp(path, &n);
    for (size_t i = 0; i < n; i++) {
        static const unsigned char flips[3] = {0xff, 0x80, 0x01};
        for (int k = 0; k < 3; k++) {
            d[i] ^= flips[k];
            spit(bad, d, n);
            d[i] ^= flips[k];
            lie_frame *g = NULL;
            lie_status st = lie_exr_read(bad, &g, &err);
            if (st == LIE_OK) {
                assert_non_null(g);
                assert_true(g->width > 0 && g->height > 0);
            } else {
                assert_null(g);
            }
            lie_frame_destroy(g);
        }
    }
    free(d);
    lie_frame_destroy(f);
}

/* Write a file the way another program might: HALF and UINT channels, a
 * data window that does not start at the origin, and a bare channel. */
static void write_foreign_exr(const char *path)
{
    exr_context_t ctx;
    assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, NULL),
                     EXR_ERR_SUCCESS);
    int part;
    assert_int_equal(exr_add_part(ctx, "beauty", EXR_STORAGE_SCANLINE, &part), EXR_ERR_SUCCESS);
    exr_attr_box2i_t win = {{{{-2, 10}}}, {{{1, 12}}}}; /* 4 x 3 */
    exr_attr_v2f_t center = {{{0.0f, 0.0f}}};
    assert_int_equal(exr_initialize_required_attr(ctx, part, &win, &win, 1.0f, &center, 1.0f,
                                                  EXR_LINEORDER_INCREASING_Y,
                                                  EXR_COMPRESSION_PIZ),
                     EXR_ERR_SUCCESS);
    assert_int_equal(exr_add_channel(ctx, part, "R", EXR_PIXEL_HALF, 0, 1, 1), EXR_ERR_SUCCESS);
    assert_int_equal(exr_add_channel(ctx, part, "G", EXR_PIXEL_HALF, 0, 1, 1), EXR_ERR_SUCCESS);
    assert_int_equal(exr_add_channel(ctx, part, "A", EXR_PIXEL_HALF, 0, 1, 1), EXR_ERR_SUCCESS);
    assert_int_equal(exr_add_channel(ctx, part, "id.X", EXR_PIXEL_UINT, 0, 1, 1),
                     EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctx), EXR_ERR_SUCCESS);
    float rg[12], a[12];
    uint32_t id[12];
    for (int i = 0; i < 12; i++) {
        rg[i] = (float)i * 0.5f; /* exact in half */
        a[i] = -(float)i;
        id[i] = (uint32_t)(1000 + i);
    }
    exr_chunk_info_t ci;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    assert_int_equal(exr_write_scanline_chunk_info(ctx, part, 10, &ci), EXR_ERR_SUCCESS);
    assert_int_equal(ci.height, 3);
    assert_int_equal(exr_encoding_initialize(ctx, part, &ci, &enc), EXR_ERR_SUCCESS);
    for (int c = 0; c < enc.channel_count; c++) {
        exr_coding_channel_info_t *ec = &enc.channels[c];
        int is_id = strcmp(ec->channel_name, "id.X") == 0;
        ec->encode_from_ptr = is_id ? (const uint8_t *)id
                              : strcmp(ec->channel_name, "A") == 0 ? (const uint8_t *)a
                                                                    : (const uint8_t *)rg;
        ec->user_pixel_stride = 4;
        ec->user_line_stride = 16;
        ec->user_bytes_per_element = 4;
        ec->user_data_type = is_id ? EXR_PIXEL_UINT : EXR_PIXEL_FLOAT;
    }
    assert_int_equal(exr_encoding_choose_default_routines(ctx, part, &enc), EXR_ERR_SUCCESS);
    assert_int_equal(exr_encoding_run(ctx, part, &enc), EXR_ERR_SUCCESS);
    exr_encoding_destroy(ctx, &enc);
    assert_int_equal(exr_finish(&ctx), EXR_ERR_SUCCESS);
}

static void test_exr_read_converts_half_and_uint_channels(void **state)
{
    (void)state;
    const char *path = tmp_path("foreign.exr");
    write_foreign_exr(path);
    lie_frame *g = NULL;
    lie_error err;
    assert_int_equal(lie_exr_read(path, &g, &err), LIE_OK);
    assert_int_equal(g->width, 4);
    assert_int_equal(g->height, 3);
    const lie_aov *a = lie_frame_find_aov(g, ""); /* bare "A" */
    const lie_aov *id = lie_frame_find_aov(g, "id");
    assert_non_null(a);
    assert_non_null(id);
    assert_int_equal(g->n_aovs, 2);
    assert_string_equal(a->channel[0], "A");
    assert_string_equal(id->channel[0], "X");
    for (int i = 0; i < 12; i++) {
        assert_true(g->rgb[3 * i + 0] == (float)i * 0.5f);
        assert_true(g->rgb[3 * i + 1] == (float)i * 0.5f);
        assert_true(g->rgb[3 * i + 2] == 0.0f); /* no "B" channel */
        assert_true(a->data[i] == -(float)i);
        assert_true(id->data[i] == (float)(1000 + i));
    }
    lie_frame_destroy(g);
}

/* ---- PNG --------------------------------------------------------------- */

typedef struct decoded_png {
    int width, height;
    int has_srgb, has_time;
    unsigned char *rgb;
} decoded_png;

static decoded_png read_png(const char *path)
{
    decoded_png out;
    memset(&out, 0, sizeof out);
    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    assert_non_null(png);
    assert_non_null(info);
    if (setjmp(png_jmpbuf(png)))
        fail_msg("libpng could not read %s", path);
    png_init_io(png, fp);
    png_read_info(png, info);
    assert_int_equal(png_get_bit_depth(png, info), 8);
    assert_int_equal(png_get_color_type(png, info), PNG_COLOR_TYPE_RGB);
    out.width = (int)png_get_image_width(png, info);
    out.height = (int)png_get_image_height(png, info);
    int intent;
    out.has_srgb = png_get_sRGB(png, info, &intent) != 0;
    out.rgb = malloc((size_t)out.width * (size_t)out.height * 3);
    assert_non_null(out.rgb);
    for (int y = 0; y < out.height; y++)
        png_read_row(png, out.rgb + (size_t)y * (size_t)out.width * 3, NULL);
    png_read_end(png, info);
    out.has_time = png_get_valid(png, info, PNG_INFO_tIME) != 0;
    png_destroy_read_struct(&png, &info, NULL);
    fclose(fp);
    return out;
}

static void test_png_pixels_are_srgb_encoded_and_rounded(void **state)
{
    (void)state;
    static const float in[8] = {0.0f, 1.0f, 0.5f, 0.25f, -1.0f, 100.0f, NAN, INFINITY};
    static const unsigned char want[8] = {0, 255, 188, 137, 0, 255, 0, 255};
    lie_frame *f = lie_frame_create(8, 1);
    for (int i = 0; i < 8; i++) {
        f->rgb[3 * i + 0] = in[i];
        f->rgb[3 * i + 1] = in[i];
        f->rgb[3 * i + 2] = in[i];
    }
    f->rgb[3 * 3 + 1] = 0.0f; /* channels stay separate */
    lie_error err;
    const char *path = tmp_path("pixels.png");
    assert_int_equal(lie_png_write(path, f, NULL, &err), LIE_OK);
    decoded_png p = read_png(path);
    assert_int_equal(p.width, 8);
    assert_int_equal(p.height, 1);
    assert_true(p.has_srgb);
    assert_false(p.has_time);
    for (int i = 0; i < 8; i++) {
        assert_int_equal(p.rgb[3 * i + 0], want[i]);
        assert_int_equal(p.rgb[3 * i + 1], i == 3 ? 0 : want[i]);
        assert_int_equal(p.rgb[3 * i + 2], want[i]);
    }
    free(p.rgb);
    lie_frame_destroy(f);
}

static void test_png_exposure_plus_one_doubles_radiance(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(2, 2);
    for (int i = 0; i < 12; i++)
        f->rgb[i] = 0.25f;
    f->rgb[9] = 0.5f;
    lie_error err;
    const char *path = tmp_path("exposure.png");
    assert_int_equal(lie_png_write(path, f, &(lie_png_options){.exposure = 1.0f}, &err), LIE_OK);
    decoded_png p = read_png(path);
    assert_int_equal(p.rgb[0], 188); /* 0.25 x 2 = 0.5 */
    assert_int_equal(p.rgb[9], 255); /* 0.5 x 2 = 1 */
    free(p.rgb);
    assert_int_equal(lie_png_write(path, f, &(lie_png_options){.exposure = -1.0f}, &err), LIE_OK);
    p = read_png(path);
    assert_int_equal(p.rgb[9], 137); /* 0.5 / 2 = 0.25 */
    free(p.rgb);
    lie_frame_destroy(f);
}

/* Reinhard et al. (2002): the log-average luminance of the covered pixels,
 * delta a share of their mean (so that k times the light is log2 k stops
 * less), the exposure taking it to the key; uncovered pixels left out. */
static void test_auto_exposure_from_log_average_of_covered_pixels(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(2, 1);
    const char *a[] = {"A"};
    float *cov = lie_frame_add_aov(f, "", 1, a);
    for (int c = 0; c < 3; c++) {
        f->rgb[c] = 0.5f;      /* L 0.5 */
        f->rgb[3 + c] = 2.0f;  /* L 2, uncovered */
    }
    cov[0] = 1.0f;
    cov[1] = 0.0f;
    lie_auto_exposure e = lie_frame_auto_exposure(f, LIE_EXPOSURE_KEY);
    assert_int_equal(e.pixels, 1);
    assert_true(fabs(e.log_average - 0.5 * (1.0 + LIE_EXPOSURE_DELTA)) < 1e-9);
    assert_true(fabsf(e.ev - (float)log2(0.18 / (0.5 * (1.0 + LIE_EXPOSURE_DELTA)))) < 1e-5f);
    for (int i = 0; i < 6; i++)
        f->rgb[i] *= 1024.0f;
    lie_auto_exposure b = lie_frame_auto_exposure(f, LIE_EXPOSURE_KEY);
    assert_true(fabsf(e.ev - b.ev - 10.0f) < 1e-4f);
    memset(f->rgb, 0, sizeof(float) * 6); /* no light: no exposure to choose */
    b = lie_frame_auto_exposure(f, LIE_EXPOSURE_KEY);
    assert_true(b.ev == 0.0f);
    lie_frame_destroy(f);
}

/* A tEXt chunk asked for is in the file, before the pixels. */
static void test_png_text_chunk_written(void **state)
{
    (void)state;
    lie_frame *f = lie_frame_create(1, 1);
    const lie_png_text t = {"lie.exposure", "auto: 1.5 stops"};
    lie_png_options o = {0.0f, &t, 1};
    lie_error err;
    const char *path = tmp_path("text.png");
    assert_int_equal(lie_png_write(path, f, &o, &err), LIE_OK);
    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    unsigned char buf[4096];
    size_t n = fread(buf, 1, sizeof buf, fp);
    fclose(fp);
    const char want[] = "tEXtlie.exposure\0auto: 1.5 stops";
    int found = 0;
    for (size_t i = 0; i + sizeof want - 1 <= n && !found; i++)
        found = memcmp(buf + i, want, sizeof want - 1) == 0;
    assert_true(found);
    lie_frame_destroy(f);
}

static void test_png_write_rgb8_stores_pixels_unchanged(void **state)
{
    (void)state;
    unsigned char rgb[5 * 3 * 3];
    for (size_t i = 0; i < sizeof rgb; i++)
        rgb[i] = (unsigned char)(i * 37);
    lie_error err;
    const char *path = tmp_path("raw.png");
    assert_int_equal(lie_png_write_rgb8(path, 5, 3, rgb, &err), LIE_OK);
    decoded_png p = read_png(path);
    assert_int_equal(p.width, 5);
    assert_int_equal(p.height, 3);
    assert_memory_equal(p.rgb, rgb, sizeof rgb);
    free(p.rgb);
    /* Deterministic bytes. */
    const char *path2 = tmp_path("raw2.png");
    assert_int_equal(lie_png_write_rgb8(path2, 5, 3, rgb, &err), LIE_OK);
    assert_files_equal(path, path2);
    assert_int_equal(lie_png_write_rgb8(tmp_path("no/dir/x.png"), 5, 3, rgb, &err), LIE_ERR_IO);
    assert_int_equal(lie_png_write_rgb8(path, 0, 3, rgb, &err), LIE_ERR_ARG);
}

/* ---- writing by extension ---------------------------------------------- */

static void test_frame_write_chooses_format_by_extension(void **state)
{
    (void)state;
    lie_frame *f = make_test_frame();
    lie_error err;
    static const char *const pngs[2] = {"a.png", "b.PnG"};
    static const char *const exrs[3] = {"c.exr", "d.png.exr", "e.EXR"};
    for (int i = 0; i < 2; i++) {
        const char *p = tmp_path(pngs[i]);
        assert_int_equal(lie_frame_write(p, f, NULL, &err), LIE_OK);
        size_t n;
        unsigned char *d = slurp(p, &n);
        assert_true(n > 8);
        assert_memory_equal(d, "\x89PNG\r\n\x1a\n", 8);
        free(d);
    }
    for (int i = 0; i < 3; i++) {
        const char *p = tmp_path(exrs[i]);
        assert_int_equal(lie_frame_write(p, f, NULL, &err), LIE_OK);
        size_t n;
        unsigned char *d = slurp(p, &n);
        assert_true(n > 4);
        assert_memory_equal(d, "\x76\x2f\x31\x01", 4);
        free(d);
    }
    /* no extension it can write: refused, nothing written */
    static const char *const bad[3] = {"f", "g.jpg", "h.exr.tif"};
    for (int i = 0; i < 3; i++) {
        const char *p = tmp_path(bad[i]);
        assert_int_equal(lie_frame_write(p, f, NULL, &err), LIE_ERR_ARG);
        assert_int_equal(access(p, F_OK), -1);
    }
    /* an explicit format wins over the name */
    lie_frame_options o;
    memset(&o, 0, sizeof o);
    assert_true(lie_frame_format_parse("png", &o.format));
    const char *p = tmp_path("i.exr");
    assert_int_equal(lie_frame_write(p, f, &o, &err), LIE_OK);
    size_t n;
    unsigned char *d = slurp(p, &n);
    assert_true(n > 8);
    assert_memory_equal(d, "\x89PNG\r\n\x1a\n", 8);
    free(d);
    lie_frame_format fmt = LIE_FORMAT_AUTO;
    assert_false(lie_frame_format_parse("jpg", &fmt));
    assert_int_equal(fmt, LIE_FORMAT_AUTO);
    assert_true(lie_frame_format_of("-", &fmt));
    assert_int_equal(fmt, LIE_FORMAT_EXR);
    lie_frame_destroy(f);
}

static void test_frame_write_dash_writes_exr_to_stdout(void **state)
{
    (void)state;
    lie_frame *f = make_test_frame();
    lie_error err;
    const char *ref = tmp_path("ref.exr"), *cap = tmp_path("stdout.exr");
    assert_int_equal(lie_exr_write(ref, f, NULL, &err), LIE_OK);

    fflush(stdout);
    int saved = dup(STDOUT_FILENO);
    int fd = open(cap, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(saved >= 0 && fd >= 0);
    dup2(fd, STDOUT_FILENO);
    close(fd);
    lie_status st = lie_frame_write("-", f, NULL, &err);
    fflush(stdout);
    dup2(saved, STDOUT_FILENO);
    close(saved);
    assert_int_equal(st, LIE_OK);
    assert_files_equal(ref, cap);
    lie_frame_destroy(f);
}

/* An optional argument runs only the tests matching that pattern. */
int main(int argc, char **argv)
{
    if (argc > 1)
        cmocka_set_test_filter(argv[1]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frame_create_zeroes_rgb),
        cmocka_unit_test(test_frame_add_aov_zeroes_data_and_copies_names),
        cmocka_unit_test(test_frame_add_aov_rejects_bad_layers),
        cmocka_unit_test(test_frame_destroy_accepts_null),
        cmocka_unit_test(test_srgb_curves_are_monotone),
        cmocka_unit_test(test_srgb_curves_invert_each_other),
        cmocka_unit_test(test_srgb_curves_clamp_to_unit_range),
        cmocka_unit_test(test_exr_round_trip_is_bit_exact),
        cmocka_unit_test(test_exr_round_trip_many_chunks),
        cmocka_unit_test(test_exr_layer_channels_read_back_in_rgba_order),
        cmocka_unit_test(test_exr_long_channel_names_round_trip),
        cmocka_unit_test(test_exr_default_layer_is_written_without_prefix),
        cmocka_unit_test(test_exr_write_rejects_duplicate_channels),
        cmocka_unit_test(test_exr_attributes_round_trip),
        cmocka_unit_test(test_exr_read_string_attr_reports_missing_wrong_type_and_short_buffer),
        cmocka_unit_test(test_exr_write_rejects_clashing_attribute),
        cmocka_unit_test(test_exr_write_is_deterministic),
        cmocka_unit_test(test_exr_chunks_compressed_in_parallel_same_bytes),
        cmocka_unit_test(test_exr_chunks_encoded_apart_same_bytes),
        cmocka_unit_test(test_exr_write_to_missing_directory_fails_with_io_error),
        cmocka_unit_test(test_exr_write_below_a_regular_file_fails_with_io_error),
        cmocka_unit_test(test_exr_write_that_cannot_be_renamed_leaves_no_temp_file),
        cmocka_unit_test(test_exr_read_rejects_every_truncation),
        cmocka_unit_test(test_exr_read_rejects_garbage),
        cmocka_unit_test(test_exr_read_survives_every_single_byte_corruption),
        cmocka_unit_test(test_exr_read_converts_half_and_uint_channels),
        cmocka_unit_test(test_exr_options_are_per_call),
        cmocka_unit_test(test_png_pixels_are_srgb_encoded_and_rounded),
        cmocka_unit_test(test_png_exposure_plus_one_doubles_radiance),
        cmocka_unit_test(test_png_write_rgb8_stores_pixels_unchanged),
        cmocka_unit_test(test_auto_exposure_from_log_average_of_covered_pixels),
        cmocka_unit_test(test_png_text_chunk_written),
        cmocka_unit_test(test_frame_write_chooses_format_by_extension),
        cmocka_unit_test(test_frame_write_dash_writes_exr_to_stdout),
    };
    return cmocka_run_group_tests_name("image", tests, group_setup, group_teardown);
}
