/* SPDX-License-Identifier: Apache-2.0 */
/* libFuzzer target for packed file sets (lib/core/fileset.c), the bytes
 * lib/dist broadcasts under mpirun.  Any input must either fail with one
 * line, or unpack to a set whose packing unpacks again and packs to the
 * same bytes (an input that repeats a path unpacks, lookups seeing the
 * first; its packing keeps both). */
#include <stdlib.h>
#include <string.h>

#include "core/core.h"
#include "fuzz_common.h"

#ifndef LIE_FUZZ_ENTRY
#define LIE_FUZZ_ENTRY LLVMFuzzerTestOneInput
#endif

int LIE_FUZZ_ENTRY(const uint8_t *data, size_t size)
{
    lie_error err;
    lie_error_clear(&err);
    lie_file_set *set = NULL;
    if (lie_file_set_unpack(data, size, &set, &err) != LIE_OK) {
        if (fuzz_msg_bad(&err) || set)
            abort();
        return 0;
    }
    unsigned char *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    lie_file_set *again = NULL;
    if (lie_file_set_pack(set, &a, &na, &err) != LIE_OK || lie_file_set_unpack(a, na, &again, &err) != LIE_OK ||
        lie_file_set_pack(again, &b, &nb, &err) != LIE_OK || na != nb || memcmp(a, b, na) != 0 ||
        lie_file_set_count(set) != lie_file_set_count(again))
        abort();
    free(a);
    free(b);
    lie_file_set_destroy(again);
    lie_file_set_destroy(set);
    return 0;
}
