/* SPDX-License-Identifier: Apache-2.0 */
/* libFuzzer target for the glTF importer (lib/scene/gltf_*.cpp over
 * tinygltf): .gltf and .glb, by content.  The importer reads files (the
 * scene and the buffers and images it names), so each input is written to
 * a scratch folder in tmpfs (/dev/shm when there is one) that also holds
 * the buffers and images the bundled scenes and test files refer to; the
 * scene is then loaded and flattened with a small triangle limit.  Any
 * input must load or fail with one line.
 *
 * Also built into tests/unit/test_fuzz_regressions.c (entry renamed
 * through LIE_FUZZ_ENTRY), which replays tests/fuzz/regressions/gltf/. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene/scene.h"
#include "fuzz_common.h"

#ifndef LIE_FUZZ_ENTRY
#define LIE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif
#ifndef TEST_SCENES
#define TEST_SCENES "tests/scenes"
#endif

static char fg_dir[256], fg_path[300];

static void fg_copy(const char *from, const char *name)
{
    char to[600];
    snprintf(to, sizeof to, "%s/%s", fg_dir, name);
    FILE *in = fopen(from, "rb"), *out = in ? fopen(to, "wb") : NULL;
    char buf[65536];
    size_t n;
    while (out && (n = fread(buf, 1, sizeof buf, in)) > 0)
        fwrite(buf, 1, n, out);
    if (out)
        fclose(out);
    if (in)
        fclose(in);
}

static void fg_cleanup(void)
{
    static const char *const names[] = {"in.gltf", "cornell.bin", "museum1.bin", "museum2.bin", "museum3.bin",
                                        "museum2_floor.png", "external.bin", "ext image.png"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char p[600];
        snprintf(p, sizeof p, "%s/%s", fg_dir, names[i]);
        unlink(p);
    }
    rmdir(fg_dir);
}

static void fg_init(void)
{
    const char *base = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    snprintf(fg_dir, sizeof fg_dir, "%s/lie-fuzz-gltf.XXXXXX", base);
    if (!mkdtemp(fg_dir))
        abort();
    snprintf(fg_path, sizeof fg_path, "%s/in.gltf", fg_dir);
    fg_copy(TEST_SCENES "/cornell.bin", "cornell.bin");
    fg_copy(TEST_SCENES "/museum1.bin", "museum1.bin");
    fg_copy(TEST_SCENES "/museum2.bin", "museum2.bin");
    fg_copy(TEST_SCENES "/museum3.bin", "museum3.bin");
    fg_copy(TEST_SCENES "/museum2_floor.png", "museum2_floor.png");
    fg_copy(TEST_SCENES "/../data/gltf/external.bin", "external.bin");
    fg_copy(TEST_SCENES "/../data/gltf/ext image.png", "ext image.png");
    atexit(fg_cleanup);
}

int LIE_FUZZ_ENTRY(const unsigned char *data, size_t size);
int LIE_FUZZ_ENTRY(const unsigned char *data, size_t size)
{
    if (!fg_dir[0])
        fg_init();
    FILE *f = fopen(fg_path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0)
        abort();
    lie_scene_options o = lie_scene_options_default();
    o.max_triangles = 1000000;
    lie_scene *s = NULL;
    lie_error err;
    if (lie_scene_load(fg_path, &o, &s, &err) != LIE_OK) {
        if (s || !err.msg[0] || fuzz_msg_bad(&err))
            abort();
        return 0;
    }
    lie_camera cam;
    if (lie_scene_camera(s, NULL, &cam, &err) != LIE_OK && fuzz_msg_bad(&err))
        abort();
    lie_scene_destroy(s);
    return 0;
}
