/* SPDX-License-Identifier: Apache-2.0 */
/* The umbrella header for the tools: everything the library offers. */
#ifndef LIE_H
#define LIE_H

#define LIE_VERSION "0.1.0"

#include "core/core.h"
#include "edit/edit.h"
#include "export/export.h"
#include "cache/cache.h"
#include "image/image.h"
#include "lie/lie.h"
#include "patch/patch.h"
#include "rst/rst.h"
#include "rt/rt.h"
#include "scene/scene.h"
#include "shade/shade.h"
#include "shade/ltc.h"
#include "update/update.h"
#include "version/version.h"

#endif
