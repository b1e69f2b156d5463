#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Scene files from elsewhere, through the tools: URIs that leave the scene's
# folder are refused unless --allow-external-uris (lie-build, lie-render,
# and the tools that reload a cache's scene), remote schemes always; a glTF
# claiming absurd sizes is refused with one line before anything is
# allocated for it.  (tests/unit/test_gltf.c covers the importer itself.)
. "$ROOT/tests/tools/lib.sh"
G="$D/gltf"

refused() { # WHAT NEEDLE CMD...: exit 1, one line naming the scene and NEEDLE, no output
    what=$1; needle=$2; shift 2
    rm -f "$TMP/o.lie" "$TMP/o.exr" "$TMP/o.png"
    run "$@"
    if [ "$rc" -eq 1 ] && [ "$(wc -l <"$TMP/err")" -eq 1 ] && grep -qF -- "$needle" "$TMP/err" &&
        [ ! -e "$TMP/o.lie" ] && [ ! -e "$TMP/o.exr" ] && [ ! -e "$TMP/o.png" ]; then
        ok "$what: $(cat "$TMP/err")"; else not_ok "$what: exit $rc, expected one line with '$needle'"; sed 's/^/# /' "$TMP/err" | head -3; fi
}
accepted() { # WHAT CMD...
    what=$1; shift
    run "$@"
    expect_rc 0 "$what"
}

# ---- URIs: ../, absolute paths, file:, remote schemes
OUT="leaves the scene's folder"
refused "lie-build: '../external.bin'" "lie-build: $G/escape/escape.gltf: URI '../external.bin' $OUT" \
    "$B/lie-build" "$G/escape/escape.gltf" -q -o "$TMP/o.lie"
accepted "lie-build --allow-external-uris: '../external.bin'" \
    "$B/lie-build" "$G/escape/escape.gltf" -q --allow-external-uris -o "$TMP/esc.lie"
refused "lie-render: '../external.bin'" "lie-render: $G/escape/escape.gltf: URI '../external.bin' $OUT" \
    "$B/lie-render" "$G/escape/escape.gltf" -q --size 8x8 -o "$TMP/o.exr"
accepted "lie-render --allow-external-uris: '../external.bin'" \
    "$B/lie-render" "$G/escape/escape.gltf" -q --size 8x8 --allow-external-uris -o "$TMP/esc.exr"
# A cache of such a scene: reloading its scene follows the same policy.
refused "lie-render of the cache" "URI '../external.bin' $OUT" "$B/lie-render" "$TMP/esc.lie" -q --size 8x8 -o "$TMP/o.exr"
accepted "lie-render of the cache --allow-external-uris" \
    "$B/lie-render" "$TMP/esc.lie" -q --size 8x8 --allow-external-uris -o "$TMP/esc2.exr"
printf '%s\n' '- move: {node: "#0", by: [0.1, 0, 0]}' >"$TMP/nudge.yaml"
refused "rst-update of the cache" "URI '../external.bin' $OUT" "$B/rst-update" "$TMP/esc.lie" "$TMP/nudge.yaml" -q -o "$TMP/o.lie"
accepted "rst-update of the cache --allow-external-uris" \
    "$B/rst-update" "$TMP/esc.lie" "$TMP/nudge.yaml" -q --allow-external-uris -o "$TMP/esc3.lie"
refused "lie-inspect verify --scene" "URI '../external.bin' $OUT" "$B/lie-inspect" verify "$TMP/esc.lie" --scene "$G/escape/escape.gltf"
accepted "lie-inspect verify --scene --allow-external-uris" \
    "$B/lie-inspect" verify "$TMP/esc.lie" --scene "$G/escape/escape.gltf" --allow-external-uris
refused "lie-inspect image" "URI '../external.bin' $OUT" "$B/lie-inspect" image "$TMP/esc.lie" -q --size 8x8 -o "$TMP/o.png"
accepted "lie-inspect image --allow-external-uris" \
    "$B/lie-inspect" image "$TMP/esc.lie" -q --size 8x8 --allow-external-uris -o "$TMP/esc.png"

# The same scene with absolute, file: and remote URIs (written into $TMP).
uri_scene() { # NAME PREFIX: external.gltf with its URIs replaced by PREFIX + absolute path
    sed -e "s|\"external.bin\"|\"$2$G/external.bin\"|" -e "s|\"ext%20image.png\"|\"$2$G/ext%20image.png\"|" \
        "$G/external.gltf" >"$TMP/$1.gltf"
}
uri_scene abs ""
refused "lie-build: an absolute path" "URI '$G/external.bin' $OUT" "$B/lie-build" "$TMP/abs.gltf" -q -o "$TMP/o.lie"
accepted "lie-build --allow-external-uris: an absolute path" \
    "$B/lie-build" "$TMP/abs.gltf" -q --allow-external-uris -o "$TMP/abs.lie"
refused "lie-render: an absolute path" "URI '$G/external.bin' $OUT" "$B/lie-render" "$TMP/abs.gltf" -q --size 8x8 -o "$TMP/o.exr"
uri_scene file "file://"
refused "lie-build: file://" "URI 'file://$G/external.bin' $OUT" "$B/lie-build" "$TMP/file.gltf" -q -o "$TMP/o.lie"
accepted "lie-build --allow-external-uris: file://" \
    "$B/lie-build" "$TMP/file.gltf" -q --allow-external-uris -o "$TMP/file.lie"
