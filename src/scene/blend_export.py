# vvgen's `.blend` import, run inside Blender:
#   blender -b --factory-startup --disable-autoexec FILE.blend --python blend_export.py -- '{"out": DIR, ...}'
# Every frame asked for is evaluated by Blender (frame_set: actions, NLA, drivers, constraints, shape keys,
# armatures, every modifier) and exported as a static glTF of what the manifest selects, in Blender's own axes
# (+Z up, metres): `frame_NNNNN.gltf` + `.bin`, textures once in `textures/`. So each frame is what Blender shows,
# not what a glTF animation can express. `info.json` says the file's frame range and rate, the frames exported,
# the files written, the external files the .blend reads (the import's discovered inputs: linked libraries,
# images) and what vvgen should warn about. Any failure is one line on stderr starting `vvgen:`, exit status 3.
#
# Deliberately dependency-free and deterministic: vvgen keys the import by this file's bytes, so editing it
# re-imports every .blend.
import json
import os
import sys


MAX_FRAMES = 100000


def animated():
    """Whether anything in the file moves over time: an action, an NLA track or a driver on any datablock."""
    import bpy
    for coll in (bpy.data.objects, bpy.data.shape_keys, bpy.data.armatures, bpy.data.meshes, bpy.data.materials,
                 bpy.data.node_groups, bpy.data.scenes, bpy.data.cameras, bpy.data.lights):
        for idb in coll:
            a = getattr(idb, "animation_data", None)
            if a is not None and (a.action is not None or len(a.nla_tracks) or len(a.drivers)):
                return True
    return False


# Object types Blender's glTF exporter skips.
UNEXPORTED = ("POINTCLOUD", "CURVES", "VOLUME", "GPENCIL", "GREASEPENCIL")


