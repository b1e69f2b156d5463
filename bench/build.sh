#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make bench-build (also run by make bench): what a lie-build costs against the
# frames it serves, per scene, measured side by side in one run.
#
# For each scene: one full-visibility frame (the reference, 100 light samples,
# SIZE), the build with the paper's subdivision rule (--split-gain 0: split
# wherever a list is too long, down to --min-patch) and with the cost rule
# (the default --split-gain), each in full frames, with its cache size, and
# the LIE frame from the default cache against the full one.  Then the
# default build on 1 thread against THREADS threads: wall time, and CPU time
# against the THREADS run's critical path (serial CPU plus its busiest
# worker's), which other processes on a shared machine do not distort.
# Last, a generated 250k-triangle atrium (bench/atrium.c; ATRIUM=0 skips it)
# whose area lights an edit file adds, built for its camera only.
#
# BIN (default bin) names the binaries, so that two trees can be set side by
# side; CLUSTERS=K builds with --emitter-clusters K (docs/measurements.md,
# "Emitters in clusters"); PAPER=0 skips the paper-rule builds, ONE=0 the 1-thread ones.
# make bench-build-scenes runs the third-party scenes of ../shared/scenes
# alone, scifi_hallway among them, which takes minutes.
#
# Targets: build <= 5 full frames on every scene with a light and
# <= 2 on museum1; cache <= 16 MB under 50k triangles; LIE frame <= half the
# full frame; the atrium built in <= 60 s.  Writes out/bench-build.json.
# Then the views table (out/bench-build-views.json) and the many-lights row
# (out/bench-build-lights.json).
set -e
cd "$(dirname "$0")/.."
SIZE=${SIZE:-512x512}
THREADS=${THREADS:-$(nproc)}
SCENES=${SCENES:-"tests/scenes/museum1.gltf tests/scenes/museum3.gltf ../shared/scenes/bedroom_corner/scene.gltf ../shared/scenes/lights_punctual_lamp/LightsPunctualLamp.gltf"}
TIMEOUT=${TIMEOUT:-900}
BIN=${BIN:-bin}
CLARGS=; [ -z "${CLUSTERS:-}" ] || CLARGS="--emitter-clusters $CLUSTERS"
mkdir -p out
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT

field() { sed -n "s/.*\"$1\":\"\{0,1\}\([^,\"}]*\).*/\1/p"; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (b > 0 && a != "-" && a != "timeout") printf "%.2f", a / b; else print "-" }'; }
mb() { awk -v b="$1" 'BEGIN { if (b + 0 > 0) printf "%.2f", b / 1048576; else print "-" }'; }

# build SCENE OUT ARGS... -> "seconds bytes segments nodes cpu critical" (or "timeout ...")
# cpu: the process's CPU seconds; critical: what the run would take with a
# core per worker (its CPU less the workers', plus the busiest worker's)
build() {
    scene=$1; out=$2; shift 2
    if timeout "$TIMEOUT" "$BIN/lie-build" "$scene" $CLARGS -q --stats=json -o "$out" "$@" 2>"$TMP/b.json"; then
        cpu=$(field seconds_cpu <"$TMP/b.json")
        crit=$(awk -v c="$cpu" -v w="$(field seconds_cpu_workers <"$TMP/b.json")" \
            -v m="$(field seconds_cpu_worker_max <"$TMP/b.json")" 'BEGIN { printf "%.3f", c - w + m }')
        echo "$(field seconds_build <"$TMP/b.json") $(field bytes <"$TMP/b.json") $(field segments <"$TMP/b.json") $(field nodes <"$TMP/b.json") $cpu $crit"
    else
        echo "timeout - - - - -"
    fi
}

echo "bench-build: $SIZE frames, 100 light samples, $THREADS threads (ratios measured side by side; load $(cut -d' ' -f1 /proc/loadavg))"
printf '  %-26s %7s %4s %8s | %9s %9s %8s | %9s %9s %8s %9s | %8s %7s %7s | %7s %7s\n' scene tris emit "frame s" \
    "paper s" "frames" "cache MB" "cost s" "frames" "cache MB" "segments" "LIE s" "LIE/full" "off>2%" "1->${THREADS}t" "cpu"