sed 's|"external.bin"|"http://example.com/external.bin"|' "$G/external.gltf" >"$TMP/http.gltf"
refused "lie-build: http:// even when allowed" "unsupported scheme" \
    "$B/lie-build" "$TMP/http.gltf" -q --allow-external-uris -o "$TMP/o.lie"
sed 's|"external.bin"|"file://remote.host/external.bin"|' "$G/external.gltf" >"$TMP/host.gltf"
refused "lie-render: file://remote.host even when allowed" "remote host" \
    "$B/lie-render" "$TMP/host.gltf" -q --size 8x8 --allow-external-uris -o "$TMP/o.exr"
# Inside the folder is fine: sub/../external.bin
accepted "lie-build: 'sub/../external.bin' stays inside" "$B/lie-build" "$G/inside_dotdot.gltf" -q -o "$TMP/in.lie"
# rst-update's add: the added file follows the policy too
printf -- '- add: {file: %s, node: "#0", as: Extra}\n' "$G/escape/escape.gltf" >"$TMP/add.yaml"
"$B/lie-build" "$S/cornell.gltf" --samples 4 --max-samples 4 --min-patch 0.5 -q -o "$TMP/c.lie" || not_ok "build cornell"
refused "rst-update: add a scene whose URIs leave its folder" "$OUT" "$B/rst-update" "$TMP/c.lie" "$TMP/add.yaml" -q -o "$TMP/o.lie"
accepted "rst-update --allow-external-uris: the same add" \
    "$B/rst-update" "$TMP/c.lie" "$TMP/add.yaml" -q --allow-external-uris -o "$TMP/added.lie"

# ---- absurd sizes: refused with one line, before allocation
tri=$(cat "$G/accessor_oob.gltf" | tr -d '\n ')
mk() { # NAME SED-EXPR: a variant of a one-triangle glTF
    printf '%s\n' "$tri" | sed -e 's/"count":4/"count":3/' -e "$2" >"$TMP/$1.gltf"
}
mk triangle ''
accepted "the one-triangle scene builds" "$B/lie-build" "$TMP/triangle.gltf" -q -o "$TMP/t.lie"
mk count 's/"bufferView":0,"componentType":5126,"count":3/"componentType":5126,"count":1999999998/'
refused "an accessor of 2e9 vertices (no bufferView)" "1999999998 vertices, 666666666 triangles, beyond the limit" \
    "$B/lie-build" "$TMP/count.gltf" -q -o "$TMP/o.lie"
refused "the same through lie-render" "beyond the limit" "$B/lie-render" "$TMP/count.gltf" -q --size 8x8 -o "$TMP/o.exr"
mk idx 's/"attributes":{"POSITION":0}/"attributes":{"POSITION":0},"indices":1/; s/"type":"VEC3"}\]/"type":"VEC3"},{"bufferView":0,"componentType":5125,"count":2000000001,"type":"SCALAR"}]/'
refused "an index accessor of 2e9 in a 36-byte view" "2000000001 elements from offset 0 run past its bufferView of 36 bytes" \
    "$B/lie-build" "$TMP/idx.gltf" -q -o "$TMP/o.lie"
mk view 's/"byteLength":36,"byteOffset":0/"byteLength":4000000000,"byteOffset":0/'
refused "a bufferView of 4e9 bytes in a 36-byte buffer" "lies outside buffer 0 of 36 bytes" \
    "$B/lie-build" "$TMP/view.gltf" -q -o "$TMP/o.lie"
mk buffer 's/"buffers":\[{"byteLength":36/"buffers":[{"byteLength":4000000000/'
refused "a buffer claiming 4e9 bytes" "lie-build: $TMP/buffer.gltf: " "$B/lie-build" "$TMP/buffer.gltf" -q -o "$TMP/o.lie"
# a texture whose PNG header claims 100000 x 100000 pixels
png=$(printf '\211PNG\r\n\032\n\000\000\000\015IHDR\000\001\206\240\000\001\206\240\010\002\000\000\000\000\000\000\000' | base64 | tr -d '\n')
mk image "s|\"meshes\":\[{\"primitives\":\[{\"attributes\":{\"POSITION\":0}|\"images\":[{\"uri\":\"data:image/png;base64,$png\"}],\"textures\":[{\"source\":0}],\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],\"meshes\":[{\"primitives\":[{\"material\":0,\"attributes\":{\"POSITION\":0}|"
refused "a texture of 100000 x 100000 pixels" "image 0 is 100000x100000, beyond the limit of 67108864 pixels" \
    "$B/lie-build" "$TMP/image.gltf" -q -o "$TMP/o.lie"
# GLB containers claiming more than they hold
cp "$G/triangle.glb" "$TMP/len.glb"
printf '\000\050\153\356' | dd of="$TMP/len.glb" bs=1 seek=8 conv=notrunc 2>/dev/null
refused "a GLB header claiming 4e9 bytes" "truncated GLB: header says 4000000000 bytes" \
    "$B/lie-build" "$TMP/len.glb" -q -o "$TMP/o.lie"
jlen=$(od -An -tu4 -j12 -N4 "$G/triangle.glb" | tr -d ' ')
cp "$G/triangle.glb" "$TMP/bin.glb"
printf '\360\377\377\377' | dd of="$TMP/bin.glb" bs=1 seek=$((20 + jlen)) conv=notrunc 2>/dev/null
refused "a GLB BIN chunk claiming 4e9 bytes" "BIN chunk of 4294967280 bytes runs past the end" \
    "$B/lie-render" "$TMP/bin.glb" -q --size 8x8 -o "$TMP/o.exr"
expect_no_temp "$TMP" "no temporary files left"
finish
