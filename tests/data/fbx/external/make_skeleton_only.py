# Writes skeleton_only.fbx into the folder given after `--` (Blender 3.4.1):
#   blender -b --python make_skeleton_only.py -- OUT
# A two-bone armature whose upper bone swings over 24 frames, exported without any mesh: what an animation-only
# download (Mixamo's "Without Skin") holds. vvgen must refuse it as a source with the way out.
import math
import os
import sys

import bpy

out = os.path.abspath(sys.argv[sys.argv.index("--") + 1])
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.object.armature_add(enter_editmode=True)
arm = bpy.context.active_object
arm.name = "Skeleton"
bones = arm.data.edit_bones
upper = bones.new("Upper")
upper.head, upper.tail = (0, 0, 1), (0, 0, 2)
upper.parent = bones["Bone"]
bpy.ops.object.mode_set(mode="POSE")
pose = arm.pose.bones["Upper"]
pose.rotation_mode = "XYZ"
for frame, angle in ((1, 0.0), (24, 60.0)):
    pose.rotation_euler = (math.radians(angle), 0, 0)
    pose.keyframe_insert("rotation_euler", frame=frame)
bpy.ops.object.mode_set(mode="OBJECT")
bpy.context.scene.frame_end = 24
bpy.ops.export_scene.fbx(filepath=os.path.join(out, "skeleton_only.fbx"), object_types={"ARMATURE"}, bake_anim=True)
