# Blender's import of an FBX file's materials, as its Principled BSDF inputs, for the FBX material mapping test:
#   blender -b --factory-startup --python benches/blender_fbx_materials.py -- FILE.fbx OUT.json
# Writes, per material in the file's order of first use by a mesh slot: base colour (RGB), alpha, roughness,
# metallic, specular, emission (colour × strength), and whether the base colour has a texture.
import json
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.fbx(filepath=args[0])
out = {}
for m in bpy.data.materials:
    if not m.use_nodes:
        continue
    p = next((n for n in m.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)
    if p is None:
        continue
    i = p.inputs
    strength = i["Emission Strength"].default_value if "Emission Strength" in i else 1.0
    emission = i["Emission"] if "Emission" in i else i["Emission Color"]
    specular = i["Specular"] if "Specular" in i else i["Specular IOR Level"]
    out[m.name] = {
        "base_color": list(i["Base Color"].default_value)[:3],
        "alpha": i["Alpha"].default_value,
        "roughness": i["Roughness"].default_value,
        "metallic": i["Metallic"].default_value,
        "specular": specular.default_value,
        "emission": [c * strength for c in list(emission.default_value)[:3]],
        "textured": bool(i["Base Color"].is_linked),
        "blend": m.blend_method,
    }
with open(args[1], "w") as fh:
    json.dump(out, fh, indent=1, sort_keys=True)
