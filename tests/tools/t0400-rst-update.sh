#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# rst-update: update equals rebuild (byte for byte) for every operation,
# chains of edits and random moves; edited caches render; bad edits leave
# everything untouched.
. "$ROOT/tests/tools/lib.sh"

"$B/lie-build" "$S/museum1.gltf" -q --min-patch 1e-2 -o "$TMP/m1.lie" || not_ok "build museum1"
"$B/lie-build" "$S/museum3.gltf" -q --min-patch 1e-2 -o "$TMP/m3.lie" || not_ok "build museum3"
"$B/lie-build" "$S/cornell.gltf" -q -o "$TMP/c.lie" || not_ok "build cornell"
"$B/lie-build" "$S/cornell.gltf" -q --blockers conservative -o "$TMP/cc.lie" || not_ok "build cornell conservative"

# same_as_rebuild CACHE WHAT EDIT...: rst-update equals a full recomputation
same_as_rebuild() {
    cache=$1; what=$2; shift 2
    run "$B/rst-update" "$cache" "$@" -q -o "$TMP/u.lie"
    if [ "$rc" -ne 0 ]; then not_ok "$what: rst-update failed"; sed 's/^/# /' "$TMP/err"; return; fi
    run "$B/rst-update" "$cache" "$@" -q --full -o "$TMP/f.lie"
    expect_same "$TMP/u.lie" "$TMP/f.lie" "$what: update = rebuild"
}

edit() { printf '%s\n' "$2" >"$TMP/$1.yaml"; }
edit move_by '- move: {node: Cube, by: [0.4, 0, -0.3]}'
edit move_to '- move: {node: Cube, to: [-1.0, 0.2, 1.5]}'
edit rotate '- rotate: {node: Chair2, axis: [0, 1, 0], degrees: 35}'
edit scale '- scale: {node: Cube, by: 1.6}'
edit scale3 '- scale: {node: Table, by: [1, 1.2, 1]}'
edit settf '- set-transform: {node: Cube, matrix: [1,0,0,0, 0,1,0,0, 0,0,1,0, -2,0.2,0.5,1]}'
edit remove '- remove: {node: Chair1}'
edit material '- set-material: {node: TableTop, base-color: [0.8, 0.1, 0.1], metallic: 0, roughness: 0.4}'
edit dim '- set-emission: {node: Light, strength: 4}'
edit off '- set-emission: {node: Light, strength: 0}'
edit lift '- move: {node: Light, by: [0, -0.3, 0]}'
cat >"$TMP/add.yaml" <<YAML
- add: {file: $S/cornell.gltf, node: TallBlock, as: Tower, transform: {translation: [1.5, 0, 1.0], scale: [2, 2, 2]}}
YAML
for op in move_by move_to rotate scale scale3 settf remove material dim lift add; do
    same_as_rebuild "$TMP/m1.lie" "museum1 $op" "$TMP/$op.yaml"
