# vvgen's `.blend` import, run inside Blender:
#   blender -b --factory-startup --disable-autoexec FILE.blend --python blend_export.py -- '{"out": DIR, ...}'
# It exports what the manifest selects as one binary glTF with every animation baked per frame (object and bone
# transforms sampled after constraints and drivers, shape-key weights sampled), in Blender's own axes (+Z up,
# metres), and writes `info.json`: the scene's frame range and rate, the external files the .blend reads (the
# import's discovered inputs: linked libraries, images), and what vvgen should warn about. Any failure is one line
# on stderr starting `vvgen:`, with exit status 3.
#
# Deliberately dependency-free and deterministic: vvgen keys the import by this file's bytes, so editing it
# re-imports every .blend.
import json
import os
import sys


def fail(message):
    sys.stderr.write("vvgen: " + message + "\n")
    sys.stderr.flush()
    os._exit(3)


def main():
    import bpy

    args = json.loads(sys.argv[sys.argv.index("--") + 1])
    out = args["out"]
    try:
        import numpy  # noqa: F401  (Blender's glTF exporter needs it; Debian packages it apart)
    except ImportError:
        fail("Blender's glTF exporter needs numpy, which this Blender's Python lacks: "
             "install it (Debian/Ubuntu: apt install python3-numpy)")
    if not hasattr(bpy.ops.export_scene, "gltf"):
        fail("this Blender has no glTF exporter (the io_scene_gltf2 add-on)")

    # The scene: the named one, else the file's active one. The others are removed (the file is never saved),
    # so the exporter's "active scene" is the chosen one.
    scenes = sorted(s.name for s in bpy.data.scenes)
    scene = bpy.context.scene
    if args.get("scene") is not None:
        scene = bpy.data.scenes.get(args["scene"])
        if scene is None:
            fail("has no scene `%s`; its scenes: %s" % (args["scene"], ", ".join(scenes)))
    for s in list(bpy.data.scenes):
        if s != scene:
            bpy.data.scenes.remove(s)
    if bpy.context.window is not None:
        bpy.context.window.scene = scene
    view_layer = scene.view_layers[0]

    # What is exported: an object (with its children and the armatures that deform them), a collection (with
    # its children), or every object the scene renders.
    chosen = None
    if args.get("object") is not None:
        o = scene.objects.get(args["object"])
        if o is None:
            fail("scene `%s` has no object `%s`; its objects: %s"
                 % (scene.name, args["object"], ", ".join(sorted(x.name for x in scene.objects))))
        chosen = [o] + list(o.children_recursive)
    elif args.get("collection") is not None:
        c = bpy.data.collections.get(args["collection"])
        if c is None:
            fail("has no collection `%s`; its collections: %s"
                 % (args["collection"], ", ".join(sorted(x.name for x in bpy.data.collections))))
        chosen = list(c.all_objects)
    if chosen is not None:
        more = []
        for o in chosen:
            for m in getattr(o, "modifiers", []):
                if m.type == "ARMATURE" and m.object is not None:
                    more.append(m.object)
            if o.parent is not None and o.parent.type == "ARMATURE":
                more.append(o.parent)
        for o in scene.objects:
            o.select_set(False, view_layer=view_layer)
        for o in chosen + more:
            o.select_set(True, view_layer=view_layer)
        exported = chosen + more
    else:
        exported = [o for o in scene.objects if not o.hide_render]
    names = sorted({o.name for o in exported})
    if not any(o.type in ("MESH", "CURVE", "SURFACE", "META", "FONT") for o in exported):
        fail("scene `%s` has nothing to draw%s" % (scene.name, "" if chosen is None else " in what was selected"))

    # What the glTF exporter leaves out, said once per object so the user knows why the render differs.
    warnings = []
    for o in sorted(exported, key=lambda x: x.name):
        kept = [m for m in getattr(o, "modifiers", []) if m.type != "ARMATURE" and m.show_render]
        if kept:
            warnings.append("object `%s`: modifier(s) %s are not applied (only armatures deform it): apply them "
                            "in Blender, or export glTF with \"Apply Modifiers\""
                            % (o.name, ", ".join("`%s` (%s)" % (m.name, m.type.lower()) for m in kept)))

    # The files the import reads besides the .blend: its key's discovered inputs.
    deps = set()
    for p in bpy.utils.blend_paths(absolute=True, packed=False, local=False):
        p = os.path.normpath(bpy.path.abspath(p))
        deps.add(p)
    missing = sorted(p for p in deps if not os.path.isfile(p))
    for p in missing:
        warnings.append("names `%s`, which is missing (Blender draws it magenta): restore it, or pack the "
                        "file's resources (File > External Data > Pack Resources)" % p)

    glb = os.path.join(out, "scene.glb")
    result = bpy.ops.export_scene.gltf(
        filepath=glb,
        export_format="GLB",
        # Blender's own axes: vvgen loads the result +Z up, as Blender shows it.
        export_yup=False,
        use_selection=chosen is not None,
        use_renderable=chosen is None,
        use_active_scene=True,
        export_apply=False,
        export_animations=True,
        export_frame_range=True,
        export_frame_step=1,
        export_force_sampling=True,
        export_nla_strips=False,
        export_nla_strips_merged_animation_name="Animation",
        export_optimize_animation_size=False,
        export_def_bones=False,
        export_skins=True,
        export_all_influences=True,
        export_morph=True,
        export_morph_normal=True,
        export_colors=True,
        export_cameras=False,
        export_lights=False,
        export_extras=False,
        export_image_format="AUTO",
    )
    if "FINISHED" not in result or not os.path.isfile(glb):
        fail("Blender's glTF exporter failed")
    info = {
        "blender": bpy.app.version_string,
        "scene": scene.name,
        "scenes": scenes,
        "objects": names,
        "fps": scene.render.fps / scene.render.fps_base,
        "frame_start": scene.frame_start,
        "frame_end": scene.frame_end,
        "deps": sorted(deps),
        "warnings": warnings,
    }
    with open(os.path.join(out, "info.json"), "w") as f:
        json.dump(info, f, indent=1, sort_keys=True)


try:
    main()
except SystemExit:
    raise
except BaseException as e:  # noqa: BLE001  (any failure is reported as one line, never a Blender prompt)
    fail("%s: %s" % (type(e).__name__, e))
