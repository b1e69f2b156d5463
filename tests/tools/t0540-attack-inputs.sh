#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The input classes of an outsider's attack (docs/tools.md, "Hostile inputs
# and outputs"), each refused with one
# line and exit 1, quickly, and never a crash:
#   1. glTF JSON nested 20,000 deep (extras, extensions, any array) and in a GLB
#   3. a URI whose text stays in the scene's folder but whose symlink leads out
#   4. a second YAML document after "---" (edit files, camera paths)
#   5. FIFOs and devices as inputs (edit file, add file, a cache's scene, a
#      cache, a camera path), YAML nested 100,000 deep, --min-patch 1e-12 and
#      the node budget
#   7. control bytes from a cache's scene path and from node names escaped
#   8. glTF the specification makes invalid: negative byteOffset/byteStride,
#      bufferView -1, material -2, a URI with a NUL, texCoord 2^31
# FIFOs and device nodes are made privately in $TMP, never the system's.
. "$ROOT/tests/tools/lib.sh"
T=$TMP
cd "$T" || exit 1

# expect_fail_line TOOL PATTERN WHAT: exit 1 and one line matching PATTERN (grep -E)
expect_fail_line() {
    lines=$(wc -l <"$T/err")
    if [ "$rc" -eq 1 ] && [ "$lines" -eq 1 ] && grep -qE -- "$2" "$T/err"; then ok "$3"; else
        not_ok "$3: rc $rc, $lines lines, expected /$2/"; sed 's/^/# /' "$T/err" | head -5; fi
}
# quick CMD...: run with a timeout of 10 s (a hang shows as rc 124)
quick() { run timeout 10 "$@"; }

cp "$D/gltf/external.gltf" "$D/gltf/external.bin" "$D/gltf/ext image.png" "$T/"
python3 - "$T" <<'EOF' || not_ok "python3 writes the glTF cases"
import json, struct, sys
T = sys.argv[1]
d = json.load(open(T + '/external.gltf'))
def write(name, change):
    e = json.loads(json.dumps(d))
    change(e)
    open(T + '/' + name, 'w').write(json.dumps(e, indent=1))
# class 1: deep nesting, spliced in as text (Python's json cannot nest so deep)
deep = '[' * 20000 + ']' * 20000
deepo = '{"a":' * 20000 + '1' + '}' * 20000
base = json.dumps(d)
open(T + '/deep-extras.gltf', 'w').write(base.replace('"asset": {', '"extras": %s, "asset": {' % deep, 1))
open(T + '/deep-ext.gltf', 'w').write(base.replace('"asset": {', '"extensions": {"X_deep": %s}, "asset": {' % deepo, 1))
open(T + '/deep-node.gltf', 'w').write(base.replace('"nodes": [{', '"nodes": [{"extras": {"x": %s}, ' % deep, 1))
j = base.replace('"asset": {', '"extras": %s, "asset": {' % deep, 1)
j = j.replace('"uri": "external.bin"', '"uri": "external.bin", "x": 0')
j = j.encode() + b' ' * ((4 - len(j) % 4) % 4)
open(T + '/deep.glb', 'wb').write(b'glTF' + struct.pack('<III', 2, 12 + 8 + len(j), len(j)) + b'JSON' + j)
# 128 levels is allowed
open(T + '/nest128.gltf', 'w').write(base.replace('"asset": {', '"extras": %s, "asset": {' % ('[' * 127 + ']' * 127), 1))
# class 8: what the glTF 2.0 schema forbids
write('neg-offset.gltf', lambda e: e['bufferViews'][1].__setitem__('byteOffset', -4))
write('neg-acc-offset.gltf', lambda e: e['accessors'][0].__setitem__('byteOffset', -12))
write('neg-stride.gltf', lambda e: e['bufferViews'][0].__setitem__('byteStride', -12))
write('odd-stride.gltf', lambda e: e['bufferViews'][0].__setitem__('byteStride', 14))
write('view-minus1.gltf', lambda e: e['accessors'][0].__setitem__('bufferView', -1))
write('material-minus2.gltf', lambda e: e['meshes'][0]['primitives'][0].__setitem__('material', -2))
write('texcoord-2e31.gltf', lambda e: e['materials'][0]['pbrMetallicRoughness']['baseColorTexture'].__setitem__('texCoord', 2**31))
write('uri-nul.gltf', lambda e: e['buffers'][0].__setitem__('uri', 'external.bin\u0000.png'))
write('attr-neg.gltf', lambda e: e['meshes'][0]['primitives'][0]['attributes'].__setitem__('POSITION', -1))
write('scene-nodes-neg.gltf', lambda e: e['scenes'][0]['nodes'].__setitem__(0, -1))
write('index-float.gltf', lambda e: e['meshes'][0]['primitives'][0].__setitem__('material', 0.5))
write('index-string.gltf', lambda e: e['nodes'][0].__setitem__('mesh', '0'))
# extras and unknown extensions are not glTF's to check
write('extras-neg.gltf', lambda e: e['nodes'][0].__setitem__('extras', {'bufferView': -1, 'material': -2}))
write('unknown-ext-neg.gltf', lambda e: e['nodes'][0].__setitem__('extensions', {'X_other': {'index': -5}}))
EOF

