/* SPDX-License-Identifier: Apache-2.0 */
/* libFuzzer target for edit files (lib/edit, formats/edit.md): any input
 * must parse or fail with one line carrying line:column; what parses is
 * applied to the Cornell box (lie_edit_apply, then the world is
 * re-flattened), which must succeed or fail with one line too.  `add`
 * operations are left out of the application: they load other files named
 * by the input, which is the glTF target's job.
 *
 * Also built into tests/unit/test_fuzz_regressions.c (entry renamed
 * through LIE_FUZZ_ENTRY), which replays tests/fuzz/regressions/edit/. */
#include <stdlib.h>
#include <string.h>

#include "edit/edit.h"
#include "fuzz_common.h"

#ifndef LIE_FUZZ_ENTRY
#define LIE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif
#ifndef TEST_SCENES
#define TEST_SCENES "tests/scenes"
#endif

static void fe_one_line(const lie_error *err)
{
    if (!err->msg[0] || fuzz_msg_bad(err))
        abort();
}

int LIE_FUZZ_ENTRY(const unsigned char *data, size_t size);
int LIE_FUZZ_ENTRY(const unsigned char *data, size_t size)
{
    lie_edit *e = NULL;
    lie_error err;
    if (lie_edit_parse(data, size, "fuzz.yaml", &e, &err) != LIE_OK) {
        fe_one_line(&err);
        if (e)
            abort();
        return 0;
    }
    /* apply everything but `add`, in order */
    lie_edit_op *all = e->ops;
    int n_all = e->n_ops, n = 0;
    lie_edit_op *kept = calloc((size_t)n_all + 1, sizeof *kept);
    if (!kept)
        abort();
    for (int i = 0; i < n_all; i++)
        if (all[i].kind != LIE_EDIT_ADD)
            kept[n++] = all[i];
    lie_scene *s = NULL;
    if (lie_scene_load(TEST_SCENES "/cornell.gltf", NULL, &s, &err) != LIE_OK)
        abort();
    e->ops = kept;
    e->n_ops = n;
    lie_edit_effect fx;
    memset(&fx, 0, sizeof fx);
    if (lie_edit_apply(s, e, NULL, &fx, &err) != LIE_OK)
        fe_one_line(&err);
    lie_edit_effect_free(&fx);
    e->ops = all;
    e->n_ops = n_all;
    free(kept);
    lie_scene_destroy(s);
    lie_edit_destroy(e);
    return 0;
}