echo "[" >out/bench-build.json
first=1

# bench_scene NAME SCENE PAPER ARGS...: one row.  The full frame renders the
# default cache (so edits in ARGS are in it); PAPER=0 skips the paper build.
bench_scene() {
    name=$1; scene=$2; paper=$3; shift 3
    tp=-; bp=-
    if [ "$paper" = 1 ] && [ "${PAPER:-1}" = 1 ]; then
        r=$(build "$scene" "$TMP/paper.lie" --split-gain 0 --threads "$THREADS" "$@")
        tp=$(echo "$r" | cut -d' ' -f1); bp=$(echo "$r" | cut -d' ' -f2)
    fi
    set -- $(build "$scene" "$TMP/cost.lie" --threads "$THREADS" "$@") "$@"
    tc=$1; bc=$2; segc=$3; cpun=$5; critn=$6; shift 6
    if [ "${ONE:-1}" = 1 ]; then
        set -- $(build "$scene" "$TMP/one.lie" --threads 1 "$@") "$@"
    else
        set -- - - - - - - "$@"
    fi
    t1=$1; cpu1=$5
    tl=-; tf=-; tris=-; emit=-; off=-
    if [ "$tc" != timeout ]; then
        "$BIN/lie-render" "$TMP/cost.lie" --visibility=full --size "$SIZE" --threads "$THREADS" -q --stats=json \
            -o "$TMP/full.exr" 2>"$TMP/f.json"
        tf=$(field seconds_render <"$TMP/f.json")
        tris=$(field triangles <"$TMP/f.json"); emit=$(field emitters <"$TMP/f.json")
        "$BIN/lie-render" "$TMP/cost.lie" --size "$SIZE" --threads "$THREADS" -q --stats=json -o "$TMP/lie.exr" \
            2>"$TMP/l.json"
        tl=$(field seconds_render <"$TMP/l.json")
        # the lists against full visibility: the same samples in the same
        # order (--exact off), so only visibility can differ
        "$BIN/lie-render" "$TMP/cost.lie" --exact off --size "$SIZE" --threads "$THREADS" -q -o "$TMP/lieo.exr"
        off=$(build/release/tests/exr-compare "$TMP/full.exr" "$TMP/lieo.exr" 1 1 |
            sed -n 's/.* by more than 2% (\([0-9.]*%\)).*/\1/p')
    fi
    printf '  %-26s %7s %4s %8s | %9s %9s %8s | %9s %9s %8s %9s | %8s %7s %7s | %7s %7s\n' "$name" "$tris" "$emit" "$tf" \
        "$tp" "$(ratio "$tp" "$tf")" "$(mb "$bp")" "$tc" "$(ratio "$tc" "$tf")" "$(mb "$bc")" "$segc" "$tl" \
        "$(ratio "$tl" "$tf")" "$off" "$(ratio "$t1" "$tc")" "$(ratio "$cpu1" "$critn")"
    [ $first = 1 ] || echo "," >>out/bench-build.json
    first=0
    printf '{"scene":"%s","triangles":"%s","emitters":"%s","full_frame_s":"%s","paper_build_s":"%s","paper_cache_bytes":"%s","cost_build_s":"%s","cost_cache_bytes":"%s","cost_segments":"%s","lie_frame_s":"%s","off_2pct":"%s","build_1_thread_s":"%s","cpu_1_thread_s":"%s","cpu_s":"%s","critical_path_s":"%s"}' \
        "$name" "$tris" "$emit" "$tf" "$tp" "$bp" "$tc" "$bc" "$segc" "$tl" "$off" "$t1" "$cpu1" "$cpun" "$critn" >>out/bench-build.json
}

for scene in $SCENES; do
    [ -f "$scene" ] || { echo "  $scene: missing, skipped"; continue; }
    bench_scene "$(basename "$(dirname "$scene")")/$(basename "$scene")" "$scene" 1
