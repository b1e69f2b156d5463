#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make bench, the equal-quality table on third-party scenes (run at the end
# of bench/quality.sh; REAL=0 there leaves it out, or run it alone).
#
# scifi_hallway, ccity_buildings, bedroom_corner and lights_punctual_lamp
# from ../shared/scenes, at QSIZE (256x256), each from a camera inside its
# lit part (chosen by looking at renders; the bounding-box default sees the
# outside of an interior, or a street at night from afar).  Both renderers
# get the same Lambertian copy of the scene (bench/lambert.c writes it to
# out/bench-scenes/NAME.glb; bench/cycles.py gives Cycles a Diffuse BSDF).
#
# Per method and budget: seconds of rendering, and the per-pixel error over
# lit pixels (exr-compare --error: RMSE, p99, share above 2%) against a
# converged image: full visibility at TRUTH light samples (rotated patterns),
# rendered once and kept in out/truth/ (delete it, or out/bench-scenes/, after
# a change to the shading or to bench/lambert.c).  Then per method the time to p99 <= 2%: the first budget that
# gets there, else "~T" extrapolated from its last two budgets (p99 taken
# as a power of the time; ">1000x" past a thousand times the last), else "-".  A method's ladder stops at the first
# budget within 2%, or once a render takes longer than STOP seconds.
#
# Methods (those the renderer at hand has; `lie-render --help` is asked):
#   full         full visibility (Embree), the default light sampler
#   lie-auto     the LIE cache, default modes
#   lie-sampled  the LIE cache, shadows from the samples (--exact off)
#   lie-exact    the LIE cache, --light-samples exact (one budget)
#   full-per-emitter, lie-per-emitter
#                the meaning of --light-samples before 0.2: N samples of
#                every emitter (--light-sampler per-emitter), when the
#                renderer has it
#   cycles       Blender Cycles 3.4 (Debian's blender), direct light only,
#                same camera, THREADS threads: its error is estimated from
#                two renders with seeds 1 and 2 (|a - b| / sqrt 2, exr-compare
#                --error2): its own converged image costs too much
# With --seed (renderers that have it), every method of ours is also
# rendered with a second seed and its two-seed estimate reported beside the
# converged image's, as the peer's is.
#
# The LIE cache is built for the view (lie-build --view) with the scene's
# build options, within BUILD_TIMEOUT seconds (else the LIE rows say so).
# Writes out/bench-quality-real.json, out/bench-quality-real.dat (one line
# per render: scene method budget seconds p99 over2 rmse) and the figure
# out/bench-quality.svg (p99 against seconds, log-log, one curve per method
# and scene; gnuplot).  BIN=DIR measures DIR's lie-render and lie-build.
set -e
cd "$(dirname "$0")/.."
QSIZE=${QSIZE:-256x256}
BIN=${BIN:-bin} # the lie-render and lie-build to measure
THREADS=${THREADS:-2}
LADDER=${REAL_LADDER:-16 64 256 1024}
CYCLES_LADDER=${CYCLES_LADDER:-16 64 256 1024 4096}
TRUTH=${REAL_TRUTH:-4096}
STOP=${STOP:-300}
BUILD_TIMEOUT=${BUILD_TIMEOUT:-900}
FOV=45
CMP=build/release/tests/exr-compare
LAMBERT=build/release/bench-lambert
make -s "$LAMBERT" "$CMP" >/dev/null
mkdir -p out/truth out/bench-scenes
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT

field() { sed -n "s/.*\"$1\":\"\{0,1\}\([^,\"}]*\).*/\1/p"; }
pct() { awk -v x="$1" 'BEGIN { printf "%.2f%%", 100 * x }'; }

has() { "$BIN"/lie-render --help | grep -q -- "$1"; }
SEED=0; has '--seed' && SEED=1
SAMPLER=0; has '--light-sampler' && SAMPLER=1
CYCLES=0; command -v blender >/dev/null 2>&1 && CYCLES=1
DEFAULT_METHODS="full lie-auto lie-sampled lie-exact"
[ $SAMPLER -eq 1 ] && DEFAULT_METHODS="$DEFAULT_METHODS full-per-emitter lie-per-emitter"
[ $CYCLES -eq 1 ] && DEFAULT_METHODS="$DEFAULT_METHODS cycles"
METHODS=${REAL_METHODS:-$DEFAULT_METHODS}

