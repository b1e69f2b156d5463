#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The example makefiles follow their inputs: the tools and the settings are prerequisites,
# `make -n` lists exactly what would run and `make -q` agrees; every documented variable
# changes what it should; lie-animate's files are one grouped target; an animated asset
# without a camera renders.  Everything is written under $TMP (OUT=, BIN=, EDITS=).
. "$(dirname "$0")/lib.sh"
unset MAKEFLAGS MFLAGS MAKELEVEL
BN="$TMP/bin"
mkdir -p "$BN"
for t in lie-build rst-update lie-render lie-animate; do cp "$B/$t" "$BN/"; done
cp -r "$ROOT/examples/edits" "$TMP/edits"
E="make -s -C $ROOT/examples OUT=$TMP/ex BIN=$BN EDITS=$TMP/edits SIZE=32x32 LIGHT_SAMPLES=4 MIN_PATCH=1e-2"
count() { grep -c -- "$1" "$TMP/out"; } # count PATTERN: lines of the last `run` naming it

run $E
expect_rc 0 "make -C examples"
[ "$(ls "$TMP/ex"/frame_*.png | wc -l)" -eq 5 ] && ok "five frames" || not_ok "frames: $(ls "$TMP/ex")"
run $E -q
expect_rc 0 "make -q: up to date right after"
run $E -n
[ ! -s "$TMP/out" ] && ok "make -n: nothing to run" || not_ok "make -n lists: $(head -3 "$TMP/out")"

run $E -n SIZE=40x40
[ "$(count 'lie-render')" -eq 5 ] && [ "$(count 'rst-update\|lie-build')" -eq 0 ] \
    && ok "SIZE=40x40: make -n lists the 5 renders and no build or update" || not_ok "make -n SIZE=40x40: $(cat "$TMP/out")"
run $E SIZE=40x40
file "$TMP/ex/frame_2.png" | grep -q '40 x 40' && ok "and make SIZE=40x40 renders them at 40x40" || not_ok "$(file "$TMP/ex/frame_2.png")"
run $E -q SIZE=40x40
expect_rc 0 "make -q SIZE=40x40 after it"

touch "$TMP/edits/step3.yaml"
run $E -n SIZE=40x40
[ "$(count 'rst-update')" -eq 2 ] && [ "$(count 'lie-render')" -eq 2 ] && grep -q 'step3.yaml' "$TMP/out" \
    && ok "an edited step3.yaml: make -n lists steps 3-4 and their frames only" || not_ok "make -n: $(cat "$TMP/out")"
run $E SIZE=40x40
run $E -q SIZE=40x40
expect_rc 0 "and they are made"

touch "$BN/lie-render"
run $E -n SIZE=40x40
[ "$(count 'lie-render')" -eq 5 ] && ok "a rebuilt lie-render: every frame again" || not_ok "make -n: $(cat "$TMP/out")"
run $E SIZE=40x40 LIGHT_SAMPLES=4
run $E -n SIZE=40x40 MIN_PATCH=2e-2
[ "$(count 'lie-build')" -eq 1 ] && [ "$(count 'rst-update')" -eq 4 ] && [ "$(count 'lie-render')" -eq 5 ] \
    && ok "MIN_PATCH: the build, the updates and the frames" || not_ok "make -n MIN_PATCH=2e-2: $(cat "$TMP/out")"

# examples/animate: a few small frames
A="make -s -C $ROOT/examples/animate OUT=$TMP/an BIN=$BN SIZE=24x16 LIGHT_SAMPLES=4 LAST=3"
run $A
expect_rc 0 "make -C examples/animate LAST=3"
[ "$(ls "$TMP/an"/frame_*.png | wc -l)" -eq 4 ] && ok "frames 0-3" || not_ok "frames: $(ls "$TMP/an")"
run $A -q
expect_rc 0 "make -q: up to date right after"
run $A -n
[ ! -s "$TMP/out" ] && ok "make -n: nothing to run" || not_ok "make -n lists $(wc -l <"$TMP/out") commands: $(head -3 "$TMP/out")"

run $A -n FPS=8
[ "$(count 'lie-animate')" -eq 1 ] && [ "$(count 'rst-update')" -eq 4 ] && [ "$(count 'lie-render')" -eq 4 ] \
    && [ "$(count 'lie-build')" -eq 0 ] && ok "FPS=8: one lie-animate for all files, the updates and frames, no build" \
    || not_ok "make -n FPS=8: $(cat "$TMP/out")"
run $A FPS=8
grep -q 't = 0.375 s' "$TMP/an/edits/frame_0003.yaml" && ok "FPS=8: frame 3 is at 0.375 s" \
    || not_ok "frame 3: $(head -1 "$TMP/an/edits/frame_0003.yaml")"
run $A FPS=8 LAST=10
expect_rc 0 "LAST=10 renders (the files of frames 9 and 10 made with the rest)"
[ -s "$TMP/an/frame_0010.png" ] && ok "frame 10 is there" || not_ok "no frame 10: $(cat "$TMP/err")"
run $A -q FPS=8 LAST=10
expect_rc 0 "make -q FPS=8 LAST=10 after it"
run $A -n FPS=8 LAST=10 SIZE=20x16
[ "$(count 'lie-render')" -eq 11 ] && [ "$(count 'lie-animate\|rst-update')" -eq 0 ] \
    && ok "SIZE: the 11 frames again, nothing else" || not_ok "make -n SIZE=20x16: $(cat "$TMP/out")"

# an animated asset without a camera: lie-render's default framing, held
N="make -s -C $ROOT/examples/animate OUT=$TMP/nc BIN=$BN SIZE=24x16 LIGHT_SAMPLES=4 LAST=2 SCENE=$D/gltf/animated_nocamera.gltf"
run $N
expect_rc 0 "SCENE=animated_nocamera.gltf (no camera) renders"
[ "$(ls "$TMP/nc"/frame_*.png 2>/dev/null | wc -l)" -eq 3 ] && ok "its three frames" || not_ok "frames: $(ls "$TMP/nc")"
[ "$(grep -c '  - eye:' "$TMP/nc/path.yaml")" -eq 3 ] && [ "$(grep '  - eye:' "$TMP/nc/path.yaml" | sort -u | wc -l)" -eq 1 ] \
    && ok "the camera path holds one framing" || not_ok "path: $(cat "$TMP/nc/path.yaml")"
run "$BN/lie-render" "$D/gltf/animated_nocamera.gltf" -q --size 24x16 --light-samples 4 -o "$TMP/still.png"
run "$BN/lie-render" "$TMP/nc/base.lie" -q --size 24x16 --light-samples 4 --path "$TMP/nc/path.yaml" --frames 0-0 -o "$TMP/p_%d.png"
run "$BN/lie-render" "$TMP/nc/base.lie" -q --size 24x16 --light-samples 4 -o "$TMP/d.png"
cmp -s "$TMP/p_0.png" "$TMP/d.png" && ok "which is lie-render's default framing" || not_ok "the path's frame 0 differs from the default framing"
finish