# ---- 1. nesting depth ---------------------------------------------------------
for f in deep-extras deep-ext deep-node; do
    quick "$B/lie-build" "$f.gltf" -q -o "$T/o.lie"
    expect_fail_line lie-build "^lie-build: $f.gltf:[0-9]+:[0-9]+: JSON nested deeper than 128 levels$" \
        "lie-build refuses $f (20,000 deep)"
done
quick "$B/lie-build" deep.glb -q -o "$T/o.lie"
expect_fail_line lie-build "^lie-build: deep.glb:.*JSON nested deeper than 128 levels" "a GLB's JSON chunk too"
quick "$B/lie-render" deep-extras.gltf -q --size 8x8 -o "$T/o.exr"
expect_fail_line lie-render "JSON nested deeper" "lie-render refuses it too"
"$B/lie-build" "$S/cornell.gltf" --samples 4 --max-samples 4 --min-patch 0.3 -q -o "$T/c.lie" || not_ok "build cornell"
printf -- '- add: {file: deep-extras.gltf, node: "0", as: Added}\n' >"$T/add-deep.yaml"
quick "$B/rst-update" "$T/c.lie" "$T/add-deep.yaml" -q -o "$T/o.lie"
expect_fail_line rst-update "add.file: .*JSON nested deeper" "rst-update add refuses it too"
run "$B/lie-build" nest128.gltf -q --samples 4 --max-samples 4 --min-patch 0.3 -o "$T/o.lie"
expect_rc 0 "128 levels of extras are fine"

# ---- 8. strict glTF -----------------------------------------------------------
strict() { # FILE PATTERN
    quick "$B/lie-build" "$1" -q -o "$T/o.lie"
    expect_fail_line lie-build "^lie-build: $1: .*$2" "refused: $1"
}
strict neg-offset.gltf 'bufferViews\[1\]\.byteOffset: -4 is not in \[0, '
strict neg-acc-offset.gltf 'accessors\[0\]\.byteOffset: -12 is not in'
strict neg-stride.gltf 'bufferViews\[0\]\.byteStride: -12 is not in \[4, 252\]'
strict odd-stride.gltf 'bufferViews\[0\]\.byteStride: 14 is not a multiple of 4'
strict view-minus1.gltf 'accessors\[0\]\.bufferView: -1 is not in \[0, 2147483647\]'
strict material-minus2.gltf 'meshes\[0\]\.primitives\[0\]\.material: -2 is not in'
strict texcoord-2e31.gltf 'baseColorTexture\.texCoord: 2147483648 is not in \[0, 2147483647\]'
strict uri-nul.gltf 'buffers\[0\]\.uri: contains a NUL byte'
strict attr-neg.gltf 'attributes\.POSITION: -1 is not in'
strict scene-nodes-neg.gltf 'scenes\[0\]\.nodes\[0\]: -1 is not in'
strict index-float.gltf 'material: 0.5 is not an integer'
strict index-string.gltf 'nodes\[0\]\.mesh: expected an integer, found string'
for f in extras-neg unknown-ext-neg; do
    run "$B/lie-build" $f.gltf -q --samples 4 --max-samples 4 --min-patch 0.3 -o "$T/o.lie"
    expect_rc 0 "$f: extras and unknown extensions are left alone"
done

# ---- 3. the sandbox checks the file actually opened ----------------------------------
mkdir -p sb/scene sb/outside
cp external.gltf "ext image.png" sb/scene/
cp external.bin sb/outside/
ln -s ../outside/external.bin sb/scene/external.bin
quick "$B/lie-build" sb/scene/external.gltf -q -o "$T/o.lie"
expect_fail_line lie-build "URI 'external.bin' resolves \(through a symlink\) outside the scene's folder" \
    "a symlinked buffer leading out of the folder"
