#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-view against the second attack: undo of set-material restores each
# primitive's own material (the screenshot equals lie-render of the unedited
# cache); navigation and drags of any size are clamped to the coordinate
# range, never an abort, and the clamped record replays; names from the
# scene reach the terminal escaped; script errors name the script's file
# and line; a node is selected by index as '#N'; a removed node cannot be
# selected; --record and --save cannot be an input.
. "$ROOT/tests/tools/lib.sh"
need_viewer
T=$TMP
cd "$T" || exit 1

# cornell with both blocks as two primitives (red, green) of one mesh, on
# a node whose name holds an escape sequence
python3 - "$S/cornell.gltf" <<'EOF' || not_ok "python3 writes the scene"
import json, sys
d = json.load(open(sys.argv[1]))
d['buffers'][0]['uri'] = 'cornell.bin'
short, tall = d['meshes'][5]['primitives'][0], d['meshes'][6]['primitives'][0]
short['material'], tall['material'] = 1, 2
d['meshes'][5]['primitives'] = [short, tall]
d['nodes'][5]['name'] = 'Blo\u001b[31mcks'
d['scenes'][0]['nodes'] = [0, 1, 2, 3, 4, 5, 7, 8]
open('blocks.gltf', 'w').write(json.dumps(d))
EOF
cp "$S/cornell.bin" .
"$B/lie-build" blocks.gltf -q --samples 4 --max-samples 4 --min-patch 0.3 -o b.lie || not_ok "build the scene"

view() { # SCRIPT-TEXT OPTIONS...: a session on b.lie, 96x96
    printf '%s\n' "$1" >s.txt
    shift
    run xvfb_run "$B/lie-view" b.lie --size 96x96 --light-samples 4 --script s.txt "$@"
}

# ---- undo of set-material on a node of two primitives
view "frames 1
select '#5'   # the blocks, by index: quoted, as edit files name it
set-material base-color: [0.2, 0.2, 0.9], roughness: 0.3
undo
wait
screenshot $T/undo.png
quit" --stats=json
expect_rc 0 "select '#5', set-material, undo, screenshot"
if grep -q "$(printf '\033')" "$TMP/err"; then not_ok "a raw ESC reached stderr"; else
    grep -q 'selected Blo\\033\[31mcks' "$TMP/err" && ok "'selected NAME' escapes the name" ||
        not_ok "selected: $(grep selected "$TMP/err")"
fi
cam=$(sed -n 's/.*"camera":"\([^"]*\)".*/\1/p' "$TMP/err")
run "$B/lie-render" b.lie --camera "$cam" --size 96x96 --light-samples 4 -q -o ref.png
expect_rc 0 "lie-render of the unedited cache from the printed camera"
expect_same undo.png ref.png "after undo, each primitive has its own material again (pixel for pixel)"

# ---- navigation and drags past the coordinate range: clamped
view "select '#5'
drag 1e30 0 0
drag 0 -1e30 3.4e38
dolly -1e30
orbit 30 10
frames 1
dolly 0.999
frames 1
quit" -q --record rec.yaml
expect_rc 0 "drag 1e30 and dolly -1e30: clamped, no abort"
grep -q '^- move: ' rec.yaml && ok "the clamped moves are recorded" || not_ok "record: $(cat rec.yaml)"
run "$B/rst-update" b.lie rec.yaml -q -o moved.lie
expect_rc 0 "rst-update replays the clamped record (inside the range)"

# ---- script errors: the script's file and line
view "frames 1
select Camera
set-material roughness: 0.5
quit" -q
expect_rc 1 "set-material on a node without a mesh"
expect_one_error_line "lie-view: s.txt:3:1: set-material: node" "the error names the script's file and line"
view "select '#5'
remove
select '#5'
quit" -q
expect_rc 1 "selecting a removed node"
expect_one_error_line "lie-view: s.txt:3:1: select: node '#5' was removed" "refused, at its line"
view "select #5
quit" -q
expect_rc 1 "an unquoted #5 is a comment: select has no argument"
expect_one_error_line "lie-view: s.txt:1:1: select: missing argument" "and says so"

# ---- outputs that are inputs
view "quit" -q --record b.lie
expect_rc 1 "--record over the cache"
expect_one_error_line "lie-view: b.lie: is also the input b.lie" "--record: one line"
view "quit" -q --save s.txt
expect_rc 1 "--save over the script"
expect_one_error_line "lie-view: s.txt: is also the input s.txt" "--save: one line"
view "screenshot $T/cornell.bin
quit" -q
expect_rc 1 "a screenshot over the scene's buffer"
expect_one_error_line "is also the input" "screenshot: one line"
view "quit" -q --record r.yaml --save r.yaml
expect_rc 1 "--record and --save the same file"
expect_one_error_line "lie-view: r.yaml: is also the output r.yaml" "one line"
finish
