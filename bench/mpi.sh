#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# make bench-mpi: lie-render and lie-build under mpirun against one process,
# measured side by side in one run on this machine: 1 process x 2 threads
# against 2 ranks x 1 thread, a 13-frame camera path (4 + 4 + 4 + 1 key frames) (each rank writes the
# frames it rendered) and a build, with the bytes each sends; and a 1024x1024
# EXR written on 1 and 2 threads.  Times are wall clock of the whole command (mpirun's
# start included) and the tool's own (load to last write, from --stats);
# REPEAT runs each, the best kept.  Writes out/bench-mpi.json.  docs/mpi.md
# turns these costs into a model for 64 nodes.
set -e
cd "$(dirname "$0")/.."
SCENE=${SCENE:-tests/scenes/museum1.gltf}
SIZE=${SIZE:-320x240}
REPEAT=${REPEAT:-3}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# --bind-to none: a shared machine's other processes sit on the cores too;
# ranks pinned to one core each cannot move away from them (threads can).
# --mca pml ob1: the point-to-point layer Open MPI picks here anyway (no
# InfiniBand or Omni-Path device), named so that MPI_Init does not first
# probe UCX and libfabric for one: 0.25 s of every launch's MPI_Init
# against 0.04 s (docs/mpi.md, "Measured"); MPI_COMPONENTS= measures the default
MPI_COMPONENTS=${MPI_COMPONENTS---mca pml ob1}
MPI="mpirun --oversubscribe --bind-to none $MPI_COMPONENTS -np 2"
mkdir -p out
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT

field() { sed -n "s/.*\"$1\":\"\{0,1\}\([^,\"}]*\).*/\1/p" | head -1; }
now() { date +%s.%N; }
best() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "" || b < a) print b; else print a }'; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (b > 0) printf "%.3f", a / b; else print "inf" }'; }

cat >"$TMP/path.yaml" <<'YAML'
interpolation: smooth
keys:
  - {eye: [3.5, 1.6, 2.9], target: [-0.6, 0.45, -0.5], fov: 50, frames: 4}
  - {eye: [0.0, 2.0, 3.5], target: [0.0, 0.5, 0.0], frames: 4}
  - {eye: [-3.0, 1.6, 2.5], target: [0.5, 0.4, -0.5], frames: 4}
  - {eye: [-3.5, 1.8, -1.0], target: [0.0, 0.5, 0.0]}
YAML

# tool seconds of a --stats=json run: load, BVH, render or build, write
tool_seconds() {
    awk -v l="$(field seconds_load <"$1")" -v v="$(field seconds_bvh <"$1")" \
        -v r="$(field seconds_render <"$1")$(field seconds_build <"$1")" -v x="$(field seconds_write <"$1")" \
        'BEGIN { print l + v + r + x }'
}
# pair LABEL "CMD1" "CMD2": the two commands alternately, REPEAT times each (so a
# change in the machine's load hits both); best wall seconds w1 w2, best tool
# seconds t1 t2, the last stats in $TMP/LABEL1.json and $TMP/LABEL2.json
pair() {
    label=$1; w1=""; w2=""; t1=""; t2=""; i=0
    while [ $i -lt "$REPEAT" ]; do
        for k in 1 2; do
            eval "cmd=\$$((k + 1))"
            a=$(now); sh -c "$cmd" 2>"$TMP/$label$k.json" >/dev/null; b=$(now)
            w=$(awk -v a="$a" -v b="$b" 'BEGIN { print b - a }'); t=$(tool_seconds "$TMP/$label$k.json")
            if [ $k -eq 1 ]; then w1=$(best "$w1" "$w"); t1=$(best "$t1" "$t"); else
                w2=$(best "$w2" "$w"); t2=$(best "$t2" "$t"); fi
        done
        i=$((i + 1))
    done
}

echo "bench-mpi: $SCENE, a 13-frame path at $SIZE; best of $REPEAT (the machine may be shared: compare ratios)"
bin/lie-build "$SCENE" -q -o "$TMP/c.lie"
mkdir -p "$TMP/a" "$TMP/b"
R="bin/lie-render $TMP/c.lie -q --size $SIZE --stats=json"
pair path "$R --threads 2 --path $TMP/path.yaml -o $TMP/a/f_%02d.exr" \
    "$MPI $R --threads 1 --path $TMP/path.yaml -o $TMP/b/f_%02d.exr"
