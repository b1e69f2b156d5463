#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Output formats (issue 18): -o refuses extensions it cannot write,
# --format streams PNG, EXR carries OpenEXR's standard camera attributes,
# an A channel of coverage and --half colour.
. "$(dirname "$0")/lib.sh"
R="$B/lie-render"
SC="$S/cornell.gltf"
SMALL="--size 32x24 --light-samples 4 -q"

# -o with an extension no writer has: one line, exit 2, nothing written
for ext in jpg tif exrx; do
    run "$R" "$SC" -o "$TMP/out.$ext" $SMALL
    expect_rc 2 "-o out.$ext refused"
    expect_one_error_line "lie-render: $TMP/out.$ext: cannot write this format" "-o out.$ext: one line"
    expect_no_file "$TMP/out.$ext" "-o out.$ext: nothing written"
done
run "$R" "$SC" -o "$TMP/o.exr" --format jpeg $SMALL
expect_rc 2 "--format jpeg refused"
run "$B/lie-inspect" image "$TMP/none.cache" -o "$TMP/fig.exr"
expect_rc 2 "lie-inspect image -o fig.exr refused"
expect_one_error_line "lie-inspect: $TMP/fig.exr: image writes PNG only" "lie-inspect image: one line"

# -o - --format png streams the same PNG as -o x.png
"$R" "$SC" -o - --format png $SMALL >"$TMP/stream.png" 2>"$TMP/err"
"$R" "$SC" -o "$TMP/file.png" $SMALL
if head -c 8 "$TMP/stream.png" | od -An -c | grep -q 'P   N   G'; then ok "-o - --format png: PNG on stdout"; else
    not_ok "-o - --format png: no PNG signature"; fi
expect_same "$TMP/stream.png" "$TMP/file.png" "streamed PNG = file PNG"
# --format exr wins over a .png name
"$R" "$SC" -o "$TMP/forced.png" --format exr $SMALL
if oiiotool --info "$TMP/forced.png" 2>/dev/null | grep -q openexr; then ok "--format exr writes EXR whatever the name"; else
    not_ok "--format exr: $(oiiotool --info "$TMP/forced.png" 2>&1 | head -1)"; fi

# standard attributes, as oiiotool reads them.  Perspective camera at the
# origin looking down +z (world) with a 90 degree vertical field: worldToCamera
# flips x (right = forward x up = -x), NDC maps the image to [0,1]^2 with y down.
CAM="eye=0,0,0,target=0,0,1,up=0,1,0,fov=90"
"$R" "$SC" -o "$TMP/p.exr" --camera "$CAM" --size 40x20 --light-samples 1 -q
oiiotool --info -v "$TMP/p.exr" >"$TMP/info" 2>&1
check_attr() { # NAME VALUE
    if grep -qxF "    $1: $2" "$TMP/info"; then ok "$1 = $2"; else
        not_ok "$1: expected '$2', got '$(grep "$1" "$TMP/info")'"; fi
}
check_attr worldToCamera "-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1"
# half_h = tan 45 = 1, half_w = 2: x_ndc = (1 - x/(2z))/2... as w = z
check_attr worldToNDC "-0.25, 0, 0, 0, 0, -0.5, 0, 0, 0.5, 0.5, 0, 1, 0, 0, 1, 0"
check_attr screenWindowWidth 4
check_attr screenWindowCenter "0, 0"
if grep -q "channel list: A, B, G, R\|channel list: R, G, B, A" "$TMP/info"; then ok "A channel present"; else
    not_ok "channel list: $(grep 'channel list' "$TMP/info")"; fi
# orthographic: 2 world units tall, eye at (1,2,3) looking down -y
"$R" "$SC" -o "$TMP/o.exr" --camera "eye=1,2,3,target=1,0,3,up=0,0,-1,ortho=2" --size 20x20 --light-samples 1 -q
oiiotool --info -v "$TMP/o.exr" >"$TMP/info" 2>&1
# right = fwd x up = (0,-1,0) x (0,0,-1) = (1,0,0); up = (0,0,-1); fwd = (0,-1,0)
check_attr worldToCamera "1, 0, 0, 0, 0, 0, -1, 0, 0, -1, 0, 0, -1, 3, 2, 1"
check_attr worldToNDC "0.5, 0, 0, 0, 0, 0, -1, 0, 0, 0.5, 0, 0, 0, -1, 2, 1"
check_attr screenWindowWidth 2

# coverage: a camera looking out of the open box sees part sky; its A is the
# fraction of eye rays that hit, 0 where none, 1 where all
"$R" "$SC" -o "$TMP/c.exr" --camera "eye=0.278,0.273,-0.8,target=0.278,0.273,0.5,fov=120" --size 24x24 --spp 4 --light-samples 1 -q
oiiotool "$TMP/c.exr" --ch A --printstats >"$TMP/stats" 2>&1
if grep -q "Min: 0.000" "$TMP/stats" && grep -q "Max: 1.000" "$TMP/stats"; then ok "A spans 0 (no hit) to 1 (all hit)"; else
    not_ok "A stats: $(grep -E 'Min|Max' "$TMP/stats")"; fi
# --half: R, G, B half, A float; the same image to half precision
"$R" "$SC" -o "$TMP/h.exr" --half $SMALL
"$R" "$SC" -o "$TMP/f.exr" $SMALL
oiiotool --info -v "$TMP/h.exr" >"$TMP/info" 2>&1
if grep -q "R (half), G (half), B (half), A (float)" "$TMP/info"; then ok "--half: colour half, A float"; else
    not_ok "--half: $(grep 'channel list' "$TMP/info")"; fi
if oiiotool "$TMP/h.exr" "$TMP/f.exr" --fail 0.002 --warn 0.002 --diff >/dev/null 2>&1; then ok "--half: same image within half precision"; else
    not_ok "--half: images differ: $(oiiotool "$TMP/h.exr" "$TMP/f.exr" --diff 2>&1 | tail -3)"; fi
finish