done
# the 250k-triangle target: a generated Sponza-class atrium (bench/atrium.c),
# its area lights added by an edit file, built for one view: <= 60 s
if [ "${ATRIUM:-1}" = 1 ]; then
    make -s build/release/atrium-gen >/dev/null
    mkdir -p out/atrium
    build/release/atrium-gen out/atrium >/dev/null
    bench_scene "atrium (--view, 250k)" out/atrium/atrium.gltf 0 --edit out/atrium/lights.yaml --view Camera
fi
echo "]" >>out/bench-build.json
printf '  (frames: build seconds / one full frame; paper: --split-gain 0; cost: the default --split-gain;\n'
printf '   1->%st: the default build on 1 thread / on %s, wall time, and cpu: its CPU seconds / the %s-thread\n' "$THREADS" "$THREADS" "$THREADS"
printf '   run'"'"'s critical path (serial CPU + the busiest worker), the speed-up with a core per thread;\n'
printf '   off>2%%: the LIE with --exact off, the same samples in the same order, against full visibility:\n'
printf '   pixels off by more than 2%%; the atrium skips the paper build; timeouts after %s s)\n' "$TIMEOUT"

# ---- break-even (BREAKEVEN=1; make bench-build-scenes): the third-party
# scenes from a camera inside their lit part, a build for that view
# against the frames it serves, at equal quality, side by side in one run
# (BSIZE, THREADS threads).  Quality is the error over lit pixels against
# a converged image (full visibility at TRUTH light samples, another seed;
# kept in out/truth/), as RMSE: at LS samples many pixels of these scenes
# are still off by 100% (p99 1.0, shown), which p99 cannot rank.  Full
# visibility at LS light samples sets the RMSE, and the LIE frame is the
# cheapest of LS x 4, 2, 1, 1/2, 1/4, 1/8 samples whose RMSE is no worse.  Break-even = build seconds /
# (full frame - that LIE frame), target <= 3 frames.  The build's seconds
# are lie-build's seconds_build (the view's eye rays and the units; loading
# the scene and Embree's BVH, which a renderer pays as well, not counted;
# "+load" adds them).  Writes out/bench-build-breakeven.json.
if [ "${BREAKEVEN:-0}" = 1 ]; then
    LS=${LS:-100}
    TRUTH=${TRUTH:-1024}
    BSIZE=${BSIZE:-256x256}
    CMP=build/release/tests/exr-compare
    BSCENES=${BSCENES:-"scifi_hallway|../shared/scenes/scifi_hallway/space_ship_hallway.glb|eye=20.1,0.5,2,target=20.1,0.3,-20
ccity_buildings|../shared/scenes/ccity_buildings/scene.gltf|eye=400,200,-5800,target=850,380,-6400
bedroom_corner|../shared/scenes/bedroom_corner/scene.gltf|eye=-12,36,42,target=-45,20,8
lights_punctual_lamp|../shared/scenes/lights_punctual_lamp/LightsPunctualLamp.gltf|eye=1.3,1.3,1.5,target=0.25,0.9,0"}
    mkdir -p out/truth
    # frame OUT.exr INPUT ARGS...: render, print its seconds
    frame() {
        o=$1; shift
        "$BIN/lie-render" "$@" --size "$BSIZE" --threads "$THREADS" -q --stats=json -o "$o" 2>"$TMP/fr.json"
        field seconds_render <"$TMP/fr.json"
    }
    err() { "$CMP" --error "$1" "$2" >"$TMP/err.json"; echo "$(field rmse <"$TMP/err.json") $(field p99 <"$TMP/err.json")"; }
    echo
    echo "bench-build break-even: a build for one view against its frames at equal quality, $BSIZE, $THREADS threads (load $(cut -d' ' -f1 /proc/loadavg))"
    printf '  %-20s | %8s %8s %8s %8s | %8s %8s %6s | %8s | %5s %8s %8s %6s %8s | %8s %8s\n' scene "build s" "+load s" \
        "cache MB" "unpaid" "full s" "rmse" "p99" "off>2%" "LIE N" "LIE s" "rmse" "p99" "LIE/full" "frames" "model"
    echo "[" >out/bench-build-breakeven.json
    bfirst=1
    echo "$BSCENES" | while IFS='|' read -r name scene cam; do
        [ -f "$scene" ] || { echo "  $name: $scene missing, skipped"; continue; }
        if ! timeout "$TIMEOUT" "$BIN/lie-build" "$scene" $CLARGS --view "$cam" --view-size "$BSIZE" --threads "$THREADS" \
            -q --stats=json -o "$TMP/be.lie" 2>"$TMP/be.json"; then
            echo "  $name: build failed or timed out after $TIMEOUT s"; continue
        fi
        J="$TMP/be.json"
        tb=$(field seconds_build <"$J")
        tall=$(awk -v a="$tb" -v b="$(field seconds_load <"$J")" -v c="$(field seconds_bvh <"$J")" 'BEGIN { printf "%.3f", a + b + c }')
        truth=out/truth/breakeven-$name-$BSIZE-$TRUTH.exr
        if [ ! -f "$truth" ] || [ "$scene" -nt "$truth" ]; then
            frame "$TMP/truth.exr" "$scene" --camera "$cam" --visibility=full --light-samples "$TRUTH" --seed 99 >/dev/null
            mv "$TMP/truth.exr" "$truth"
        fi
        tf=$(frame "$TMP/bf.exr" "$TMP/be.lie" --camera "$cam" --visibility=full --light-samples "$LS")
        set -- $(err "$truth" "$TMP/bf.exr"); rf=$1 pf=$2
        # lists right on real geometry: the LIE at the same samples and seed
        # as full visibility (--exact off: the same samples in the same order),
        # pixels off by more than 2% (target <= 0.1%)
        frame "$TMP/bo.exr" "$TMP/be.lie" --camera "$cam" --light-samples "$LS" --exact off >/dev/null
        boff=$("$CMP" "$TMP/bf.exr" "$TMP/bo.exr" 1 1 | sed -n 's/.* by more than 2% (\([0-9.]*%\)).*/\1/p')
        # the LIE's budgets, from 4 LS down: the cheapest as good as full
        bn=-; btl=-; bpl=-; brl=-
        for k in 4 2 1 0.5 0.25 0.125; do
            n=$(awk -v l="$LS" -v k="$k" 'BEGIN { printf "%d", l * k }')
            [ "$n" -ge 1 ] || break
            tl=$(frame "$TMP/bl.exr" "$TMP/be.lie" --camera "$cam" --light-samples "$n")
            set -- $(err "$truth" "$TMP/bl.exr")
            awk -v a="$1" -v b="$rf" 'BEGIN { exit !(a <= b) }' || break
            bn=$n; btl=$tl; brl=$1; bpl=$2
        done
        be=$(awk -v b="$tb" -v f="$tf" -v l="$btl" 'BEGIN { if (l != "-" && f - l > 0) printf "%.1f", b / (f - l); else print "never" }')
        model=$(field break_even_frames_predicted <"$J")
        printf '  %-20s | %8.2f %8.2f %8s %8s | %8.3f %8s %6s | %8s | %5s %8s %8s %6s %8s | %8s %8s\n' "$name" "$tb" "$tall" \
            "$(mb "$(field bytes <"$J")")" "$(field units_unpaid <"$J")" "$tf" "$rf" "$pf" "$boff" "$bn" "$btl" "$brl" "$bpl" \
            "$(ratio "$btl" "$tf")" "$be" "$model"
        [ $bfirst = 1 ] || echo "," >>out/bench-build-breakeven.json
        bfirst=0
        printf '{"scene":"%s","camera":"%s","size":"%s","build_s":"%s","build_with_load_s":"%s","cache_bytes":"%s","units_unpaid":"%s","full_samples":"%s","full_frame_s":"%s","full_rmse":"%s","full_p99":"%s","off_2pct":"%s","lie_samples":"%s","lie_frame_s":"%s","lie_rmse":"%s","lie_p99":"%s","break_even_frames":"%s","break_even_frames_model":"%s"}' \
            "$name" "$cam" "$BSIZE" "$tb" "$tall" "$(field bytes <"$J")" "$(field units_unpaid <"$J")" "$LS" "$tf" "$rf" "$pf" \
            "$boff" "$bn" "$btl" "$brl" "$bpl" "$be" "$model" >>out/bench-build-breakeven.json
    done
    echo "]" >>out/bench-build-breakeven.json
    printf '  (rmse, p99: error over lit pixels against full visibility at %s samples; full at %s samples; LIE N:\n' "$TRUTH" "$LS"
    printf '   the fewest samples of 4x .. 1/8x %s whose rmse is no worse, - if none; frames: build s / (full s - LIE s),\n' "$LS"
    printf '   target <= 3; model: lie-build --stats=json'"'"'s prediction, -1 where it predicts no saving;\n'
    printf '   unpaid: units the cost model left to Embree; off>2%%: the LIE at %s samples, --exact off, against full\n' "$LS"
    printf '   visibility at the same samples and seed, pixels off by more than 2%%, target <= 0.1%%)\n'
fi

# ---- views (§4.3.1, §4.3.3): what a build for the scene's camera costs and
# saves, whole against --view with the views choosing units only (--frames
# 0) and with the pixel rule (the default --frames), with the image against
# full visibility (share of pixels off by more than 2%, --exact off: the
# same samples as full visibility's; target <= 0.1%),
# then the cost model's predictions against what was measured (CPU seconds,
# from /usr/bin/time: the build; one frame's shadow rays, full and LIE, less
# an eye-rays-only frame), the constants those measurements give (ns per
# build segment, per Embree shadow ray, per blocker-list entry) beside the
# defaults, and --into: a second view added to the cache against one build
# for both (cmp).
VIEW_SCENES=${VIEW_SCENES:-"tests/scenes/museum1.gltf tests/scenes/museum3.gltf"}
CMP=build/release/tests/exr-compare
second_view() {
    case $1 in
    *museum3*) echo "eye=2,1.7,2,target=9,1,6" ;;
    *) echo "eye=3,2,-2,target=0,0.5,0" ;;
    esac
}
cpu() { awk '{ s += $1 } END { printf "%.3f", s }' "$1"; }
# timed OUT.cpu CMD...: runs CMD, its user + system CPU seconds to OUT.cpu
timed() { out=$1; shift; /usr/bin/time -f "%U %S" -o "$out.t" "$@" && tr ' ' '\n' <"$out.t" >"$out"; }
off() { "$CMP" "$1" "$2" 1 1 | sed -n 's/.* by more than 2% (\([0-9.]*%\)).*/\1/p'; }
echo
echo "bench-build views: the scene's camera at $SIZE, $THREADS threads; CPU seconds (user + system)"
printf '  %-22s %-6s | %8s %8s %8s | %8s %-19s %7s | %-24s | %-24s | %s\n' scene build "wall s" "cache MB" "off>2%" \
    "cpu s" "build cpu meas/model" "LIE/ful" "frame full cpu: meas/model" "frame LIE cpu: meas/model" "ns seg/ray/blk measured"
