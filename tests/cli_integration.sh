#!/usr/bin/env bash
# Integration test with real readers: vdb_print, pyopenvdb and h5py (Debian's /usr/bin/python3).
# Usage: cli_integration.sh SPALL_BINARY SCRATCH_DIR
set -euo pipefail
spall=$1
dir=$2
rm -rf "$dir" && mkdir -p "$dir"
py=/usr/bin/python3
fail() { echo "FAIL: $*" >&2; exit 1; }

# --version names the program and its version
version=$("$spall" --version)
[[ $version =~ ^spall\ [0-9]+\.[0-9]+\.[0-9]+$ ]] || fail "--version printed: $version"

# voxelise: a primitive and a mesh, read back by vdb_print and pyopenvdb
"$spall" voxelise --primitive box:1,0.5,0.4 --voxel-size 0.1 -o "$dir/box.vdb" --quiet > "$dir/box.txt"
grep -q "voxels: *200" "$dir/box.txt" || fail "box voxel count: $(cat "$dir/box.txt")"
vdb_print "$dir/box.vdb" | grep -q "solid" || fail "vdb_print cannot read box.vdb"
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n' > "$dir/cube.obj"
"$spall" voxelise "$dir/cube.obj" --voxel-size 0.08 -o "$dir/cube.vdb" --quiet > /dev/null
$py - "$dir/box.vdb" "$dir/cube.vdb" <<'PY'
import sys, pyopenvdb as vdb
names = [m.name for m in vdb.readAllGridMetadata(sys.argv[1])]
assert sorted(names) == ["links", "solid"], names
g = vdb.read(sys.argv[1], "solid")
assert g.activeVoxelCount() == 200, g.activeVoxelCount()
assert abs(g.metadata["voxel_size_m"] - 0.1) < 1e-12
cube = vdb.read(sys.argv[2], "solid")
assert cube.activeVoxelCount() == 13 ** 3, cube.activeVoxelCount()
PY

# bad input: non-zero exit, message names the file, no output left behind
echo "not a mesh" > "$dir/bad.stl"
if "$spall" voxelise "$dir/bad.stl" --voxel-size 0.1 -o "$dir/bad.vdb" 2> "$dir/err.txt"; then fail "bad mesh accepted"; fi
grep -q "bad.stl" "$dir/err.txt" || fail "error does not name the file: $(cat "$dir/err.txt")"
[[ ! -e "$dir/bad.vdb" ]] || fail "output left behind"
if "$spall" voxelise --primitive box:1,1,1 --voxel-size -1 -o "$dir/neg.vdb" 2> /dev/null; then fail "negative voxel size accepted"; fi
# a header that claims 3.5 billion vertices in a 45-byte file: refused in well under a second,
# with or without a memory limit, naming the counts
printf 'OFF\n3500000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n' > "$dir/huge.off"
for limit in unlimited 2000000; do
  start_ns=$(date +%s%N)
  if (ulimit -v "$limit"; "$spall" voxelise "$dir/huge.off" --voxel-size 0.1 -o "$dir/huge.vdb" 2> "$dir/err.txt"); then fail "huge header accepted"; fi
  took_ms=$(( ($(date +%s%N) - start_ns) / 1000000 ))
  grep -q "huge.off.*declares 3500000000 vertices" "$dir/err.txt" || fail "huge header (ulimit -v $limit): $(cat "$dir/err.txt")"
  (( took_ms < 500 )) || fail "huge header (ulimit -v $limit): took $took_ms ms"
done
# a sphere (r = 1.5 m, 14.1 m^3) with its top cap cut away: the winding number fills it; the
# level set, forced, loses the inside through the hole and is refused
cat > "$dir/holed_sphere.py" <<'PY'
import math, sys
n = int(sys.argv[2]); v = []; f = []
for i in range(n + 1):
    for j in range(2 * n):
        t, p = math.pi * i / n, math.pi * j / n
        v.append((1.5 * math.sin(t) * math.cos(p), 1.5 * math.sin(t) * math.sin(p), 1.5 * math.cos(t)))
at = lambda i, j: i * 2 * n + j % (2 * n)
for i in range(n):
    for j in range(2 * n):
        for tri in ((at(i, j), at(i + 1, j), at(i + 1, j + 1)), (at(i, j), at(i + 1, j + 1), at(i, j + 1))):
            if not all(v[k][2] > 1.2 for k in tri): f.append(tri)
