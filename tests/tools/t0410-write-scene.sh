#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# rst-update --write-scene: the edited scene as glTF (.gltf with side files,
# or one .glb), which lie-build and lie-render take; building it gives the
# updated cache's blocker lists and scene state.  A bad path fails with one
# line and writes nothing; so does a side file that is not ours (--force).
. "$ROOT/tests/tools/lib.sh"

"$B/lie-build" "$S/museum2.gltf" -q --min-patch 1e-2 -o "$TMP/m2.lie" || not_ok "build museum2"
cat >"$TMP/e.yaml" <<YAML
- move: {node: Cube, by: [0.4, 0, -0.3]}
- set-material: {node: TableTop, base-color: [0.8, 0.1, 0.1], metallic: 0, roughness: 0.4}
- set-emission: {node: Light, strength: 30}
- add: {file: $S/cornell.gltf, node: TallBlock, as: Tower, transform: {translation: [1.5, 0, 1.0]}}
YAML
mkdir "$TMP/scene"
run "$B/rst-update" "$TMP/m2.lie" "$TMP/e.yaml" -q -o "$TMP/u.lie" --write-scene "$TMP/scene/out.gltf"
expect_rc 0 "rst-update --write-scene"
expect_file "$TMP/scene/out.gltf" "the .gltf is written"
expect_file "$TMP/scene/out.bin" "its .bin beside it"
expect_file "$TMP/scene/out_img0.png" "its image beside it, the bytes the scene read"
expect_same "$TMP/scene/out_img0.png" "$S/museum2_floor.png" "the PNG written is the file read, byte for byte"
expect_no_temp "$TMP/scene" "no temporary files left"

run "$B/lie-build" "$TMP/scene/out.gltf" -q --min-patch 1e-2 -o "$TMP/b.lie"
expect_rc 0 "lie-build takes the written scene"
run "$B/lie-inspect" diff "$TMP/u.lie" "$TMP/b.lie"
expect_rc 0 "building the written scene gives the updated cache's lists"
state() { "$B/lie-inspect" summary "$1" --json | tr ',' '\n' | grep '"state_hash"'; }
if [ -n "$(state "$TMP/u.lie")" ] && [ "$(state "$TMP/u.lie")" = "$(state "$TMP/b.lie")" ]; then
    ok "the written scene has the edited scene's content hash"
else
    not_ok "state hashes differ: $(state "$TMP/u.lie") vs $(state "$TMP/b.lie")"
fi
run "$B/lie-render" "$TMP/scene/out.gltf" -q --visibility full --size 32x32 -o "$TMP/r.exr"
expect_rc 0 "lie-render renders the written scene"
expect_file "$TMP/r.exr" "an image"

run "$B/rst-update" "$TMP/m2.lie" "$TMP/e.yaml" -q -o "$TMP/bad.lie" --write-scene "$TMP/nowhere/out.gltf"
expect_rc 1 "a scene path in a missing folder fails"
expect_one_error_line "rst-update: $TMP/nowhere/out" "one line naming the file"
expect_no_file "$TMP/bad.lie" "and no cache is written"
run "$B/rst-update" "$TMP/m2.lie" "$TMP/e.yaml" -q -o "$TMP/bad.lie" --write-scene -
expect_rc 2 "--write-scene - is a usage error (a scene goes to a named .gltf or .glb)"
expect_no_file "$TMP/bad.lie" "and no cache is written"
run "$B/rst-update" "$TMP/m2.lie" "$TMP/e.yaml" -q -o "$TMP/bad.lie" --write-scene "$TMP/scene/out.obj"
expect_rc 2 "--write-scene of neither .gltf nor .glb is a usage error"

# .glb: one file, the same content hash as the .gltf
mkdir "$TMP/glb"
run "$B/rst-update" "$TMP/m2.lie" "$TMP/e.yaml" -q -o "$TMP/g.lie" --write-scene "$TMP/glb/out.glb"
expect_rc 0 "rst-update --write-scene out.glb"
if [ "$(ls "$TMP/glb")" = out.glb ] && [ "$(head -c 4 "$TMP/glb/out.glb")" = glTF ]; then
    ok "one binary glTF, no side file"
else
    not_ok "the .glb folder holds: $(ls "$TMP/glb")"
fi
run "$B/lie-build" "$TMP/glb/out.glb" -q --min-patch 1e-2 -o "$TMP/bg.lie"
[ "$(state "$TMP/bg.lie")" = "$(state "$TMP/u.lie")" ] && ok "the .glb has the edited scene's content hash" ||
    not_ok "the .glb's hash: $(state "$TMP/bg.lie")"

# side files: our own are replaced, another's are refused unless --force
run "$B/rst-update" "$TMP/m2.lie" "$TMP/e.yaml" -q -o "$TMP/u2.lie" --write-scene "$TMP/scene/out.gltf"
expect_rc 0 "writing over our own .bin and texture"
printf 'mine' >"$TMP/scene/other.bin"
run "$B/rst-update" "$TMP/m2.lie" "$TMP/e.yaml" -q -o "$TMP/u3.lie" --write-scene "$TMP/scene/other.gltf"
expect_rc 1 "another's other.bin is refused"
expect_one_error_line "rst-update: $TMP/scene/other.bin: exists (use --force to overwrite)" "one line"
expect_no_file "$TMP/u3.lie" "and nothing is written: no cache"
expect_no_file "$TMP/scene/other.gltf" "no .gltf"
[ "$(cat "$TMP/scene/other.bin")" = mine ] && ok "the .bin is untouched" || not_ok "the .bin was replaced"
run "$B/rst-update" "$TMP/m2.lie" "$TMP/e.yaml" -q -o "$TMP/u3.lie" --write-scene "$TMP/scene/other.gltf" --force
expect_rc 0 "--force replaces it"
expect_file "$TMP/scene/other_img0.png" "with the rest"

run "$B/rst-update" --help
if grep -q -- '--write-scene OUT.gltf' "$TMP/out" && grep -q -- '--force' "$TMP/out"; then
    ok "--help lists --write-scene and --force"
else
    not_ok "--help"
fi
finish
