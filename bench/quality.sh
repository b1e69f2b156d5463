#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make bench, the equal-quality table: for each scene, per method and
# setting, the render time and the per-pixel error over lit pixels against
# a converged image (full visibility at 4096 rotated samples, rendered once
# and kept in out/truth/; delete it after a change to the shading); then the
# time each method needs to reach p99 <= 2% and the ratio.  All runs of a
# scene are measured side by side in this one run (one render each).
# Methods: full visibility (Embree streams) at LADDER samples; the LIE path
# with shadows from the samples (--exact off), with all samples at once as
# bitmasks (--bitmask only, lib/shade/bitmask.h) and as chosen per pair by
# the cost model (the default) at LADDER samples; and exact shadows
# (--light-samples exact).  Each scene also gets its eye-rays-only frame,
# and the best LIE setting's time against it.  The bundled scenes' caches are conservative
# (complete lists); the third-party scenes' are sampled with coarse patches
# (--min-patch 1e-2), built for the bench's view.  Writes
# out/bench-quality.json.
#
# BASE=DIR (a folder holding another build's lie-build and lie-render, for
# example an older commit's bin/) renders every LIE row with those too, in
# the same run, row by row: the table gains "before" columns (its own
# cache, built with BASE_BUILD if set, else the scene's options).  Full
# visibility is rendered once, by this tree.  Bitmasks answer the
# per-emitter sampler's fixed pattern: lie-bitmask runs with
# --light-sampler per-emitter (BASE's build, older, takes it as its only
# meaning).
# REPS=R renders each row R times and keeps the fastest (a loaded machine).
# Then the table of the third-party scenes against Blender Cycles
# (bench/quality-real.sh; REAL=0 leaves it out).
set -e
cd "$(dirname "$0")/.."
QSIZE=${QSIZE:-256x256}
SIZE0=$QSIZE
THREADS=${THREADS:-$(nproc)}
LADDER=${LADDER:-64 128 256 512 1024 2048 4096}
TRUTH=${TRUTH:-4096}
CMP=build/release/tests/exr-compare
[ -x "$CMP" ] || make -s build-tests >/dev/null
mkdir -p out/truth
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT

field() { sed -n "s/.*\"$1\":\"\{0,1\}\([^,\"}]*\).*/\1/p"; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (b > 0) printf "%.1f", a / b; else print "-" }'; }

