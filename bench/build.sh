#!/bin/sh
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
# Targets (issue 14): build <= 5 full frames on every scene with a light and
# <= 2 on museum1; cache <= 16 MB under 50k triangles; LIE frame <= half the
# full frame; the atrium built in <= 60 s.  Writes out/bench-build.json.
set -e
cd "$(dirname "$0")/.."
SIZE=${SIZE:-512x512}
THREADS=${THREADS:-$(nproc)}
SCENES=${SCENES:-"tests/scenes/museum1.gltf tests/scenes/museum3.gltf ../shared/scenes/bedroom_corner/scene.gltf ../shared/scenes/lights_punctual_lamp/LightsPunctualLamp.gltf"}
TIMEOUT=${TIMEOUT:-900}
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
    if timeout "$TIMEOUT" bin/lie-build "$scene" -q --stats=json -o "$out" "$@" 2>"$TMP/b.json"; then
        cpu=$(field seconds_cpu <"$TMP/b.json")
        crit=$(awk -v c="$cpu" -v w="$(field seconds_cpu_workers <"$TMP/b.json")" \
            -v m="$(field seconds_cpu_worker_max <"$TMP/b.json")" 'BEGIN { printf "%.3f", c - w + m }')
        echo "$(field seconds_build <"$TMP/b.json") $(field bytes <"$TMP/b.json") $(field segments <"$TMP/b.json") $(field nodes <"$TMP/b.json") $cpu $crit"
    else
        echo "timeout - - - - -"
    fi
}

echo "bench-build: $SIZE frames, 100 light samples, $THREADS threads (ratios measured side by side; load $(cut -d' ' -f1 /proc/loadavg))"
printf '  %-26s %7s %4s %8s | %9s %9s %8s | %9s %9s %8s %9s | %8s %7s | %7s %7s\n' scene tris emit "frame s" \
    "paper s" "frames" "cache MB" "cost s" "frames" "cache MB" "segments" "LIE s" "LIE/full" "1->${THREADS}t" "cpu"
echo "[" >out/bench-build.json
first=1

# bench_scene NAME SCENE PAPER ARGS...: one row.  The full frame renders the
# default cache (so edits in ARGS are in it); PAPER=0 skips the paper build.
bench_scene() {
    name=$1; scene=$2; paper=$3; shift 3
    tp=-; bp=-
    if [ "$paper" = 1 ]; then
        r=$(build "$scene" "$TMP/paper.lie" --split-gain 0 --threads "$THREADS" "$@")
        tp=$(echo "$r" | cut -d' ' -f1); bp=$(echo "$r" | cut -d' ' -f2)
    fi
    set -- $(build "$scene" "$TMP/cost.lie" --threads "$THREADS" "$@") "$@"
    tc=$1; bc=$2; segc=$3; cpun=$5; critn=$6; shift 6
    set -- $(build "$scene" "$TMP/one.lie" --threads 1 "$@") "$@"
    t1=$1; cpu1=$5
    tl=-; tf=-; tris=-; emit=-
    if [ "$tc" != timeout ]; then
        bin/lie-render "$TMP/cost.lie" --visibility=full --size "$SIZE" --threads "$THREADS" -q --stats=json \
            -o "$TMP/full.exr" 2>"$TMP/f.json"
        tf=$(field seconds_render <"$TMP/f.json")
        tris=$(field triangles <"$TMP/f.json"); emit=$(field emitters <"$TMP/f.json")
        bin/lie-render "$TMP/cost.lie" --size "$SIZE" --threads "$THREADS" -q --stats=json -o "$TMP/lie.exr" \
            2>"$TMP/l.json"
        tl=$(field seconds_render <"$TMP/l.json")
    fi
    printf '  %-26s %7s %4s %8s | %9s %9s %8s | %9s %9s %8s %9s | %8s %7s | %7s %7s\n' "$name" "$tris" "$emit" "$tf" \
        "$tp" "$(ratio "$tp" "$tf")" "$(mb "$bp")" "$tc" "$(ratio "$tc" "$tf")" "$(mb "$bc")" "$segc" "$tl" \
        "$(ratio "$tl" "$tf")" "$(ratio "$t1" "$tc")" "$(ratio "$cpu1" "$critn")"
    [ $first = 1 ] || echo "," >>out/bench-build.json
    first=0
    printf '{"scene":"%s","triangles":"%s","emitters":"%s","full_frame_s":"%s","paper_build_s":"%s","paper_cache_bytes":"%s","cost_build_s":"%s","cost_cache_bytes":"%s","cost_segments":"%s","lie_frame_s":"%s","build_1_thread_s":"%s","cpu_1_thread_s":"%s","cpu_s":"%s","critical_path_s":"%s"}' \
        "$name" "$tris" "$emit" "$tf" "$tp" "$bp" "$tc" "$bc" "$segc" "$tl" "$t1" "$cpu1" "$cpun" "$critn" >>out/bench-build.json
}

for scene in $SCENES; do
    [ -f "$scene" ] || { echo "  $scene: missing, skipped"; continue; }
    bench_scene "$(basename "$(dirname "$scene")")/$(basename "$scene")" "$scene" 1
done
# issue 14's 250k-triangle target: a generated Sponza-class atrium (bench/atrium.c),
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
printf '   the atrium skips the paper build; timeouts after %s s)\n' "$TIMEOUT"
