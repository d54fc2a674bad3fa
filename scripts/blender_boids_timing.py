# Blender's particle boids timed on this machine, for docs/performance.md's flocking line
# (issue 32): N boids with Blender's default rules (goal, avoid, avoid collision,
# separate, flock, average speed) and flight on, emitted at frame 1 from a 20 m cube's
# volume, stepped frame by frame headless. Prints the seconds and bird-steps per second
# (boids x frames / s), the unit of `kodawari bench flock`.
#
#   blender --background --factory-startup --python scripts/blender_boids_timing.py -- [COUNT] [FRAMES]
#
# COUNT defaults to 10000, FRAMES to 60. Frame 1 (the emission) is left out of the time.
import sys
import time

import bpy


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    count = int(argv[0]) if argv else 10000
    frames = int(argv[1]) if len(argv) > 1 else 60
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_cube_add(size=20.0)
    emitter = bpy.context.active_object
    settings = emitter.modifiers.new("boids", "PARTICLE_SYSTEM").particle_system.settings
    settings.count = count
    settings.frame_start = 1
    settings.frame_end = 1
    settings.lifetime = frames + 10
    settings.emit_from = "VOLUME"
    settings.physics_type = "BOIDS"
    settings.boids.use_flight = True
    scene = bpy.context.scene
    scene.frame_start = 1
    scene.frame_end = frames + 1
    scene.frame_set(1)
    alive = sum(1 for p in emitter.evaluated_get(bpy.context.evaluated_depsgraph_get()).particle_systems[0].particles
                if p.alive_state == "ALIVE")
    start = time.perf_counter()
    for frame in range(2, frames + 2):
        scene.frame_set(frame)
    seconds = time.perf_counter() - start
    print(f"blender {bpy.app.version_string} boids: {count} boids ({alive} alive after frame 1), {frames} frames "
          f"in {seconds:.2f} s: {count * frames / seconds:.4g} bird-steps/s")


main()
