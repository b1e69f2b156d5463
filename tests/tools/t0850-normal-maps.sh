#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Normal maps (glTF 2.0 normalTexture): tangents made from texture
# coordinates shade exactly as the same tangents given as TANGENT; the map
# changes the image; the LIE image matches full visibility on it; and scenes
# without normal maps render byte for byte as before normal maps were read
# (the checksums are of the images and cache the build before them made).
. "$(dirname "$0")/lib.sh"
G="$D/gltf"
cd "$TMP" || exit 1

# images and a cache of tests/scenes, copied here so that the paths the
# files record are the same everywhere; uncompressed EXR (no zlib in the bytes)
cp "$S"/cornell.gltf "$S"/cornell.bin "$S"/museum1.gltf "$S"/museum1.bin "$S"/museum2.gltf "$S"/museum2.bin \
    "$S"/museum2_floor.png .
"$B/lie-render" cornell.gltf -q --size 32x32 --light-samples 8 --compression none -o cornell.exr
"$B/lie-render" museum2.gltf -q --size 32x32 --light-samples 8 --compression none -o museum2.exr
"$B/lie-build" museum1.gltf -q -o m1.lie
"$B/lie-render" m1.lie -q --size 32x32 --light-samples 8 --compression none -o m1-lie.exr
same_sum() { # FILE SHA256 WHAT
    got=$(sha256sum "$1" | cut -c1-64)
    if [ "$got" = "$2" ]; then ok "$3: the same bytes as before normal maps"; else
        not_ok "$3: sha256 $got, before normal maps $2"; fi
}
same_sum cornell.exr eab09d0ff50d73b8962a9f5e8de7501ac2c777a45c722170bc362c4d5f44bb0a "cornell, full visibility"
same_sum museum2.exr e81beec404e4b671d42bb808ae91a81915dd9259aa24d47a9f1a357b676884ef "museum2 (textured), full visibility"
# (format version 7: PARAMS records whole-pixels, and the whole build's cost model leaves the
# units that cannot pay unbuilt; before it, with version 6, a83a4d4c...; the image from it is
# the same bytes)
same_sum m1.lie e87bbbb3628918e11f4268adbef5b1013ad5a8f8bbb50ce4e86b3d73158bb31d "museum1's cache"
same_sum m1-lie.exr e9f44c389b99eab9cdda30096eb43669532f52d5676f03aa0119e90ef2f75fea "museum1 from its cache"

R="--size 40x40 --light-samples 4 -q"
for v in normal_map normal_map_tangent normal_map_none; do
    "$B/lie-render" "$G/$v.gltf" $R -o "$v.exr"
done
if "$H/exr-compare" normal_map.exr normal_map_tangent.exr 0 0 >cmp.txt; then
    ok "tangents made from UVs shade as the same TANGENT given: $(cat cmp.txt)"; else
    not_ok "made and given tangents: $(cat cmp.txt)"; fi
if "$H/exr-compare" normal_map.exr normal_map_none.exr 0.2 1 >cmp.txt; then
    not_ok "the normal map changes too few pixels: $(cat cmp.txt)"; else
    ok "the normal map changes the floor: $(cat cmp.txt)"; fi
run "$B/lie-build" "$G/normal_map.gltf" -o nm.lie -q
expect_rc 0 "lie-build of a normal-mapped scene"
"$B/lie-render" nm.lie $R -o nm-lie.exr
expect_near_full normal_map.exr nm-lie.exr "normal map"
finish