with open(sys.argv[1], "w") as out:
    out.writelines("v %f %f %f\n" % p for p in v)
    out.writelines("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in f)
PY
$py "$dir/holed_sphere.py" "$dir/holed.obj" 64
"$spall" voxelise "$dir/holed.obj" --voxel-size 0.05 -o "$dir/holed.vdb" --quiet > "$dir/holed.txt" 2> "$dir/err.txt" || fail "holed sphere: $(cat "$dir/err.txt")"
grep -q "winding number" "$dir/err.txt" || fail "holed sphere: no note of the inside test: $(cat "$dir/err.txt")"
awk '/volume:/ { exit !($2 > 13.4 && $2 < 14.8) }' "$dir/holed.txt" || fail "holed sphere: volume $(grep volume: "$dir/holed.txt")"
if "$spall" voxelise "$dir/holed.obj" --voxel-size 0.05 --inside level-set -o "$dir/leak.vdb" --quiet > /dev/null 2> "$dir/err.txt"; then
  fail "a near-empty level-set fill was accepted"
fi
grep -q "holed.obj: the voxels hold .* lost most of the volume" "$dir/err.txt" || fail "leaky fill: $(cat "$dir/err.txt")"
[[ ! -e "$dir/leak.vdb" ]] || fail "leaky fill: output left behind"
# Ctrl-C while voxelising a large mesh (320 000 triangles at 1 cm): stops within a second, exit
# 130, nothing written
$py "$dir/holed_sphere.py" "$dir/big-holed.obj" 400
"$spall" voxelise "$dir/big-holed.obj" --voxel-size 0.01 -o "$dir/big.vdb" > /dev/null 2> "$dir/err.txt" &
pid=$!
for _ in $(seq 600); do grep -q "%" "$dir/err.txt" && break; sleep 0.05; done
kill -s INT "$pid"
start_ns=$(date +%s%N)
status=0; wait "$pid" || status=$?
stop_ms=$(( ($(date +%s%N) - start_ns) / 1000000 ))
[[ $status -eq 130 ]] || fail "Ctrl-C while voxelising: exit status $status, expected 130: $(cat "$dir/err.txt")"
(( stop_ms < 1000 )) || fail "Ctrl-C while voxelising: took $stop_ms ms to stop"
grep -q "interrupted; nothing was written" "$dir/err.txt" || fail "Ctrl-C while voxelising: $(cat "$dir/err.txt")"
[[ ! -e "$dir/big.vdb" ]] || fail "Ctrl-C while voxelising: output left behind"
if "$spall" blast --tnt-kg 0 --distance-m 3 2> /dev/null; then fail "zero charge accepted"; fi
# The burst follows the height above the ground; a surface burst 2 m up is refused.
"$spall" blast --tnt-kg 20 --distance-m 4 --height-m 0.1 | grep -q "surface burst" || fail "a charge on the ground is not a surface burst"
"$spall" blast --tnt-kg 20 --distance-m 4 --height-m 2 | grep -q "free-air burst" || fail "a charge 2 m up is not in free air"
if "$spall" blast --tnt-kg 20 --distance-m 4 --height-m 2 --burst surface 2> /dev/null; then fail "a surface burst 2 m up accepted"; fi

# blast JSON keys with units
"$spall" blast --tnt-kg 8 --distance-m 4 --dataset kinney-graham --json > "$dir/blast.json"
$py - "$dir/blast.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
for key in ["peak_overpressure_Pa", "arrival_time_s", "positive_duration_s", "decay_coefficient", "positive_impulse_Pa_s",
            "negative_peak_Pa", "negative_duration_s", "reflected_pressure_Pa", "shock_speed_m_s", "scaled_distance_m_kg13"]:
    assert key in j, key
assert abs(j["peak_overpressure_Pa"] - 207.9e3) < 0.01 * 207.9e3
PY

# blast curves: CSV and a PNG plot
"$spall" blast --tnt-kg 4 --distance-m 3 --curve "$dir/curve.csv" > /dev/null
head -1 "$dir/curve.csv" | grep -q "time_s,overpressure_Pa" || fail "curve CSV header"
"$spall" blast --tnt-kg 4 --distance-m 3 --curve "$dir/curve.png" > /dev/null
# Decoded in full by Pillow (python3-pil, which python3-matplotlib brings): a PNG cut short or with
# a bad checksum fails here.
$py -c "import sys; from PIL import Image; im = Image.open(sys.argv[1]); im.load(); assert im.size == (900, 560), im.size" "$dir/curve.png" \
  || fail "curve PNG"

# glTF (embedded buffer): a unit cube through assimp
$py - "$dir/cube.gltf" <<'PY'
import base64, json, struct, sys
v = [(0,0,0),(1,0,0),(1,1,0),(0,1,0),(0,0,1),(1,0,1),(1,1,1),(0,1,1)]
f = [(0,3,2),(0,2,1),(4,5,6),(4,6,7),(0,1,5),(0,5,4),(1,2,6),(1,6,5),(2,3,7),(2,7,6),(3,0,4),(3,4,7)]
data = b"".join(struct.pack("<3f", *p) for p in v) + b"".join(struct.pack("<3H", *t) for t in f)
json.dump({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "scene": 0, "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96}, {"buffer": 0, "byteOffset": 96, "byteLength": 72}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [0,0,0], "max": [1,1,1]},
                         {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]}, open(sys.argv[1], "w"))
PY
"$spall" voxelise "$dir/cube.gltf" --voxel-size 0.08 -o "$dir/gltf.vdb" --quiet | grep -q "voxels: *2197" || fail "glTF cube"

# run: a short scene, then every frame through vdb_print and pyopenvdb, the history through h5py
# (the paper's rule, which breaks this wall into many pieces within a quarter second)
cat > "$dir/scene.json" <<'JSON'
{"voxel_size_m": 0.1, "duration_s": 0.25, "frame_rate_hz": 24, "seed": 5,
 "objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [2.0, 0.3, 1.5]},
              "position_m": [0, 0, 0.75], "material": "reinforced-concrete", "anchor": "ground"}],
 "charges": [{"position_m": [0.2, -2.0, 0.0], "tnt_kg": 0.5, "burst": "surface"}],
 "fracture": {"algorithm": "yield-limit"}}
