# Imports a glTF file into an empty Blender scene with Blender's own glTF importer and
# prints one JSON line saying what Blender made of it:
#
#   blender -b --factory-startup --python-exit-code 1 -P tests/tools/blender_check.py -- FILE.glb
#
# The line starts with {"check": "kodawari-blender", ...} (Blender prints its own lines
# around it) and holds: "blender" (version), "actions" (number of actions) and
# "action_names", "armatures" (per armature object: the sorted names of the bones that
# have F-curves in any action the object uses, active or in its NLA tracks), "meshes"
# (mesh data-blocks), "armature_count", "mesh_objects" and "objects".
# Exit status: 0 imported, 1 the import failed (or any error), 2 usage.
import json
import re
import sys

import bpy

try:
    import numpy
except ImportError:
    print('blender_check: Blender\'s glTF importer needs NumPy, which this Blender cannot import '
          '(Debian: python3-numpy; bash scripts/setup --with-blender installs it)', file=sys.stderr)
    sys.exit(1)

# Blender 3.4's glTF importer uses numpy.bool, an alias that NumPy 1.24 removed (Debian 12
# ships Blender 3.4.1 with NumPy 1.24, and its blender package does not even depend on
# python3-numpy). Putting the alias back is all the importer needs.
if 'bool' not in numpy.__dict__:
    numpy.bool = bool

BONE_PATH = re.compile(r'^pose\.bones\["((?:[^"\\]|\\.)*)"\]')


def arguments():
    argv = sys.argv
    args = argv[argv.index('--') + 1:] if '--' in argv else []
    if len(args) != 1:
        print('usage: blender -b --factory-startup --python-exit-code 1 -P blender_check.py -- FILE.glb',
              file=sys.stderr)
        sys.exit(2)
    return args[0]


def actions_of(obj):
    """The actions an object uses: its active one and those in its NLA strips."""
    found = []
    data = obj.animation_data
    if data is None:
        return found
    if data.action is not None:
        found.append(data.action)
    for track in data.nla_tracks:
        for strip in track.strips:
            if strip.action is not None and strip.action not in found:
                found.append(strip.action)
    return found


def animated_bones(obj):
    bones = set()
    for action in actions_of(obj):
        for curve in action.fcurves:
            match = BONE_PATH.match(curve.data_path)
            if match:
                bones.add(match.group(1).replace('\\"', '"').replace('\\\\', '\\'))
    return sorted(bones)


def main():
    path = arguments()
    # An empty scene: no default cube, camera or light in the counts.
    bpy.ops.wm.read_factory_settings(use_empty=True)
    try:
        result = bpy.ops.import_scene.gltf(filepath=path)
    except Exception as error:  # the importer reports failures as exceptions
        print(f'blender_check: importing {path} failed: {error}', file=sys.stderr)
        sys.exit(1)
    if 'FINISHED' not in result:
        print(f'blender_check: importing {path} did not finish: {sorted(result)}', file=sys.stderr)
        sys.exit(1)
    objects = list(bpy.data.objects)
    armatures = [o for o in objects if o.type == 'ARMATURE']
    report = {
        'blender': bpy.app.version_string,
        'actions': len(bpy.data.actions),
        'action_names': sorted(a.name for a in bpy.data.actions),
        'armatures': {o.name: animated_bones(o) for o in armatures},
        'meshes': len(bpy.data.meshes),
        'armature_count': len(armatures),
        'mesh_objects': sum(1 for o in objects if o.type == 'MESH'),
        'objects': len(objects),
    }
    # "check" first, as the readers look for the line by its start
    # (testing_support::blender_report_line); the rest sorted, so that two runs print the
    # same line. json.dumps(sort_keys=True) on the whole report would put "action_names"
    # first and the readers would find no report (issue 33).
    line = {'check': 'kodawari-blender'}
    line.update(sorted(report.items()))
    line['armatures'] = dict(sorted(line['armatures'].items()))
    print(json.dumps(line), flush=True)


main()
