/* SPDX-License-Identifier: Apache-2.0 */
/* Growable arrays (lib/core/core.h). */
#include "core/core.h"

#include <stdlib.h>
#include <string.h>

int lie_grow(void *arr, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap)
        return 1;
    size_t nc = *cap > 8 ? *cap : 8;
    while (nc < need) {
        if (nc > SIZE_MAX / 2)
            return 0;
        nc *= 2;
    }
    if (size && nc > SIZE_MAX / size)
        return 0;
    void *old; /* *arr is some T *: moved as bytes, never read as void * */
    memcpy(&old, arr, sizeof old);
    void *grown = realloc(old, nc * size);
    if (!grown)
        return 0;
    memcpy(arr, &grown, sizeof grown);
    *cap = nc;
    return 1;
}
