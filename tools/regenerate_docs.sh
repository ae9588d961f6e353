#!/usr/bin/env bash
# Makes every picture README.md and docs/ show, from the built binaries, so that a change to
# what spall computes cannot leave the pictures describing an older build (issue 50).
#
#   tools/regenerate_docs.sh [--check] [--full] [--keep DIR] [BUILD_DIR]     (BUILD_DIR: build)
#
# Without --full, the pictures that take about a minute in all: the default scene, the loads on
# its wall, where its debris lands and Blender's render of it, its wall during the deformable phase at 2 ms intervals,
# the timber post. --full adds the concrete slab,
# the glass pane and its cracks, a block thrown at a pane at 2 ms intervals, the house wall (3 minutes), the 3 M-voxel wall (8 minutes) and
# the accuracy plots (whose run times vary from run to run, so --check leaves them out).
# --check writes into a scratch directory and compares each picture byte for byte with the one
# in docs/images (runs are deterministic); it exits 1 naming those that differ. ctest runs
# `--check` (test docs_pictures). Without --check the pictures in docs/images are replaced.
# --keep DIR runs into DIR and keeps it: the runs' history.h5 (spall inspect, spall debris) and
# accuracy/accuracy.csv hold the figures the text beside each picture quotes, to update with it.
set -euo pipefail

check=0
full=0
build=build
keep=
while [ $# -gt 0 ]; do
    case "$1" in
        --check) check=1 ;;
        --full) full=1 ;;
        --keep) keep=${2:?regenerate_docs.sh: --keep needs a directory}; shift ;;
        -h|--help) sed -n 2,16p "$0"; exit 0 ;;
        -*) echo "regenerate_docs.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
        *) build=$1 ;;
    esac
    shift
done
root=$(cd "$(dirname "$0")/.." && pwd)
spall=$(cd "$build" && pwd)/spall
[ -x "$spall" ] || { echo "regenerate_docs.sh: no spall binary at $spall (build first: tools/build.sh)" >&2; exit 2; }
images=$root/docs/images
if [ -n "$keep" ]; then
    mkdir -p "$keep"
    scratch=$(cd "$keep" && pwd)
else
    scratch=$(mktemp -d)
    trap 'rm -rf "$scratch"' EXIT
fi
differ=()

# scene_with BASE OUT KEY=JSON ...: BASE with the dotted keys set (charges.0.tnt_kg=20).
scene_with() {
    local base=$1 out=$2
    shift 2
    python3 - "$base" "$out" "$@" <<'EOF'
import json, sys
scene = json.load(open(sys.argv[1]))
for assignment in sys.argv[3:]:
    path, value = assignment.split("=", 1)
    keys = path.split(".")
    node = scene
    for key in keys[:-1]:
        node = node[int(key)] if isinstance(node, list) else node.setdefault(key, {})
    node[keys[-1]] = json.loads(value)
json.dump(scene, open(sys.argv[2], "w"), indent=2)
EOF
}

# place PICTURE MADE: MADE is docs/images/PICTURE as this build makes it.
place() {
    local picture=$1 made=$2
    if [ "$check" = 1 ]; then
        if cmp -s "$made" "$images/$picture"; then echo "  $picture: as committed"; else echo "  $picture: DIFFERS"; differ+=("$picture"); fi
    else
        cp "$made" "$images/$picture"
        echo "  $picture: written"
    fi
}

# run_scene NAME [SCENE]: a run of SCENE (default: the built-in scene) into $scratch/NAME.
run_scene() {
    local name=$1
    shift
    echo "running $name ..."
    "$spall" run "$@" -o "$scratch/$name" --overwrite --quiet >/dev/null
}

run_scene default
place default-scene.png "$scratch/default/preview.png"
"$spall" loads "$scratch/default" --quiet >/dev/null
place default-wall-loads.png "$scratch/default/loads_front.png"
"$spall" debris "$scratch/default" >/dev/null
place default-debris-density.png "$scratch/default/debris_density.png"

# Blender's Cycles render of the glTF (tools/blender_import.py); its pixels are the same run to
# run, the render's timings in its metadata are not, so the picture is saved again without them.
"$spall" export gltf "$scratch/default" --quiet >/dev/null
blender -b --python "$root/tools/blender_import.py" -- "$scratch/default" --render 24 "$scratch/blender.png" >/dev/null 2>&1
/usr/bin/python3 -c "import sys; from PIL import Image; Image.open(sys.argv[1]).save(sys.argv[2])" "$scratch/blender.png" "$scratch/default-blender.png"
place default-blender.png "$scratch/default-blender.png"

scene_with "$root/assets/scenes/default.json" "$scratch/phase.json" frame_rate_hz=500 duration_s=0.016
run_scene phase "$scratch/phase.json" --no-preview
"$spall" render "$scratch/phase" --sheet -o "$scratch/phase-sheet" >/dev/null
place default-wall-phase-2ms.png "$scratch/phase-sheet/sheet.png"

run_scene timber-post "$root/assets/scenes/timber-post.json"
place timber-post.png "$scratch/timber-post/preview.png"

if [ "$full" = 1 ]; then
    run_scene concrete-slab "$root/assets/scenes/concrete-slab-spall.json"
    place concrete-slab-spall.png "$scratch/concrete-slab/preview.png"

    run_scene glass-pane "$root/assets/scenes/glass-pane.json"
    place glass-pane.png "$scratch/glass-pane/preview.png"
    /usr/bin/python3 "$root/tools/fragments_front_view.py" "$scratch/glass-pane/fragments.0002.vdb" "$scratch/glass-cracks.png" >/dev/null
    place glass-pane-cracks.png "$scratch/glass-cracks.png"

    run_scene block-at-pane "$root/assets/scenes/block-at-pane.json" --no-preview
    "$spall" render "$scratch/block-at-pane" --sheet -o "$scratch/block-at-pane-sheet" >/dev/null
    place block-at-pane-2ms.png "$scratch/block-at-pane-sheet/sheet.png"

    run_scene house-wall "$root/assets/scenes/house-wall.json"
    place house-wall.png "$scratch/house-wall/preview.png"

    scene_with "$root/assets/scenes/brick-wall-lattice.json" "$scratch/wall-3m.json" voxel_size_m=0.01 lattice.particle_voxels=3
    run_scene wall-3m "$scratch/wall-3m.json"
    place wall-3m-voxels.png "$scratch/wall-3m/preview.png"

    if [ "$check" = 0 ]; then
        echo "running spall bench accuracy ..."
        rm -rf "$scratch/accuracy"
        "$spall" bench accuracy -o "$scratch/accuracy" --scene-duration 0.3 >/dev/null
        for plot in accuracy-integrators-friedlander-pulse.png accuracy-default-scene.png; do
            place "$plot" "$scratch/accuracy/$plot"
        done
    fi
fi

if [ "${#differ[@]}" -gt 0 ]; then
    echo "regenerate_docs.sh: ${differ[*]} no longer show(s) what this build makes; run tools/regenerate_docs.sh$([ "$full" = 1 ] && echo " --full") and update the text that quotes them" >&2
    exit 1
fi