echo "[" >out/bench-build-views.json
first=1
for scene in $VIEW_SCENES; do
    [ -f "$scene" ] || { echo "  $scene: missing, skipped"; continue; }
    name=$(basename "$scene")
    timed "$TMP/eye.cpu" bin/lie-render "$scene" --visibility=full --light-samples 0 --size "$SIZE" \
        --threads "$THREADS" -q -o "$TMP/eye.exr"
    timed "$TMP/full.cpu" bin/lie-render "$scene" --visibility=full --size "$SIZE" --threads "$THREADS" -q \
        -o "$TMP/vfull.exr"
    for kind in whole units pixels; do
        case $kind in
        whole) args="" ;;
        units) args="--view 0 --view-size $SIZE --frames 0" ;;
        pixels) args="--view 0 --view-size $SIZE" ;;
        esac
        if ! timed "$TMP/b.cpu" timeout "$TIMEOUT" bin/lie-build "$scene" $args --threads "$THREADS" -q \
            --stats=json -o "$TMP/$kind.lie" 2>"$TMP/$kind.json"; then
            echo "  $name $kind: failed or timed out"; continue
        fi
        timed "$TMP/lie.cpu" bin/lie-render "$TMP/$kind.lie" --size "$SIZE" --threads "$THREADS" -q \
            -o "$TMP/$kind.exr"
        bin/lie-render "$TMP/$kind.lie" --exact off --size "$SIZE" --threads "$THREADS" -q -o "$TMP/$kind.exr"
        bin/lie-render "$TMP/$kind.lie" --visibility=full --size "$SIZE" --threads "$THREADS" -q -o "$TMP/kfull.exr"
        J="$TMP/$kind.json"
        wall=$(field seconds_build <"$J"); bytes=$(field bytes <"$J"); segs=$(field segments <"$J")
        bcpu=$(cpu "$TMP/b.cpu"); bmodel=$(field build_cpu_s_predicted <"$J"); bmeas=$(field build_cpu_s_measured <"$J")
        ecpu=$(cpu "$TMP/eye.cpu"); fcpu=$(cpu "$TMP/full.cpu"); lcpu=$(cpu "$TMP/lie.cpu")
        pf=$(field frame_shadow_cpu_s_full <"$J"); pl=$(field frame_shadow_cpu_s_lie <"$J")
        rays=$(field frame_full_rays <"$J"); ents=$(field frame_list_entries <"$J"); lrays=$(field frame_lie_rays <"$J")
        fs=$(awk -v a="$fcpu" -v b="$ecpu" 'BEGIN { printf "%.3f", a - b }')
        ls=$(awk -v a="$lcpu" -v b="$ecpu" 'BEGIN { printf "%.3f", a - b }')
        consts=$(awk -v bc="$bmeas" -v sg="$segs" -v fs="$fs" -v r="$rays" -v ls="$ls" -v e="$ents" -v lr="$lrays" \
            'BEGIN { if (r == "" || r == 0) { printf "%.0f/-/-", 1e9 * bc / sg; exit }
                     ray = 1e9 * fs / r; blk = e > 0 ? (1e9 * ls - lr * ray) / e : 0
                     printf "%.0f/%.1f/%.3f", 1e9 * bc / sg, ray, blk }')
        [ -n "$pf" ] || { pf=-; pl=-; }
        printf '  %-22s %-6s | %8s %8s %8s | %8s %8.3f / %-8.3f %7s | %10s / %-11s | %10s / %-11s | %s\n' "$name" "$kind" \
            "$wall" "$(mb "$bytes")" "$(off "$TMP/kfull.exr" "$TMP/$kind.exr")" "$bcpu" "$bmeas" "$bmodel" \
            "$(ratio "$lcpu" "$fcpu")" "$fs" "$pf" "$ls" "$pl" "$consts"
        [ $first = 1 ] || echo "," >>out/bench-build-views.json
        first=0
        printf '{"scene":"%s","build":"%s","build_s":%s,"cache_bytes":%s,"off_2pct":"%s","process_cpu_s":%s,"build_cpu_s":%s,"build_cpu_s_model":%s,"full_frame_cpu_s":%s,"lie_frame_cpu_s":%s,"eye_frame_cpu_s":%s,"frame_shadow_cpu_s_full_model":"%s","frame_shadow_cpu_s_lie_model":"%s","ns_measured":"%s"}' \
            "$name" "$kind" "$wall" "$bytes" "$(off "$TMP/kfull.exr" "$TMP/$kind.exr")" "$bcpu" "$bmeas" "$bmodel" "$fcpu" \
            "$lcpu" "$ecpu" "$pf" "$pl" "$consts" >>out/bench-build-views.json
    done
    # --into: view B added to the view-0 cache, against one build for both
    B=$(second_view "$scene")
    cp "$TMP/pixels.lie" "$TMP/ab.lie"
    timed "$TMP/i.cpu" bin/lie-build --into "$TMP/ab.lie" --view "$B" --threads "$THREADS" -q --stats=json \
        2>"$TMP/into.json"
    timed "$TMP/j.cpu" bin/lie-build "$scene" --view 0 --view "$B" --view-size "$SIZE" --threads "$THREADS" -q \
        -o "$TMP/both.lie"
    same=differ; cmp -s "$TMP/ab.lie" "$TMP/both.lie" && same=identical
    printf '  %-22s --into B: %s s CPU (units kept %s, refined %s, new %s) against %s s CPU for A and B at once: %s\n' \
        "$name" "$(cpu "$TMP/i.cpu")" "$(field units_kept <"$TMP/into.json")" \
        "$(field units_refined <"$TMP/into.json")" "$(field units_new <"$TMP/into.json")" "$(cpu "$TMP/j.cpu")" "$same"
