"""A spall run in Blender: the debris as solid pieces from OUTDIR/debris.glb (per scene material
`<name>`, `<name> interior` and for masonry `<name> joint`), the charges as empties, optionally the
frames' `debris` level set as a volume sequence with one Volume to Mesh, and a stage (ground, sun,
sky, a camera framing the debris). Used by the add-on and by tools/blender_import.py.

Frames: the glTF's keys are in seconds from the run's start; the run's time t is frame
output.first_frame + t × frame_rate_hz (scene.json), in Blender as in the .vdb files' names.

Debian's Blender 3.4: the glTF importer needs import_shading 'FLAT' or 'SMOOTH' (its default path
uses np.bool, which Debian's numpy 1.24 no longer has), and Cycles needs use_denoising off (no
OpenImageDenoise).
"""
import glob
import json
import math
import os
import re

import bpy
from mathutils import Vector


class ImportFailed(Exception):
    pass


def run_scene(outdir):
    """The run's scene.json (the resolved scene, every key with its value)."""
    path = os.path.join(outdir, "scene.json")
    if not os.path.exists(path):
        raise ImportFailed(f"{path} does not exist: is {outdir} a spall run's output?")
    with open(path) as f:
        return json.load(f)


def import_debris(outdir, scene):
    """Imports debris.glb into `scene`, its animation starting at the run's first frame.
    Returns the fragment objects."""
    glb = os.path.join(outdir, "debris.glb")
    if not os.path.exists(glb):
        raise ImportFailed(f"{glb} does not exist: write it with `spall export gltf {outdir}` (or `spall run --gltf`)")
    spall_scene = run_scene(outdir)
    scene.render.fps = round(spall_scene["frame_rate_hz"])  # glTF keys are in seconds
    scene.render.fps_base = scene.render.fps / spall_scene["frame_rate_hz"]
    before = set(bpy.data.objects)
    bpy.ops.import_scene.gltf(filepath=glb, import_shading="FLAT")
    imported = [o for o in bpy.data.objects if o not in before]
    pieces = [o for o in imported if o.name.startswith("fragment_")]
    if not pieces:
        raise ImportFailed(f"{glb}: no fragment_<id> objects")
    first = int(spall_scene.get("output", {}).get("first_frame", 0))
    actions = {o.animation_data.action for o in pieces if o.animation_data and o.animation_data.action}
    for action in actions:
        for curve in action.fcurves:
            for key in curve.keyframe_points:
                for point in (key.co, key.handle_left, key.handle_right):
                    point.x += first
    last = max((k.co.x for a in actions for c in a.fcurves for k in c.keyframe_points), default=first)
    scene.frame_start, scene.frame_end = first, int(round(last))
    return pieces


def import_volumes(outdir, scene):
    """The frames' `debris` level set (output.debris_level_set) as a volume sequence that plays
    frame for frame with the glTF, and a mesh object `debris` made of it by one Volume to Mesh.
    Returns that mesh object."""
    spall_scene = run_scene(outdir)
    if not spall_scene.get("output", {}).get("debris_level_set", False):
        raise ImportFailed(f"{outdir}: its frames hold no `debris` grid: run the scene with \"output\": {{\"debris_level_set\": true}}")
    paths = sorted(glob.glob(os.path.join(outdir, "fragments.*.vdb")), key=lambda p: int(re.findall(r"\d+", os.path.basename(p))[0]))
    if not paths:
        raise ImportFailed(f"{outdir}: no fragments.NNNN.vdb frames")
    first = int(re.findall(r"\d+", os.path.basename(paths[0]))[0])
    volume = bpy.data.volumes.new("debris_frames")
    volume.filepath = paths[0]
    volume.is_sequence = True
    volume.frame_duration = len(paths)
    # Blender shows file number (scene frame − frame_start + 1 + frame_offset): scene frame F, file F.
    volume.frame_start = first
    volume.frame_offset = first - 1
    volume.sequence_mode = "CLIP"
    volume_object = bpy.data.objects.new("debris_frames", volume)
    volume_object.hide_render = True
    volume_object.hide_viewport = True
    scene.collection.objects.link(volume_object)
    mesh_object = bpy.data.objects.new("debris", bpy.data.meshes.new("debris"))
    materials = [m for m in bpy.data.materials if not m.name.endswith((" interior", " joint"))]
    if materials:
        mesh_object.data.materials.append(materials[0])  # the first object's material
    modifier = mesh_object.modifiers.new("debris level set", "VOLUME_TO_MESH")
    modifier.object = volume_object
    modifier.grid_name = "debris"
    modifier.resolution_mode = "GRID"
    modifier.threshold = 0.0  # the level set's zero: the pieces' surface
    scene.collection.objects.link(mesh_object)
    return mesh_object


def world_points(obj, depsgraph):
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    points = [evaluated.matrix_world @ v.co for v in mesh.vertices]
    evaluated.to_mesh_clear()
    return points