JSON
"$spall" run "$dir/scene.json" -o "$dir/out" --quiet > "$dir/run.txt"
ls "$dir"/out/fragments.*.vdb > /dev/null || fail "no frames"
for f in "$dir"/out/fragments.*.vdb; do vdb_print "$f" > /dev/null || fail "vdb_print cannot read $f"; done
$py - "$dir/out" <<'PY'
import glob, sys, h5py, numpy as np, pyopenvdb as vdb
out = sys.argv[1]
frames = sorted(glob.glob(out + "/fragments.*.vdb"))
h = h5py.File(out + "/history.h5", "r")
assert h.attrs["format"] in (b"spall-history", "spall-history")
assert h.attrs["run_complete"] == 1
n = len(h["frames/time_s"])
assert n == len(frames) == 7, (n, len(frames))
offsets = h["frames/body_offset"][:]
total = None
for i, path in enumerate(frames):
    # Every frame's grid list; the level sets of the first and last frames meshed by pyopenvdb
    # (reading thousands of trees through it is slow): each a solid of its voxels' volume.
    metas = vdb.readAllGridMetadata(path)
    fragments = [m for m in metas if m.name.startswith("fragment_")]
    assert any(m.name == "density" for m in metas)
    voxels = sum(m.metadata["voxel_count"] for m in fragments)
    if i in (0, len(frames) - 1):
        for m in fragments:
            grid = vdb.read(path, m.name)
            assert grid.gridClass == vdb.GridClass.LEVEL_SET, grid.gridClass
            points, quads = grid.convertToQuads()
            p = points[quads] - points[0]
            volume = abs(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum()
                         + np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 2], p[:, 3])).sum()) / 6
            expected = m.metadata["voxel_count"] * m.metadata["voxel_size_m"] ** 3
            assert abs(volume - expected) <= 0.1 * expected, (m.name, volume, expected)
    total = total or voxels
    assert voxels == total, (i, voxels, total)   # voxels only move between bodies
    assert len(fragments) == offsets[i + 1] - offsets[i]
    assert voxels == h["frames/voxel_count"][i]
assert len(fragments) > 1, "the wall should have broken"
p = h["frames/linear_momentum_kg_m_s"][:]
assert np.all(np.isfinite(p))
PY
# glTF: the run's debris as meshes, checked by the Khronos validator (tools/js, installed by setup)
"$spall" export gltf "$dir/out" --quiet > "$dir/gltf.txt" || fail "export gltf failed"
grep -q "debris.glb" "$dir/gltf.txt" || fail "export gltf printed no summary"
node "$(dirname "$0")/../tools/js/validate_gltf.mjs" "$dir/out/debris.glb" > "$dir/validator.txt" || fail "glTF validator: $(cat "$dir/validator.txt")"
# spall view: the self-contained page in headless Chromium (software WebGL) for a crate blown
# apart in the open; its first and last moments both show debris (brick-coloured pixels), and differ
cat > "$dir/crate.json" <<'JSON'
{"voxel_size_m": 0.1, "duration_s": 0.5, "frame_rate_hz": 24, "seed": 5,
 "objects": [{"name": "crate", "primitive": {"shape": "box", "size_m": [0.6, 0.6, 0.6]},
              "position_m": [0, 0, 0.3], "material": "brick-masonry"}],
 "charges": [{"position_m": [1.5, 0, 0.3], "tnt_kg": 2.0}]}
JSON
"$spall" run "$dir/crate.json" -o "$dir/crate" --quiet --no-preview > /dev/null
"$spall" view "$dir/crate" --quiet > "$dir/view.txt" || fail "spall view failed"
grep -q "view.html" "$dir/view.txt" || fail "spall view printed no summary"
node "$(dirname "$0")/../tools/js/screenshot_view.mjs" "$dir/crate/view.html" "$dir/view_" 0 1e9 > "$dir/view.log" 2>&1 \
  || fail "viewer in Chromium: $(cat "$dir/view.log")"
$py - "$dir/view_0.png" "$dir/view_1e9.png" "$dir/view.log" "$dir/crate/history.h5" <<'PY'
import re, sys, h5py, numpy as np
from PIL import Image
# The 3D stage without the status line and the control bar.
first, last = (np.asarray(Image.open(p).convert("RGB"), dtype=float)[30:-50] for p in sys.argv[1:3])
def charge(image):  # the viewer's charge marker, pure orange (255, 110, 0)
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    return (r > 230) & (g > 80) & (g < 140) & (b < 30)
def debris(image):  # the background and the grid are bluish greys; brick and mortar are warm
    return ((image[..., 0] - image[..., 2]) > 8) & ~charge(image)
for name, image in (("first", first), ("last", last)):
    assert debris(image).sum() > 500, (name, debris(image).sum())
    assert charge(image).sum() > 20, f"no charge marker in the {name} picture ({charge(image).sum()} orange pixels)"
# (a fragment moving its own width changes a few per cent of the picture: 1 % is about 5 000 pixels)
changed = (debris(first) != debris(last)).mean()
assert changed > 0.01, f"the debris did not move between the first and last moments ({changed:.4f} of pixels changed)"
# The ground grid reaches past every fragment's resting place (history.h5, spall's Z-up axes;
# the page reports its grid in glTF's Y-up axes, x and -y).
x0, x1, z0, z1 = map(float, re.search(r"ground (\S+)", open(sys.argv[3]).read()).group(1).split(","))
with h5py.File(sys.argv[4]) as h:
    offsets = h["frames/body_offset"][:]
    rest = h["bodies/position_m"][offsets[-2]:offsets[-1]]
assert len(rest) > 0
inside = (rest[:, 0] > x0) & (rest[:, 0] < x1) & (-rest[:, 1] > z0) & (-rest[:, 1] < z1)
assert inside.all(), f"{(~inside).sum()} fragments rest beyond the viewer's ground {x0, x1, z0, z1}"
PY
# spall loads: the crate's faces as it stood, read back by h5py and pyopenvdb; the face toward the
# charge (+x) is its front and took more than any other; a directory without a scene is refused
"$spall" loads "$dir/crate" --quiet > "$dir/loads.txt" || fail "spall loads failed"
grep -q "front face +x" "$dir/loads.txt" || fail "spall loads did not find the front face: $(cat "$dir/loads.txt")"
grep -q "normally reflected Ir" "$dir/loads.txt" || fail "spall loads printed no hand calculation"
[[ -s "$dir/crate/loads_front.png" ]] || fail "spall loads wrote no picture"
$py - "$dir/crate/loads.h5" "$dir/crate/loads.vdb" <<'PY'
import sys, h5py, numpy as np, pyopenvdb as vdb
with h5py.File(sys.argv[1]) as h:
    crate = h["objects/crate"]
    impulse, face, normal = crate["impulse_Pa_s"][:], crate["face"][:], crate["normal"][:]
    assert crate.attrs["front_face"] == 1, crate.attrs["front_face"]
    assert impulse[face == 1].mean() > impulse[face != 1].max() * 0.5
    assert (crate["negative_impulse_Pa_s"][:] <= 0).all() and (impulse >= 0).all()
    # Kingery-Bulmash's free-air Ir is the direct wave's; 0.3 m up, the ground's reflection
    # nearly doubles it (a surface burst is a free-air charge of twice the mass)
    ratio = impulse[crate.attrs["nearest_face"]] / crate.attrs["reference_reflected_impulse_Pa_s"]
    assert 1.0 < ratio < 2.2, ratio
    grid = vdb.read(sys.argv[2], "crate.impulse_Pa_s")
    assert abs(grid.evalMinMax()[1] - impulse.max()) < 1e-3 * impulse.max(), (grid.evalMinMax(), impulse.max())
    assert grid.activeVoxelCount() > 0
