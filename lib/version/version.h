/* SPDX-License-Identifier: Apache-2.0 */
/* What this build of the library is: its version, the commit it was built from, and the
 * versions of the libraries it renders and writes with.  Used by every tool's --version. */
#ifndef LIE_VERSION_VERSION_H
#define LIE_VERSION_VERSION_H

#include <stddef.h>

#pragma GCC visibility push(default) /* the public API: exported from liblie.so */

#ifdef __cplusplus
extern "C" {
#endif

/* The library's version, "MAJOR.MINOR.PATCH" (the same as LIE_VERSION in lie.h). */
const char *lie_version_string(void);

/* The commit the library was built from (`git describe --always --dirty`), or "unknown"
 * when it was built outside a git checkout. */
const char *lie_version_commit(void);

/* Writes the multi-line report `--version` prints:
 *     PROG 0.1.0 (commit abc1234)
 *     Embree 3.13.5, OpenEXR 3.1.5, ...
 * into buf (always NUL-terminated); returns the length it needed, as snprintf does. */
int lie_version_report(const char *prog, char *buf, size_t size);

#ifdef __cplusplus
}
#endif
#pragma GCC visibility pop

#endif
