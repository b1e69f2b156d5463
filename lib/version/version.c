/* SPDX-License-Identifier: Apache-2.0 */
/* --version for every tool: our version and commit, and the libraries we were built with. */
#include "version/version.h"

#include <embree3/rtcore_config.h>
#include <OpenEXR/openexr.h>
#include <png.h>
#include <stdio.h>
#include <yaml.h>
#include <xxhash.h>

#ifndef LIE_COMMIT
#define LIE_COMMIT "unknown"
#endif

#define LIE_VERSION_TEXT "0.1.0"

const char *lie_version_string(void) { return LIE_VERSION_TEXT; }

const char *lie_version_commit(void) { return LIE_COMMIT; }

int lie_version_report(const char *prog, char *buf, size_t size)
{
    int maj = 0, min = 0, patch = 0;
    const char *extra = NULL;
    exr_get_library_version(&maj, &min, &patch, &extra);
    /* Embree's version is the one compiled against (rtcore_config.h); OpenEXR, libpng and
     * libyaml report the shared library loaded at run time. */
    return snprintf(buf, size,
                    "%s %s (commit %s)\n"
                    "built with Embree %s, OpenEXR %d.%d.%d%s, libpng %s, libyaml %s, xxHash %u.%u.%u\n",
                    prog, LIE_VERSION_TEXT, LIE_COMMIT, RTC_VERSION_STRING, maj, min, patch,
                    extra ? extra : "", png_get_libpng_ver(NULL), yaml_get_version_string(),
                    XXH_VERSION_MAJOR, XXH_VERSION_MINOR, XXH_VERSION_RELEASE);
}
