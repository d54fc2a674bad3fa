"""Kodawari in Blender (issue 33): flocks of skinned bird armatures from Bezier curves, and
a character's hair, tail and ear chains baked into an action.

The add-on drives the Kodawari library through its Python package (`kodawari`, ctypes over
libkodawari.so), which the add-on's zip carries in this folder with the library and the
shared libraries it needs: installing the zip (Preferences > Add-ons > Install, or
bpy.ops.preferences.addon_install) is all it takes.
"""

bl_info = {
    "name": "Kodawari",
    "author": "Kodawari",
    "version": (0, 3, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Kodawari; F3 > Kodawari: Flock from Curve",
    "description": "Flocks of birds along Bezier curves, and chains (hair, tails, spring bones) baked on armatures",
    "category": "Animation",
}

import bpy

from . import chains, flock

classes = (flock.KODAWARI_OT_flock_from_curve, flock.KODAWARI_PT_flock, chains.KODAWARI_OT_bake_chains)


def menu(self, context):
    self.layout.operator(flock.KODAWARI_OT_flock_from_curve.bl_idname, text="Kodawari Flock from Curve")
    self.layout.operator(chains.KODAWARI_OT_bake_chains.bl_idname, text="Kodawari Bake Chains")


def register():
    flock.restore_numpy_bool()  # Blender 3.4's glTF importer on NumPy 1.24 (flock.py)
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.VIEW3D_MT_object.append(menu)


def unregister():
    bpy.types.VIEW3D_MT_object.remove(menu)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
