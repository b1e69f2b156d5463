#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# KHR_materials_transmission: a point light and an emissive quad inside a
# closed box of coloured glass light the floor outside through it, tinted
# by the glass (base colour (1, 0.5, 0.25) x transmission 0.9), where the
# same box without transmission leaves it black; the LIE image equals full
# visibility's with the same samples; the extension may be required.
. "$(dirname "$0")/lib.sh"
G="$D/gltf"
cd "$TMP" || exit 1
R="--size 40x40 --light-samples 16 --light-sampler per-emitter -q"
"$B/lie-render" "$G/glass_box.gltf" $R -o glass.exr
"$B/lie-render" "$G/glass_box_opaque.gltf" $R -o opaque.exr
avg() { oiiotool "$1" --printstats 2>/dev/null | sed -n 's/.*Stats Avg: *//p' | head -1; }
max_of() { oiiotool "$1" --printstats 2>/dev/null | sed -n 's/.*Stats Max: *//p' | head -1; }
set -- $(max_of opaque.exr)
if [ "$1" = "0.000000" ] && [ "$2" = "0.000000" ] && [ "$3" = "0.000000" ]; then
    ok "an opaque box keeps its lights in: the image is black"; else not_ok "opaque box: max $*"; fi
set -- $(avg glass.exr)
if awk -v r="$1" -v g="$2" -v b="$3" 'BEGIN { exit !(r > 0.001 && g / r > 0.49 && g / r < 0.51 && b / r > 0.245 && b / r < 0.255) }'; then
    ok "the glass lets its lights through, tinted 1 : 0.5 : 0.25 (mean $1 $2 $3)"; else
    not_ok "through the glass: mean $1 $2 $3"; fi
run "$B/lie-build" "$G/glass_box.gltf" -o glass.lie -q
expect_rc 0 "lie-build of a scene with glass"
"$B/lie-render" glass.lie $R -o glass-lie.exr
if "$H/exr-compare" glass.exr glass-lie.exr 0 0 >cmp.txt; then
    ok "LIE = full through the glass, the same samples: $(cat cmp.txt)"; else
    not_ok "LIE against full: $(cat cmp.txt)"; fi
# the default light sampler, in the oracle's mode (--exact off: the same samples as full)
"$B/lie-render" glass.lie --size 40x40 --light-samples 16 --exact off -q -o glass-lie-tree.exr
"$B/lie-render" "$G/glass_box.gltf" --size 40x40 --light-samples 16 -q -o glass-tree.exr
expect_near_full glass-tree.exr glass-lie-tree.exr "the light tree through the glass"
tr -d '\n' <"$G/glass_box.gltf" | sed 's/"extensionsUsed"/"extensionsRequired":["KHR_materials_transmission"],"extensionsUsed"/' >req.gltf
run "$B/lie-render" req.gltf $R -o req.exr
expect_rc 0 "KHR_materials_transmission as a required extension"
finish