# NAME|SCENE|EYE|TARGET|BUILD (lie-build options)
SCENES=${REAL_SCENES:-"scifi_hallway|../shared/scenes/scifi_hallway/space_ship_hallway.glb|20.1,0.5,2|20.1,0.3,-20|--min-patch 1e-2
ccity_buildings|../shared/scenes/ccity_buildings/scene.gltf|400,200,-5800|850,380,-6400|--min-patch 1e-2
bedroom_corner|../shared/scenes/bedroom_corner/scene.gltf|-12,36,42|-45,20,8|--min-patch 1e-2
lights_punctual_lamp|../shared/scenes/lights_punctual_lamp/LightsPunctualLamp.gltf|1.3,1.3,1.5|0.25,0.9,0|--min-patch 1e-2"}

# render INPUT OUT.exr ARGS...: seconds_render (stats on stderr in $TMP/last.json)
render() {
    input=$1; out=$2; shift 2
    "$BIN"/lie-render "$input" --size "$QSIZE" --threads "$THREADS" -q --stats=json -o "$out" "$@" 2>"$TMP/last.json"
    field seconds_render <"$TMP/last.json"
}

# time to p99 <= 2% from a method's rows "seconds p99" (one a line)
time_to() {
    awk 'BEGIN { best = "" }
         { t[NR] = $1; p[NR] = $2; if ($2 <= 0.02 && best == "") best = sprintf("%.3f", $1) }
         END {
             if (best != "") { print best; exit }
             n = NR
             if (n >= 2 && p[n] > 0 && p[n-1] > p[n] && t[n] > t[n-1]) {
                 a = -log(p[n] / p[n-1]) / log(t[n] / t[n-1])
                 x = log(p[n] / 0.02) / a
                 if (x < log(1000)) printf "~%.0f\n", t[n] * exp(x); else print ">1000x"
             } else print "-"
         }'
}

# the scenes and their Lambertian copies through the Khronos validator
# (make deps installs it: scripts/npm)
validate() {
    if command -v node >/dev/null 2>&1 && NODE_PATH=scripts/npm/node_modules node -e "require('gltf-validator')" 2>/dev/null; then
        NODE_PATH=scripts/npm/node_modules node bench/validate.js "$@" | sed 's/^/  gltf-validator: /'
    else
        echo "  gltf-validator: not installed (make deps installs it), skipped"
    fi
}

uptime_now=$(uptime | sed 's/.*load average: //')
echo
echo "bench-quality (real scenes): $QSIZE, $THREADS threads, load $uptime_now; error against full visibility at $TRUTH rotated samples"
[ $SEED -eq 1 ] && echo "  (with a second seed: the two-seed estimate |a - b| / sqrt 2 beside it)"
: >"$TMP/rows.dat"
json="{\"size\":\"$QSIZE\",\"threads\":$THREADS,\"truth_samples\":$TRUTH,\"load\":\"$uptime_now\",\"scenes\":{"
first=1
echo "$SCENES" | while IFS='|' read -r name scene eye target build; do
    [ -n "$name" ] || continue
    if [ ! -f "$scene" ]; then echo "  $name: $scene missing, skipped"; continue; fi
    lam=out/bench-scenes/$name.glb
    # the copy is made again when the scene or bench-lambert (the exporter it
    # links) is newer, and then the converged image below too: a copy made
    # by an older exporter (one that dropped normal maps) is another scene
    if [ ! -f "$lam" ] || [ "$scene" -nt "$lam" ] || [ "$LAMBERT" -nt "$lam" ]; then
        "$LAMBERT" "$scene" "$lam"
    fi
    validate "$scene" "$lam"
    cam="eye=$eye,target=$target,fov=$FOV"
    truth=out/truth/$name-lambert-$QSIZE.exr
    if [ ! -f "$truth" ] || [ "$lam" -nt "$truth" ]; then
        set -- --visibility=full --light-samples "$TRUTH" --camera "$cam"
        [ $SAMPLER -eq 1 ] || set -- "$@" --pattern rotated
        [ $SEED -eq 1 ] && set -- "$@" --seed 99
        t=$(render "$lam" "$TMP/truth.exr" "$@")
        mv "$TMP/truth.exr" "$truth"
        echo "  $name: converged image rendered in $t s"
    fi
    built=0
    if echo "$METHODS" | grep -q lie; then
        # shellcheck disable=SC2086
        if timeout "$BUILD_TIMEOUT" "$BIN"/lie-build "$lam" -q --threads "$THREADS" $build --view "$cam" \
            --view-size "$QSIZE" -o "$TMP/c.lie" 2>"$TMP/build.err"; then
            built=1
        fi
    fi
    printf '\n  %s (%s, camera %s)\n  %-18s %6s %9s %8s %8s %8s' "$name" "$QSIZE" "$cam" method N seconds rmse p99 ">2%"
    [ $SEED -eq 1 ] && printf ' | %8s %8s (two seeds)' p99 ">2%"
    printf '\n'
    rows=""
    for method in $METHODS; do
        case $method in
        lie-*) if [ $built -eq 0 ]; then
                   printf '  %-18s   cache not built in %s s (%s)\n' "$method" "$BUILD_TIMEOUT" \
                       "$(head -c 120 "$TMP/build.err" | tr '\n' ' ')"
                   continue
               fi ;;
        esac
        list=$LADDER
        [ "$method" = lie-exact ] && list=exact
        [ "$method" = cycles ] && list=$CYCLES_LADDER
        : >"$TMP/m.rows"
        for n in $list; do
            e2=""
            if [ "$method" = cycles ]; then
                blender -b --factory-startup -noaudio -P bench/cycles.py -- "$lam" "$eye" "$target" "$FOV" "$QSIZE" \
                    "$THREADS" "$TMP" "$n:1" "$n:2" 2>/dev/null | grep '"samples"' >"$TMP/cy.json"
                t=$(head -1 "$TMP/cy.json" | field seconds)
                "$CMP" --error2 "$TMP/cycles-$n-1.exr" "$TMP/cycles-$n-2.exr" >"$TMP/e.json"
                rmse=$(field rmse <"$TMP/e.json"); p99=$(field p99 <"$TMP/e.json"); over=$(field over2 <"$TMP/e.json")
            else
                set -- --camera "$cam"
                case $method in
                full) input=$lam; set -- "$@" --visibility=full --light-samples "$n" ;;
                full-per-emitter) input=$lam; set -- "$@" --visibility=full --light-sampler per-emitter --light-samples "$n" ;;
                lie-auto) input=$TMP/c.lie; set -- "$@" --light-samples "$n" ;;
                lie-sampled) input=$TMP/c.lie; set -- "$@" --exact off --light-samples "$n" ;;
                lie-exact) input=$TMP/c.lie; set -- "$@" --light-samples exact ;;
                lie-per-emitter) input=$TMP/c.lie; set -- "$@" --light-sampler per-emitter --light-samples "$n" ;;
                *) echo "  unknown method $method" >&2; exit 2 ;;
                esac
                t=$(render "$input" "$TMP/a.exr" "$@")
                "$CMP" --error "$truth" "$TMP/a.exr" >"$TMP/e.json"
                rmse=$(field rmse <"$TMP/e.json"); p99=$(field p99 <"$TMP/e.json"); over=$(field over2 <"$TMP/e.json")
                if [ $SEED -eq 1 ]; then
                    render "$input" "$TMP/b.exr" "$@" --seed 1 >/dev/null
                    "$CMP" --error2 "$TMP/a.exr" "$TMP/b.exr" >"$TMP/e2.json"
                    e2=$(printf ' | %8s %8s' "$(pct "$(field p99 <"$TMP/e2.json")")" "$(pct "$(field over2 <"$TMP/e2.json")")")
                fi
            fi
            printf '  %-18s %6s %9.3f %8s %8s %8s%s\n' "$method" "$n" "$t" "$(pct "$rmse")" "$(pct "$p99")" "$(pct "$over")" "$e2"
            echo "$t $p99" >>"$TMP/m.rows"
            echo "$name $method $n $t $p99 $over $rmse" >>"$TMP/rows.dat"
            rows="$rows${rows:+,}{\"method\":\"$method\",\"samples\":\"$n\",\"seconds\":$t,\"rmse\":$rmse,\"p99\":$p99,\"over2\":$over}"
            awk -v p="$p99" -v t="$t" -v s="$STOP" 'BEGIN { exit !(p <= 0.02 || t > s) }' && break
        done
        tt=$(time_to <"$TMP/m.rows")
        printf '  %-18s time to p99 <= 2%%: %s s\n' "$method" "$tt"
        echo "$name $method $tt" >>"$TMP/times"
    done
    [ $first -eq 1 ] || printf ',' >>"$TMP/scenes.json"
    first=0
    printf '"%s":{"camera":"%s","rows":[%s]}' "$name" "$cam" "$rows" >>"$TMP/scenes.json"
    cp "$TMP/scenes.json" "$TMP/scenes.keep"
    cp "$TMP/rows.dat" out/bench-quality-real.dat