rm sb/scene/external.bin
cp sb/outside/external.bin sb/real.bin
ln -s ../real.bin sb/scene/external.bin
mv "sb/scene/ext image.png" sb/outside/
ln -s "../outside/ext image.png" "sb/scene/ext image.png"
quick "$B/lie-build" sb/scene/external.gltf -q -o "$T/o.lie"
expect_fail_line lie-build "resolves \(through a symlink\) outside" "a symlinked image or a symlink to a sibling folder"
run "$B/lie-build" sb/scene/external.gltf --allow-external-uris -q --samples 4 --max-samples 4 --min-patch 0.3 -o "$T/o.lie"
expect_rc 0 "--allow-external-uris permits it"
mkdir -p sb2/scene/sub
cp external.gltf "ext image.png" sb2/scene/
cp external.bin sb2/scene/sub/
ln -s sub/external.bin sb2/scene/external.bin
run "$B/lie-build" sb2/scene/external.gltf -q --samples 4 --max-samples 4 --min-patch 0.3 -o "$T/o.lie"
expect_rc 0 "a symlink that stays inside the folder is fine"

# ---- 5. FIFOs and devices as inputs --------------------------------------------------
mkfifo fifo.yaml fifo.gltf fifo.lie
mknod zero c 1 5 2>/dev/null || ln -s /dev/zero zero # a private node where mknod works
quick "$B/rst-update" "$T/c.lie" fifo.yaml -q -o "$T/o.lie"
expect_fail_line rst-update "^rst-update: fifo.yaml: cannot read a FIFO: only regular files" "a FIFO as edit file"
printf -- '- add: {file: fifo.gltf, node: X, as: Y}\n' >add-fifo.yaml
quick "$B/rst-update" "$T/c.lie" add-fifo.yaml -q -o "$T/o.lie"
expect_fail_line rst-update "add.file: fifo.gltf: cannot read a FIFO" "a FIFO as add file"
quick "$B/lie-inspect" verify zero
expect_fail_line lie-inspect "^lie-inspect: zero: cannot read a character device" "lie-inspect verify of /dev/zero fails fast"
quick "$B/lie-inspect" verify fifo.lie
expect_fail_line lie-inspect "cannot read a FIFO" "a FIFO as cache"
quick "$B/lie-render" "$T/c.lie" --scene fifo.gltf -q --size 8x8 -o "$T/o.exr"
expect_fail_line lie-render "^lie-render: fifo.gltf: cannot read a FIFO" "a FIFO as --scene"
quick "$B/lie-render" "$T/c.lie" --path fifo.yaml -q --size 8x8 -o "$T/o_%04d.exr"
expect_fail_line lie-render "fifo.yaml: cannot read a FIFO" "a FIFO as camera path"
# a cache whose recorded scene path is a FIFO (then the device)
mkdir sc && cp "$S/cornell.gltf" "$S/cornell.bin" sc/
(cd sc && "$B/lie-build" cornell.gltf --samples 4 --max-samples 4 --min-patch 0.3 -q -o ../sc.lie) || not_ok "build in sc/"
rm sc/cornell.gltf && mkfifo sc/cornell.gltf
(cd sc && quick "$B/lie-render" ../sc.lie -q --size 8x8 -o "$T/o.exr")
expect_fail_line lie-render "cornell.gltf: cannot read a FIFO" "a FIFO as a cache's scene path"
rm sc/cornell.gltf && ln -s "$T/zero" sc/cornell.gltf
(cd sc && quick "$B/lie-render" ../sc.lie -q --size 8x8 -o "$T/o.exr")
expect_fail_line lie-render "cornell.gltf: cannot read a character device" "a device (/dev/zero) as a cache's scene path"
(cd sc && quick "$B/lie-inspect" verify ../sc.lie --scene cornell.gltf)
expect_fail_line lie-inspect "cornell.gltf: cannot read a character device" "and as verify --scene"
quick "$B/lie-build" "$T" -q -o "$T/o.lie"
expect_fail_line lie-build "cannot read a directory" "a directory as scene"

# YAML: nested 100,000 deep (200 KB) fails at once, not after a minute
python3 -c "print('- move: {node: TallBlock, by: ' + '[' * 100000 + ']' * 100000 + '}')" >deep.yaml
start=$(date +%s)
quick "$B/rst-update" "$T/c.lie" deep.yaml -q -o "$T/o.lie"
end=$(date +%s)
expect_fail_line rst-update "^rst-update: deep.yaml:1:[0-9]+: YAML nested deeper than 64 levels" "YAML 100,000 deep"
if [ $((end - start)) -le 3 ]; then ok "in $((end - start)) s"; else not_ok "YAML depth took $((end - start)) s"; fi
python3 -c "print('- move: {node: TallBlock, by: ' + '{a: ' * 80 + '1' + '}' * 80 + '}')" >deepmap.yaml
quick "$B/rst-update" "$T/c.lie" deepmap.yaml -q -o "$T/o.lie"
expect_fail_line rst-update "YAML nested deeper than 64" "nested flow mappings"
python3 -c "
s = 'keys:\n'
for i in range(70): s += '  ' * i + 'k%d:\n' % i
open('deepblock.yaml', 'w').write(s + '  ' * 70 + 'x\n')"
quick "$B/lie-render" "$T/c.lie" --path deepblock.yaml -q --size 8x8 -o "$T/o_%04d.exr"
expect_fail_line lie-render "deepblock.yaml:[0-9]+:[0-9]+: YAML nested deeper than 64" "nested block mappings (camera path)"