PY
if "$spall" loads "$dir/nowhere" 2> "$dir/err.txt"; then fail "loads of a missing directory accepted"; fi
grep -q "nowhere" "$dir/err.txt" || fail "loads error does not name the source: $(cat "$dir/err.txt")"
# ... and refuses what it cannot mesh, naming it, leaving nothing behind
if "$spall" export gltf "$dir/nowhere" 2> "$dir/err.txt"; then fail "export of a missing directory accepted"; fi
grep -q "nowhere" "$dir/err.txt" || fail "error does not name the directory: $(cat "$dir/err.txt")"
$py - "$dir/scene.json" "$dir/fog.json" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["output"] = {"fragment_grids": "fog"}
json.dump(scene, open(sys.argv[2], "w"))
PY
"$spall" run "$dir/fog.json" -o "$dir/fog" --frames 1 --quiet --no-preview > /dev/null
if "$spall" export gltf "$dir/fog" 2> "$dir/err.txt"; then fail "export of fog frames accepted"; fi
grep -q "fragments.0000.vdb: fragments are not level sets" "$dir/err.txt" || fail "fog export error unclear: $(cat "$dir/err.txt")"
[[ ! -e "$dir/fog/debris.glb" ]] || fail "a refused export left a file"
# a run asked for a .glb it could not mesh is refused before it starts
if "$spall" run "$dir/fog.json" -o "$dir/fog-gltf" --gltf --quiet 2> "$dir/err.txt"; then fail "run --gltf of fog frames accepted"; fi
grep -q "a .glb is meshed from level-set frames" "$dir/err.txt" || fail "run --gltf refusal unclear: $(cat "$dir/err.txt")"
[[ ! -e "$dir/fog-gltf/fragments.0000.vdb" ]] || fail "a refused run --gltf wrote frames"
if "$spall" view "$dir/fog" 2> "$dir/err.txt"; then fail "view of fog frames accepted"; fi
grep -q "fragments are not level sets" "$dir/err.txt" || fail "fog view error unclear: $(cat "$dir/err.txt")"
[[ ! -e "$dir/fog/view.html" ]] || fail "a refused view left a page"

# an output directory that cannot be created: a clear error naming it
if "$spall" run "$dir/scene.json" -o "$dir/cube.obj/out" --quiet > /dev/null 2> "$dir/err.txt"; then fail "unwritable output accepted"; fi
grep -q "cube.obj/out" "$dir/err.txt" || fail "error does not name the output directory: $(cat "$dir/err.txt")"
if "$spall" run "$dir/missing-scene.json" -o "$dir/x" --quiet > /dev/null 2> "$dir/err.txt"; then fail "missing scene accepted"; fi
grep -q "missing-scene.json" "$dir/err.txt" || fail "error does not name the scene: $(cat "$dir/err.txt")"

# outputs never mix: a second run into a run's directory is refused, naming --overwrite, and
# leaves it as it was; with --overwrite it replaces it (a shorter run leaves no frames of the
# longer); a run that fails before its first frame leaves nothing; no run leaves its lock
frames_before=$(ls "$dir"/out/fragments.*.vdb | wc -l)
if "$spall" run "$dir/scene.json" -o "$dir/out" --quiet --no-preview > /dev/null 2> "$dir/err.txt"; then fail "a second run into out/ accepted"; fi
grep -q -- "--overwrite" "$dir/err.txt" || fail "the refusal does not name --overwrite: $(cat "$dir/err.txt")"
[[ $(ls "$dir"/out/fragments.*.vdb | wc -l) -eq $frames_before ]] || fail "a refused run changed out/"
cp -r "$dir/out" "$dir/out-again"
"$spall" run "$dir/scene.json" -o "$dir/out-again" --frames 2 --overwrite --quiet --no-preview > /dev/null
[[ $(ls "$dir"/out-again/fragments.*.vdb | wc -l) -eq 2 ]] || fail "--overwrite left the earlier run's frames: $(ls "$dir/out-again")"
[[ ! -e "$dir/out-again/preview.png" && ! -e "$dir/out-again/run.lock" ]] || fail "--overwrite left the earlier preview or a lock: $(ls "$dir/out-again")"
sed 's/"position_m": \[0.2, -2.0, 0.0\], "tnt_kg": 0.5, "burst": "surface"/"position_m": [0.2, -2.0, -1.0], "tnt_kg": 0.5, "burst": "free-air"/' \
  "$dir/scene.json" > "$dir/buried.json"
if "$spall" run "$dir/buried.json" -o "$dir/buried" --quiet > /dev/null 2> "$dir/err.txt"; then fail "a buried charge accepted"; fi
grep -q "below the ground" "$dir/err.txt" || fail "the buried charge was not refused at set-up: $(cat "$dir/err.txt")"
[[ -d "$dir/buried" && -z "$(ls -A "$dir/buried")" ]] || fail "a run that failed at set-up left files: $(ls "$dir/buried")"