def exporter_options(bpy, options):
    """The glTF exporter's options as this Blender's exporter names them. Blender 4.2 replaced `export_colors`
    (every mesh's colour attribute) with `export_vertex_color`, whose "ACTIVE" exports the active one whether or
    not a material reads it; 4.x refused the old name."""
    names = bpy.ops.export_scene.gltf.get_rna_type().properties.keys()
    if "export_colors" not in names and "export_vertex_color" in names:
        options["export_vertex_color"] = "ACTIVE" if options.pop("export_colors") else "NONE"
    if "export_gn_mesh" not in names:
        del options["export_gn_mesh"]
    return options


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

    # What is exported: an object (with its children), a collection (with its child collections), or every
    # object the scene renders.
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
        # Armatures, hooks and the like need not be exported: each frame is the evaluated mesh.
        for o in scene.objects:
            o.select_set(False, view_layer=view_layer)
        for o in chosen:
            o.select_set(True, view_layer=view_layer)
        exported = chosen
    else:
        exported = [o for o in scene.objects if not o.hide_render]
    names = sorted({o.name for o in exported})

    # The frames: the manifest's `frames` (Blender's frame numbers), the file's range for what it leaves out
    # (vvgen resolves them alike from `info.json`'s facts: `FrameSpec::resolve`).
    is_animated = animated()
    spec = args.get("frames") or {}
    step = max(1, int(spec.get("step") or 1))
    first = spec.get("start")
    first = scene.frame_start if first is None else int(first)
    if spec.get("end") is not None:
        last = int(spec["end"])
    elif spec.get("count") is not None:
        last = first + (int(spec["count"]) - 1) * step
    else:
        last = scene.frame_end if is_animated else first
    frames = list(range(first, last + 1, step))
    if not frames:
        fail("frames %d to %d select no frame of scene `%s` (its range is %d to %d)"
             % (first, last, scene.name, scene.frame_start, scene.frame_end))
    if len(frames) > MAX_FRAMES:
        fail("%d frames asked for, over vvgen's limit of %d: choose fewer with `frames`" % (len(frames), MAX_FRAMES))

    # The exporter writes an object's own mesh, without its shape keys' mix, unless the object has modifiers
    # (then it writes the evaluated mesh). A modifier that does nothing (an armature with no armature) makes
    # every mesh take the evaluated path, so each frame is exactly what Blender shows. An object linked from
    # another file takes no modifier (linked data is read-only): it is made local first (its mesh, shape keys
    # and their animation stay linked, and still evaluate). The file is never saved.
    for o in list(bpy.data.objects):
        if o.type == "MESH" and len(o.modifiers) == 0:
            if o.library is not None:
                o = o.make_local()
            o.modifiers.new("vvgen-evaluate", "ARMATURE")

    # The files the import reads besides the .blend: its key's discovered inputs.
    # Blender's bundled asset libraries (the essentials brushes a 4.3+ file links, by their path in the
    # authoring machine's Blender) are not the file's content: Blender reads its own copies, so they are
    # neither inputs nor missing.
    deps = set()
    for p in bpy.utils.blend_paths(absolute=True, packed=False, local=False):
        p = os.path.normpath(bpy.path.abspath(p))
        if os.sep.join(("datafiles", "assets", "")) not in p:
            deps.add(p)
    warnings = []
    for p in sorted(p for p in deps if not os.path.isfile(p)):
        warnings.append("names `%s`, which is missing (Blender draws it magenta): restore it, or pack the "
                        "file's resources (File > External Data > Pack Resources)" % p)

    for i, f in enumerate(frames):
        scene.frame_set(f)
        path = os.path.join(out, "frame_%05d.gltf" % i)
        result = bpy.ops.export_scene.gltf(**exporter_options(bpy, dict(
            filepath=path,
            export_format="GLTF_SEPARATE",
            export_texture_dir="textures",
            # Blender's own axes: vvgen loads the result +Z up, as Blender shows it.
            export_yup=False,
            use_selection=chosen is not None,
            use_renderable=chosen is None,
            use_active_scene=True,
            # The evaluated mesh (modifiers, shape keys and armatures applied) at this frame, and each object's
            # evaluated world matrix: nothing is left for glTF animation to express.
            export_apply=True,
            # Without it the exporter evaluates frame 0 (and bones at rest), whatever frame is set.
            export_current_frame=True,
            export_animations=False,
            export_skins=False,
            export_morph=False,
            export_colors=True,
            export_cameras=False,
            export_lights=False,
            export_extras=False,
            export_image_format="AUTO",
            # Geometry nodes' instances, as Blender renders them (left out, a scattering node tree exported
            # nothing); exporters before 4.1 lack the option (`exporter_options` drops it).
            export_gn_mesh=True,
        )))
        if "FINISHED" not in result or not os.path.isfile(path):
            fail("Blender's glTF exporter failed at frame %d" % f)
        if i == 0:
            with open(path) as fh:
                if not json.load(fh).get("meshes"):
                    skipped = sorted(o.name for o in (chosen or scene.objects) if o.type in UNEXPORTED)
                    hint = ""
                    if skipped:
                        hint = (": Blender's glTF exporter writes no point cloud, hair curves, volume or grease "
                                "pencil objects (%s); convert them to meshes (Object > Convert > Mesh), save, and "
                                "name that file" % ", ".join(skipped[:4] + (["…"] if len(skipped) > 4 else [])))
                    fail("scene `%s` has nothing to draw%s%s"
                         % (scene.name, "" if chosen is None else " in what was selected", hint))
    files = []
    for base, _, names_here in os.walk(out):
        for n in names_here:
            rel = os.path.relpath(os.path.join(base, n), out).replace(os.sep, "/")
            if rel != "info.json":
                files.append(rel)
    info = {
        "blender": bpy.app.version_string,
        "scene": scene.name,
        "scenes": scenes,
        "objects": names,
        "fps": scene.render.fps / scene.render.fps_base,
        "frame_start": scene.frame_start,
        "frame_end": scene.frame_end,
        "animated": is_animated,
        "frames": frames,
        "files": sorted(files),
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
    # An operator's failure carries its Python traceback: its last line says what went wrong (a texture the
    # exporter cannot read, say).
    said = [l.strip() for l in str(e).splitlines() if l.strip()]
    said = [l for l in said if not l.startswith(("Traceback", "File ", "Location:", "^", "~"))] or [str(e)]
    last = said[-1]
    while last.startswith(("RuntimeError: ", "Error: ")):
        last = last.split(": ", 1)[1]
    fail("%s: %s" % (type(e).__name__, last))
