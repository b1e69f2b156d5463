/* SPDX-License-Identifier: Apache-2.0 */
/* What every fuzz target asks of an error: a message, on one line, with no
 * control byte left in it or in the file name (lib/core escapes them, as
 * git does, since names from files reach terminals: issue 19). */
#ifndef LIE_FUZZ_COMMON_H
#define LIE_FUZZ_COMMON_H

#include "core/core.h"

static inline int fuzz_has_control(const char *s)
{
    for (const unsigned char *p = (const unsigned char *)s; *p; p++)
        if (*p < 0x20 || *p == 0x7f || (p[0] == 0xc2 && p[1] >= 0x80 && p[1] < 0xa0))
            return 1;
    return 0;
}

/* 1 if err is not a fit one-line message */
static inline int fuzz_msg_bad(const lie_error *err)
{
    return !err->msg[0] || fuzz_has_control(err->msg) || fuzz_has_control(err->file);
}

#endif