# --min-patch's lower bound, and the node budget
run "$B/lie-build" "$S/cornell.gltf" --min-patch 1e-12 -q -o "$T/o.lie"
expect_rc 2 "--min-patch 1e-12 is a usage error"
grep -q "expected a fraction in \[1e-08, 1\]" "$T/err" && ok "and says the bound" || not_ok "bound not in: $(cat "$T/err")"
rm -f "$T/o.lie"
quick "$B/lie-build" "$S/cornell.gltf" --min-patch 1e-8 --max-blockers 0 --max-nodes 2000 --samples 4 --max-samples 4 --frames 0 -q -o "$T/o.lie"
expect_fail_line lie-build "the patch trees need more than 2000 nodes \(max-nodes\): raise min-patch or max-nodes" \
    "the node budget"
expect_no_file "$T/o.lie" "no cache when over budget"
run "$B/lie-build" "$S/cornell.gltf" --max-nodes 0 -q -o "$T/o.lie"
expect_rc 2 "--max-nodes 0 is a usage error"

# edit_fails NAME TEXT PATTERN WHAT: rst-update with edit file NAME holding TEXT fails with PATTERN
edit_fails() {
    printf -- "$2" >"$1"
    quick "$B/rst-update" "$T/c.lie" "$1" -q -o "$T/o.lie"
    expect_fail_line rst-update "$3" "$4"
}

# ---- 4. one YAML document ---------------------------------------------------------
edit_fails multi.yaml '- move: {node: TallBlock, by: [0, 0, 0]}\n---\n- bogus: 1\n' \
    "^rst-update: multi.yaml:2:1: a second YAML document" "a second edit document, even invalid"
edit_fails multi2.yaml '- move: {node: TallBlock, by: [0, 0, 0]}\n---\n- move: {node: TallBlock, by: [1, 0, 0]}\n' \
    "a second YAML document" "a second edit document, valid"
printf -- '- move: {node: TallBlock, by: [0, 0, 0]}\n...\n' >end.yaml
run "$B/rst-update" "$T/c.lie" end.yaml -q -o "$T/o.lie"
expect_rc 0 "an end marker without a second document is fine"
printf 'keys:\n  - {eye: [0, 1, 5], target: [0, 1, 0]}\n---\nkeys: []\n' >multi-path.yaml
quick "$B/lie-render" "$T/c.lie" --path multi-path.yaml -q --size 8x8 -o "$T/o_%04d.exr"
expect_fail_line lie-render "multi-path.yaml:3:1: a second YAML document" "a second camera-path document"

# ---- 7. control bytes in messages ------------------------------------------------------
dir=$(printf 'we\nird\033]0;pwned\007')
mkdir "$dir" && cp "$S/cornell.gltf" "$S/cornell.bin" "$dir/"
"$B/lie-build" "$dir/cornell.gltf" --samples 4 --max-samples 4 --min-patch 0.3 -q -o "$T/ctl.lie" || not_ok "build in $dir"
rm -rf "$dir"
quick "$B/lie-render" "$T/ctl.lie" -q --size 8x8 -o "$T/o.exr"
expect_fail_line lie-render '^lie-render: we\\nird\\033\]0;pwned\\007/cornell\.gltf: cannot open' \
    "a scene path from a cache is escaped"
if tr -d '\n' <"$T/err" | LC_ALL=C grep -q "$(printf '[\001-\037\177]')"; then
    not_ok "control bytes reached stderr"; else ok "no control byte reaches stderr"; fi
run "$B/lie-inspect" summary "$T/ctl.lie"
grep '^scene ' "$T/out" | grep -qF 'we\x0aird\x1b]0;pwned\x07/cornell.gltf' &&
    ok "lie-inspect summary escapes the scene path too" || { not_ok "summary"; grep '^scene' "$T/out" | od -c | head -3; }
edit_fails ctl.yaml '- move: {node: "Tall\\nBlock\\e[31m\\u009b", by: [0, 0, 0]}\n' \
    'Tall\\nBlock\\033\[31m\\302\\233' "a node name with a newline, ESC and a C1 CSI"
edit_fails utf8.yaml '- move: {node: "Zoë", by: [0, 0, 0]}\n' 'Zoë' "UTF-8 passes unescaped"

finish