# Identical content of output directories (history, fragment metadata and transforms, density).
compare="$(dirname "$0")/../tools/compare_runs.py"

# determinism: 1 and 2 threads, and a repeated run, give identical frames and history content
"$spall" run "$dir/scene.json" -o "$dir/t1" --threads 1 --quiet --no-preview > /dev/null
"$spall" run "$dir/scene.json" -o "$dir/t2" --threads 2 --quiet --no-preview > /dev/null
$py "$compare" "$dir/t1" "$dir/t2" "$dir/out" || fail "runs differ between thread counts or repeats"
[[ ! -e "$dir/out/checkpoint.spall" ]] || fail "a complete run left its checkpoint behind"

# determinism on the built-in default scene, shortened to its first 4 frames (the blast, the
# wall breaking into 3000 bricks and their first collisions): 1 and 2 threads, identical content
"$spall" run -o "$dir/default-1" --frames 4 --threads 1 --quiet --no-preview > /dev/null
"$spall" run -o "$dir/default-2" --frames 4 --threads 2 --quiet --no-preview > /dev/null
$py "$compare" "$dir/default-1" "$dir/default-2" || fail "the default scene differs between 1 and 2 threads"

# interruption: a run killed (SIGKILL) part-way, and one stopped by Ctrl-C (SIGINT), each resumed
# with --resume, end exactly as the uninterrupted run. long.json keeps the default checkpoint
# interval (30 s, longer than the run), so only Ctrl-C writes its checkpoint; every.json writes
# one after every frame, which a SIGKILL needs.
sed 's/"duration_s": 0.25/"duration_s": 0.5/' "$dir/scene.json" > "$dir/long.json"
sed 's/"duration_s": 0.25/"duration_s": 0.5, "output": {"checkpoint_every_s": 1e-9}/' "$dir/scene.json" > "$dir/every.json"
"$spall" run "$dir/long.json" -o "$dir/whole" --quiet --no-preview > /dev/null
start_ns=$(date +%s%N)
"$spall" run "$dir/every.json" -o "$dir/whole-every" --quiet --no-preview > /dev/null
whole_s=$(( ($(date +%s%N) - start_ns) / 1000000 ))e-3
for signal in KILL INT; do
  out="$dir/cut-$signal"
  if [[ $signal == KILL ]]; then scene=every whole=whole-every; else scene=long whole=whole; fi
  "$spall" run "$dir/$scene.json" -o "$out" --quiet > /dev/null 2> "$dir/err.txt" &
  pid=$!
  for _ in $(seq 600); do [[ -e "$out/fragments.0004.vdb" ]] && break; sleep 0.05; done
  kill -s "$signal" "$pid"
  status=0; wait "$pid" || status=$?
  [[ $status -ne 0 ]] || fail "SIG$signal: the run finished before it could be interrupted"
  [[ -e "$out/checkpoint.spall" ]] || fail "SIG$signal: no checkpoint"
  if [[ $signal == INT ]]; then
    [[ $status -eq 130 ]] || fail "SIGINT: exit status $status, expected 130"
    grep -q -- "--resume $out" "$dir/err.txt" || fail "SIGINT: no hint to resume: $(cat "$dir/err.txt")"
    grep -q "spall: stopping: the current step finishes" "$dir/err.txt" || fail "SIGINT: not acknowledged: $(cat "$dir/err.txt")"
  fi
  "$spall" run --resume "$out" --quiet > /dev/null || fail "SIG$signal: --resume failed"
  [[ -s "$out/preview.png" ]] || fail "SIG$signal: the resumed run wrote no preview"
  $py "$compare" "$dir/$whole" "$out" || fail "SIG$signal: the resumed run differs from the uninterrupted one"
done
# killed before its first checkpoint (long.json writes one every 30 s): --resume runs the
# resolved scene again, says so, and ends as the uninterrupted run
out="$dir/cut-early"
"$spall" run "$dir/long.json" -o "$out" --quiet > /dev/null 2>&1 &
pid=$!
for _ in $(seq 600); do [[ -e "$out/fragments.0002.vdb" ]] && break; sleep 0.05; done
kill -s KILL "$pid"; wait "$pid" 2> /dev/null || true
[[ ! -e "$out/checkpoint.spall" ]] || fail "early kill: a checkpoint was written after all"
"$spall" run --resume "$out" --quiet > /dev/null 2> "$dir/err.txt" || fail "early kill: --resume failed: $(cat "$dir/err.txt")"
grep -q "started again from $out/scene.json" "$dir/err.txt" || fail "early kill: --resume did not say what it did: $(cat "$dir/err.txt")"
$py "$compare" "$dir/whole" "$out" || fail "early kill: the restarted run differs from the uninterrupted one"
# killed (SIGKILL) at random moments, resumed, killed again, until it finishes: each --resume
# takes up whatever the kill left (a checkpoint, a frame half written, a resume half started) and
# the run ends as the uninterrupted one. The moments are seeded, so they repeat from run to run.
RANDOM=21
out="$dir/cut-random"
"$spall" run "$dir/every.json" -o "$out" --quiet --no-preview > /dev/null 2>&1 &
pid=$!
finished=0 delays=""
for _ in 1 2 3; do
  delay=$(awk -v r=$RANDOM -v t="$whole_s" 'BEGIN { printf "%.3f", (0.1 + 0.8 * r / 32767) * t }')
  delays="$delays $delay"
  sleep "$delay"
  kill -s KILL "$pid" 2> /dev/null || true
  status=0; wait "$pid" 2> /dev/null || status=$?
  if [[ $status -eq 0 ]]; then finished=1; break; fi
  "$spall" run --resume "$out" --quiet --no-preview > /dev/null 2> "$dir/err-random.txt" &
  pid=$!
