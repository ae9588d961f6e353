"""spall in Blender's 3D view (sidebar › spall): mark meshes as the objects to blow up (material
preset, anchor), add charges of TNT as empties, run spall in the background with a progress bar
and a cancel button, and import the debris animation when it finishes (docs/vfx.md).
Install: Edit › Preferences › Add-ons › Install…, pick spall_blender.zip (built with spall, in its
build folder), tick "Physics: spall", and give the spall binary's path in its preferences."""
import math
import os
import shutil

import bpy

from . import importer, scene_export
from .job import SpallJob

bl_info = {
    "name": "spall",
    "description": "Debris from a physically based blast: set up, run and import spall",
    "author": "spall",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > spall",
    "category": "Physics",
}

# spall's presets (`spall run` names them when a scene asks for another; the add-on's test checks
# this list against it).
MATERIAL_PRESETS = ["brick-masonry", "concrete", "reinforced-concrete", "glass", "wood"]
MATERIAL_ITEMS = [(m, m, "") for m in MATERIAL_PRESETS]
ANCHOR_ITEMS = [("NONE", "None", "free"), ("GROUND", "Ground", "bonded to the ground where it touches it"),
                ("SUPPORTS", "Supports", "bonded to the ground and colliders")]
TNT_DENSITY_KG_M3 = 1600.0

_jobs = {}  # per scene name: the run in progress


def _preferences(context):
    return context.preferences.addons[__name__].preferences


class SpallPreferences(bpy.types.AddonPreferences):
    bl_idname = __name__
    spall_path: bpy.props.StringProperty(name="spall binary", subtype="FILE_PATH", default=shutil.which("spall") or "")


class SpallObjectSettings(bpy.types.PropertyGroup):
    role: bpy.props.EnumProperty(name="Role", items=[("NONE", "None", ""), ("OBJECT", "Object", "blown up by spall"),
                                                     ("CHARGE", "Charge", "a charge of TNT")], default="NONE")
    material: bpy.props.EnumProperty(name="Material", items=MATERIAL_ITEMS, default="brick-masonry")
    anchor: bpy.props.EnumProperty(name="Anchor", items=ANCHOR_ITEMS, default="GROUND")
    tnt_kg: bpy.props.FloatProperty(name="TNT (kg)", min=1e-4, max=1e6, default=1.0, update=lambda self, context: _size_charge(self.id_data))


class SpallSceneSettings(bpy.types.PropertyGroup):
    voxel_size_m: bpy.props.FloatProperty(name="Voxel size", min=0.002, max=10.0, default=0.05, unit="LENGTH", precision=3)
    duration_s: bpy.props.FloatProperty(name="Duration (s)", min=0.0, max=600.0, default=2.0)
    seed: bpy.props.IntProperty(name="Seed", min=0, default=1)
    debris_level_set: bpy.props.BoolProperty(name="Debris level set", default=False,
                                             description="Also write the frames' world-space `debris` grid (one Volume to Mesh for all the debris)")
    output_dir: bpy.props.StringProperty(name="Output", subtype="DIR_PATH", default="//spall_run")
    progress: bpy.props.FloatProperty(name="Progress", subtype="PERCENTAGE", min=0.0, max=100.0, default=0.0)
    status: bpy.props.StringProperty(name="Status", default="")


def _size_charge(empty):
    if empty.type == "EMPTY":
        empty.empty_display_size = (3.0 * empty.spall.tnt_kg / (4.0 * math.pi * TNT_DENSITY_KG_M3)) ** (1.0 / 3.0)


class SPALL_OT_mark_object(bpy.types.Operator):
    """Mark the selected meshes as objects spall blows up, in the panel's material and anchor"""
    bl_idname = "spall.mark_object"
    bl_label = "Mark as Object"
    bl_options = {"REGISTER", "UNDO"}
    material: bpy.props.EnumProperty(name="Material", items=MATERIAL_ITEMS, default="brick-masonry")
    anchor: bpy.props.EnumProperty(name="Anchor", items=ANCHOR_ITEMS, default="GROUND")

    def execute(self, context):
        meshes = [o for o in context.selected_objects if o.type == "MESH"]
        if not meshes:
            self.report({"ERROR"}, "select a mesh first")
            return {"CANCELLED"}
        for o in meshes:
            o.spall.role, o.spall.material, o.spall.anchor = "OBJECT", self.material, self.anchor
        return {"FINISHED"}


class SPALL_OT_add_charge(bpy.types.Operator):
    """Add a charge of TNT at the 3D cursor (an empty sized as the charge)"""
    bl_idname = "spall.add_charge"
    bl_label = "Add Charge"
    bl_options = {"REGISTER", "UNDO"}
    tnt_kg: bpy.props.FloatProperty(name="TNT (kg)", min=1e-4, max=1e6, default=1.0)

    def execute(self, context):
        empty = bpy.data.objects.new("charge", None)
        empty.empty_display_type = "SPHERE"
        empty.location = context.scene.cursor.location
        context.scene.collection.objects.link(empty)
        empty.spall.role, empty.spall.tnt_kg = "CHARGE", self.tnt_kg
        _size_charge(empty)
        return {"FINISHED"}


