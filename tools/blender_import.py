"""Import a spall run into Blender: the .vdb sequence as one volume, a volume material on the
`density` grid, a camera that frames it, a sun, Cycles on the CPU.

    blender -b --python tools/blender_import.py -- OUTDIR [--render FRAME OUT.png] [--save FILE.blend]

With --render the script renders one frame and exits non-zero if the picture is empty.
"""
import glob
import os
import sys

import bpy
from mathutils import Vector


def main(argv):
    if not argv:
        raise SystemExit("usage: blender -b --python blender_import.py -- OUTDIR [--render FRAME OUT.png] [--save FILE.blend]")
    outdir = os.path.abspath(argv[0])
    frames = sorted(glob.glob(os.path.join(outdir, "fragments.*.vdb")))
    if not frames:
        raise SystemExit(f"{outdir}: no fragments.NNNN.vdb frames")

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.object.volume_import(filepath=frames[0], directory=outdir + os.sep,
                                 files=[{"name": os.path.basename(f)} for f in frames])
    volume = bpy.context.selected_objects[0]
    volume.data.is_sequence = True
    volume.data.frame_duration = len(frames)
    volume.data.frame_start = 0
    scene.frame_start, scene.frame_end = 0, len(frames) - 1

    # Volume material on the world-space density grid (1 inside a fragment).
    material = bpy.data.materials.new("spall_debris")
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    shader = nodes.new("ShaderNodeVolumePrincipled")
    shader.inputs["Color"].default_value = (0.75, 0.35, 0.25, 1.0)
    shader.inputs["Density"].default_value = 20.0
    shader.inputs["Density Attribute"].default_value = "density"
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(shader.outputs["Volume"], output.inputs["Volume"])
    volume.data.materials.append(material)

    # Camera framing the first frame's bounds from the front-left and above, and a sun.
    bpy.context.view_layer.update()
    corners = [volume.matrix_world @ Vector(c) for c in volume.bound_box]
    centre = sum(corners, Vector()) / 8.0
    radius = max((c - centre).length for c in corners) or 1.0
    camera_data = bpy.data.cameras.new("camera")
    camera = bpy.data.objects.new("camera", camera_data)
    scene.collection.objects.link(camera)
    camera.location = centre + Vector((-0.55, -1.0, 0.5)).normalized() * radius * 3.2
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

    if "--save" in argv:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(argv[argv.index("--save") + 1]))
    if "--render" in argv:
        i = argv.index("--render")
        scene.frame_set(int(argv[i + 1]))
        scene.render.filepath = os.path.abspath(argv[i + 2])
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        pixels = list(image.pixels)
        reds = pixels[0::4]
        if max(reds) - min(reds) < 0.05:
            raise SystemExit(f"{scene.render.filepath}: the render is empty")
        print(f"rendered frame {argv[i + 1]} to {scene.render.filepath}")


main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
