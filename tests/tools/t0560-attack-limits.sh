#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# A second outside attack, the input classes:
#   coordinates past the range (core.h, LIE_COORD_MAX) from a file, an edit,
#     a camera, a camera path or an animation frame: one line, exit 1, never
#     Embree's abort (exit 134);
#   huge animation times: the error a 1e13 s key gets, no undefined cast;
#   camera paths: numbers out of range refused before any conversion, and
#     every interpolated frame checked as --camera checks one camera;
#   names from files reach the terminal escaped (lie-inspect summary);
#   images of every format stb reads refused past the pixel limit from their
#     header, and decoded only when a material uses them.
. "$ROOT/tests/tools/lib.sh"
T=$TMP
cd "$T" || exit 1
G="$D/gltf"
BUILD="--samples 4 --max-samples 4 --min-patch 0.3 -q"

# one line, exit 1, no OUT file: WHAT NEEDLE OUT CMD...
refused() {
    what=$1; needle=$2; out=$3; shift 3
    rm -f "$out"
    run "$@"
    if [ "$rc" -eq 1 ] && [ "$(wc -l <"$TMP/err")" -eq 1 ] && grep -qF -- "$needle" "$TMP/err" && [ ! -e "$out" ]; then
        ok "$what: $(cat "$TMP/err")"
    else
        not_ok "$what: exit $rc, expected one line with '$needle'"; sed 's/^/# /' "$TMP/err" | head -3
    fi
}

"$B/lie-build" "$S/cornell.gltf" $BUILD -o c.lie || not_ok "build cornell"
RANGE="outside the coordinate range"

# ---- coordinates: edits, scenes, cameras, paths, animation frames ----------------
for by in "2e18, 0, 0" "0, -1e30, 0" "0, 0, 3.4e38"; do
    printf -- '- move: {node: TallBlock, by: [%s]}\n' "$by" >far.yaml
    refused "rst-update: move by [$by]" "far.yaml: the edited scene: node 'TallBlock': a vertex at" o.lie \
        "$B/rst-update" c.lie far.yaml -q -o o.lie
done
printf -- '- set-transform: {node: Light, matrix: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,3e18,0,1]}\n' >far.yaml
refused "rst-update: the light's set-transform to 3e18" "$RANGE" o.lie "$B/rst-update" c.lie far.yaml -q -o o.lie
refused "lie-build --edit: the light's set-transform to 3e18" "$RANGE" o.lie "$B/lie-build" "$S/cornell.gltf" --edit far.yaml $BUILD -o o.lie

python3 - "$S/cornell.gltf" <<'EOF' || not_ok "python3 writes the far scenes"
import json, sys
d = json.load(open(sys.argv[1]))
def write(name, change):
    e = json.loads(json.dumps(d))
    change(e)
    e['buffers'][0]['uri'] = sys.argv[1].rsplit('/', 1)[0] + '/' + e['buffers'][0]['uri']
    open(name, 'w').write(json.dumps(e))
def node(name):
    return lambda e: [n for n in e['nodes'] if n.get('name') == name][0]
write('far-node.gltf', lambda e: node('TallBlock')(e).update(translation=[3e18, 0, 0]))
write('far-scale.gltf', lambda e: node('TallBlock')(e).update(scale=[1e13, 1, 1]))
write('far-camera.gltf', lambda e: node('Camera')(e).update(translation=[0, 0, 1e15]))
EOF
for f in far-node far-scale far-camera; do
    refused "lie-build $f.gltf" "$RANGE" o.lie "$B/lie-build" $f.gltf --allow-external-uris $BUILD -o o.lie
    refused "lie-render $f.gltf" "$RANGE" o.png "$B/lie-render" $f.gltf --allow-external-uris -q --size 8x8 -o o.png
done

for eye in "2e18,1,0" "0,1e15,0" "0,1,-3.4e38"; do
    refused "lie-render --camera eye=$eye" "--camera: eye and target must lie within" o.png \
        "$B/lie-render" c.lie --camera "eye=$eye,target=0,1,0" -q --size 8x8 -o o.png
done
refused "lie-render --camera target=1e16" "--camera: eye and target must lie within" o.png \
    "$B/lie-render" c.lie --camera "eye=0,1,3,target=0,1e16,0" -q --size 8x8 -o o.png