def _output_dir(scene):
    return os.path.abspath(bpy.path.abspath(scene.spall.output_dir))


def start_run(context):
    """Writes the scene and starts spall on it. Returns the job; raises ValueError with the reason."""
    scene = context.scene
    binary = bpy.path.abspath(_preferences(context).spall_path)
    if not binary or not os.path.isfile(binary):
        raise ValueError("set the spall binary's path in the add-on's preferences")
    folder = _output_dir(scene)
    source = os.path.join(folder, "source")
    os.makedirs(source, exist_ok=True)
    scene_path = scene_export.write_scene(context, source)
    job = SpallJob([binary, "run", scene_path, "-o", os.path.join(folder, "out"), "--overwrite", "--gltf", "--no-preview"],
                   scene.spall.duration_s)
    _jobs[scene.name] = job
    scene.spall.progress, scene.spall.status = 0.0, "starting"
    return job


def follow_run(context):
    """Updates the panel from the run; when it ends, imports the debris. Returns True while it runs."""
    scene = context.scene
    job = _jobs.get(scene.name)
    if job is None:
        return False
    code = job.poll()
    scene.spall.progress, scene.spall.status = 100.0 * job.fraction, job.status
    if code is None:
        return True
    del _jobs[scene.name]
    if job.cancelled:
        scene.spall.status = f"stopped: its frames are kept; resume with spall run --resume {os.path.join(_output_dir(scene), 'out')}"
    elif code != 0:
        scene.spall.status = "failed: " + job.error()
    else:
        import_result(context)
        scene.spall.status = "done"
    return False


DEBRIS_COLLECTION = "spall debris"


def import_result(context):
    """The debris into the present scene, in the collection `spall debris` in place of an earlier
    run's; the marked objects hidden (their debris stands for them)."""
    scene = context.scene
    debris = bpy.data.collections.get(DEBRIS_COLLECTION)
    if debris is None:
        debris = bpy.data.collections.new(DEBRIS_COLLECTION)
        scene.collection.children.link(debris)
    for o in list(debris.objects):
        bpy.data.objects.remove(o)
    before = set(bpy.data.objects)
    importer.import_debris(os.path.join(_output_dir(scene), "out"), scene)
    for o in [o for o in bpy.data.objects if o not in before]:
        if o.name.startswith("charge_"):
            bpy.data.objects.remove(o)  # the scene's own charge empties stay
            continue
        for collection in list(o.users_collection):
            collection.objects.unlink(o)
        debris.objects.link(o)
    for o in scene_export.spall_objects(scene):
        o.hide_render = True
        o.hide_set(True)


class SPALL_OT_run(bpy.types.Operator):
    """Run spall on this scene in the background and import the debris when it finishes"""
    bl_idname = "spall.run"
    bl_label = "Run spall"
    _timer = None

    def execute(self, context):
        try:
            start_run(context)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if bpy.app.background:
            return {"FINISHED"}  # no event loop: the caller follows the run (follow_run)
        self._timer = context.window_manager.event_timer_add(0.25, window=context.window)
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        running = follow_run(context)
        for area in context.screen.areas:
            area.tag_redraw()
        if running:
            return {"PASS_THROUGH"}
        context.window_manager.event_timer_remove(self._timer)
        return {"FINISHED"}


class SPALL_OT_cancel(bpy.types.Operator):
    """Stop the run: the frames written so far are kept, with a checkpoint to resume from"""
    bl_idname = "spall.cancel"
    bl_label = "Cancel"

    def execute(self, context):
        job = _jobs.get(context.scene.name)
        if job:
            job.cancel()
        return {"FINISHED"}


class SPALL_PT_panel(bpy.types.Panel):
    bl_label = "spall"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "spall"

    def draw(self, context):
        layout, settings = self.layout, context.scene.spall
        for name in ("voxel_size_m", "duration_s", "seed", "debris_level_set", "output_dir"):
            layout.prop(settings, name)
        obj = context.active_object
        if obj is not None and obj.spall.role == "OBJECT":
            box = layout.box()
            box.label(text=f"{obj.name}: spall object")
            box.prop(obj.spall, "material")
            box.prop(obj.spall, "anchor")
        elif obj is not None and obj.spall.role == "CHARGE":
            layout.box().prop(obj.spall, "tnt_kg")
        row = layout.row()
        row.operator(SPALL_OT_mark_object.bl_idname)
        row.operator(SPALL_OT_add_charge.bl_idname)
        if context.scene.name in _jobs:
            layout.prop(settings, "progress", slider=True, text=settings.status or "running")
            layout.operator(SPALL_OT_cancel.bl_idname)
        else:
            layout.operator(SPALL_OT_run.bl_idname)
            if settings.status:
                layout.label(text=settings.status)


_classes = (SpallPreferences, SpallObjectSettings, SpallSceneSettings, SPALL_OT_mark_object, SPALL_OT_add_charge, SPALL_OT_run,
            SPALL_OT_cancel, SPALL_PT_panel)


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.Object.spall = bpy.props.PointerProperty(type=SpallObjectSettings)
    bpy.types.Scene.spall = bpy.props.PointerProperty(type=SpallSceneSettings)


def unregister():
    del bpy.types.Scene.spall
    del bpy.types.Object.spall
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
