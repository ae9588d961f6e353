"""The Blender add-on driven through bpy in `blender -b` (tests/blender_addon.sh): installed from its
zip as a user would, a wall marked with a material and anchor, a charge added, spall run in the
background and followed to the end, the debris imported from the film's first frame; run again, the
new debris replaces the old; a run stopped with Cancel keeps its frames and imports nothing; the
add-on's presets are spall's.

    blender -b --factory-startup --python tests/blender_addon_test.py -- ADDON.zip SPALL WORKDIR
"""
import glob
import json
import os
import re
import subprocess
import sys
import time

import bpy

zip_path, spall, work = sys.argv[sys.argv.index("--") + 1:][:3]


def fail(message):
    print(f"blender_addon_test: FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)


bpy.ops.wm.read_factory_settings(use_empty=True)  # first: it would disable the add-on
bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
bpy.ops.preferences.addon_enable(module="spall_blender")
import spall_blender  # noqa: E402  (installed just now)

bpy.context.preferences.addons["spall_blender"].preferences.spall_path = spall

# The presets the add-on offers are the ones spall knows (spall names them for an unknown one).
with open(os.path.join(work, "unknown-material.json"), "w") as f:
    json.dump({"objects": [{"primitive": {"shape": "box", "size_m": [1, 1, 1]}, "material": "?"}]}, f)
said = subprocess.run([spall, "run", os.path.join(work, "unknown-material.json"), "-o", os.path.join(work, "never")],
                      capture_output=True, text=True).stderr
known = re.search(r"presets: ([^)]*)\)", said)
check(known and sorted(known.group(1).split(", ")) == sorted(spall_blender.MATERIAL_PRESETS),
      f"the add-on offers {spall_blender.MATERIAL_PRESETS}, spall says: {said.strip()}")

scene = bpy.context.scene
scene.frame_start = 1001
scene.render.fps = 24
settings = scene.spall
settings.voxel_size_m, settings.duration_s, settings.seed = 0.1, 0.25, 5
settings.output_dir = os.path.join(work, "addon_run")

# A brick wall 2 x 0.3 x 1.5 m standing on the ground, and 0.5 kg of TNT 1 m in front of it.
bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 0.75))
wall = bpy.context.active_object
wall.name = "wall"
wall.scale = (2.0, 0.3, 1.5)
check(bpy.ops.spall.mark_object(material="brick-masonry", anchor="GROUND") == {"FINISHED"}, "marking the wall failed")
scene.cursor.location = (0.2, -1.0, 0.0)
check(bpy.ops.spall.add_charge(tnt_kg=0.5) == {"FINISHED"}, "adding the charge failed")
charge = [o for o in scene.objects if o.spall.role == "CHARGE"][0]
check(abs(charge.empty_display_size - 0.0423) < 1e-3, f"the charge's sphere is {charge.empty_display_size} m, 0.5 kg of TNT is 0.0423 m")


def follow(what, stop_after_progress=False):
    """Calls the add-on's own update, as its timer does, until the run ends. Returns the progress seen."""
    seen, start = [], time.time()
    while spall_blender.follow_run(bpy.context):
        seen.append(scene.spall.progress)
        if stop_after_progress and scene.spall.progress > 0:
            check(bpy.ops.spall.cancel() == {"FINISHED"}, "cancel failed")
            stop_after_progress = False
        check(time.time() - start < 600, f"{what}: still running after 10 minutes")
        time.sleep(0.1)
    return seen


check(bpy.ops.spall.run() == {"FINISHED"}, "starting the run failed")
job = spall_blender._jobs[scene.name]
seen = follow("the run")
check(scene.spall.status == "done" and scene.spall.progress == 100.0, f"the run ended with: {scene.spall.status}, {scene.spall.progress} %")
# What the panel showed depends on when the timer looked; what the run reported does not: a
# progress after each of its 7 frames, rising.
check(seen == sorted(seen), f"the panel's progress fell: {seen}")
check(job.fractions == sorted(job.fractions) and len([f for f in job.fractions if 0 < f < 1]) >= 5,
      f"progress did not rise through the run: {job.fractions}")

# What spall was given: the wall's mesh in metres and world coordinates, its material and anchor,
# the charge, Blender's frame rate and first frame.
source = json.load(open(os.path.join(work, "addon_run", "source", "scene.json")))
check(source["objects"][0]["material"] == "brick-masonry" and source["objects"][0]["anchor"] == "ground", f"{source['objects']}")
check(len(source["charges"]) == 1 and source["charges"][0]["tnt_kg"] == 0.5
      and max(abs(a - b) for a, b in zip(source["charges"][0]["position_m"], [0.2, -1.0, 0.0])) < 1e-6, f"{source['charges']}")
check(source["frame_rate_hz"] == 24 and source["output"]["first_frame"] == 1001, f"{source}")
out = os.path.join(work, "addon_run", "out")
check(os.path.exists(os.path.join(out, "fragments.1001.vdb")), f"no frame 1001 in {sorted(os.listdir(out))[:4]}")

# The debris in the scene: pieces keyed from frame 1001, the wall's own object hidden behind them.
pieces = [o for o in scene.objects if o.name.startswith("fragment_")]
check(len(pieces) > 1, f"{len(pieces)} pieces imported: the wall should break")
keys = [k.co.x for o in pieces if o.animation_data and o.animation_data.action for c in o.animation_data.action.fcurves for k in c.keyframe_points]
check(min(keys) == 1001 and scene.frame_start == 1001, f"the debris starts at frame {min(keys)}, the scene at {scene.frame_start}")
check(wall.hide_render and wall.hide_get(), "the marked wall is still shown over its debris")
check(not [o for o in scene.objects if o.name.startswith("charge_")], "the run's charge was imported beside the scene's own")
print(f"blender_addon_test: {len(pieces)} pieces from frame {int(min(keys))}, {len(job.fractions)} progress reports")

# Run again: the new debris replaces the old (in the collection `spall debris`), not beside it.
check(bpy.ops.spall.run() == {"FINISHED"}, "starting the run again failed")
follow("the second run")
again = [o for o in scene.objects if o.name.startswith("fragment_")]
check(len(again) == len(pieces) and all("." not in o.name for o in again),
      f"the second run left {len(again)} pieces ({sorted(o.name for o in again)[:4]} …), the first {len(pieces)}")
check(all(o.users_collection[0].name == "spall debris" for o in again), "the debris is not in its collection")

# A longer run stopped with Cancel: its frames stay, readable, with a checkpoint; nothing imported.
settings.duration_s = 30.0
settings.output_dir = os.path.join(work, "addon_cancelled")
before = len([o for o in scene.objects if o.name.startswith("fragment_")])
check(bpy.ops.spall.run() == {"FINISHED"}, "starting the second run failed")
follow("the cancelled run", stop_after_progress=True)
check(scene.spall.status.startswith("stopped"), f"the cancelled run ended with: {scene.spall.status}")
cancelled = os.path.join(work, "addon_cancelled", "out")
check(os.path.exists(os.path.join(cancelled, "checkpoint.spall")), f"no checkpoint in {sorted(os.listdir(cancelled))}")
check(glob.glob(os.path.join(cancelled, "fragments.*.vdb")), "the cancelled run kept no frames")
check(len([o for o in scene.objects if o.name.startswith("fragment_")]) == before, "a cancelled run imported debris")
print("blender_addon_test: passed")
