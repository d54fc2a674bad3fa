#!/usr/bin/env bash
# Makes the README's pictures in docs/images/ with `kodawari render` (build first:
# cmake --preset release && cmake --build build/release --target kodawari).
# usage: scripts/make_readme_images.sh [KODAWARI_BINARY]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/release/host/kodawari}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p docs/images

# The ahoge from the front, its left, the back and its right: the camera orbits once in
# 12 s (720 frames), so frames 0, 180, 360 and 540; --zoom 1.7 brings the curl close
# without moving the camera (whose position blends the strand's rest shape).
"$bin" render scenes/ahoge.json --frames 0:720:180 --size 960x540 --zoom 1.7 --out "$work/ahoge" \
    --contact-sheet docs/images/ahoge-angles.png --columns 2
# The ahoge as the camera orbits it, animated (APNG): the first third of the orbit, every
# 4th frame, so 60 frames at 15 per second.
"$bin" render scenes/ahoge.json --frames 0:240:4 --size 480x360 --zoom 1.5 --out "$work/orbit" \
    --animation docs/images/ahoge-orbit.png
# The bangs from the front (parted off the eyes), 45 degrees to its left, its left and
# 135 degrees: frames 0, 90, 180 and 270 of the 12 s orbit (the sheet shrinks each frame
# by its 4 columns, so 480x360 cells).
"$bin" render scenes/bangs.json --frames 0:360:90 --size 1920x1440 --zoom 1.7 --out "$work/bangs" \
    --contact-sheet docs/images/bangs.png --columns 4
# Keyed examples: the ponytail standing, walking, sprinting and stopped (0, 2.5, 5 and
# 7.5 s), and the bangs held looking down (3 s) and looking up (7 s).
"$bin" render scenes/ponytail.json --frames 0:600:150 --size 960x540 --zoom 1.6 --out "$work/ponytail" \
    --contact-sheet docs/images/ponytail.png --columns 2
"$bin" render scenes/nod.json --frames 180:421:240 --size 960x720 --zoom 1.4 --out "$work/nod" \
    --contact-sheet docs/images/nod.png --columns 2
# The three wing types mid-wingbeat, the camera flying with them (frame 60 of 240).
"$bin" render scenes/birds-closeup.json --frames 60 --size 640x360 --out "$work/birds"
cp "$work/birds/birds-closeup_00060.png" docs/images/birds-closeup.png
# Pigeons crouching and taking off one after another from a roof line, and 30 s later
# landed on the other, wings folded (scenes/perch.json, docs/flight-modes.md). The roofs
# are drawn under the perched birds (render::add_perches).
"$bin" render scenes/perch.json --frames 150:1951:1800 --size 1280x720 --zoom 1.8 --out "$work/perch" \
    --contact-sheet docs/images/perch.png --columns 2
# perch-flock.json: its flocking pigeons leaving the roof one by one (frame 150, the scene
# camera) and coming down on the other (frame 1650, from beside that roof).
"$bin" render scenes/perch-flock.json --frames 150 --size 640x360 --zoom 1.8 --out "$work/perch-flock"
cp "$work/perch-flock/perch-flock_00150.png" docs/images/perch-flock-takeoff.png
"$bin" render scenes/perch-flock.json --frames 1650 --size 640x360 --zoom 3 --camera 20,11,56,0,8.8,69 --out "$work/perch-flock"
cp "$work/perch-flock/perch-flock_01650.png" docs/images/perch-flock-landing.png
# perch.json's hummingbirds hovering over their flower bed (a roof garden) 22.7 s in, from
# a camera of their own (--camera: the scene camera never comes within 14.5 m of them, where
# they are 8-pixel specks; the simulation keeps the scene camera).
"$bin" render scenes/perch.json --frames 1360 --size 960x540 --zoom 1.6 --camera 13.6,6.3,44.3,11.4,6.45,46.8 \
    --out "$work/hummingbirds"
cp "$work/hummingbirds/perch_01360.png" docs/images/hummingbirds.png
# The flock 3.3 s in, and the crowd 2 s in.
"$bin" render scenes/flock.json --frames 200 --size 640x360 --zoom 2.2 --out "$work/flock"
cp "$work/flock/flock_00200.png" docs/images/flock.png
"$bin" render scenes/crowd.json --frames 120 --size 640x360 --out "$work/crowd"
cp "$work/crowd/crowd_00120.png" docs/images/crowd.png
# One of the crowd (critter#431, near the middle) running in and stopping dead at frame
# 66 (its own clock's 3.6 s), seen from behind its right shoulder with --camera: its ears
# overshoot forward at the stop and swing back (frames 57 to 72, every 3rd; at the scene
# camera, 38 m out, they are a few pixels).
"$bin" render scenes/crowd.json --frames 57:75:3 --size 1440x810 --zoom 2.2 --camera 1.0,2.3,-1.35,-0.43,1.72,-0.32 \
    --out "$work/crowd-stop" --contact-sheet docs/images/crowd-stop.png --columns 3
# The crowd in a gusty wind (scenes/windy.json), frames 40, 80 and 120 from the side.
"$bin" render scenes/windy.json --frames 40:160:40 --size 1440x810 --zoom 2.0 --camera 2.5,2.2,4.5,0.5,1.5,-2.5 \
    --out "$work/windy" --contact-sheet docs/images/windy.png --columns 3
# Bunnies whose chains carry every angle limit kind (scenes/limits.json), frames 100, 200, 300.
"$bin" render scenes/limits.json --frames 100:400:100 --size 1440x810 --zoom 1.8 --camera 3.2,2.0,3.4,0.0,1.4,0.0 \
    --out "$work/limits" --contact-sheet docs/images/limits.png --columns 3
# The rigged crowd (64 of scenes/characters/chibi.glb, skinned in the vertex shader) 2 s in.
"$bin" render scenes/crowd-gltf.json --frames 120 --size 640x360 --out "$work/crowd-gltf"
cp "$work/crowd-gltf/crowd-gltf_00120.png" docs/images/crowd-gltf.png
# VRM avatars (issue 18) walking circles and idling with retargeted VRM Animation clips,
# 2.5 s and 7.5 s in.
"$bin" render scenes/avatars.json --frames 150:451:300 --size 1920x1080 --zoom 2.0 --out "$work/avatars" \
    --contact-sheet docs/images/avatars.png --columns 2
ls -l docs/images