printf 'keys:\n  - {eye: [0, 1, 3], target: [0, 1, 0], frames: 2}\n  - {eye: [2e18, 1, 3], target: [0, 1, 0]}\n' >far-path.yaml
refused "lie-render --path with an eye at 2e18" "far-path.yaml:3:5: keys[1]: eye and target must lie within" o_0000.png \
    "$B/lie-render" c.lie --path far-path.yaml -q --size 8x8 -o o_%04d.png
# a spline through keys within the range that overshoots it between them
printf 'keys:\n  - {eye: [0, 1, 3], target: [0, 1, 0], frames: 8}\n  - {eye: [9e13, 1, 3], target: [0, 1, 0], frames: 8}\n  - {eye: [9.9e13, 1, 3], target: [0, 1, 0]}\n' >over.yaml
refused "a spline overshooting the range between its keys" "over.yaml: frame" o_0000.png \
    "$B/lie-render" c.lie --path over.yaml -q --size 8x8 -o o_%04d.png
grep -q "outside the coordinate range" "$TMP/err" && ok "and says the range" || not_ok "overshoot: $(cat "$TMP/err")"

# animation frames: lie-animate writes them, the edit's load refuses them
python3 - "$G/animated.gltf" <<'EOF' || not_ok "python3 writes the animation cases"
import base64, json, struct, sys
d = json.load(open(sys.argv[1]))
def write(name, change):
    e = json.loads(json.dumps(d))
    change(e)
    open(name, 'w').write(json.dumps(e))
def blob(e):
    uri = e['buffers'][0]['uri']
    head, data = uri.split(',', 1)
    return head, bytearray(base64.b64decode(data))
def add_floats(e, values, acc_type='SCALAR'):
    """a new accessor of floats at the end of the buffer; its index"""
    head, b = blob(e)
    while len(b) % 4:
        b.append(0)
    off = len(b)
    b += struct.pack('<%df' % len(values), *values)
    e['buffers'][0]['uri'] = head + ',' + base64.b64encode(bytes(b)).decode()
    e['buffers'][0]['byteLength'] = len(b)
    e['bufferViews'].append({'buffer': 0, 'byteOffset': off, 'byteLength': 4 * len(values)})
    n = len(values) if acc_type == 'SCALAR' else len(values) // 3
    acc = {'bufferView': len(e['bufferViews']) - 1, 'componentType': 5126, 'count': n, 'type': acc_type}
    if acc_type == 'SCALAR':
        acc['min'] = [min(values)]; acc['max'] = [max(values)]
    e['accessors'].append(acc)
    return len(e['accessors']) - 1
def slider(e):
    a = e['animations'][0]
    return [ch for ch in a['channels'] if ch['target']['node'] == 2][0]['sampler']
def last_key(t):
    def f(e):
        a = e['animations'][0]
        s = a['samplers'][slider(e)]
        n = e['accessors'][s['input']]['count']
        s['input'] = add_floats(e, [0.25 * i for i in range(n - 1)] + [t])
    return f
write('key-1e13.gltf', last_key(1e13))
write('key-3e38.gltf', last_key(3e38))
def unused(e):
    a = e['animations'][0]
    a['samplers'].append({'input': add_floats(e, [0.0, 1e30]), 'output': a['samplers'][0]['output']})
write('unused-1e30.gltf', unused)
def no_channels(e):
    e['animations'].insert(0, {'name': 'Empty', 'channels': [],
                               'samplers': [{'input': add_floats(e, [0.0, 1e30]), 'output': 0}]})
write('empty-1e30.gltf', no_channels)
def far(e):
    s = e['animations'][0]['samplers'][slider(e)]
    n = e['accessors'][s['input']]['count']
    s['output'] = add_floats(e, [3e38, 0.0, 0.0] * n, 'VEC3')
write('far-frame.gltf', far)
EOF
refused "lie-animate: a last key at 1e13 s" "frames (" "f_0000.yaml" "$B/lie-animate" key-1e13.gltf --fps 24 -q -o f_%04d.yaml
want=$(sed 's/.*: \([^:]*\)$/\1/' "$TMP/err" | sed 's/[0-9.e+]* frames ([0-9.e+]* s/N frames (T s/')
for f in key-3e38 unused-1e30 empty-1e30; do
    refused "lie-animate: $f" "more than 1000000" "f_0000.yaml" "$B/lie-animate" $f.gltf --fps 24 -q -o f_%04d.yaml
    got=$(sed 's/.*: \([^:]*\)$/\1/' "$TMP/err" | sed 's/[0-9.e+]* frames ([0-9.e+]* s/N frames (T s/')
    [ "$got" = "$want" ] && ok "$f: the same error as a 1e13 s key" || not_ok "$f: '$got', not '$want'"