def box_of(points):
    lo = Vector((min(p.x for p in points), min(p.y for p in points), min(p.z for p in points)))
    hi = Vector((max(p.x for p in points), max(p.y for p in points), max(p.z for p in points)))
    return lo, hi


def weighted_quantile(values, weights, q):
    order = sorted(range(len(values)), key=lambda i: values[i])
    total, running = sum(weights), 0.0
    for i in order:
        running += weights[i]
        if running >= q * total:
            return values[i]
    return values[order[-1]]


def debris_box(scene, pieces, frames):
    """The box holding the debris at each of `frames`, less the 2 % of its volume furthest out
    each way (a piece's weight is its box's volume), so a stray brick does not shrink the rest to
    a corner: per axis, the 2 % quantile of the pieces' lower sides and the 98 % one of their
    upper sides."""
    lo, hi = Vector((math.inf,) * 3), Vector((-math.inf,) * 3)
    for frame in frames:
        scene.frame_set(frame)
        boxes = [box_of([o.matrix_world @ Vector(c) for c in o.bound_box]) for o in pieces
                 if o.matrix_world.to_scale().length > 1e-6]  # a piece not yet (or no longer) in the run has no size
        weights = [max((b - a).x * (b - a).y * (b - a).z, 1e-12) for a, b in boxes]
        for axis in range(3):
            lo[axis] = min(lo[axis], weighted_quantile([a[axis] for a, _ in boxes], weights, 0.02))
            hi[axis] = max(hi[axis], weighted_quantile([b[axis] for _, b in boxes], weights, 0.98))
    return lo, hi


def distance_to_frame(scene, camera, lo, hi):
    """How far back along its view the camera must stand, looking at the box's centre, for each of
    the box's corners to lie inside the picture with a 5 % margin (a perspective camera: a point
    o from the centre is in view while |o · right| ≤ (d − o · back) tan(fov_x / 2), and likewise up)."""
    axes = camera.rotation_euler.to_matrix()
    right, up, back = axes.col[0], axes.col[1], axes.col[2]
    aspect = scene.render.resolution_x / scene.render.resolution_y
    tan_x = math.tan(camera.data.angle_x / 2)
    tan_y = tan_x / aspect
    centre, distance = (lo + hi) / 2, 0.0
    for corner in range(8):
        point = Vector([hi[a] if corner >> a & 1 else lo[a] for a in range(3)])
        o = point - centre
        distance = max(distance, o.dot(back) + abs(o.dot(right)) / tan_x, o.dot(back) + abs(o.dot(up)) / tan_y)
    return 1.05 * distance


def stage(scene, pieces, frames):
    """Ground, sun, sky and a camera that sees the debris at `frames` filling the picture, exposed
    so the pieces keep their colours (Filmic, a dim sky, a darker ground)."""
    lo, hi = debris_box(scene, pieces, frames)
    centre, radius = (lo + hi) / 2, max((hi - lo).length / 2, 0.25)
    scene.render.resolution_x, scene.render.resolution_y = 480, 270

    bpy.ops.mesh.primitive_plane_add(size=max(radius * 12, 4.0), location=(centre.x, centre.y, 0.0))
    ground = bpy.context.active_object
    ground.name = "ground"
    ground_material = bpy.data.materials.new("ground")
    ground_material.use_nodes = True
    ground_material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.16, 0.16, 0.15, 1.0)
    ground_material.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.9
    ground.data.materials.append(ground_material)

    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.rotation_euler = Vector((0.55, 1.0, -0.45)).to_track_quat("-Z", "Y").to_euler()
    camera.location = centre + camera.rotation_euler.to_matrix() @ Vector((0.0, 0.0, distance_to_frame(scene, camera, lo, hi)))
    camera.data.clip_end = max(100.0, 4 * (camera.location - centre).length)
    scene.camera = camera

    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 3.0
    sun.data.angle = math.radians(3.0)
    sun.rotation_euler = (math.radians(50), 0.0, math.radians(-35))
    scene.collection.objects.link(sun)
    scene.world = bpy.data.worlds.new("sky")
    scene.world.use_nodes = True
    background = scene.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.42, 0.5, 0.62, 1.0)
    background.inputs["Strength"].default_value = 0.35

    scene.view_settings.view_transform = "Filmic"
    scene.view_settings.look = "Medium High Contrast"
    scene.view_settings.exposure = 0.0
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 16
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA"
    for stamp in [name for name in dir(scene.render) if name.startswith("use_stamp")]:
        setattr(scene.render, stamp, False)  # no date or render time in the file: the same run, the same bytes
    return camera


def build(outdir, volumes=False):
    """A fresh Blender scene of the run in `outdir`: returns (scene, pieces, debris mesh or None)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    pieces = import_debris(outdir, scene)
    debris = None
    if volumes:
        debris = import_volumes(outdir, scene)
        for piece in pieces:  # one route at a time: the volumes' mesh stands for the pieces
            piece.hide_render = True
            piece.hide_set(True)
    stage(scene, pieces, [scene.frame_start, (scene.frame_start + scene.frame_end) // 2, scene.frame_end])
    return scene, pieces, debris
