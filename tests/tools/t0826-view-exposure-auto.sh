#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# lie-view --exposure auto, under a real X server (Xvfb): each image gets
# its own exposure as lie-render --exposure auto gives a frame (the stops
# that take its log-average luminance to 0.18, Reinhard et al. 2002).  The
# screenshot equals lie-render --exposure auto of the saved cache, byte for
# byte (the tEXt that says the exposure too); a scene 1000 times brighter,
# white at --exposure 0, is the same picture with 9.97 stops less.
. "$ROOT/tests/tools/lib.sh"

need_viewer
cd "$TMP" || exit 1
VIEW="-q --size 48x48 --light-samples 4 --view-size 64x64"
camera_of() { sed -n 's/.*"camera":"\([^"]*\)".*/\1/p' "$1"; }
# the pixels of a PNG clipped to white (every channel)
clipped() { oiiotool "$1" --minchan --rangecheck 0 0.99 2>/dev/null | sed -n 's/^ *\([0-9]*\) *> .*/\1/p'; }

sed 's/"emissiveStrength": *17}/"emissiveStrength": 17000}/' "$S/cornell.gltf" >bright.gltf
cp "$S/cornell.gltf" "$S/cornell.bin" .
printf 'frames 1\nwait\nscreenshot %s\nquit\n' a.png >a.txt
printf 'frames 1\nwait\nscreenshot %s\nquit\n' b.png >b.txt
printf 'frames 1\nwait\nscreenshot %s\nquit\n' w.png >w.txt

run xvfb_run "$B/lie-view" cornell.gltf $VIEW --exposure auto --script a.txt --save a.lie --stats=json
expect_rc 0 "--exposure auto"
cp "$TMP/err" a.json
ev=$(field exposure <a.json)
cam=$(camera_of a.json)
if grep -q '"exposure_mode":"auto"' a.json && [ -n "$ev" ]; then ok "--stats=json says the exposure shown ($ev stops)"; else
    not_ok "--stats=json: no auto exposure: $(cat a.json)"; fi
"$B/lie-render" a.lie --camera "$cam" --size 48x48 --light-samples 4 --exposure auto -q -o ref.png
expect_same a.png ref.png "the screenshot equals lie-render --exposure auto of the saved cache, byte for byte"

run xvfb_run "$B/lie-view" bright.gltf $VIEW --exposure auto --script b.txt --stats=json
expect_rc 0 "--exposure auto on a scene 1000 times brighter"
ev2=$(field exposure <"$TMP/err")
if awk -v a="$ev" -v b="$ev2" 'BEGIN { d = a - b - 9.9658; exit !(d < 0.01 && d > -0.01) }'; then
    ok "1000 times the light, 9.97 stops less exposure ($ev against $ev2)"; else
    not_ok "exposures $ev and $ev2 are not 9.97 stops apart"; fi
run xvfb_run "$B/lie-view" bright.gltf $VIEW --script w.txt
expect_rc 0 "the brighter scene at --exposure 0"
ca=$(clipped a.png) cb=$(clipped b.png) cw=$(clipped w.png)
if [ -n "$cw" ] && [ -n "$cb" ] && [ "$cw" -gt 1152 ] && [ "$((2 * cb))" -lt "$cw" ]; then
    ok "at --exposure 0 the brighter scene is white ($cw of 2304 pixels clipped), auto exposes it ($cb)"; else
    not_ok "clipped pixels: --exposure 0 '$cw', auto '$cb' (the dimmer scene's auto: '$ca')"; fi
if oiiotool a.png b.png --fail 0.02 --failpercent 1 --diff >/dev/null 2>&1; then
    ok "the brighter scene's auto-exposed screenshot is the same picture"; else
    not_ok "auto-exposed screenshots differ: $(oiiotool a.png b.png --diff 2>&1 | tail -3)"; fi
run "$B/lie-view" cornell.gltf --exposure bright
expect_rc 2 "--exposure bright is a usage error"
finish
