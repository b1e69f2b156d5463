#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# glTF images the decoder cannot read (issue 18): a warning naming the image,
# one line per tool run (every tool that loads a scene: lie-render, lie-build,
# rst-update, lie-inspect, lie-animate, lie-view), and the texture slot falls back to its factor (as
# Blender and three.js do); required extensions stay refused by name.
. "$(dirname "$0")/lib.sh"
G="$D/gltf"
cd "$TMP" || exit 1
tri=$(tr -d '\n ' <"$G/accessor_oob.gltf")
mk() { # NAME SED-EXPR: a variant of a one-triangle glTF
    printf '%s\n' "$tri" | sed -e 's/"count":4/"count":3/' -e "$2" >"$TMP/$1.gltf"
}
MAT='"materials":[{"emissiveFactor":[0.5,0.5,0.5],"pbrMetallicRoughness":{"baseColorFactor":[0.2,0.4,0.6,1]TEX}}],"meshes":[{"primitives":[{"material":0,"attributes":{"POSITION":0}'
with_material() { # NAME TEXTURE-JSON IMAGES-JSON
    m=$(printf '%s' "$MAT" | sed "s|TEX|$2|")
    mk "$1" "s|\"meshes\":\[{\"primitives\":\[{\"attributes\":{\"POSITION\":0}|$3$m|"
}
# a PNG signature and header of 4 x 4 pixels, then garbage
bad=$(printf '\211PNG\r\n\032\n\000\000\000\015IHDR\000\000\000\004\000\000\000\004\010\002\000\000\000garbage-garbage' | base64 | tr -d '\n')
with_material plain "" ""
with_material corrupt ',"baseColorTexture":{"index":0}' "\"images\":[{\"name\":\"wood\",\"uri\":\"data:image/png;base64,$bad\"}],\"textures\":[{\"source\":0}],"
printf '\253KTX 20\273\r\n\032\n0000000000000000' >tex.ktx2
with_material ktx ',"baseColorTexture":{"index":0}' '"images":[{"uri":"tex.ktx2"}],"textures":[{"source":0}],'

CAM="--camera eye=0.3,0.3,2,target=0.3,0.3,0 --size 16x16 --light-samples 1 --aov albedo"
run "$B/lie-render" corrupt.gltf $CAM -o corrupt.exr
expect_rc 0 "lie-render: a corrupt PNG is not fatal"
expect_one_error_line "lie-render: corrupt.gltf: warning: image 0 'wood': cannot decode" "one warning naming the image"
run "$B/lie-render" plain.gltf $CAM -o plain.exr -q
if oiiotool corrupt.exr plain.exr --fail 0 --warn 0 --diff >/dev/null 2>&1; then
    ok "the slot falls back to baseColorFactor: the same pixels as without the texture"; else
    not_ok "pixels differ: $(oiiotool corrupt.exr plain.exr --diff 2>&1 | tail -2)"; fi
run "$B/lie-render" corrupt.gltf $CAM -o q.exr -q
if [ "$rc" -eq 0 ] && [ ! -s "$TMP/err" ]; then ok "-q: no warning"; else not_ok "-q printed: $(cat "$TMP/err")"; fi
run "$B/lie-build" corrupt.gltf -o c.lie
expect_rc 0 "lie-build: a corrupt PNG is not fatal"
expect_one_error_line "lie-build: corrupt.gltf: warning: image 0 'wood': cannot decode" "lie-build: one warning"
# every tool that loads the scene says it once, and -q silences it
printf -- '- move: {node: "#0", by: [0.1, 0, 0]}\n' >move.yaml
warned() { # TOOL WHAT: exit 0 and the image's warning exactly once
    if [ "$rc" -eq 0 ] && [ "$(grep -c "warning: image 0 'wood'" "$TMP/err")" -eq 1 ] &&
        grep -q "^$1: [^ ]*: warning: image 0 'wood': cannot decode" "$TMP/err"; then
        ok "$1 $2: one warning"
    else
        not_ok "$1 $2 (exit $rc):"; sed 's/^/# /' "$TMP/err" | head -5
    fi
}
silent() { if [ "$rc" -eq 0 ] && [ ! -s "$TMP/err" ]; then ok "$1 -q: silent"; else not_ok "$1 -q: $(cat "$TMP/err")"; fi; }
run "$B/rst-update" c.lie move.yaml -o c2.lie
warned rst-update ""
run "$B/rst-update" c.lie move.yaml -o c2.lie -q
silent rst-update
run "$B/lie-inspect" image c.lie --camera eye=0.3,0.3,2,target=0.3,0.3,0 --size 16x16 -o fig.png
warned lie-inspect image
run "$B/lie-inspect" verify c.lie --scene corrupt.gltf -q
silent "lie-inspect verify"
anim=$(tr -d '\n ' <"$G/animated.gltf" | sed "s|\"materials\":\[{\"pbrMetallicRoughness\":{|\"images\":[{\"name\":\"wood\",\"uri\":\"data:image/png;base64,$bad\"}],\"textures\":[{\"source\":0}],\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},|")
printf '%s\n' "$anim" >anim.gltf
run "$B/lie-animate" anim.gltf --fps 2 -o "a_%d.yaml"
warned lie-animate ""
run "$B/lie-animate" anim.gltf --fps 2 -o "a_%d.yaml" -q
silent lie-animate
if command -v Xvfb >/dev/null 2>&1; then
    printf 'quit\n' >quit.txt
    # X libraries keep a few allocations to the end of the process: not ours (as in t0800)
    run xvfb_run env ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
        "$B/lie-view" corrupt.gltf --size 16x16 --light-samples 1 --script quit.txt
    warned lie-view ""
fi

run "$B/lie-render" ktx.gltf $CAM -o ktx.exr
expect_rc 0 "lie-render: a .ktx2 source without KHR_texture_basisu is not fatal"
expect_one_error_line "lie-render: ktx.gltf: warning: image 0 'tex.ktx2': cannot decode" "one warning naming the .ktx2"
# a required extension is still refused by name
sed 's|"asset":|"extensionsUsed":["KHR_texture_basisu"],"extensionsRequired":["KHR_texture_basisu"],"asset":|' ktx.gltf >req.gltf
run "$B/lie-render" req.gltf $CAM -o req.exr
expect_rc 1 "a required KHR_texture_basisu is refused"
expect_one_error_line "KHR_texture_basisu" "the refusal names the extension"
expect_no_file req.exr "nothing written"
finish
