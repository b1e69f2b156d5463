#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make bench-view: lie-view's interactive loop under Xvfb (its targets below,
# 512x512 museum1, 100 light samples): frames per second while the
# view orbits (progressive: each orbit step shows at least its coarse
# level), the first image of an edit's world after each drag, and how long
# the constructor takes to catch up after the last edit.  Writes
# out/bench-view.json.  The figures depend on the load of the machine.
# BIN (default bin) names the binaries: another build's, to compare two
# side by side in one run.
set -e
cd "$(dirname "$0")/.."
field() { sed -n "s/.*\"$1\":\([0-9.e+-]*\).*/\1/p"; }
BIN=${BIN:-bin}
SCENE=${SCENE:-tests/scenes/museum1.gltf}
SIZE=${SIZE:-512x512}
LIGHT_SAMPLES=${LIGHT_SAMPLES:-100}
STEPS=${STEPS:-120}
DRAGS=${DRAGS:-10}
mkdir -p out
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
command -v xvfb-run >/dev/null || { echo "bench-view: xvfb-run is missing (make deps)" >&2; exit 1; }

if [ "${PARTS:-all}" != ctor ]; then # PARTS=ctor: the constructor's part alone
"$BIN"/lie-build "$SCENE" -q -o "$TMP/scene.lie"

# orbit: STEPS steps of 3 degrees, each waiting for its first image
{
    echo "frames 3"
    i=0
    while [ $i -lt "$STEPS" ]; do echo "orbit 3 0"; echo "frames 1"; i=$((i + 1)); done
    echo "frames 100"   # until every level of the last view is done
    echo "wait"
    echo "quit"
} >"$TMP/orbit.txt"
xvfb-run -a -s "-screen 0 1024x768x24" "$BIN"/lie-view "$TMP/scene.lie" --size "$SIZE" \
    --light-samples "$LIGHT_SAMPLES" --script "$TMP/orbit.txt" -q --stats=json 2>"$TMP/orbit.json"

# drags: DRAGS moves of the cube, a few frames apart, then wait for the constructor
{
    echo "frames 3"
    echo "select Cube"
    i=0
    while [ $i -lt "$DRAGS" ]; do echo "drag 0.05 0 -0.03"; echo "frames 2"; i=$((i + 1)); done
    echo "wait"
    echo "frames 3"
    echo "quit"
} >"$TMP/drag.txt"
xvfb-run -a -s "-screen 0 1024x768x24" "$BIN"/lie-view "$TMP/scene.lie" --size "$SIZE" \
    --light-samples "$LIGHT_SAMPLES" --script "$TMP/drag.txt" -q --stats=json 2>"$TMP/drag.json"

fps=$(sed -n 's/.*"fps_mean":\([0-9.]*\).*/\1/p' "$TMP/orbit.json")
list() { sed -n "s/.*\"$1\":\[\([^]]*\)\].*/\1/p" "$TMP/drag.json" | tr ',' '\n'; }
stat() { awk 'NF { n++; s += $1; if ($1 > m) m = $1 } END { if (n) printf "%.1f %.1f %d", s / n, m, n; else print "0 0 0" }'; }
set -- $(list first_frame_ms | stat); first_mean=$1 first_max=$2 first_n=$3
set -- $(list update_ms | stat); upd_mean=$1 upd_max=$2
catchup=$(list catchup_ms | tail -1)
refine=$(sed -n 's/.*"refine_ms":\[\([^]]*\)\].*/\1/p' "$TMP/orbit.json" | tr ',' '\n' | tail -1)
load=$(cut -d' ' -f1 /proc/loadavg)

printf '%-46s %10s %10s\n' "lie-view, $SIZE, $LIGHT_SAMPLES light samples" measured target
printf '%-46s %10s %10s\n' "fps while orbiting (progressive)" "$fps" ">= 15"
printf '%-46s %10s %10s\n' "  (each a whole coarse image: 1/16 of the pixels)" "" ""
printf '%-46s %10s %10s\n' "full image once the orbit stops (ms)" "${refine:-?}" ""
printf '%-46s %10s %10s\n' "first frame after a drag, mean (ms)" "$first_mean" "<= 100"
printf '%-46s %10s %10s\n' "first frame after a drag, worst (ms)" "$first_max" "<= 100"
printf '%-46s %10s %10s\n' "phase 1 of an edit, mean / worst (ms)" "$upd_mean / $upd_max" ""
printf '%-46s %10s %10s\n' "constructor catch-up after the last edit (ms)" "${catchup:-?}" "<= 1000"
printf '%-46s %10s\n' "load average during the run" "$load"
cat >out/bench-view.json <<EOF
{"scene":"$SCENE","size":"$SIZE","light_samples":$LIGHT_SAMPLES,"orbit_fps":${fps:-0},"first_frame_ms_mean":$first_mean,"first_frame_ms_max":$first_max,"drags":$first_n,"update_ms_mean":$upd_mean,"update_ms_max":$upd_max,"catchup_ms":${catchup:-0},"refine_ms":${refine:-0},"loadavg":$load}
EOF
echo "bench-view: wrote out/bench-view.json"
fi

