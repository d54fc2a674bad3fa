"""The README's "From Blender" picture, rendered by Blender itself (Workbench): the add-on
installed from kodawari_blender.zip, a Bezier curve of three control points, 60 gulls
from it, frame 70 seen from beside the flock with the curve drawn.

    BLENDER_USER_SCRIPTS=$(mktemp -d) xvfb-run -a blender -b --factory-startup \\
        -P scripts/blender_flock_picture.py -- build/release/kodawari_blender.zip docs/images/blender-flock.png

Blender needs an OpenGL context to render even in the background: xvfb-run gives it one
(Mesa's llvmpipe) where there is no display. BLENDER_USER_SCRIPTS keeps the add-on's
install out of the user's own scripts folder.
"""
import sys

import bpy
from mathutils import Vector

zip_path, out = sys.argv[sys.argv.index("--") + 1:][:2]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
bpy.ops.preferences.addon_enable(module="kodawari_blender")
scene = bpy.context.scene
scene.render.fps = 24
scene.frame_start, scene.frame_end = 1, 120

curve = bpy.data.curves.new("route", "CURVE")
curve.dimensions = "3D"
curve.bevel_depth = 0.08
spline = curve.splines.new("BEZIER")
spline.bezier_points.add(2)
for point, (co, left, right) in zip(spline.bezier_points, [
        ((-30, 0, 8), (-40, -6, 6), (-20, 6, 10)),
        ((0, 4, 14), (-10, 4, 14), (10, 4, 14)),
        ((30, -2, 9), (20, 2, 12), (40, -6, 6))]):
    point.handle_left_type = point.handle_right_type = "FREE"
    point.co, point.handle_left, point.handle_right = co, left, right
route = bpy.data.objects.new("route", curve)
scene.collection.objects.link(route)
route.select_set(True)
bpy.context.view_layer.objects.active = route
bpy.ops.kodawari.flock_from_curve(count=60, wing_type="GULL", spread=3.0, trail=2.0, frames=120, seed=3)

# The camera beside the flock at frame 70, looking at the birds' middle.
scene.frame_set(70)
birds = [o for o in bpy.data.objects if o.type == "ARMATURE"]
middle = sum(((o.matrix_world @ o.pose.bones["Body"].matrix).translation for o in birds), Vector()) / len(birds)
camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
camera.location = middle + Vector((-9, -15, 3))
camera.rotation_euler = (middle - camera.location).to_track_quat("-Z", "Y").to_euler()
camera.data.lens = 35
scene.camera = camera
scene.render.engine = "BLENDER_WORKBENCH"
scene.display.shading.light = "STUDIO"
scene.display.shading.color_type = "OBJECT"
scene.display.shading.show_cavity = True
scene.world = bpy.data.worlds.new("sky")
scene.world.color = (0.62, 0.74, 0.86)
scene.render.resolution_x, scene.render.resolution_y = 960, 540
scene.render.image_settings.file_format = "PNG"
scene.render.image_settings.color_mode = "RGB"
scene.render.image_settings.compression = 100
for obj in bpy.data.objects:
    obj.color = (0.85, 0.35, 0.1, 1) if obj.name == "route" else (0.25, 0.25, 0.28, 1)
scene.frame_set(70)
scene.render.filepath = out
bpy.ops.render.render(write_still=True)
print("wrote", out)
