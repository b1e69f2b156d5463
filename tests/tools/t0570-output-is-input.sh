#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# An output that is an input of the run, or another of its outputs, is
# refused before anything is written, for every tool and output option
# (lib/core lie_file_set_claim): by name, through a symlink or a hard link,
# or through "..", including the scene's buffers and images and the files
# --write-scene writes beside its .gltf.  An update in place of the cache a
# run reads (rst-update -o CACHE, lie-build --resume/--into) stays allowed.
. "$ROOT/tests/tools/lib.sh"
T=$TMP
cd "$T" || exit 1
BUILD="--samples 4 --max-samples 4 --min-patch 0.3 -q"

# exit 1, one line with NEEDLE, and FILE (if given) unchanged: WHAT NEEDLE FILE CMD...
refused() {
    what=$1; needle=$2; file=$3; shift 3
    before=""
    [ -n "$file" ] && [ -e "$file" ] && before=$(cksum <"$file")
    run "$@"
    after=""
    [ -n "$file" ] && [ -e "$file" ] && after=$(cksum <"$file")
    if [ "$rc" -eq 1 ] && [ "$(wc -l <"$TMP/err")" -eq 1 ] && grep -qF -- "$needle" "$TMP/err" && [ "$before" = "$after" ]; then
        ok "$what: $(cat "$TMP/err")"
    else
        not_ok "$what: exit $rc, expected one line with '$needle' and $file unchanged"; sed 's/^/# /' "$TMP/err" | head -3
    fi
}

cp "$S/cornell.gltf" "$S/cornell.bin" .
cp "$S/museum2.gltf" "$S/museum2.bin" "$S/museum2_floor.png" .
"$B/lie-build" cornell.gltf $BUILD -o c.lie || not_ok "build cornell"
printf -- '- move: {node: TallBlock, by: [0.01, 0, 0]}\n' >e.yaml
printf -- '- set-material: {node: Floor, base-color: [0.5, 0.5, 0.5]}\n' >m.yaml
ALSO="refusing to write over it"

# ---- lie-build
refused "lie-build -o the scene" "cornell.gltf: is also the input cornell.gltf" cornell.gltf \
    "$B/lie-build" cornell.gltf $BUILD -o cornell.gltf
refused "lie-build -o the scene's buffer" "is also the input ./cornell.bin" cornell.bin \
    "$B/lie-build" cornell.gltf $BUILD -o cornell.bin
refused "lie-build -o an --edit file" "e.yaml: is also the input e.yaml" e.yaml \
    "$B/lie-build" cornell.gltf --edit e.yaml $BUILD -o e.yaml
ln -s cornell.gltf link.lie
refused "lie-build -o a symlink to the scene" "link.lie: is also the input" cornell.gltf \
    "$B/lie-build" cornell.gltf $BUILD -o link.lie
ln cornell.bin hard.lie
refused "lie-build -o a hard link to the buffer" "hard.lie: is also the input" cornell.bin \
    "$B/lie-build" cornell.gltf $BUILD -o hard.lie
mkdir sub
refused "lie-build -o sub/../cornell.gltf" "is also the input" cornell.gltf \
    "$B/lie-build" cornell.gltf $BUILD -o sub/../cornell.gltf

# ---- rst-update
refused "rst-update -o the edit file" "e.yaml: is also the input e.yaml" e.yaml \
    "$B/rst-update" c.lie e.yaml -q -o e.yaml
refused "rst-update -o the second edit file" "m.yaml: is also the input m.yaml" m.yaml \
    "$B/rst-update" c.lie e.yaml m.yaml -q -o m.yaml
refused "rst-update -o the cache's scene" "is also the input" cornell.gltf \
    "$B/rst-update" c.lie e.yaml -q -o cornell.gltf
refused "rst-update --write-scene over the cache's scene" "is also the input" cornell.gltf \
    "$B/rst-update" c.lie e.yaml -q -o o.lie --write-scene cornell.gltf
ln -s c.lie cache.glb
refused "rst-update --write-scene over the cache (through a symlink)" "cache.glb: is also the input c.lie" c.lie \
    "$B/rst-update" c.lie e.yaml -q -o o.lie --write-scene cache.glb
[ -e o.lie ] && not_ok "o.lie written beside a refused scene" || ok "nothing written"
refused "rst-update -o s.glb --write-scene s.glb" "s.glb: is also the output s.glb" "" \
    "$B/rst-update" c.lie e.yaml -q -o s.glb --write-scene s.glb
[ -e s.glb ] && not_ok "s.glb written" || ok "s.glb not written"
refused "rst-update -o out.bin --write-scene out.gltf (its side file)" "out.bin: is also the output out.bin" "" \
    "$B/rst-update" c.lie e.yaml -q -o out.bin --write-scene out.gltf
[ -e out.bin ] || [ -e out.gltf ] && not_ok "out.bin or out.gltf written" || ok "neither written"
run "$B/rst-update" c.lie e.yaml -q -o c2.lie
cp c.lie inplace.lie
run "$B/rst-update" inplace.lie e.yaml -q -o inplace.lie
expect_rc 0 "rst-update -o the input cache: an update in place"
expect_same inplace.lie c2.lie "in place = to another file"

# ---- lie-render, lie-inspect image, lie-animate
refused "lie-render -o the scene's texture" "museum2_floor.png: is also the input" museum2_floor.png \
    "$B/lie-render" museum2.gltf -q --size 8x8 -o museum2_floor.png
printf 'keys:\n  - {eye: [0, 1, 3], target: [0, 1, 0], frames: 3}\n  - {eye: [0, 1, 2], target: [0, 1, 0]}\n' >p.yaml
ln -s museum2_floor.png f2.png
refused "lie-render --path: one frame a symlink to the texture" "f2.png: is also the input" museum2_floor.png \
    "$B/lie-render" museum2.gltf --path p.yaml -q --size 8x8 -o f%d.png
[ -e f0.png ] && not_ok "frame 0 written before the refusal" || ok "no frame written"
ln -s c.lie c.png
refused "lie-inspect image -o the cache (a symlink)" "c.png: is also the input c.lie" c.lie \
    "$B/lie-inspect" image c.lie -o c.png
ln -s cornell.bin bin.png
refused "lie-inspect image -o the scene's buffer (a symlink)" "bin.png: is also the input" cornell.bin \
    "$B/lie-inspect" image c.lie -o bin.png
cp "$D/gltf/animated.gltf" .
refused "lie-animate --camera-path over the scene" "animated.gltf: is also the input animated.gltf" animated.gltf \
    "$B/lie-animate" animated.gltf --fps 2 -q -o f_%04d.yaml --camera-path animated.gltf
refused "lie-animate --camera-path one of the frames" "f_0001.yaml: is also the output f_0001.yaml" "" \
    "$B/lie-animate" animated.gltf --fps 2 -q -o f_%04d.yaml --camera-path f_0001.yaml
ln -s animated.gltf g_0000.yaml
refused "lie-animate: a frame that is a symlink to the scene" "g_0000.yaml: is also the input" animated.gltf \
    "$B/lie-animate" animated.gltf --fps 2 -q --frames 0-1 -o g_%04d.yaml
[ -e f_0000.yaml ] || [ -e g_0001.yaml ] && not_ok "frames written" || ok "no frame written"
expect_no_temp "$T" "no temporary left"
finish
