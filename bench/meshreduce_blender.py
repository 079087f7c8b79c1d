# The Blender peer of `meso meshreduce` (bench/meshreduce_peers): the Decimate modifier in
# Collapse mode (Blender's quadric edge collapse) at a face ratio, timed around the modifier's
# application alone.
#
#   blender -b --factory-startup -t 1 --python bench/meshreduce_blender.py -- IN.obj OUT.obj RATIO
#
# Prints one line `meshreduce_blender: seconds S faces_in N faces_out M` on stdout, where S is
# the wall time of bpy.ops.object.modifier_apply (Blender builds the decimated mesh there,
# including its Mesh <-> BMesh conversions, as meso's time includes its own). The OBJ import
# and export are not timed. Axes are kept as they are (forward Y, up Z both ways), so the
# output lies in the input's coordinates; the output is triangulated, positions only.
import sys
import time

import bpy


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 3:
        print("usage: blender -b --factory-startup --python meshreduce_blender.py -- IN.obj OUT.obj RATIO", file=sys.stderr)
        sys.exit(2)
    source, target, ratio = argv[0], argv[1], float(argv[2])

    # The factory scene's cube, camera and light would otherwise be exported with the result.
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    bpy.ops.wm.obj_import(filepath=source, forward_axis="Y", up_axis="Z")
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    if len(meshes) != 1:
        print(f"meshreduce_blender: expected one mesh in {source}, got {len(meshes)}", file=sys.stderr)
        sys.exit(3)
    obj = meshes[0]
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    faces_in = len(obj.data.polygons)

    mod = obj.modifiers.new(name="decimate", type="DECIMATE")
    mod.decimate_type = "COLLAPSE"
    mod.ratio = ratio
    # Output triangles rather than the quads Collapse may leave; the others output triangles.
    mod.use_collapse_triangulate = True
    start = time.perf_counter()
    bpy.ops.object.modifier_apply(modifier=mod.name)
    seconds = time.perf_counter() - start

    faces_out = len(obj.data.polygons)
    bpy.ops.wm.obj_export(filepath=target, export_selected_objects=True, apply_modifiers=False,
                          export_uv=False, export_normals=False, export_materials=False,
                          export_triangulated_mesh=True, forward_axis="Y", up_axis="Z")
    print(f"meshreduce_blender: seconds {seconds:.6f} faces_in {faces_in} faces_out {faces_out}", flush=True)


main()
