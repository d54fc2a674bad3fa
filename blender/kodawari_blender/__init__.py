"""Kodawari in Blender (issue 33): flocks of skinned bird armatures from Bezier curves.

The add-on drives the Kodawari library through its Python package (`kodawari`, ctypes over
libkodawari.so), which the add-on's zip carries in this folder with the library and the
shared libraries it needs: installing the zip (Preferences > Add-ons > Install, or
bpy.ops.preferences.addon_install) is all it takes.
"""

bl_info = {
    "name": "Kodawari",
    "author": "Kodawari",
    "version": (0, 2, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Kodawari; F3 > Kodawari: Flock from Curve",
    "description": "Flocks of flapping birds along Bezier curves, simulated by Kodawari",
    "category": "Animation",
}

import bpy

from . import flock

classes = (flock.KODAWARI_OT_flock_from_curve, flock.KODAWARI_PT_flock)


def menu(self, context):
    self.layout.operator(flock.KODAWARI_OT_flock_from_curve.bl_idname, text="Kodawari Flock from Curve")


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.VIEW3D_MT_object.append(menu)


def unregister():
    bpy.types.VIEW3D_MT_object.remove(menu)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
