#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-render --visibility=full on the bundled scenes: outputs, formats,
# determinism across thread counts, the command-line contract.
. "$ROOT/tests/tools/lib.sh"

run "$B/lie-render" --help
expect_rc 0 "--help exits 0"
if grep -q -- '--light-samples' "$TMP/out"; then ok "--help goes to stdout"; else not_ok "--help output"; fi
run "$B/lie-render" --version
expect_rc 0 "--version exits 0"

run "$B/lie-render" "$S/museum1.gltf" --size 64x48 --light-samples 8 -q -o "$TMP/m1.exr"
expect_rc 0 "render museum1 to EXR"
expect_file "$TMP/m1.exr" "EXR written"
if head -c 4 "$TMP/m1.exr" | od -An -tx1 | grep -q "76 2f 31 01"; then ok "EXR magic"; else not_ok "EXR magic"; fi

run "$B/lie-render" "$S/museum1.gltf" --size 64x48 --light-samples 8 -q -o "$TMP/m1.png"
expect_rc 0 "render museum1 to PNG"
if head -c 8 "$TMP/m1.png" | od -An -tx1 | grep -q "89 50 4e 47 0d 0a 1a 0a"; then ok "PNG magic"; else not_ok "PNG magic"; fi

# Determinism: the same bytes for --threads 1 and --threads 2.
run "$B/lie-render" "$S/museum1.gltf" --size 96x64 --light-samples 12 --threads 1 -q -o "$TMP/t1.exr"
run "$B/lie-render" "$S/museum1.gltf" --size 96x64 --light-samples 12 --threads 2 -q -o "$TMP/t2.exr"
expect_same "$TMP/t1.exr" "$TMP/t2.exr" "museum1: identical EXR for 1 and 2 threads"
run "$B/lie-render" "$S/museum2.gltf" --size 64x64 --light-samples 6 --pattern rotated --spp 2 --threads 1 -q -o "$TMP/r1.exr"
run "$B/lie-render" "$S/museum2.gltf" --size 64x64 --light-samples 6 --pattern rotated --spp 2 --threads 2 -q -o "$TMP/r2.exr"
expect_same "$TMP/r1.exr" "$TMP/r2.exr" "museum2 (mirror, texture, rotated, 2 spp): identical for 1 and 2 threads"

# EXR to stdout.
"$B/lie-render" "$S/cornell.gltf" --size 32x32 --light-samples 4 -q -o - >"$TMP/stdout.exr" 2>"$TMP/err"; rc=$?
expect_rc 0 "EXR to stdout"
run "$B/lie-render" "$S/cornell.gltf" --size 32x32 --light-samples 4 -q -o "$TMP/file.exr"
expect_same "$TMP/stdout.exr" "$TMP/file.exr" "stdout EXR equals file EXR"

# AOVs, stats.
run "$B/lie-render" "$S/museum3.gltf" --size 32x32 --light-samples 2 --aov albedo,normal,depth --stats=json -q -o "$TMP/aov.exr"
expect_rc 0 "museum3 with AOVs and --stats=json"
if grep -q '"shadow_rays":' "$TMP/err" && [ "$(wc -l <"$TMP/err")" -eq 1 ]; then ok "--stats=json prints one JSON line"; else not_ok "--stats=json"; fi
if grep -a -q 'albedo.R' "$TMP/aov.exr" && grep -a -q 'depth.Z' "$TMP/aov.exr"; then ok "AOV channels in the EXR"; else not_ok "AOV channels"; fi
run "$B/lie-render" "$S/museum1.gltf" --size 16x16 --light-samples 0 --stats -q -o "$TMP/eye.exr"
expect_rc 0 "--light-samples 0 (eye rays only)"
if grep -q '0 shadow' "$TMP/err"; then ok "no shadow rays with --light-samples 0"; else not_ok "eye-only stats"; sed 's/^/# /' "$TMP/err"; fi

# Cameras.
run "$B/lie-render" "$S/cornell.gltf" --size 16x16 --light-samples 2 -q --camera "eye=0.278,0.273,-0.8,target=0.278,0.273,0,fov=40" -o "$TMP/c.exr"
expect_rc 0 "explicit --camera eye=...,target=..."
run "$B/lie-render" "$S/cornell.gltf" --size 16x16 --light-samples 2 -q --camera "eye=0.278,0.273,-0.8,target=0.278,0.273,0,ortho=0.6" -o "$TMP/c.exr"
expect_rc 0 "explicit orthographic --camera eye=...,target=...,ortho=H"
run "$B/lie-render" "$S/cornell.gltf" --size 16x16 -q --camera "eye=0,0,-1,target=0,0,0,fov=40,ortho=1" -o "$TMP/c3.exr"
expect_rc 1 "--camera with both fov= and ortho= is refused"
expect_one_error_line "lie-render: $S/cornell.gltf: --camera: fov= is for a perspective view" "fov= with ortho=: one line"
expect_no_file "$TMP/c3.exr" "no output for fov= with ortho="
run "$B/lie-render" "$S/cornell.gltf" --size 16x16 --light-samples 2 -q --camera 0 -o "$TMP/c.exr"
expect_rc 0 "--camera by index"
run "$B/lie-render" "$S/cornell.gltf" --size 16x16 -q --camera NoSuchCamera -o "$TMP/c2.exr"
expect_rc 1 "unknown camera name"
expect_one_error_line "lie-render: $S/cornell.gltf: no camera named" "unknown camera: one line"
expect_no_file "$TMP/c2.exr" "no output for an unknown camera"

# --compression: every codec is lossless, the header names it.
run "$B/lie-render" "$S/cornell.gltf" --size 32x32 --light-samples 4 -q -o "$TMP/zip.exr"
for c in zips piz rle none; do
    run "$B/lie-render" "$S/cornell.gltf" --size 32x32 --light-samples 4 -q --compression $c -o "$TMP/$c.exr"
    if [ "$rc" -eq 0 ] && "$H/exr-compare" "$TMP/zip.exr" "$TMP/$c.exr" 0 0 >/dev/null 2>&1; then
        ok "--compression $c: the same pixels as zip"; else not_ok "--compression $c"; sed 's/^/# /' "$TMP/err"; fi
done
if [ "$(wc -c <"$TMP/none.exr")" -gt "$(wc -c <"$TMP/zip.exr")" ]; then ok "--compression none writes more bytes than zip"; else
    not_ok "--compression none: not larger than zip"; fi

# A scene without emitters renders (emission only), with a warning unless -q.
G="$ROOT/tests/data/gltf"
run "$B/lie-render" "$G/hierarchy.gltf" --size 8x8 -o "$TMP/dark.exr"
expect_rc 0 "a scene without emitters renders"
if grep -q "lie-render: $G/hierarchy.gltf: warning: no emitters" "$TMP/err"; then ok "and says it has no emitters"; else
    not_ok "no-emitter warning"; sed 's/^/# /' "$TMP/err"; fi
run "$B/lie-render" "$G/hierarchy.gltf" --size 8x8 -q -o "$TMP/dark.exr"
if [ "$rc" -eq 0 ] && [ ! -s "$TMP/err" ]; then ok "-q silences the warning"; else not_ok "-q and the warning"; fi
run "$B/lie-build" "$G/hierarchy.gltf" -o "$TMP/dark.lie"
if [ "$rc" -eq 0 ] && grep -q "lie-build: $G/hierarchy.gltf: warning: no emitters" "$TMP/err"; then
    ok "lie-build warns too"; else not_ok "lie-build no-emitter warning"; sed 's/^/# /' "$TMP/err"; fi
finish