# The asynchronous constructor (§4.3.1) on third-party scenes opened as
# glTF (../shared/scenes): the time to the first frame ("first": lie-view's
# first_frame_ms, from the start of its main to the present of the first
# whole image the window shows, of any level: the coarsest, a quarter of
# the resolution each way and a tenth of the light samples, shaded with
# lights prepared without the textured emitters' distributions, which are
# prepared beside it for the finer levels); the full frame's
# time first (every shadow ray Embree's: the constructor paused until
# then) and once the constructor has
# caught up with the view (CATCHUP seconds at most; "pending" says what it
# had not built by then); on each, a drag's catch-up against
# rst-update of the same edit on the cache of the same view.
# NAME|SCENE|CAMERA|PICK|MOVE (a pixel of an object to drag, or empty, and
# how far, in the scene's units)
CSIZE=${CSIZE:-256x256}
CLS=${CLS:-32}
CATCHUP=${CATCHUP:-300}
CSCENES=${CSCENES:-"bedroom_corner|../shared/scenes/bedroom_corner/scene.gltf|eye=30,25,35,target=-40,20,-20|128 200|3 0 -2
scifi_hallway|../shared/scenes/scifi_hallway/space_ship_hallway.glb|eye=20.1,0.4,-2,target=20.1,0.2,-15|40 128|0.3 0 0.2
ccity_buildings|../shared/scenes/ccity_buildings/scene.gltf|eye=-10000,300,-5000,target=-15000,200,-13000|118 140|300 0 200"}
printf '\n%-16s %8s %9s %9s %7s %9s %10s %10s\n' "lie-view $CSIZE" "first" "full 1st" "full end" "ratio" "pending" "drag up" "rst-update"
printf '%-16s %8s %9s %9s %7s %9s %10s %10s\n' "target" "<= 1 s" "" "" ">= 5" "" "" ">= drag"
echo "$CSCENES" | while IFS='|' read -r name scene cam pick move; do
    [ -f "$scene" ] || { echo "$name: $scene missing"; continue; }
    {
        echo "pause"      # the first full frames with every shadow ray Embree's
        echo "frames 1"
        echo "redraw 1"
        echo "resume"
        echo "wait-at-most $CATCHUP"
        echo "redraw 3"
        if [ -n "$pick" ]; then
            echo "pick $pick"
            echo "drag ${move:-3 0 -2}"
            echo "wait-at-most $CATCHUP"
            echo "redraw 1"
        fi
        echo "quit"
    } >"$TMP/c.txt"
    xvfb-run -a -s "-screen 0 1024x768x24" "$BIN"/lie-view "$scene" --camera "$cam" --size "$CSIZE" \
        --light-samples "$CLS" --script "$TMP/c.txt" --record "$TMP/c.yaml" -q --stats=json 2>"$TMP/c.json"
    J="$TMP/c.json"
    first=$(field first_frame_ms <"$J"); f1=$(field full_frame_first_ms <"$J"); fa=$(field full_frame_after_ms <"$J")
    pend=$(field units_pending <"$J")
    ratio=$(awk -v a="$f1" -v b="$fa" 'BEGIN { if (b > 0) printf "%.1f", a / b; else print "-" }')
    drag=$(sed -n 's/.*"catchup_ms":\[\([0-9.]*\).*/\1/p' "$J")
    rst=""
    if [ -n "$pick" ] && [ -s "$TMP/c.yaml" ]; then
        vcam=$(sed -n 's/.*"camera":"\([^"]*\)".*/\1/p' "$J") # the viewer's, as it printed it
        "$BIN"/lie-build "$scene" --view "${vcam:-$cam}" -q -o "$TMP/c.lie"
        t0=$(date +%s.%N)
        "$BIN"/rst-update "$TMP/c.lie" "$TMP/c.yaml" -q -o "$TMP/c2.lie"
        rst=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.0f", 1e3 * (b - a) }')
    fi
    printf '%-16s %8s %9s %9s %7s %9s %10s %10s\n' "$name" "${first:-?}" "${f1:-?}" "${fa:--}" "$ratio" "${pend:-?}" \
        "${drag:--}" "${rst:--}"
    cp "$J" "out/bench-view-$name.json"
done
echo "(ms; full end: full frames after the catch-up; pending: units not built after $CATCHUP s; load $(cut -d' ' -f1 /proc/loadavg))"
