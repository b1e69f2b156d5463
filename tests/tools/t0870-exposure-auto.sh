#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-render --exposure auto: the exposure that takes the frame's
# log-average luminance to the key 0.18 (Reinhard et al. 2002), the same
# bytes for any --threads, written in the PNG (tEXt lie.exposure) and the
# EXR header (lie.exposure, lie.exposureMode, lie.logAverageLuminance) and
# printed by --stats; a scene 1000 times brighter gets 1000 times less
# exposure (log2 1000 = 9.97 stops), so its PNG is the same picture.
. "$(dirname "$0")/lib.sh"
cd "$TMP" || exit 1
R="--size 32x32 --light-samples 4 -q"
"$B/lie-render" "$S/cornell.gltf" $R --exposure auto --threads 1 -o a1.png
"$B/lie-render" "$S/cornell.gltf" $R --exposure auto --threads 2 -o a2.png
expect_same a1.png a2.png "the same PNG bytes for 1 and 2 threads"
if oiiotool --info -v a1.png 2>/dev/null | grep -q 'lie.exposure: "auto: [0-9.-]* stops, from a log-average luminance of'; then
    ok "the PNG says the exposure it chose (tEXt lie.exposure)"; else
    not_ok "no lie.exposure text in the PNG: $(oiiotool --info -v a1.png 2>&1 | tail -5)"; fi
run "$B/lie-render" "$S/cornell.gltf" $R --exposure auto -o a.exr --stats=json
expect_rc 0 "--exposure auto with an EXR and --stats=json"
ev=$(field exposure_auto <"$TMP/err")
hdr=$(oiiotool --info -v a.exr 2>/dev/null)
if printf '%s\n' "$hdr" | grep -q 'lie.exposureMode: "auto"' && printf '%s\n' "$hdr" | grep -q 'lie.logAverageLuminance' &&
    printf '%s\n' "$hdr" | grep -qF "lie.exposure: $(printf '%s' "$ev" | cut -c1-4)"; then
    ok "the EXR header records the exposure --stats reports ($ev stops)"; else
    not_ok "EXR header and --stats: $ev; $(printf '%s\n' "$hdr" | grep -i 'lie.exp\|logAv')"; fi
# a brighter copy of the scene: its light's emissive strength 17 x 1000
sed 's/"emissiveStrength": *17}/"emissiveStrength": 17000}/' "$S/cornell.gltf" >bright.gltf
cp "$S/cornell.bin" .
run "$B/lie-render" bright.gltf $R --exposure auto -o b.png --stats=json
ev2=$(field exposure_auto <"$TMP/err")
if awk -v a="$ev" -v b="$ev2" 'BEGIN { d = a - b - 9.9658; exit !(d < 0.01 && d > -0.01) }'; then
    ok "1000 times the light, 9.97 stops less exposure ($ev against $ev2)"; else
    not_ok "exposures $ev and $ev2 are not 9.97 stops apart"; fi
"$B/lie-render" "$S/cornell.gltf" $R --exposure auto -o a.png
if oiiotool a.png b.png --fail 0.02 --failpercent 1 --diff >/dev/null 2>&1; then
    ok "the brighter scene's auto-exposed PNG is the same picture"; else
    not_ok "auto-exposed PNGs differ: $(oiiotool a.png b.png --diff 2>&1 | tail -3)"; fi
run "$B/lie-render" "$S/cornell.gltf" $R --exposure bright -o x.png
expect_rc 2 "--exposure bright is a usage error"
finish
