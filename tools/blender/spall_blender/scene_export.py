"""The Blender scene as a spall scene (docs/scene-format.md): each mesh marked as a spall object
written as an OBJ in world coordinates (metres: the scene's unit scale applied), each charge empty
as a charge at its place, the frame rate and first frame Blender's."""
import json
import os

import bpy


def metres_per_unit(scene):
    return scene.unit_settings.scale_length if scene.unit_settings.system != "NONE" else 1.0


def write_obj(obj, path, scale, depsgraph):
    """The object's evaluated mesh (modifiers applied) in world coordinates, times `scale`."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        with open(path, "w") as f:
            f.write(f"# {obj.name}, written by the spall add-on (metres, world coordinates)\n")
            for v in mesh.vertices:
                p = evaluated.matrix_world @ v.co * scale
                f.write(f"v {p.x:.9g} {p.y:.9g} {p.z:.9g}\n")
            for polygon in mesh.polygons:
                f.write("f " + " ".join(str(i + 1) for i in polygon.vertices) + "\n")
        return len(mesh.polygons)
    finally:
        evaluated.to_mesh_clear()


def spall_objects(scene):
    return [o for o in scene.objects if o.type == "MESH" and o.spall.role == "OBJECT"]


def spall_charges(scene):
    return [o for o in scene.objects if o.type == "EMPTY" and o.spall.role == "CHARGE"]


def write_scene(context, folder):
    """Writes folder/scene.json and folder/meshes/*.obj. Returns the scene file's path; raises
    ValueError naming what is missing."""
    scene = context.scene
    settings = scene.spall
    objects, charges = spall_objects(scene), spall_charges(scene)
    if not objects:
        raise ValueError("no mesh is marked as a spall object (select one and press Mark as Object)")
    if not charges:
        raise ValueError("no charge: press Add Charge")
    scale = metres_per_unit(scene)
    meshes = os.path.join(folder, "meshes")
    os.makedirs(meshes, exist_ok=True)
    depsgraph = context.evaluated_depsgraph_get()
    spec = {
        "voxel_size_m": settings.voxel_size_m,
        "duration_s": settings.duration_s,
        "frame_rate_hz": scene.render.fps / scene.render.fps_base,
        "seed": settings.seed,
        "objects": [],
        "charges": [],
        "output": {"first_frame": scene.frame_start, "debris_level_set": settings.debris_level_set},
    }
    for obj in objects:
        path = os.path.join(meshes, bpy.path.clean_name(obj.name) + ".obj")
        if write_obj(obj, path, scale, depsgraph) == 0:
            raise ValueError(f"{obj.name}: its mesh has no faces")
        spec["objects"].append({"name": obj.name, "mesh": os.path.relpath(path, folder),
                                "material": obj.spall.material, "anchor": obj.spall.anchor.lower()})
    for empty in charges:
        p = empty.matrix_world.translation * scale
        spec["charges"].append({"position_m": [p.x, p.y, p.z], "tnt_kg": empty.spall.tnt_kg})
    path = os.path.join(folder, "scene.json")
    with open(path, "w") as f:
        json.dump(spec, f, indent=1)
    return path