done
# (a kill that lands after the run marked itself complete, while it exits, leaves a run that
# --resume rightly refuses as complete: nothing was lost, which the comparison below checks)
if [[ $finished -eq 0 ]]; then
  wait "$pid" || grep -q "the run is complete" "$dir/err-random.txt" ||
    fail "kills after$delays s: the last --resume failed: $(cat "$dir/err-random.txt")"
fi
$py "$compare" "$dir/whole-every" "$out" || fail "kills after$delays s: the resumed run differs from the uninterrupted one"
# a full disk: a 2 MB tmpfs, about half of what the run writes. A clear error naming the file,
# every frame and history row written so far readable, no partial file left looking whole, and
# --resume finishes the run once there is room (here: after moving the directory elsewhere)
mkdir -p "$dir/small-disk"
if mount -t tmpfs -o size=2m tmpfs "$dir/small-disk" 2> /dev/null; then
  trap 'umount "$dir/small-disk" 2> /dev/null || true' EXIT
  if "$spall" run "$dir/every.json" -o "$dir/small-disk/out" --quiet --no-preview > /dev/null 2> "$dir/err.txt"; then
    fail "a run on a full disk reported success"
  fi
  grep -q "small-disk/out/.*disk full" "$dir/err.txt" || fail "full disk: $(cat "$dir/err.txt")"
  ! ls "$dir/small-disk/out" | grep -q partial || fail "full disk: a partial file was left behind: $(ls "$dir/small-disk/out")"
  for f in "$dir"/small-disk/out/fragments.*.vdb; do vdb_print "$f" > /dev/null || fail "full disk: $f does not read"; done
  $py -c "import h5py, sys; n = len(h5py.File(sys.argv[1])['frames/time_s']); assert n >= 1, n" "$dir/small-disk/out/history.h5" \
    || fail "full disk: the history of the frames written does not read"
  cp -r "$dir/small-disk/out" "$dir/full-disk"
  umount "$dir/small-disk"
  trap - EXIT
  "$spall" run --resume "$dir/full-disk" --quiet --no-preview > /dev/null || fail "full disk: --resume failed"
  $py "$compare" "$dir/whole-every" "$dir/full-disk" || fail "full disk: the resumed run differs from the uninterrupted one"
else
  echo "skipped: the full-disk test needs to mount a 2 MB tmpfs (root); it could not"
fi

if "$spall" run --resume "$dir/whole" 2> "$dir/err.txt"; then fail "--resume of a complete run accepted"; fi
grep -q "nothing to resume" "$dir/err.txt" || fail "--resume of a complete run: $(cat "$dir/err.txt")"
if "$spall" run --resume "$dir/nowhere" 2> "$dir/err.txt"; then fail "--resume of a missing directory accepted"; fi
grep -q "nowhere/checkpoint.spall" "$dir/err.txt" || fail "--resume of a missing directory: $(cat "$dir/err.txt")"
if "$spall" run "$dir/long.json" --resume "$dir/whole" 2> /dev/null; then fail "--resume with a scene accepted"; fi

# render: a frame, a contact sheet, the run's own preview; bad input named
[[ -s "$dir/out/preview.png" ]] || fail "spall run wrote no preview.png"
"$spall" render "$dir/out" --frame 2 -o "$dir/pics" --size 320x180 > /dev/null
"$spall" render "$dir/out" --sheet -o "$dir/pics" --size 320x180 > /dev/null
$py "$(dirname "$0")/../tools/fragments_front_view.py" "$dir/out/fragments.0002.vdb" "$dir/pics/front.png" \
  || fail "tools/fragments_front_view.py could not draw a frame"
for png in "$dir/pics/frame.0002.png" "$dir/pics/sheet.png" "$dir/pics/front.png"; do
  head -c 8 "$png" | od -c | grep -q "P   N   G" || fail "$png is not a PNG"
done
if $py "$(dirname "$0")/../tools/fragments_front_view.py" "$dir/nowhere.vdb" "$dir/pics/x.png" 2> "$dir/err.txt"; then
  fail "fragments_front_view.py drew a missing frame"
fi
grep -q "nowhere.vdb" "$dir/err.txt" || fail "fragments_front_view.py did not name the missing frame: $(cat "$dir/err.txt")"
$py - "$dir/pics/frame.0002.png" <<'PY' || fail "the rendered frame shows no fragment colours"
import sys, zlib, struct
data = open(sys.argv[1], "rb").read()
# Decode the PNG (8-bit RGB, filter per row) and look for saturated fragment colours.
pos, idat, w, h = 8, b"", 0, 0
while pos < len(data):
    n, kind = struct.unpack(">I4s", data[pos:pos + 8]); chunk = data[pos + 8:pos + 8 + n]; pos += 12 + n
    if kind == b"IHDR": w, h = struct.unpack(">II", chunk[:8])
    if kind == b"IDAT": idat += chunk