done
run "$B/lie-animate" far-frame.gltf --fps 4 --frames 0-1 -q -o f_%04d.yaml
expect_rc 0 "lie-animate writes the frames of a translation to 3e38"
refused "lie-build --edit of that frame" "f_0001.yaml: the edited scene: node 'Slider'" o.lie \
    "$B/lie-build" far-frame.gltf --edit f_0001.yaml $BUILD -o o.lie

# ---- camera paths: numbers out of range, degenerate frames ----------------------
for bad in "first-frame: 641e38" "first-frame: -1e300" "first-frame: 1.5"; do
    printf '%s\nkeys:\n  - {eye: [0, 1, 3], target: [0, 1, 0]}\n' "$bad" >p.yaml
    refused "camera path $bad" "p.yaml:1:14: first-frame: expected an integer" o_0000.png \
        "$B/lie-render" c.lie --path p.yaml -q --size 8x8 -o o_%04d.png
done
for bad in "frames: 1e300" "frames: -2147483649" "fov: 1e300"; do
    printf 'keys:\n  - {eye: [0, 1, 3], target: [0, 1, 0], %s}\n  - {eye: [0, 1, 2], target: [0, 1, 0]}\n' "$bad" >p.yaml
    refused "camera path $bad" "p.yaml:2:" o_0000.png "$B/lie-render" c.lie --path p.yaml -q --size 8x8 -o o_%04d.png
done
# keys that swap eye and target: the middle frame looks nowhere
printf 'interpolation: linear\nkeys:\n  - {eye: [0, 1, 3], target: [0, 1, -3], frames: 2}\n  - {eye: [0, 1, -3], target: [0, 1, 3]}\n' >swap.yaml
refused "linear keys swapping eye and target" "swap.yaml: frame 1 (between keys[0] and keys[1]): no view direction" \
    o_0000.png "$B/lie-render" c.lie --path swap.yaml -q --size 8x8 -o o_%04d.png
printf 'first-frame: 10\nkeys:\n  - {eye: [0, 1, 3], target: [0, 1, -3], frames: 4}\n  - {eye: [0, 1, -3], target: [0, 1, 3]}\n' >swap2.yaml
refused "smooth keys crossing: the frame numbered from first-frame" "swap2.yaml: frame 12 (between keys[0] and keys[1])" \
    o_0010.png "$B/lie-render" c.lie --path swap2.yaml -q --size 8x8 -o o_%04d.png
refused "lie-build --path refuses the same path" "swap.yaml: frame 1" o.lie \
    "$B/lie-build" "$S/cornell.gltf" --path swap.yaml $BUILD -o o.lie
refused "the middle frame's camera through --camera" "--camera: eye and target coincide" o.png \
    "$B/lie-render" c.lie --camera "eye=0,1,0,target=0,1,0" -q --size 8x8 -o o.png

# ---- names from files reach the terminal escaped ---------------------------------
esc=$(printf 'e\033]0;x\007\033[31m.yaml')
printf -- '- move: {node: TallBlock, by: [0.01, 0, 0]}\n' >"$esc"
run "$B/rst-update" c.lie "$esc" -q -o named.lie
expect_rc 0 "an edit file whose name holds escape sequences"
run "$B/lie-inspect" summary named.lie
expect_rc 0 "lie-inspect summary"
if grep -q "$(printf '\033')" "$TMP/out" "$TMP/err" || grep -q "$(printf '\007')" "$TMP/out"; then
    not_ok "raw control bytes in summary's output"
else
    grep -q 'e\\x1b\]0;x\\x07\\x1b\[31m.yaml' "$TMP/out" && ok "summary escapes the edit-log name as dump does" ||
        not_ok "summary: $(grep yaml "$TMP/out")"
fi
run "$B/lie-inspect" summary "$T/$esc"
grep -q "$(printf '\033')" "$TMP/out" "$TMP/err" && not_ok "raw ESC from the cache path" || ok "the cache's path is escaped too"