done
echo "$json$(cat "$TMP/scenes.keep" 2>/dev/null)}}" >out/bench-quality-real.json

# time to p99 <= 2%, one line per scene, one column per method
if [ -f "$TMP/times" ]; then
    echo
    echo "  time to p99 <= 2% (seconds; ~ extrapolated, - not reached)"
    awk '{ if (!($2 in seen)) { seen[$2] = 1; order[++m] = $2 } if (!($1 in sn)) { sn[$1] = 1; sorder[++k] = $1 } v[$1 SUBSEP $2] = $3 }
         END { printf "  %-22s", "scene"; for (j = 1; j <= m; j++) printf " %16s", order[j]; printf "\n"
               for (i = 1; i <= k; i++) { printf "  %-22s", sorder[i]
                   for (j = 1; j <= m; j++) { x = v[sorder[i] SUBSEP order[j]]; printf " %16s", x == "" ? "n/a" : x }
                   printf "\n" } }' "$TMP/times"
fi

# the figure: p99 against seconds, log-log, a panel per scene, a curve per method
if command -v gnuplot >/dev/null 2>&1 && [ -s out/bench-quality-real.dat ]; then
    scenes=$(awk '{ print $1 }' out/bench-quality-real.dat | awk '!s[$0]++' | tr '\n' ' ')
    n=$(echo "$scenes" | wc -w)
    {
        echo "set terminal svg size 1000,$((360 * ((n + 1) / 2))) dynamic font 'sans,11'"
        echo "set output 'out/bench-quality.svg'"
        echo "set multiplot layout $(((n + 1) / 2)),2 title 'p99 per-pixel error against render seconds ($QSIZE, $THREADS threads; dashed: 2%)'"
        echo "set logscale xy; set grid; set key top right font ',9'"
        echo "set xlabel 'seconds'; set ylabel 'p99 error'; set format y '%g'"
        for s in $scenes; do
            methods=$(awk -v s="$s" '$1 == s { print $2 }' out/bench-quality-real.dat | awk '!m[$0]++' | tr '\n' ' ')
            printf "set title '%s'\nplot 0.02 with lines dt 2 lc rgb 'grey' notitle" "$s"
            for m in $methods; do
                printf ", 'out/bench-quality-real.dat' using (strcol(1) eq '%s' && strcol(2) eq '%s' ? \$4 : 1/0):5 with linespoints title '%s'" \
                    "$s" "$m" "$m"
            done
            printf '\n'
        done
        echo "unset multiplot"
    } >"$TMP/plot.gp"
    gnuplot "$TMP/plot.gp" && echo "bench-quality: wrote out/bench-quality.svg"
fi
echo "bench-quality: wrote out/bench-quality-real.json, out/bench-quality-real.dat"