raw, stride, prev, coloured = zlib.decompress(idat), w * 3, bytearray(w * 3), 0
for y in range(h):
    f, row = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    for i in range(stride):
        a = row[i - 3] if i >= 3 else 0; b = prev[i]; c = prev[i - 3] if i >= 3 else 0
        if f == 1: row[i] = (row[i] + a) & 255
        elif f == 2: row[i] = (row[i] + b) & 255
        elif f == 3: row[i] = (row[i] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            row[i] = (row[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    coloured += sum(1 for x in range(w) if max(row[3*x:3*x+3]) - min(row[3*x:3*x+3]) > 60)
    prev = row
assert coloured > 50, coloured
PY
if "$spall" render "$dir/nowhere" 2> "$dir/err.txt"; then fail "render accepted a missing directory"; fi
grep -q "nowhere" "$dir/err.txt" || fail "render error: $(cat "$dir/err.txt")"
if "$spall" render "$dir/out" --size 10x 2> "$dir/err.txt"; then fail "render accepted a bad size"; fi
grep -q "size" "$dir/err.txt" || fail "render error: $(cat "$dir/err.txt")"
# A camera of one's own: another picture than the framing one; an eye of two numbers, or one on
# its target, is refused.
"$spall" render "$dir/out" --frame 2 -o "$dir/pics-eye" --size 320x180 --eye 0,-12,1.5 --target 0,0,0.4 --fov 30 > /dev/null \
  || fail "render with --eye, --target, --fov failed"
cmp -s "$dir/pics/frame.0002.png" "$dir/pics-eye/frame.0002.png" && fail "--eye and --target did not move the camera"
if "$spall" render "$dir/out" --eye 1,2 2> "$dir/err.txt"; then fail "render accepted --eye 1,2"; fi
grep -q "eye" "$dir/err.txt" || fail "render error: $(cat "$dir/err.txt")"
if "$spall" render "$dir/out" --eye 0,0,1 --target 0,0,1 2> "$dir/err.txt"; then fail "render accepted an eye on its target"; fi
grep -q "same point" "$dir/err.txt" || fail "render error: $(cat "$dir/err.txt")"
if "$spall" run "$dir/scene.json" -o "$dir/neg" --threads -1 2> /dev/null; then fail "run accepted --threads -1"; fi
mkdir -p "$dir/empty"
if "$spall" render "$dir/empty" 2> "$dir/err.txt"; then fail "render accepted an empty directory"; fi
if "$spall" render "$dir/out" --frame 999 2> "$dir/err.txt"; then fail "render accepted a missing frame"; fi
grep -q "frame 999 does not exist" "$dir/err.txt" || fail "render error: $(cat "$dir/err.txt")"
mkdir -p "$dir/corrupt" && echo "garbage" > "$dir/corrupt/fragments.0000.vdb"
if "$spall" render "$dir/corrupt" 2> "$dir/err.txt"; then fail "render accepted a corrupt frame"; fi
grep -q "fragments.0000.vdb" "$dir/err.txt" || fail "render error: $(cat "$dir/err.txt")"

# inspect: text and JSON, a frame and a body; bad input named
"$spall" inspect "$dir/out" | grep -q "7 frames" || fail "inspect summary"
"$spall" inspect "$dir/out/history.h5" --json --frame 3 --body 0 | $py -c "import json,sys; j=json.load(sys.stdin); assert j['frame']['index']==3 and j['body']['id']==0"
# its size histogram by decades: every body of the last frame in the bucket its voxel count names
"$spall" inspect "$dir/out/history.h5" --json | $py -c "
import json, sys, h5py
j = json.load(sys.stdin); counts = j['frame']['fragment_voxel_counts']
f = h5py.File(sys.argv[1]); start = int(f['frames/body_offset'][-2]); vox = f['bodies/voxel_count'][start:]
edges = {'1': (1, 1), '2-9': (2, 9), '10-99': (10, 99), '100-999': (100, 999), '1000-9999': (1000, 9999), '>=10000': (10000, 1 << 62)}
for name, (lo, hi) in edges.items():
    assert counts[name] == sum(1 for v in vox if lo <= v <= hi), (name, counts, sorted(vox))
" "$dir/out/history.h5" || fail "inspect's size histogram"

if "$spall" inspect "$dir/out" --frame 99 2> "$dir/err.txt"; then fail "inspect accepted a missing frame"; fi
grep -q "frame 99 does not exist" "$dir/err.txt" || fail "inspect error: $(cat "$dir/err.txt")"
if "$spall" inspect "$dir/cube.obj" 2> "$dir/err.txt"; then fail "inspect accepted a non-HDF5 file"; fi
grep -q "not an HDF5 file" "$dir/err.txt" || fail "inspect error: $(cat "$dir/err.txt")"

# Debian's Blender imports debris.glb (one object per fragment, each where history.h5 puts it at
# every frame, within 1 mm), stages it and renders a frame that is not empty
blender -b --python "$(dirname "$0")/../tools/blender_import.py" -- "$dir/out" --check-history --render 3 "$dir/blender.png" --check-framing \
  > "$dir/blender.log" 2>&1 || fail "Blender import/render failed: $(grep -E "blender_import|Error" "$dir/blender.log" | tail -5)"
grep -q "largest position error" "$dir/blender.log" || fail "Blender did not check the positions"

# The film route: frames numbered from 1001 with a world-space `debris` level set; the level set
# holds the pieces' volume (within 6 %: interpolating the distance cuts their corners, 4 % of this
# wall's single voxels, 1.5 % of the default scene's bricks), and in Blender the
# volume sequence plays frame for frame with the glTF, under a camera that frames the debris
sed 's/"fracture": {"algorithm": "yield-limit"}}/"fracture": {"algorithm": "yield-limit"}, "output": {"debris_level_set": true, "first_frame": 1001}}/' \
  "$dir/scene.json" > "$dir/film.json"
grep -q first_frame "$dir/film.json" || fail "the film scene was not written"
"$spall" run "$dir/film.json" -o "$dir/film" --quiet --no-preview --gltf > /dev/null || fail "the film run failed"
[[ -e "$dir/film/fragments.1001.vdb" && -e "$dir/film/fragments.1007.vdb" && ! -e "$dir/film/fragments.0000.vdb" ]] \
  || fail "frames not numbered from 1001: $(ls "$dir/film" | head -3)"
$py - "$dir/film/fragments.1007.vdb" <<'PY' || fail "the debris level set"
import sys, numpy as np, pyopenvdb as vdb
grids, meta = vdb.readAll(sys.argv[1])
assert meta["frame"] == 1007 and meta["first_frame"] == 1001 and meta["frame_rate_hz"] == 24, meta
def volume(grid):
    points, quads = grid.convertToQuads()
    p = points[quads].astype(float) - points[0]
    return abs(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() + np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 2], p[:, 3])).sum()) / 6
