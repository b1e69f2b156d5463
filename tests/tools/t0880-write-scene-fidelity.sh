#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# rst-update --write-scene keeps what the scene's file holds: its images
# byte for byte (a JPEG stays that JPEG, a PNG those bytes), the normal map
# with its scale and KHR_texture_transform, TANGENT, KHR_materials_transmission,
# KHR_lights_punctual and KHR_materials_emissive_strength: the scene read back
# has the edited scene's content hash, which counts them all; what it does
# not write it says, one warning line each.  The Khronos validator checks
# the output (npm gltf-validator, which make deps installs; bench/validate.js).
. "$(dirname "$0")/lib.sh"
G="$D/gltf"
cd "$TMP" || exit 1
"$B/lie-build" "$G/fidelity.gltf" -q -o f.lie
printf -- '- move: {node: Glass, by: [0, 0, 0.01]}\n' >e.yaml
mkdir sc glb
run "$B/rst-update" f.lie e.yaml -o u.lie --write-scene sc/x.gltf
expect_rc 0 "rst-update --write-scene of a scene with a JPEG, a normal map and glass"
expect_same sc/x_img0.jpg "$G/checker.jpg" "the JPEG is written as it was read"
if [ "$(grep -c 'warning: not written: occlusionTexture (not read)' "$TMP/err")" -eq 1 ]; then
    ok "one warning line for what it does not write: $(grep 'not written' "$TMP/err")"; else
    not_ok "the warnings: $(cat "$TMP/err")"; fi
for k in normalTexture '"TANGENT"' KHR_materials_transmission transmissionTexture KHR_texture_transform \
    KHR_lights_punctual KHR_materials_emissive_strength; do
    if grep -q -- "$k" sc/x.gltf; then ok "the .gltf keeps $k"; else not_ok "$k is missing from the .gltf"; fi
done
state() { "$B/lie-inspect" summary "$1" --json | tr ',' '\n' | grep '"state_hash"'; }
"$B/lie-build" sc/x.gltf -q -o b.lie
if [ -n "$(state u.lie)" ] && [ "$(state u.lie)" = "$(state b.lie)" ]; then
    ok "the written scene has the edited scene's content hash"; else
    not_ok "content hashes: $(state u.lie) and $(state b.lie)"; fi
# written again from the written scene: the same image bytes
"$B/rst-update" b.lie e.yaml -q -o u2.lie --write-scene sc/y.gltf
expect_same sc/y_img0.jpg sc/x_img0.jpg "the JPEG again, unchanged"
expect_same sc/y_img1.png sc/x_img1.png "the normal map's PNG again, unchanged"
run "$B/rst-update" f.lie e.yaml -q -o g.lie --write-scene glb/x.glb
expect_rc 0 "--write-scene x.glb"
if grep -q 'image/jpeg' glb/x.glb; then ok "the .glb holds the JPEG with its mimeType"; else not_ok "no image/jpeg in the .glb"; fi
"$B/lie-build" glb/x.glb -q -o bg.lie
[ "$(state bg.lie)" = "$(state u.lie)" ] && ok "the .glb has the edited scene's content hash" ||
    not_ok "the .glb's hash: $(state bg.lie)"
# make deps installs the validator (scripts/npm, its version pinned)
if NODE_PATH="$ROOT/scripts/npm/node_modules" node -e "require('gltf-validator')" >/dev/null 2>&1; then
    NODE_PATH="$ROOT/scripts/npm/node_modules" node "$ROOT/bench/validate.js" sc/x.gltf glb/x.glb >val.json 2>&1
    if [ "$(grep -c '"errors":0,' val.json)" = 2 ]; then ok "the Khronos validator finds no error: $(cat val.json)"; else
        not_ok "validator: $(cat val.json)"; fi
    # the generated scenes, as tests/scenes/README.md says: no error, no warning
    NODE_PATH="$ROOT/scripts/npm/node_modules" node "$ROOT/bench/validate.js" "$ROOT"/tests/scenes/*.gltf >gen.json 2>&1
    if [ "$(grep -c '"errors":0,"warnings":0,' gen.json)" = "$(ls "$ROOT"/tests/scenes/*.gltf | wc -l)" ]; then
        ok "tests/scenes pass the validator with no error or warning"; else not_ok "tests/scenes: $(cat gen.json)"; fi
else
    not_ok "gltf-validator is not installed: run make deps (scripts/npm)"
fi
finish
