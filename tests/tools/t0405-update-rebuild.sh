#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# rst-update equals a fresh lie-build of the scene it writes (--write-scene),
# in sampled and conservative modes, where a unit's content could depend on
# more than its own patch and emitter: emitters renumbered (an emitter that
# appears or goes before others), the scene's extent and bounds growing
# (shaft tolerances; how far a directional light's shafts reach), and
# coordinates pushed far out by morph weights.
. "$ROOT/tests/tools/lib.sh"

# same_as_build SCENE EDIT WHAT [lie-build options]: in both modes, the
# update of SCENE's cache by EDIT has the content of a build of the scene
# the update writes (lie-inspect diff: the same units, nodes and lists)
same_as_build() {
    scene=$1; edit=$2; what=$3; shift 3
    for mode in sampled conservative; do
        "$B/lie-build" "$scene" -q --blockers $mode "$@" -o "$TMP/base.lie" || { not_ok "$what ($mode): build"; continue; }
        run "$B/rst-update" "$TMP/base.lie" "$edit" -q -o "$TMP/upd.lie" --write-scene "$TMP/edited.gltf"
        if [ "$rc" -ne 0 ]; then not_ok "$what ($mode): rst-update failed"; sed 's/^/# /' "$TMP/err"; continue; fi
        "$B/lie-build" "$TMP/edited.gltf" -q --blockers $mode "$@" -o "$TMP/fresh.lie" ||
            { not_ok "$what ($mode): build of the edited scene"; continue; }
        if "$B/lie-inspect" diff "$TMP/upd.lie" "$TMP/fresh.lie" >"$TMP/diff" 2>&1; then
            ok "$what ($mode): update = build of the written scene"
        else
            not_ok "$what ($mode): update differs from a build of the written scene"
            grep '^units:' "$TMP/diff" | sed 's/^/# /'
        fi
    done
}

edit() { printf '%s\n' "$2" >"$TMP/$1.yaml"; }

# (a) emitters renumbered: walls made emissive come before the light (the
# renumbered light's units are the ones that differed); museum1's walls
# lit cost seconds each, tests/unit/test_update.c has more of these
edit backwall '- set-emission: {node: BackWall, emissive: [1, 1, 1], strength: 1}'
edit twowalls '- set-emission: {node: LeftWall, emissive: [1, 0.2, 0.2], strength: 1}
- set-emission: {node: RightWall, emissive: [0.2, 1, 0.2], strength: 1}'
same_as_build "$S/cornell.gltf" "$TMP/backwall.yaml" "cornell: the back wall lit" --min-patch 1e-2
same_as_build "$S/cornell.gltf" "$TMP/twowalls.yaml" "cornell: two walls lit" --min-patch 1e-2

# (b) the largest extent grows: the cube leaves through the east wall
edit cubex '- move: {node: Cube, by: [4.5, 0, 0]}'
same_as_build "$S/museum1.gltf" "$TMP/cubex.yaml" "museum1: the cube out through a wall" --min-patch 1e-2

# (d) a directional light: museum1 without its ceiling, lit by a sun; moves
# and an add that grow the bounds, and a move inside them
cp "$ROOT/tests/data/gltf/lights_cameras.gltf" "$TMP/"
cat >"$TMP/sun.yaml" <<YAML
- remove: {node: Ceiling}
- add: {file: lights_cameras.gltf, node: "#3", as: Sun, transform: {rotation: [-0.3535534, 0.3535534, 0.1464466, 0.8535534]}}
YAML
"$B/lie-build" "$S/museum1.gltf" -q --min-patch 1e-2 -o "$TMP/m.lie" &&
    "$B/rst-update" "$TMP/m.lie" "$TMP/sun.yaml" -q -o "$TMP/msun.lie" --write-scene "$TMP/msun.gltf" ||
    not_ok "museum1 with a sun"