pieces = sum(volume(g) for g in grids if g.name.startswith("fragment_"))
debris = volume(next(g for g in grids if g.name == "debris"))
print(f"debris level set {debris:.5f} m3, pieces {pieces:.5f} m3")
assert abs(debris - pieces) <= 0.06 * pieces, (debris, pieces)
PY
blender -b --python "$(dirname "$0")/../tools/blender_import.py" -- "$dir/film" --check-history --check-volumes --render 1007 "$dir/film.png" \
  --check-framing > "$dir/film.log" 2>&1 || fail "Blender's film route failed: $(grep -E "blender_import|Error" "$dir/film.log" | tail -5)"
grep -q "the volumes' mesh over 7 frames" "$dir/film.log" || fail "Blender did not check the volume sequence: $(tail -3 "$dir/film.log")"

# the h5py example of docs/file-formats.md, as written there
docs=$(dirname "$0")/../docs/file-formats.md
sed -n '/^```python/,/^```/p' "$docs" | sed '1d;$d' | sed "s#out/history.h5#$dir/out/history.h5#" > "$dir/example.py"
$py "$dir/example.py" | grep -q "bodies, heaviest" || fail "the documented h5py example does not run"

# interruption: Ctrl-C finishes the current frame; SIGKILL leaves complete frames and a readable history
cat > "$dir/long.json" <<'JSON'
{"voxel_size_m": 0.1, "duration_s": 30.0, "frame_rate_hz": 24, "seed": 5,
 "objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [2.0, 0.3, 1.5]},
              "position_m": [0, 0, 0.75], "material": "reinforced-concrete", "anchor": "ground"}],
 "charges": [{"position_m": [0.2, -2.0, 0.0], "tnt_kg": 0.5, "burst": "surface"}],
 "solver": {"sleep": false}}
JSON
for signal in INT KILL; do
  "$spall" run "$dir/long.json" -o "$dir/long_$signal" --quiet > /dev/null 2>&1 &
  pid=$!
  for _ in $(seq 100); do [[ -e "$dir/long_$signal/fragments.0010.vdb" ]] && break; sleep 0.1; done
  kill -$signal $pid
  set +e; wait $pid; code=$?; set -e
  if [[ $signal == INT ]]; then [[ $code == 130 ]] || fail "Ctrl-C exit code $code, expected 130"; fi
  $py - "$dir/long_$signal" <<'PY'
import glob, sys, h5py, pyopenvdb as vdb
out = sys.argv[1]
frames = sorted(glob.glob(out + "/fragments.*.vdb"))
for path in frames[-2:]:
    for m in vdb.readAllGridMetadata(path):
        vdb.read(path, m.name)
h = h5py.File(out + "/history.h5", "r")
assert h.attrs["run_complete"] == 0
n = len(h["frames/time_s"])
assert n >= 10 and abs(n - len(frames)) <= 1, (n, len(frames))
assert len(h["frames/body_offset"]) >= n + 1
PY
done
# spall debris: a wall blown down by a lattice run; every figure recomputed from history.h5 with
# numpy (tests/check_debris.py); an unfinished run is refused and leaves no report behind
cat > "$dir/debris.json" <<'JSON'
{"voxel_size_m": 0.1, "duration_s": 4.0, "frame_rate_hz": 24, "seed": 5,
 "objects": [{"name": "wall", "primitive": {"shape": "box", "size_m": [1.2, 0.2, 0.8]},
              "position_m": [0, 0, 0.4], "material": "brick-masonry", "anchor": "ground"}],
 "charges": [{"position_m": [0, -0.8, 0.2], "tnt_kg": 4.0}],
 "fracture": {"algorithm": "lattice"}}
JSON
"$spall" run "$dir/debris.json" -o "$dir/debris" --quiet --no-preview > /dev/null
"$spall" debris "$dir/debris" > "$dir/debris.txt" || fail "spall debris failed"
grep -q "hazardous fragment distance" "$dir/debris.txt" || fail "spall debris printed no summary"
$py "$(dirname "$0")/check_debris.py" "$dir/debris" || fail "debris figures differ from the recomputation"
$py - "$dir/debris" <<'PY'
import csv, sys, h5py
from PIL import Image
out = sys.argv[1]
rows = list(csv.DictReader(open(out + "/debris.csv")))
assert len(rows) == len(h5py.File(out + "/debris.h5")["fragments/id"]) > 10, len(rows)
for name in ("throw", "density", "mass"):
    Image.open(f"{out}/debris_{name}.png").load()
PY
if "$spall" debris "$dir/long_INT" 2> "$dir/debris.err"; then fail "spall debris accepted an unfinished run"; fi
grep -q "history.h5: the run is not complete" "$dir/debris.err" || fail "unclear refusal: $(cat "$dir/debris.err")"
[[ ! -e "$dir/long_INT/debris.h5" ]] || fail "a refused debris analysis left debris.h5"
# collision benchmark, smallest sizes: one JSON row per method and size, every method present
if "$spall" bench collisions --max-boundary-voxels 0 2> "$dir/bench.err"; then echo "bench accepted a size of 0"; exit 1; fi
grep -q "max-boundary-voxels" "$dir/bench.err"
"$spall" bench collisions --json --max-boundary-voxels 200 > "$dir/bench.json"
$py - "$dir/bench.json" <<'PY'
import json, sys
rows = json.load(open(sys.argv[1]))
methods = {r["method"] for r in rows}
assert {"none", "pairwise", "buckets", "tree-lookup"} <= methods, methods
for r in rows:
    assert set(r) == {"scene", "method", "boundary_voxels", "steps_per_s"}, r
    assert r["steps_per_s"] is None or r["steps_per_s"] > 0, r
assert {r["scene"] for r in rows} == {"pile", "explosion"}
PY

echo "cli integration: ok"