done
echo "]" >>out/bench-build-views.json
printf '  (units: --view 0 --frames 0, the views choose units; pixels: --view 0 with the pixel rule, %s frames;\n' \
    "$(bin/lie-build --help | sed -n 's/.*frames the cache will serve (default \([0-9]*\).*/\1/p')"
printf '   frame cpu: one frame less an eye-rays-only frame, measured / the model (lie-build --stats=json);\n'
printf '   ns measured: build CPU / segments, full shadow CPU / rays, LIE shadow CPU less its rays / list entries)\n'

# ---- many lights (a build with 20 lights must not cost more than 20
# single-light builds): museum1 with 20 small panels under its ceiling
# (bench/museum1-20lights.yaml: its light shrunk to 0.6 x 0.3 and copied on
# a 5 x 4 grid) against the 20 builds of one such panel at each of those
# points, on 1 thread, CPU seconds and segments side by side; the
# one-light build of the centre (bench/museum1-1light.yaml) for scale.
# MANYLIGHTS=0 skips it.
if [ "${MANYLIGHTS:-1}" = 1 ]; then
    echo
    echo "bench-build many lights: museum1, 1 thread, CPU seconds (load $(cut -d' ' -f1 /proc/loadavg))"
    set -- $(build tests/scenes/museum1.gltf "$TMP/l20.lie" --threads 1 --edit bench/museum1-20lights.yaml)
    cpu20=$5 seg20=$3 bytes20=$2
    set -- $(build tests/scenes/museum1.gltf "$TMP/l1.lie" --threads 1 --edit bench/museum1-1light.yaml)
    cpu1=$5 seg1=$3
    cpus=0 segs=0
    sed -n 's/.*\(to\|translation\): \[\([^]]*\)\].*/\2/p' bench/museum1-20lights.yaml >"$TMP/points"
    while read -r at; do
        printf -- '- scale: {node: Light, by: [0.3, 1, 0.3]}\n- move: {node: Light, to: [%s]}\n' "$at" >"$TMP/one.yaml"
        set -- $(build tests/scenes/museum1.gltf "$TMP/one.lie" --threads 1 --edit "$TMP/one.yaml")
        cpus=$(awk -v a="$cpus" -v b="$5" 'BEGIN { printf "%.3f", a + b }'); segs=$((segs + $3))
    done <"$TMP/points"
    printf '  20 lights at once: %s s, %s segments, %s MB; the 20 one-light builds: %s s, %s segments: %s (segments %s)\n' \
        "$cpu20" "$seg20" "$(mb "$bytes20")" "$cpus" "$segs" "$(ratio "$cpu20" "$cpus")" "$(ratio "$seg20" "$segs")"
    printf '  (one light at the centre: %s s, %s segments; 20 lights = %s x that)\n' "$cpu1" "$seg1" "$(ratio "$cpu20" "$cpu1")"
    printf '{"cpu_20_lights_s":"%s","cpu_20_single_builds_s":"%s","segments_20_lights":"%s","segments_20_single_builds":"%s","cpu_1_light_s":"%s","segments_1_light":"%s"}\n' \
        "$cpu20" "$cpus" "$seg20" "$segs" "$cpu1" "$seg1" >out/bench-build-lights.json
fi