# NAME|SCENE|CAMERA|SIZE|BUILD (CAMERA empty: the scene's own; SIZE empty:
# QSIZE; BUILD: lie-build options).  The third-party scenes measure the
# fallbacks: their emitters are what the closed form does not serve
# (bedroom_corner: an emissive texture; lights_punctual_lamp: textured
# emitters and five point lights).  scifi_hallway is left out: lie-build
# takes more than two minutes on its emitters of 1,570 triangles.
# The bundled scenes are built with --complex-cap 1024: their lists of up
# to 1024 blockers cost less as bitmasks than Embree's rays (museum3 at
# 1024 samples: 10,266 complex pairs at the default cap of 128, 1,181 at
# 1024, and a frame 1.5 times faster; docs/measurements.md, "Complex pairs"),
# and every unit built (--frames 0): the table renders them at up to 4096
# samples, where the default cost model's 10 frames at 100 samples would
# leave units to Embree that pay at these budgets.
SCENES=${SCENES:-"museum1|tests/scenes/museum1.gltf|||--blockers conservative --complex-cap 1024 --frames 0
museum3|tests/scenes/museum3.gltf|||--blockers conservative --complex-cap 1024 --frames 0
cornell|tests/scenes/cornell.gltf|||--blockers conservative --complex-cap 1024 --frames 0
bedroom_corner|../shared/scenes/bedroom_corner/scene.gltf|eye=30,25,35,target=-40,20,-20|64x64|--min-patch 1e-2
lights_punctual_lamp|../shared/scenes/lights_punctual_lamp/LightsPunctualLamp.gltf||64x64|--min-patch 1e-2"}

# one INPUT ARGS...: seconds_render and the error against $truth, as
# "seconds rmse p99 over2"; the stats JSON is left in $TMP/last.json
# (RENDER: the lie-render to run, bin/lie-render unless set)
# (REPS renders, default 1, the fastest kept: images are the same each time)
one() {
    input=$1; shift
    best=""
    k=0
    while [ $k -lt "${REPS:-1}" ]; do
        ${RENDER:-bin/lie-render} "$input" --size "$QSIZE" --threads "$THREADS" -q --stats=json -o "$TMP/f.exr" "$@" \
            2>"$TMP/last.json"
        t=$(field seconds_render <"$TMP/last.json")
        if [ -z "$best" ] || awk -v a="$best" -v b="$t" 'BEGIN { exit !(b < a) }'; then best=$t; fi
        k=$((k + 1))
    done
    "$CMP" --error "$truth" "$TMP/f.exr" >"$TMP/e.json"
    echo "$best $(field rmse <"$TMP/e.json") $(field p99 <"$TMP/e.json") $(field over2 <"$TMP/e.json")"
}

echo "bench-quality: $QSIZE, $THREADS threads, error against full visibility at $TRUTH rotated samples"
echo "  (one render per setting; a loaded machine makes times noisy, the ratios are taken within one run)"
json="{\"size\":\"$QSIZE\",\"threads\":$THREADS,\"truth_samples\":$TRUTH,\"scenes\":{"
first=1
echo "$SCENES" | while IFS='|' read -r name scene cam size build; do
    [ -n "$name" ] || continue
    QSIZE=${size:-$SIZE0}
    if [ ! -f "$scene" ]; then echo "  $name: $scene missing, skipped"; continue; fi
    set --
    [ -n "$cam" ] && set -- --camera "$cam"
    truth="out/truth/$name-$QSIZE.exr"
    if [ ! -f "$truth" ] || [ "$scene" -nt "$truth" ]; then
        bin/lie-render "$scene" --size "$QSIZE" --threads "$THREADS" -q --visibility=full --pattern rotated \
            --light-samples "$TRUTH" -o "$truth" "$@"
    fi
    view=""
    [ -n "$cam" ] && view="--view $cam --view-size $QSIZE"
    # shellcheck disable=SC2086
    bin/lie-build "$scene" -q --threads "$THREADS" $build $view -o "$TMP/c.lie"
    if [ -n "$BASE" ]; then
        # shellcheck disable=SC2086
        "$BASE/lie-build" "$scene" -q --threads "$THREADS" ${BASE_BUILD:-$build} $view -o "$TMP/b.lie"
        printf '\n  %s (%s)\n  %-26s %6s %9s %8s %8s %8s | %9s %8s %8s %8s (before)\n' "$name" "$QSIZE" "method" "N" \
            "seconds" "rmse" "p99" ">2%" "seconds" "rmse" "p99" ">2%"
    else
        printf '\n  %s (%s)\n  %-26s %6s %9s %8s %8s %8s\n' "$name" "$QSIZE" "method" "N" "seconds" "rmse" "p99" ">2%"
    fi
    rows=""
    best_full=""; best_lie=""; best_lie_what=""; full1024=""; auto1024=""; best_base=""; best_base_what=""; base1024=""
    t_eye=$(one "$scene" --light-samples 0 "$@"); t_eye=${t_eye%% *}
    for method in ${METHODS:-full lie-sampled lie-bitmask lie-auto lie-exact}; do
        list=$LADDER
        [ "$method" = lie-exact ] && list=exact
        for n in $list; do
            case $method in
            full) r=$(one "$scene" --visibility=full --light-samples "$n" "$@") ;;
            lie-sampled) r=$(one "$TMP/c.lie" --exact off --light-samples "$n" "$@") ;;
            lie-bitmask) r=$(one "$TMP/c.lie" --light-sampler per-emitter --bitmask only --light-samples "$n" "$@") ;;
            lie-auto) r=$(one "$TMP/c.lie" --light-samples "$n" "$@") ;;
            lie-exact) r=$(one "$TMP/c.lie" --light-samples exact "$@") ;;
            esac
            t=${r%% *}; rest=${r#* }; rmse=${rest%% *}; rest=${rest#* }; p99=${rest%% *}; over=${rest#* }
            base=""
            if [ -n "$BASE" ] && [ "$method" != full ]; then
                cp "$TMP/last.json" "$TMP/keep.json"
                case $method in
                lie-sampled) b=$(RENDER=$BASE/lie-render one "$TMP/b.lie" --exact off --light-samples "$n" "$@") ;;
                lie-bitmask) b=$(RENDER=$BASE/lie-render one "$TMP/b.lie" --bitmask only --light-samples "$n" "$@") ;;
                lie-auto) b=$(RENDER=$BASE/lie-render one "$TMP/b.lie" --light-samples "$n" "$@") ;;
                lie-exact) b=$(RENDER=$BASE/lie-render one "$TMP/b.lie" --light-samples exact "$@") ;;
                esac
                cp "$TMP/keep.json" "$TMP/last.json"
                bt=${b%% *}; rest=${b#* }; brmse=${rest%% *}; rest=${rest#* }; bp99=${rest%% *}; bover=${rest#* }
                base=$(printf ' | %9.3f %7.2f%% %7.2f%% %7.2f%%' "$bt" "$(awk -v x="$brmse" 'BEGIN{print 100 * x}')" \
                    "$(awk -v x="$bp99" 'BEGIN{print 100 * x}')" "$(awk -v x="$bover" 'BEGIN{print 100 * x}')")
                if awk -v p="$bp99" 'BEGIN { exit !(p <= 0.02) }'; then
                    if [ -z "$best_base" ] || awk -v a="$best_base" -v b="$bt" 'BEGIN { exit !(b < a) }'; then
                        best_base=$bt; best_base_what="$method $n"
                    fi
                fi
                [ "$method" = lie-auto ] && [ "$n" = 1024 ] && base1024="$bt $bp99"
            fi
            printf '  %-26s %6s %9.3f %7.2f%% %7.2f%% %7.2f%%%s\n' "$method" "$n" "$t" \
                "$(awk -v x="$rmse" 'BEGIN{print 100 * x}')" "$(awk -v x="$p99" 'BEGIN{print 100 * x}')" \
                "$(awk -v x="$over" 'BEGIN{print 100 * x}')" "$base"
            rows="$rows${rows:+,}{\"method\":\"$method\",\"samples\":\"$n\",\"seconds\":$t,\"rmse\":$rmse,\"p99\":$p99,\"over2\":$over,\"pairs_exact\":$(field pairs_exact <"$TMP/last.json"),\"pairs_blockers\":$(field pairs_blockers <"$TMP/last.json"),\"pairs_embree\":$(field pairs_embree <"$TMP/last.json"),\"pairs_bitmask\":$(field pairs_bitmask <"$TMP/last.json")}"
            if awk -v p="$p99" 'BEGIN { exit !(p <= 0.02) }'; then
                if [ "$method" = full ]; then
                    if [ -z "$best_full" ] || awk -v a="$best_full" -v b="$t" 'BEGIN { exit !(b < a) }'; then
                        best_full=$t
                    fi
                else
                    if [ -z "$best_lie" ] || awk -v a="$best_lie" -v b="$t" 'BEGIN { exit !(b < a) }'; then
                        best_lie=$t; best_lie_what="$method $n"
                    fi
                fi
            fi
            [ "$method" = full ] && [ "$n" = 1024 ] && full1024="$t $p99"
            [ "$method" = lie-auto ] && [ "$n" = 1024 ] && auto1024="$t $p99"
        done
    done
    if [ -n "$best_full" ] && [ -n "$best_lie" ]; then
        printf '  time to p99 <= 2%%: full %.3f s, LIE %.3f s (%s): %sx; eye rays alone %.3f s, LIE/eye %s\n' \
            "$best_full" "$best_lie" "$best_lie_what" "$(ratio "$best_full" "$best_lie")" "$t_eye" \
            "$(ratio "$best_lie" "$t_eye")"
    else
        printf '  time to p99 <= 2%%: full %s, LIE %s\n' "${best_full:-not reached}" "${best_lie:-not reached}"
    fi
    if [ -n "$full1024" ] && [ -n "$auto1024" ]; then
        printf '  at 1024 samples: LIE (auto) %sx faster than full, p99 %s against %s\n' \
            "$(ratio "${full1024%% *}" "${auto1024%% *}")" "${auto1024#* }" "${full1024#* }"
    fi
    if [ -n "$BASE" ]; then
        if [ -n "$best_full" ] && [ -n "$best_base" ]; then
            printf '  before: time to p99 <= 2%%: LIE %.3f s (%s): %sx; LIE/eye %s\n' "$best_base" "$best_base_what" \
                "$(ratio "$best_full" "$best_base")" "$(ratio "$best_base" "$t_eye")"
        fi
        if [ -n "$full1024" ] && [ -n "$base1024" ]; then
            printf '  before: at 1024 samples: LIE (auto) %sx faster than full, p99 %s\n' \
                "$(ratio "${full1024%% *}" "${base1024%% *}")" "${base1024#* }"
        fi
    fi
    # where the best LIE setting's frame goes, from per-worker timers
    bin/lie-render "$TMP/c.lie" --size "$QSIZE" --threads "$THREADS" -q --stats=json --timers -o "$TMP/f.exr" \
        --light-samples exact "$@" 2>"$TMP/t.json"
    printf '  exact frame, worker seconds: closed form %s, exact shadows %s, blocker samples %s, Embree %s, sampled shading %s\n' \
        "$(field cpu_seconds_analytic <"$TMP/t.json")" "$(field cpu_seconds_exact <"$TMP/t.json")" \
        "$(field cpu_seconds_blockers <"$TMP/t.json")" "$(field cpu_seconds_embree <"$TMP/t.json")" \
        "$(field cpu_seconds_sampled_shading <"$TMP/t.json")"
    bin/lie-render "$TMP/c.lie" --size "$QSIZE" --threads "$THREADS" -q --stats=json --timers -o "$TMP/f.exr" \
        --light-samples 1024 "$@" 2>"$TMP/a.json"
    printf '  auto frame at 1024 samples, worker seconds: closed form %s, exact shadows %s, bitmasks %s, blocker samples %s, Embree %s, sampled shading %s\n' \
        "$(field cpu_seconds_analytic <"$TMP/a.json")" "$(field cpu_seconds_exact <"$TMP/a.json")" \
        "$(field cpu_seconds_bitmask <"$TMP/a.json")" "$(field cpu_seconds_blockers <"$TMP/a.json")" \
        "$(field cpu_seconds_embree <"$TMP/a.json")" "$(field cpu_seconds_sampled_shading <"$TMP/a.json")"
    printf '  its pairs: %s exact, %s bitmask, %s blocker samples, %s Embree\n' "$(field pairs_exact <"$TMP/a.json")" \
        "$(field pairs_bitmask <"$TMP/a.json")" "$(field pairs_blockers <"$TMP/a.json")" "$(field pairs_embree <"$TMP/a.json")"
    printf '  pairs: %s occluded, %s closed form, %s exact, %s blocker samples, %s Embree, %s seen whole and sampled\n' \
        "$(field pairs_occluded <"$TMP/t.json")" "$(field pairs_analytic <"$TMP/t.json")" \
        "$(field pairs_exact <"$TMP/t.json")" "$(field pairs_blockers <"$TMP/t.json")" \
        "$(field pairs_embree <"$TMP/t.json")" "$(field pairs_unshadowed <"$TMP/t.json")"
    [ $first -eq 1 ] || printf ',' >>"$TMP/scenes.json"
    first=0
    printf '"%s":{"size":"'"$QSIZE"'","eye_only":%s,"rows":[%s],"p99_2pct":{"full":%s,"lie":%s}}' "$name" "$t_eye" "$rows" \
        "${best_full:-null}" "${best_lie:-null}" >>"$TMP/scenes.json"
    cp "$TMP/scenes.json" "$TMP/scenes.keep"
done
echo "$json$(cat "$TMP/scenes.keep" 2>/dev/null)}}" >out/bench-quality.json
echo
echo "bench-quality: wrote out/bench-quality.json"
[ "${REAL:-1}" = 0 ] || sh bench/quality-real.sh