done
# the update's parallel parts (tree regions, recomputation waves) give the
# same bytes for any thread count
run "$B/rst-update" "$TMP/m1.lie" "$TMP/move_by.yaml" -q --threads 1 -o "$TMP/t1.lie"
run "$B/rst-update" "$TMP/m1.lie" "$TMP/move_by.yaml" -q --threads 2 -o "$TMP/t2.lie"
run "$B/rst-update" "$TMP/m1.lie" "$TMP/move_by.yaml" -q --threads 7 -o "$TMP/t7.lie"
expect_same "$TMP/t1.lie" "$TMP/t2.lie" "rst-update: identical caches for 1 and 2 threads"
expect_same "$TMP/t1.lie" "$TMP/t7.lie" "rst-update: identical caches for 1 and 7 threads"
# an added object with vertex colours (COLOR_0) and no name: the edit log
# replays it, so the updated cache renders
cat >"$TMP/addcol.yaml" <<YAML
- add: {file: $ROOT/tests/data/gltf/vertex_colors.gltf, node: "#0", as: Painted, transform: {translation: [0, 0.8, 0]}}
YAML
same_as_rebuild "$TMP/m1.lie" "museum1 add with vertex colours" "$TMP/addcol.yaml"
# an emitter of many triangles (its shafts bounded by an oriented box), moved and turned
cp "$ROOT/tests/data/gltf/panel_light.gltf" "$TMP/"
"$B/lie-build" "$TMP/panel_light.gltf" -q -o "$TMP/pl.lie" || not_ok "build panel_light"
edit plmove '- move: {node: Box, by: [0.7, 0, 0.3]}'
edit plturn '- rotate: {node: Panel, axis: [0, 1, 0], degrees: 20}'
same_as_rebuild "$TMP/pl.lie" "panel_light: box moved" "$TMP/plmove.yaml"
same_as_rebuild "$TMP/pl.lie" "panel_light: panel turned" "$TMP/plturn.yaml"
# an alpha-masked screen (its pairs go to Embree) moved over the floor
cp "$ROOT/tests/data/gltf/alpha_mask.gltf" "$TMP/"
"$B/lie-build" "$TMP/alpha_mask.gltf" -q -o "$TMP/am.lie" || not_ok "build alpha_mask"
edit ammove '- move: {node: Screen, by: [0.3, 0.2, -0.4]}'
same_as_rebuild "$TMP/am.lie" "alpha_mask: screen moved" "$TMP/ammove.yaml"
run "$B/lie-render" "$TMP/u.lie" -q --size 32x32 -o "$TMP/addcol.exr"
expect_rc 0 "the cache with the coloured object renders"
same_as_rebuild "$TMP/m1.lie" "museum1: light off" "$TMP/off.yaml"
# -q: the warning that no emitter is left goes, the cache is the same
run "$B/rst-update" "$TMP/m1.lie" "$TMP/off.yaml" -o "$TMP/loud.lie"
if [ "$rc" -eq 0 ] && grep -q "^rst-update: $TMP/m1.lie: warning: the edited scene has no emitters" "$TMP/err"; then
    ok "light off: a warning without -q"; else not_ok "light off: no warning without -q"; fi
run "$B/rst-update" "$TMP/m1.lie" "$TMP/off.yaml" -q -o "$TMP/quiet.lie"
if [ "$rc" -eq 0 ] && [ ! -s "$TMP/err" ]; then ok "light off: -q prints nothing"; else not_ok "light off: -q printed"; fi
expect_same "$TMP/loud.lie" "$TMP/quiet.lie" "light off: -q changes no byte"
edit on '- set-emission: {node: Light, strength: 14}'
same_as_rebuild "$TMP/m1.lie" "museum1: light off then on again" "$TMP/off.yaml" "$TMP/on.yaml"
same_as_rebuild "$TMP/m1.lie" "museum1: a chain of three files" "$TMP/move_by.yaml" "$TMP/rotate.yaml" "$TMP/remove.yaml"
# successive updates: update of an update
"$B/rst-update" "$TMP/m1.lie" "$TMP/move_by.yaml" -q -o "$TMP/step1.lie"
same_as_rebuild "$TMP/step1.lie" "museum1: an update of an update" "$TMP/rotate.yaml"
edit box '- move: {node: Box, by: [-2, 0, 1]}'
same_as_rebuild "$TMP/m3.lie" "museum3 (six lights): move Box" "$TMP/box.yaml"
edit tall '- rotate: {node: TallBlock, axis: [0, 1, 0], degrees: -20}'
same_as_rebuild "$TMP/c.lie" "cornell: rotate the tall block" "$TMP/tall.yaml"
same_as_rebuild "$TMP/cc.lie" "cornell, conservative lists: rotate the tall block" "$TMP/tall.yaml"

# Random moves (deterministic seed): the trees must never miss a changed list.
i=0
for node in Cube Chair3 Pedestal1 Table Cube Chair4; do
    i=$((i + 1))
    dx=$(awk -v i=$i 'BEGIN { srand(17 * i); printf "%.3f", rand() * 1.2 - 0.6 }')
    dz=$(awk -v i=$i 'BEGIN { srand(31 * i); printf "%.3f", rand() * 1.2 - 0.6 }')
    printf -- '- move: {node: %s, by: [%s, 0, %s]}\n' "$node" "$dx" "$dz" >"$TMP/r$i.yaml"
    same_as_rebuild "$TMP/m1.lie" "random move $i ($node by $dx, 0, $dz)" "$TMP/r$i.yaml"
