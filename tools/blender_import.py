"""Build a Blender scene a lighting artist can start from, out of a spall run: the debris as solid
pieces from OUTDIR/debris.glb (write it with `spall export gltf OUTDIR`) in its materials (per
scene material `<name>`, `<name> interior` and for masonry `<name> joint`), the charges as empties,
a ground, a sun, and a camera framing the action; Cycles on the CPU.

    blender -b --python tools/blender_import.py -- OUTDIR [--render FRAME OUT.png] [--save FILE.blend]
        [--check-history]

--render renders one frame and exits non-zero if the picture is empty. --check-history compares
every fragment's position at every frame with OUTDIR/history.h5 (within 1 mm) and exits non-zero
on a difference. Debian's Blender 3.4: the glTF importer needs import_shading 'FLAT' or 'SMOOTH'
(its default path uses np.bool, which Debian's numpy 1.24 no longer has), and Cycles needs
use_denoising off (no OpenImageDenoise).
"""
import json
import os
import sys

import bpy
from mathutils import Vector


def fail(message):
    print(f"blender_import: {message}", file=sys.stderr)
    sys.exit(1)


def import_debris(outdir):
    glb = os.path.join(outdir, "debris.glb")
    if not os.path.exists(glb):
        fail(f"{glb} does not exist: write it with `spall export gltf {outdir}` (or `spall run --gltf`)")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    with open(os.path.join(outdir, "scene.json")) as f:
        spall_scene = json.load(f)
    scene.render.fps = round(spall_scene["frame_rate_hz"])  # glTF keys are in seconds
    bpy.ops.import_scene.gltf(filepath=glb, import_shading="FLAT")
    pieces = [o for o in scene.objects if o.name.startswith("fragment_")]
    if not pieces:
        fail(f"{glb}: no fragment_<id> objects")
    frames = [fc for o in pieces if o.animation_data and o.animation_data.action
              for fc in o.animation_data.action.fcurves]
    last = max((k.co.x for fc in frames for k in fc.keyframe_points), default=0)
    scene.frame_start, scene.frame_end = 0, int(round(last))
    return scene, pieces, spall_scene


def bounds(scene, pieces, frame):
    scene.frame_set(frame)
    points = [o.matrix_world @ Vector(c) for o in pieces if o.matrix_world.to_scale().length > 1e-6 for c in o.bound_box]
    lo = Vector((min(p.x for p in points), min(p.y for p in points), min(p.z for p in points)))
    hi = Vector((max(p.x for p in points), max(p.y for p in points), max(p.z for p in points)))
    return lo, hi


def stage(scene, pieces):
    """Ground, sun, sky and a camera that sees the debris at the start and at the end."""
    lo0, hi0 = bounds(scene, pieces, scene.frame_start)
    lo1, hi1 = bounds(scene, pieces, scene.frame_end)
    lo = Vector((min(lo0.x, lo1.x), min(lo0.y, lo1.y), min(lo0.z, lo1.z)))
    hi = Vector((max(hi0.x, hi1.x), max(hi0.y, hi1.y), max(hi0.z, hi1.z)))
    centre, radius = (lo + hi) / 2, max((hi - lo).length / 2, 0.5)

    bpy.ops.mesh.primitive_plane_add(size=radius * 8, location=(centre.x, centre.y, 0.0))
    ground = bpy.context.active_object
    ground.name = "ground"
    ground_material = bpy.data.materials.new("ground")
    ground_material.diffuse_color = (0.35, 0.36, 0.33, 1.0)
    ground_material.use_nodes = True
    ground_material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.35, 0.36, 0.33, 1.0)
    ground.data.materials.append(ground_material)

    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.location = centre + Vector((-0.55, -1.0, 0.45)).normalized() * radius * 3.0
    camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 4.0
    sun.rotation_euler = (0.7, 0.2, -0.6)
    scene.collection.objects.link(sun)
    scene.world = bpy.data.worlds.new("world")
    scene.world.color = (0.6, 0.65, 0.75)

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 16
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.render.resolution_x, scene.render.resolution_y = 480, 270
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"


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
        scene.frame_set(int(round(t * scene.render.fps)))
        for row in range(offsets[f], offsets[f + 1]):
            o = by_name.get(f"fragment_{ids[row]}")
            if o is None:
                fail(f"frame {f}: no object for body {ids[row]}")
            worst = max(worst, float(np.linalg.norm(np.array(o.matrix_world.translation) - positions[row])))
    print(f"blender_import: {len(by_name)} fragments over {len(times)} frames, largest position error {worst * 1e3:.3f} mm")
    if worst > 1e-3:
        fail(f"a fragment is {worst * 1e3:.3f} mm from where history.h5 puts it")


def main(argv):
    if not argv:
        fail("usage: blender -b --python blender_import.py -- OUTDIR [--render FRAME OUT.png] [--save FILE.blend] [--check-history]")
    outdir = os.path.abspath(argv[0])
    scene, pieces, _ = import_debris(outdir)
    if "--check-history" in argv:
        check_history(outdir, scene, pieces)
    stage(scene, pieces)
    if "--save" in argv:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(argv[argv.index("--save") + 1]))
    if "--render" in argv:
        i = argv.index("--render")
        scene.frame_set(int(argv[i + 1]))
        scene.render.filepath = os.path.abspath(argv[i + 2])
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        reds = list(image.pixels)[0::4]
        if max(reds) - min(reds) < 0.05:
            fail(f"{scene.render.filepath}: the render is empty")
        print(f"rendered frame {argv[i + 1]} to {scene.render.filepath}")


main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
