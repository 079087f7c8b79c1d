# The Blender peer of `meso bake` (bench/bake_peers.sh): Cycles "selected to active" bake of a
# tangent-space normal map from a high mesh onto a UV-mapped base mesh, timed around the bake
# call alone.
#
#   blender -b --factory-startup --python bench/bake_blender.py -- \
#     --low base.obj --high high.obj --size 2048 --extrusion 0.05 --max-ray 0.1 \
#     --threads 2 --samples 1 --out normal.rgba32f --report blender.json
#
# Rays, as Blender casts them: from the base point pushed `extrusion` along the base normal,
# inward along -normal, at most `max-ray` long; the hit nearest to that origin wins. So
# extrusion = meso's --front and max-ray = --front + --back give both bakers the same reach.
#
# Output: the baked image's pixels as raw little-endian float32 RGBA, bottom row first
# (Blender's order), width = height = size; texels the bake did not write keep (0, 0, 0, 0)
# (use_clear off: Blender's clear would paint them (0.5, 0.5, 1), a flat normal). Margin 0.
# Normal space: tangent (MikkTSpace), R = +X, G = +Y, B = +Z (OpenGL "Y+"), colour n*0.5+0.5,
# image in Non-Color (no colour management).
import argparse
import json
import sys
import time

import bpy


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="bake_blender.py")
    ap.add_argument("--low", required=True)
    ap.add_argument("--high", required=True)
    ap.add_argument("--size", type=int, required=True)
    ap.add_argument("--extrusion", type=float, required=True)
    ap.add_argument("--max-ray", type=float, required=True)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--samples", type=int, default=1)
    ap.add_argument("--space", choices=["TANGENT", "OBJECT"], default="TANGENT", help="normal space (OBJECT: a diagnostic)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--report", required=True)
    a = ap.parse_args(argv)

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene

    def import_obj(path):
        before = set(bpy.data.objects)
        # Keep the file's axes (no Y-up to Z-up turn): both meshes stay where meso sees them.
        bpy.ops.wm.obj_import(filepath=path, forward_axis="Y", up_axis="Z")
        new = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
        if len(new) != 1:
            raise RuntimeError(f"{path}: expected one mesh object, got {len(new)}")
        return new[0]

    t0 = time.perf_counter()
    high = import_obj(a.high)
    low = import_obj(a.low)
    t_import = time.perf_counter() - t0
    # Smooth shading with Blender's own vertex normals (corner-angle weighted, the definition
    # meso writes into the OBJ's vn): the importer's custom split normals are dropped and auto
    # smooth is off. (Blender 3.4 baked with the imported custom normals gives normals ~20
    # degrees off the file's vn on the brick wall; without them the object-space bake agrees
    # with meso's to 0.01 degrees.)
    for ob in (high, low):
        bpy.context.view_layer.objects.active = ob
        if ob.data.has_custom_normals:
            bpy.ops.mesh.customdata_custom_splitnormals_clear()
        ob.data.use_auto_smooth = False
        for p in ob.data.polygons:
            p.use_smooth = True
    if not low.data.uv_layers:
        raise RuntimeError(f"{a.low}: no UVs")

    # The bake target: a float image, Non-Color, every texel (0, 0, 0, 0) until baked.
    img = bpy.data.images.new("normal_ts", a.size, a.size, alpha=True, float_buffer=True)
    img.colorspace_settings.name = "Non-Color"
    img.generated_color = (0.0, 0.0, 0.0, 0.0)
    mat = bpy.data.materials.new("bake_target")
    mat.use_nodes = True
    node = mat.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = img
    mat.node_tree.nodes.active = node
    node.select = True
    low.data.materials.clear()
    low.data.materials.append(mat)

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = a.samples
    scene.cycles.use_denoising = False
    scene.render.threads_mode = "FIXED"
    scene.render.threads = a.threads
    bake = scene.render.bake
    bake.margin = 0
    bake.use_clear = False

    for ob in scene.objects:
        ob.select_set(False)
    high.select_set(True)
    low.select_set(True)
    bpy.context.view_layer.objects.active = low

    t0 = time.perf_counter()
    result = bpy.ops.object.bake(type="NORMAL", normal_space=a.space, normal_r="POS_X", normal_g="POS_Y", normal_b="POS_Z",
                                 use_selected_to_active=True, use_cage=False, cage_extrusion=a.extrusion,
                                 max_ray_distance=a.max_ray, margin=0, use_clear=False, target="IMAGE_TEXTURES",
                                 save_mode="INTERNAL")
    t_bake = time.perf_counter() - t0
    if "FINISHED" not in result:
        raise RuntimeError(f"bake returned {result}")

    # Raw pixels out, without colour management: image.pixels in Blender's order.
    import array
    buf = array.array("f", bytes(4 * 4 * a.size * a.size))
    img.pixels.foreach_get(buf)
    with open(a.out, "wb") as f:
        buf.tofile(f)

    report = {
        "blender": bpy.app.version_string,
        "size": a.size,
        "samples": a.samples,
        "normal_space": a.space,
        "threads": a.threads,
        "extrusion": a.extrusion,
        "max_ray_distance": a.max_ray,
        "high_polygons": len(high.data.polygons),
        "low_polygons": len(low.data.polygons),
        "import_seconds": t_import,
        "bake_seconds": t_bake,
    }
    with open(a.report, "w") as f:
        json.dump(report, f, indent=1)
    print("bake_blender:", json.dumps(report))


try:
    main()
except Exception as e:  # Blender keeps running after a script error: exit non-zero instead.
    import traceback
    traceback.print_exc()
    sys.stderr.write(f"bake_blender.py: {e}\n")
    sys.exit(1)
