/* SPDX-License-Identifier: Apache-2.0 */
/* libFuzzer target for camera paths (lib/shade, formats/camera-path.md):
 * any input must parse or fail with one line; a parsed path's first, middle
 * and last frames are evaluated, and must be finite cameras when the keys
 * hold moderate numbers (coordinates near FLT_MAX may overflow in the
 * spline, which is not the reader's business).
 *
 * Also built into tests/unit/test_fuzz_regressions.c (entry renamed
 * through LIE_FUZZ_ENTRY), which replays tests/fuzz/regressions/campath/. */
#include <stdlib.h>
#include <string.h>

#include "shade/shade.h"
#include "fuzz_common.h"

#ifndef LIE_FUZZ_ENTRY
#define LIE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

static int fp_finite(lie_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

int LIE_FUZZ_ENTRY(const unsigned char *data, size_t size);
int LIE_FUZZ_ENTRY(const unsigned char *data, size_t size)
{
    lie_camera_path *p = NULL;
    lie_error err;
    if (lie_camera_path_parse(data, size, "fuzz.yaml", &p, &err) != LIE_OK) {
        if (p || !err.msg[0] || fuzz_msg_bad(&err))
            abort();
        return 0;
    }
    if (p->n_keys < 1 || p->n_frames < 1)
        abort();
    int moderate = 1;
    for (int k = 0; k < p->n_keys; k++) {
        const lie_camera_key *key = &p->keys[k];
        const lie_vec3 v[3] = {key->eye, key->target, key->up};
        for (int j = 0; j < 3; j++)
            moderate &= fabsf(v[j].x) < 1e6f && fabsf(v[j].y) < 1e6f && fabsf(v[j].z) < 1e6f;
        moderate &= fabsf(key->fov_deg) < 1e6f;
    }
    int frames[3] = {0, p->n_frames / 2, p->n_frames - 1};
    for (int i = 0; i < 3; i++) {
        lie_camera c = lie_camera_path_frame(p, frames[i]);
        if (moderate && (!fp_finite(c.eye) || !fp_finite(c.forward) || !fp_finite(c.up) || !isfinite(c.yfov)))
            abort();
    }
    lie_camera_path_destroy(p);
    return 0;
}
