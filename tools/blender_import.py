"""Build a Blender scene a lighting artist can start from, out of a spall run: the debris as solid
pieces from OUTDIR/debris.glb (write it with `spall export gltf OUTDIR`) in its materials, or with
--volumes as one mesh made by Volume to Mesh of the frames' `debris` level set (run the scene with
"output": {"debris_level_set": true}); the charges as empties, a ground, a sun, and a camera framing
the debris; Cycles on the CPU. The work is the add-on's (tools/blender/spall_blender/importer.py).

    blender -b --python tools/blender_import.py -- OUTDIR [--volumes] [--render FRAME OUT.png]
        [--save FILE.blend] [--check-history] [--check-volumes] [--check-framing]

--render renders one frame (numbered as the run's files are) and exits non-zero if the picture is
empty. --check-history compares every fragment's position at every frame with OUTDIR/history.h5
(within 1 mm); --check-volumes compares the volumes' mesh with the pieces at every frame (their
boxes within two level-set samples: interpolating the distance cuts corners); --check-framing renders the debris alone and checks
it fills the picture's middle and is not washed out. Each exits non-zero on a difference.
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "blender"))
from spall_blender import importer  # noqa: E402


def fail(message):
    print(f"blender_import: {message}", file=sys.stderr)
    sys.exit(1)


def check_history(outdir, scene, pieces):
    """Every body of every frame: its object's origin (the centre of mass) where history.h5 says."""
    import h5py
    import numpy as np
    by_name = {o.name: o for o in pieces}
    with h5py.File(os.path.join(outdir, "history.h5"), "r") as h:
        times, offsets = h["frames/time_s"][:], h["frames/body_offset"][:]
        ids, positions = h["bodies/id"][:], h["bodies/position_m"][:]
    if len(by_name) != len(set(ids.tolist())):
        fail(f"{len(by_name)} fragment objects, {len(set(ids.tolist()))} bodies in the history")
    worst = 0.0
    for f, t in enumerate(times):
        scene.frame_set(scene.frame_start + int(round(t * scene.render.fps / scene.render.fps_base)))
        for row in range(offsets[f], offsets[f + 1]):
            o = by_name.get(f"fragment_{ids[row]}")
            if o is None:
                fail(f"frame {f}: no object for body {ids[row]}")
            worst = max(worst, float(np.linalg.norm(np.array(o.matrix_world.translation) - positions[row])))
    print(f"blender_import: {len(by_name)} fragments over {len(times)} frames, largest position error {worst * 1e3:.3f} mm")
    if worst > 1e-3:
        fail(f"a fragment is {worst * 1e3:.3f} mm from where history.h5 puts it")


def check_volumes(outdir, scene, pieces, debris):
    """At every frame the volumes' mesh spans the box the pieces' meshes span: a sequence a frame
    behind, or a piece missing, is off by its motion or its size."""
    spall_scene = importer.run_scene(outdir)
    sample = spall_scene["voxel_size_m"] / spall_scene["output"]["level_set_subdivisions"]
    worst = 0.0
    for frame in range(scene.frame_start, scene.frame_end + 1):
        scene.frame_set(frame)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        points = importer.world_points(debris, depsgraph)
        if not points:
            fail(f"frame {frame}: the volumes' mesh is empty")
        shown = [p for o in pieces if o.matrix_world.to_scale().length > 1e-6 for p in importer.world_points(o, depsgraph)]
        (lo, hi), (plo, phi) = importer.box_of(points), importer.box_of(shown)
        worst = max(worst, max((lo - plo).length, (hi - phi).length))
    print(f"blender_import: the volumes' mesh over {scene.frame_end - scene.frame_start + 1} frames, "
          f"largest difference from the pieces' box {worst * 1e3:.1f} mm (a sample is {sample * 1e3:.1f} mm)")
    if worst > 2 * sample:
        fail(f"the volumes' mesh is {worst * 1e3:.1f} mm from the pieces: the sequence does not play with the glTF")


def render(scene, frame, path):
    """Renders `frame` to `path` and returns its pixels (RGBA, flat)."""
    scene.frame_set(frame)
    scene.render.filepath = os.path.abspath(path)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(scene.render.filepath)
    pixels = list(image.pixels)
    bpy.data.images.remove(image)
    return pixels


def check_framing(scene, frame, path):
    """The debris alone (no ground, a transparent sky): its pixels' box is centred in the picture
    and spans at least a third of it, and in the full render under 5 % of them are clipped white."""
    ground = bpy.data.objects["ground"]
    ground.hide_render, scene.render.film_transparent = True, True
    alpha = render(scene, frame, path)[3::4]
    ground.hide_render, scene.render.film_transparent = False, False
    width, height = scene.render.resolution_x, scene.render.resolution_y
    covered = [i for i, a in enumerate(alpha) if a > 0.5]
    if not covered:
        fail("no debris in the picture")
    xs, ys = [i % width for i in covered], [i // width for i in covered]
    centre = ((min(xs) + max(xs)) / 2 / width, (min(ys) + max(ys)) / 2 / height)
    span = max((max(xs) - min(xs)) / width, (max(ys) - min(ys)) / height)
    colour = render(scene, frame, path)
    clipped = sum(1 for i in covered if min(colour[4 * i:4 * i + 3]) > 0.98) / len(covered)
    print(f"blender_import: debris spans {span:.2f} of the picture, centred at ({centre[0]:.2f}, {centre[1]:.2f}), "
          f"{clipped * 100:.1f} % of its pixels clipped")
    if not (0.3 <= centre[0] <= 0.7 and 0.3 <= centre[1] <= 0.7) or span < 1 / 3 or clipped > 0.05:
        fail("the camera does not frame the debris, or the light washes it out")


def main(argv):
    if not argv:
        fail("usage: blender -b --python blender_import.py -- OUTDIR [--volumes] [--render FRAME OUT.png] [--save FILE.blend] "
             "[--check-history] [--check-volumes] [--check-framing]")
    outdir = os.path.abspath(argv[0])
    try:
        scene, pieces, debris = importer.build(outdir, volumes="--volumes" in argv or "--check-volumes" in argv)
    except importer.ImportFailed as e:
        fail(str(e))
    if "--check-history" in argv:
        check_history(outdir, scene, pieces)
    if "--check-volumes" in argv:
        check_volumes(outdir, scene, pieces, debris)
    if "--save" in argv:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(argv[argv.index("--save") + 1]))
    if "--render" in argv:
        i = argv.index("--render")
        frame, path = int(argv[i + 1]), argv[i + 2]
        if "--check-framing" in argv:
            check_framing(scene, frame, path)
        reds = render(scene, frame, path)[0::4]
        if max(reds) - min(reds) < 0.05:
            fail(f"{path}: the render is empty")
        print(f"rendered frame {frame} to {os.path.abspath(path)}")


main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