cat >"$TMP/addfar.yaml" <<YAML
- add: {file: $S/cornell.gltf, node: ShortBlock, as: Far, transform: {translation: [9, 0, 0], scale: [3, 3, 3]}}
YAML
edit cubeup '- move: {node: Cube, by: [0, 6, 0]}'
edit cubein '- move: {node: Cube, by: [-0.3, 0, 0.2]}'
for e in cubex addfar cubeup cubein; do
    same_as_build "$TMP/msun.gltf" "$TMP/$e.yaml" "museum1 in the sun: $e" --min-patch 1e-2
done

# (c) morph weights that push a sheet far out (the scene's extent grows a
# billionfold, still inside the coordinate range), and past the range (1e30:
# the edit is refused with one line, and no cache is written)
edit w9 '- set-weights: {node: Half, weights: [1e9, 0]}'
edit w9b '- set-weights: {node: Rest, weights: [0, 1e9]}'
same_as_build "$ROOT/tests/data/gltf/morph_lit.gltf" "$TMP/w9.yaml" "morph_lit: a sheet lifted to 1e9"
same_as_build "$ROOT/tests/data/gltf/morph_lit.gltf" "$TMP/w9b.yaml" "morph_lit: a corner pushed to 1e9"
edit w30 '- set-weights: {node: Half, weights: [1e30, 0]}'
"$B/lie-build" "$ROOT/tests/data/gltf/morph_lit.gltf" -q -o "$TMP/m30.lie" || not_ok "morph_lit: build"
rm -f "$TMP/u30.lie"
run "$B/rst-update" "$TMP/m30.lie" "$TMP/w30.yaml" -q -o "$TMP/u30.lie"
expect_rc 1 "morph_lit: a sheet lifted to 1e30 is refused"
expect_one_error_line "rst-update: " "morph_lit: one line for the sheet at 1e30"
expect_no_file "$TMP/u30.lie" "morph_lit: no cache written for the sheet at 1e30"

# a cache whose log holds an `add` loads from any directory: the added
# file resolves relative to the edit file, whose name the log records
# relative to the cache's folder (as the scene's path resolves)
mkdir -p "$TMP/w/sub" "$TMP/w/edits" "$TMP/w/out" "$TMP/elsewhere"
cp "$S/cornell.gltf" "$S/cornell.bin" "$TMP/w/"
cp "$S/cornell.gltf" "$S/cornell.bin" "$TMP/w/sub/"
cp "$S/cornell.gltf" "$S/cornell.bin" "$TMP/w/out/"
printf '%s\n' '- add: {file: sub/cornell.gltf, node: TallBlock, as: T2, transform: {translation: [0.1, 0, 0.1], scale: [0.3, 0.3, 0.3]}}' >"$TMP/w/e.yaml"
printf '%s\n' '- add: {file: ../sub/cornell.gltf, node: ShortBlock, as: S2, transform: {translation: [0.2, 0, 0.1], scale: [0.3, 0.3, 0.3]}}' >"$TMP/w/edits/e2.yaml"
(cd "$TMP/w" && "$B/lie-build" cornell.gltf -q --min-patch 1e-2 -o c.lie &&
    "$B/rst-update" c.lie e.yaml edits/e2.yaml -q -o u.lie &&
    "$B/rst-update" c.lie e.yaml -q -o out/u.lie &&
    "$B/lie-build" cornell.gltf --edit edits/e2.yaml -q --min-patch 1e-2 -o out/b.lie) || not_ok "caches with added files"
for c in u.lie out/u.lie out/b.lie; do
    (cd "$TMP/elsewhere" && "$B/lie-render" "$TMP/w/$c" -q --size 16x16 -o x.exr) >"$TMP/out" 2>"$TMP/err"
    rc=$?
    expect_rc 0 "$c, whose log adds a file, renders from another directory"
done
(cd "$TMP/w/sub" && "$B/lie-inspect" verify ../u.lie --scene ../cornell.gltf) >"$TMP/out" 2>"$TMP/err"
rc=$?
expect_rc 0 "and verifies from another directory with --scene"
if "$B/lie-inspect" dump "$TMP/w/out/u.lie" | grep -q '\.\./e\.yaml'; then
    ok "the log records the edit file relative to the cache's folder"
else not_ok "the log does not record ../e.yaml"; fi

finish