# ---- images: every format's header, before decoding; only used ones --------------
python3 - "$S/cornell.gltf" <<'EOF' || not_ok "python3 writes the image cases"
import base64, json, struct, sys
d = json.load(open(sys.argv[1]))
W, H = 40000, 13000
bmp = b'BM' + struct.pack('<IHHI', 70, 0, 0, 54) + struct.pack('<IiiHHIIiiII', 40, W, H, 1, 24, 0, 0, 0, 0, 0, 0) + b'\0' * 16
tga = struct.pack('<BBBHHBHHHHBB', 0, 0, 2, 0, 0, 0, 0, 0, W, H, 24, 0) + b'\0' * 16
files = {
    'big.bmp': bmp,
    'big.ppm': b'P6\n%d %d\n255\n' % (W, H) + b'\0' * 16,
    'big.pgm': b'P5\n%d %d\n255\n' % (W, H) + b'\0' * 16,
    'big.tga': tga,
    'big.gif': b'GIF89a' + struct.pack('<HHBBB', W, H, 0, 0, 0) + b'\0' * 16,
    'big.hdr': b'#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n' % (H, W) + b'\0' * 16,
    'big.psd': b'8BPS' + struct.pack('>H6xHIIHH', 1, 3, H, W, 8, 3) + b'\0' * 16,
}
for name, data in files.items():
    open(name, 'wb').write(data)
    for used in (0, 1):
        e = json.loads(json.dumps(d))
        e['buffers'][0]['uri'] = 'cornell.bin'
        e['images'] = [{'uri': name}]
        e['textures'] = [{'source': 0}]
        if used:
            e['materials'][0].setdefault('pbrMetallicRoughness', {})['baseColorTexture'] = {'index': 0}
        open('%s-%s.gltf' % (name.replace('.', '-'), 'used' if used else 'unused'), 'w').write(json.dumps(e))
EOF
cp "$S/cornell.bin" .
for f in bmp ppm pgm tga gif hdr psd; do
    refused "a $f texture claiming 40000x13000, used" "image 0 is 40000x13000, beyond the limit of 67108864 pixels" o.lie \
        "$B/lie-build" big-$f-used.gltf $BUILD -o o.lie
    start=$(date +%s)
    run "$B/lie-build" big-$f-unused.gltf $BUILD -o o.lie
    end=$(date +%s)
    if [ "$rc" -eq 0 ] && [ $((end - start)) -le 3 ] && [ ! -s "$TMP/err" ]; then
        ok "the same $f unused: not decoded, built in $((end - start)) s"
    else
        not_ok "the same $f unused: exit $rc in $((end - start)) s"; sed 's/^/# /' "$TMP/err" | head -3
    fi
done
# ---- a removed skin joint still poses its mesh: --write-scene writes it bare
cp "$G/animated.gltf" anim.gltf
"$B/lie-build" anim.gltf $BUILD -o anim.lie || not_ok "build animated.gltf"
for joint in Bone0 Bone1; do
    printf -- '- remove: {node: %s}\n' $joint >rm.yaml
    run "$B/rst-update" anim.lie rm.yaml -q -o rm.lie --write-scene rm.gltf
    expect_rc 0 "remove the joint $joint, then --write-scene"
    run "$B/lie-build" rm.gltf $BUILD -o rebuilt.lie
    expect_rc 0 "the written scene builds"
    "$B/lie-inspect" diff rm.lie rebuilt.lie | tail -1 | grep -qx same &&
        ok "and equals the update (lie-inspect diff)" || not_ok "$joint: the written scene differs from the update"
done
printf -- '- remove: {node: Bone0}\n- remove: {node: Arm}\n' >rm.yaml
run "$B/rst-update" anim.lie rm.yaml -q -o rm.lie --write-scene rm2.gltf
expect_rc 0 "remove the joint and its mesh"
python3 -c "import json,sys; d=json.load(open('rm2.gltf')); sys.exit(0 if not d.get('skins') and all(n.get('name') not in ('Bone0', 'Arm') for n in d['nodes']) else 1)" &&
    ok "neither is written" || not_ok "rm2.gltf still holds the joint or the skin"
expect_no_temp "$T" "no temporary left"
finish