done

# Edited caches render, from files and through pipes.
run "$B/lie-render" "$TMP/u.lie" -q --size 32x32 -o "$TMP/u.exr"
expect_rc 0 "an edited cache renders"
"$B/lie-build" "$S/cornell.gltf" -q -o - | "$B/rst-update" - "$TMP/tall.yaml" -q -o - | "$B/lie-render" - -q --size 32x32 -o "$TMP/pipe.exr" 2>"$TMP/err"; rc=$?
expect_rc 0 "lie-build | rst-update | lie-render"
run "$B/rst-update" "$TMP/m1.lie" "$TMP/move_by.yaml" --stats=json -q -o "$TMP/s.lie"
if grep -q '"precision":' "$TMP/err" && grep -q '"units_flagged":' "$TMP/err"; then ok "--stats=json reports flagged and changed"; else not_ok "--stats=json"; fi

# Bad edits: one line with file:line:col, exit 1, the input untouched, no output.
cp "$TMP/m1.lie" "$TMP/orig.lie"
bad_edit() { # NAME TEXT EXPECT WHAT
    printf '%s\n' "$2" >"$TMP/$1.yaml"
    run "$B/rst-update" "$TMP/m1.lie" "$TMP/$1.yaml" -q -o "$TMP/bad.lie"
    expect_rc 1 "$4"
    expect_one_error_line "rst-update: $TMP/$1.yaml:$3" "$4: one line with file:line:col"
    expect_no_file "$TMP/bad.lie" "$4: no output"
}
bad_edit missing '- move: {node: NoSuchNode, by: [1, 0, 0]}' "1:3: node 'NoSuchNode'" "missing node"
bad_edit badyaml '- move: {node: Cube, by: [1, 0' "2:1: YAML" "bad YAML"
bad_edit type '- move: {node: Cube, by: [1, zero, 0]}' "1:30: move.by" "wrong type"
bad_edit unknown '- move: {node: Cube, by: [1, 0, 0], speed: 3}' "1:37: move.speed" "unknown key"
bad_edit op '- teleport: {node: Cube}' "1:3: teleport" "unknown operation"
bad_edit ambiguous '- remove: {node: "#99999"}' "1:3: node '#99999'" "node index out of range"
bad_edit addfail '- add: {file: nowhere.gltf, node: X, as: Y}' "1:3: add.file" "an add whose file fails to load"
expect_same "$TMP/m1.lie" "$TMP/orig.lie" "the input cache is untouched"
# restore undoes a remove: the environments equal the untouched cache's, and the update a rebuild
printf -- '- remove: {node: Cube}\n' >"$TMP/rm.yaml"
printf -- '- restore: {node: Cube}\n' >"$TMP/back.yaml"
"$B/rst-update" "$TMP/m1.lie" "$TMP/rm.yaml" -q -o "$TMP/rm.lie" || not_ok "remove Cube"
run "$B/rst-update" "$TMP/rm.lie" "$TMP/back.yaml" -q -o "$TMP/back.lie"
expect_rc 0 "restore after remove"
"$B/rst-update" "$TMP/rm.lie" "$TMP/back.yaml" -q --full -o "$TMP/backf.lie" || not_ok "restore --full"
expect_same "$TMP/back.lie" "$TMP/backf.lie" "restore: update = rebuild"
run "$B/lie-inspect" diff "$TMP/m1.lie" "$TMP/back.lie"
expect_rc 0 "restore: the same environments as before the remove (the edit log is a note)"
bad_edit restore '- restore: {node: Cube}' "1:3: restore: node 'Cube' was not removed" "restore of a node that was not removed"
run "$B/rst-update" "$TMP/m1.lie" -o "$TMP/x.lie"
expect_rc 2 "no edit files: usage error"
finish