pw1=$w1; pt1=$t1; pw2=$w2; pt2=$t2
same=yes; for f in "$TMP"/a/*.exr; do cmp -s "$f" "$TMP/b/$(basename "$f")" || same=no; done
fb=$(field bytes_gathered_per_frame <"$TMP/path2.json"); fbc=$(field bytes_broadcast <"$TMP/path2.json")
pwr1=$(field seconds_write <"$TMP/path1.json"); pwr2=$(field seconds_write <"$TMP/path2.json")

# one frame, shared out by tiles
pair frame "$R --threads 2 -o $TMP/one1.exr" "$MPI $R --threads 1 -o $TMP/one2.exr"
fw1=$w1; ft1=$t1; fw2=$w2; ft2=$t2
t_items=$(field items <"$TMP/frame2.json")

B="bin/lie-build $SCENE -q --stats=json"
pair build "$B --threads 2 -o $TMP/b1.lie" "$MPI $B --threads 1 -o $TMP/b2.lie"
bw1=$w1; bt1=$t1; bw2=$w2; bt2=$t2
cmp -s "$TMP/b1.lie" "$TMP/b2.lie" && bsame=yes || bsame=no
bb=$(field bytes_gathered <"$TMP/build2.json"); cache=$(stat -c %s "$TMP/b1.lie")
# the last 2-rank build's balance: seconds in items per rank, rank 0's service thread
rank_secs() { grep -o '"rank":[0-9]*,"items":[0-9]*,"[a-z]*":[0-9]*,"seconds":[0-9.]*' "$1" | sed 's/.*"seconds":/ /' | tr -d '\n'; }
bal=$(rank_secs "$TMP/build2.json"); bsvc=$(field seconds_cpu_service <"$TMP/build2.json")
pbal=$(rank_secs "$TMP/path2.json"); psvc=$(field seconds_cpu_service <"$TMP/path2.json")

# EXR encoding on threads: a 1024x1024 frame with zip (the default), its
# chunks compressed on 1 and on 2 threads (--threads; the bytes are the same)
X="bin/lie-render $TMP/c.lie -q --size 1024x1024 --light-samples 1 --stats=json"
xw1=""; xw2=""; i=0
while [ $i -lt "$REPEAT" ]; do
    $X --threads 1 -o "$TMP/x1.exr" 2>"$TMP/x1.json"; xw1=$(best "$xw1" "$(field seconds_write <"$TMP/x1.json")")
    $X --threads 2 -o "$TMP/x2.exr" 2>"$TMP/x2.json"; xw2=$(best "$xw2" "$(field seconds_write <"$TMP/x2.json")")
    i=$((i + 1))
done
cmp -s "$TMP/x1.exr" "$TMP/x2.exr" && xsame=yes || xsame=no

# mpirun's own start and stop: --version exits before MPI
pair start "bin/lie-render --version" "$MPI bin/lie-render --version"
sw=$w2

printf '%-34s %12s %12s %8s\n' "" "1 x 2 thr" "2 ranks x 1" "ratio"
printf '%-34s %12.3f %12.3f %8s\n' "path, 13 frames: tool seconds" "$pt1" "$pt2" "$(ratio "$pt2" "$pt1")"
printf '%-34s %12.3f %12.3f %8s\n' "path, 13 frames: wall seconds" "$pw1" "$pw2" "$(ratio "$pw2" "$pw1")"
printf '%-34s %12.3f %12.3f %8s\n' "one frame ($t_items items): tool s" "$ft1" "$ft2" "$(ratio "$ft2" "$ft1")"
printf '%-34s %12.3f %12.3f %8s\n' "build: tool seconds" "$bt1" "$bt2" "$(ratio "$bt2" "$bt1")"
printf '%-34s %12.3f %12.3f %8s\n' "build: wall seconds" "$bw1" "$bw2" "$(ratio "$bw2" "$bw1")"
printf '%-34s %12.3f %12.3f %8s\n' "EXR 1024x1024 zip write: seconds" "$xw1" "$xw2" "$(ratio "$xw2" "$xw1")"
echo "  (EXR row: 1 thread against 2 threads in one process; the same bytes: $xsame)"
echo "mpirun -np 2 start and stop: $sw s; path EXR writing: $pwr1 s (2 threads), $pwr2 s (rank 0's own, 1 thread)"
echo "bytes: per frame gathered $fb, inputs broadcast (cache, scene, its .bin) $fbc (to 1 other rank), per build gathered $bb (cache $cache)"
echo "2 ranks, last run: seconds in items per rank: path$pbal, build$bal; rank 0's service thread CPU s: path $psvc, build $bsvc"
echo "identical to one process: path $same, build $bsame"
cat >out/bench-mpi.json <<JSON
{"scene":"$SCENE","size":"$SIZE","frames":13,
 "path":{"one_process_2_threads":{"tool_seconds":$pt1,"wall_seconds":$pw1},"two_ranks_1_thread":{"tool_seconds":$pt2,"wall_seconds":$pw2},"ratio_tool":$(ratio "$pt2" "$pt1"),"identical":"$same"},
 "frame":{"one_process_2_threads":{"tool_seconds":$ft1},"two_ranks_1_thread":{"tool_seconds":$ft2},"items":$t_items},
 "build":{"one_process_2_threads":{"tool_seconds":$bt1,"wall_seconds":$bw1},"two_ranks_1_thread":{"tool_seconds":$bt2,"wall_seconds":$bw2},"ratio_tool":$(ratio "$bt2" "$bt1"),"identical":"$bsame"},
 "exr_1024_zip_write":{"threads_1":$xw1,"threads_2":$xw2,"ratio":$(ratio "$xw2" "$xw1"),"identical":"$xsame"},
 "seconds_write_path":{"one_process":$pwr1,"rank0":$pwr2},"bytes_per_frame":$fb,"bytes_broadcast":$fbc,"bytes_per_build":$bb,"cache_bytes":$cache,"mpirun_start_seconds":$sw}
JSON
echo "wrote out/bench-mpi.json"
