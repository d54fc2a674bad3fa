#!/usr/bin/env bash
# `kodawari view` in a real window under Xvfb: a scripted key sequence (one key per drawn
# frame), the frame it ends on, and a screenshot of the last frame; then real X input
# (xdotool) to live viewers. Exits 77 (CTest: skipped) where xvfb-run is not installed; the
# real input checks are skipped where xdotool is not.
# usage: viewer_test.sh KODAWARI_BINARY SOURCE_DIR
set -uo pipefail
bin=$1
src=$2
if ! command -v xvfb-run >/dev/null 2>&1; then
    echo "SKIPPED: no X server (xvfb-run not installed; scripts/setup installs xvfb)"
    exit 77
fi
source "$(dirname "${BASH_SOURCE[0]}")/check.sh"
view() {  # view OUT-PREFIX ARGS...: the viewer in a fresh Xvfb screen
    local out=$1; shift
    # -f: our own authority file, so that xvfb-run makes no temporary folder of its own
    # (removing one failed once in CI, exit 5, with the viewer's result right).
    xvfb-run -a -f "$out.xauth" -s "-screen 0 1024x768x24" "$bin" view "$@" >"$out.out" 2>"$out.err"
    local rc=$?
    cat "$out.out" "$out.err"
    return $rc
}
cd "$src"

# png.py FILE R,G,B...: exit 0 when the RGBA8 PNG (as write_png makes them) has a pixel of
# each colour and more than 10 colours in all (not a blank image). ~R,G,B: a lit shade of
# the colour, as the chains are drawn (render::kAmbientLight..1 times it, within 2 per
# channel for the 8-bit rounding). Its read() decodes one (pngcmp.py below uses it too).
cat >"$work/png.py" <<'PY'
import struct, sys, zlib


def read(path):  # -> width, height, rows of RGBA bytes
    data = open(path, 'rb').read()
    pos, idat, width, height = 8, b'', 0, 0
    while pos < len(data):
        n, kind = struct.unpack('>I4s', data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b'IHDR':
            width, height, depth, ctype = struct.unpack('>IIBB', body[:10])
            assert depth == 8 and ctype == 6, (depth, ctype)
        elif kind == b'IDAT':
            idat += body
        pos += 12 + n
    raw, stride, rows, prev = zlib.decompress(idat), width * 4, [], bytearray(width * 4)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 4] if i >= 4 else 0
            b = prev[i]
            c = prev[i - 4] if i >= 4 else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return width, height, rows


def lit_shade(pixel, base):  # whether pixel = f * base, f in [0.45, 1] (render::kAmbientLight)
    f = sum(p * b for p, b in zip(pixel, base)) / sum(b * b for b in base)
    f = min(max(f, 0.45), 1.0)
    return max(abs(p - f * b) for p, b in zip(pixel, base)) <= 2


def has(pixels, arg):
    base = bytes(int(v) for v in arg.lstrip('~').split(','))
    return any(lit_shade(p, base) for p in pixels) if arg.startswith('~') else base in pixels


if __name__ == '__main__':
    width, height, rows = read(sys.argv[1])
    pixels = {bytes(r[i:i + 3]) for r in rows for i in range(0, width * 4, 4)}
    missing = [arg for arg in sys.argv[2:] if not has(pixels, arg)]
    if missing or len(pixels) <= 10:
        print(f"png.py: {sys.argv[1]}: missing colours {missing}, {len(pixels)} colours in all")
        sys.exit(1)
PY

# pngcmp.py same|differ A B: exit 0 when the two screenshots are the same (differ) above
# the status band (its 14 bottom rows show ms/frame, which changes from frame to frame).
cat >"$work/pngcmp.py" <<'PY'
import sys
from png import read
wa, ha, a = read(sys.argv[2])
wb, hb, b = read(sys.argv[3])
assert (wa, ha) == (wb, hb), ((wa, ha), (wb, hb))
changed = sum(a[y][4 * x:4 * x + 3] != b[y][4 * x:4 * x + 3] for y in range(ha - 14) for x in range(wa))
print(f"pngcmp.py: {changed} pixels of {wa}x{ha - 14} differ between {sys.argv[2]} and {sys.argv[3]}")
sys.exit(0 if (changed == 0) == (sys.argv[1] == 'same') else 1)
PY

# Space pauses before the first step, then two steps: frame 2, paused.
view "$work/keys" scenes/ahoge.json --size 320x240 --frames 30 --keys "space,right,right" --screenshot "$work/shot.png"
rc=$?
check "view exits 0" test $rc -eq 0
check "view ends at frame 2, paused" grep -q "view ended at frame 2 (t 0.033 s, paused) on backend .* after 30 drawn frames" "$work/keys.out"
check "screenshot is a 320x240 PNG" python3 -c "import struct,sys; d=open(sys.argv[1],'rb').read(24); sys.exit(d[:8]!=b'\\x89PNG\\r\\n\\x1a\\n' or struct.unpack('>II', d[16:24])!=(320, 240))" "$work/shot.png"
# The chain is drawn lit in its colour (render::kChainColor) and the status line in white.
check "screenshot shows the chain and the status line" python3 "$work/png.py" "$work/shot.png" '~235,95,20' 255,255,255

# Scrubbing: a second forward (60 frames at 60 fps), a step, two steps back (re-simulated
# from frame 0), then the backend switch to cpu (re-simulated up to the same frame).
view "$work/scrub" scenes/ahoge.json --size 160x120 --frames 8 --keys "space,],right,left,left,2"
rc=$?
check "scrub exits 0" test $rc -eq 0
check "scrub ends at frame 59 on the cpu backend" grep -q "view ended at frame 59 (t 0.983 s, paused) on backend cpu" "$work/scrub.out"

# A resized window gets a new swapchain (the image keeps --size, scaled into the window).
view "$work/resize" scenes/ahoge.json --size 160x120 --frames 8 --keys "resize:300:200,space,resize:120:90" --screenshot "$work/resized.png"
rc=$?
check "resize exits 0" test $rc -eq 0
check "resize keeps the image size" python3 -c "import struct,sys; d=open(sys.argv[1],'rb').read(24); sys.exit(struct.unpack('>II', d[16:24])!=(160, 120))" "$work/resized.png"

# The other shipped scenes start at their camera too: the crowd's chains and the ground
# grid (render::kGridColor); the flock's grid (the birds are lit, no exact colour to look for).
view "$work/crowd" scenes/crowd.json --size 320x180 --frames 2 --screenshot "$work/crowd.png"
check "crowd: chains and grid in view" python3 "$work/png.py" "$work/crowd.png" '~235,95,20' 150,156,168
view "$work/flock" scenes/flock.json --size 320x180 --frames 2 --screenshot "$work/flock.png"
check "flock: grid in view" python3 "$work/png.py" "$work/flock.png" 150,156,168

# One device, buffers shared (issue 5): on the vulkan backend the chains, the birds and
# the rigged characters' skinned meshes are drawn from the backends' own buffers, and the
# rigged characters' rod input is written from their poses on the device, so playing
# reads no simulation state back (the counter counts every read back of kernel output on
# the device, see Renderer::read_back_bytes). Only the rigged crowd's frame 0 is read
# (its poses, for the rod backend's load() on the host): 3 frames and 9 frames read the
# same, more than 0 bytes (so the counter sees it).
view "$work/shared-rods" scenes/ahoge.json --backend vulkan --size 160x120 --frames 20
check "ahoge on vulkan: nothing read back in 20 frames" grep -q "simulation and drawing on one device .*; 0 bytes of simulation state read back in 20 frames" "$work/shared-rods.out"
view "$work/shared-birds" scenes/flock.json --backend vulkan --size 160x120 --frames 20
check "flock on vulkan: nothing read back in 20 frames" grep -q "; 0 bytes of simulation state read back in 20 frames" "$work/shared-birds.out"
view "$work/rigged3" scenes/crowd-gltf.json --backend vulkan --size 160x120 --frames 3
view "$work/rigged9" scenes/crowd-gltf.json --backend vulkan --size 160x120 --frames 9
read_back() { sed -n 's/.*; \([0-9]*\) bytes of simulation state read back in .*/\1/p' "$1"; }
check "rigged crowd on vulkan: frame 0 read back, nothing after" \
    bash -c "test '$(read_back "$work/rigged3.out")' -gt 0 && test '$(read_back "$work/rigged3.out")' = '$(read_back "$work/rigged9.out")'"

# C follows the scene's camera (its motion and projection, which then drive the view-
# dependent shapes as in `run` and `render`): frame 29 in the window is `kodawari render`'s
# frame 29, pixel for pixel above the status band (14 rows at this size). Without C the
# orbit camera stays where the scene camera was at frame 0 (ahoge's orbits): they differ.
# O makes the orbit camera orthographic: the picture changes.
view "$work/follow" scenes/ahoge.json --backend vulkan --size 200x150 --frames 30 --keys c --screenshot "$work/follow.png"
view "$work/orbit" scenes/ahoge.json --backend vulkan --size 200x150 --frames 30 --screenshot "$work/orbit.png"
view "$work/ortho" scenes/ahoge.json --backend vulkan --size 200x150 --frames 30 --keys o --screenshot "$work/ortho.png"
"$bin" render scenes/ahoge.json --backend vulkan --size 200x150 --frames 0:30 --out "$work/frames" >/dev/null
check "C: the window shows what render shows" python3 "$work/pngcmp.py" same "$work/follow.png" "$work/frames/ahoge_00029.png"
check "without C: the orbit camera shows another view" python3 "$work/pngcmp.py" differ "$work/orbit.png" "$work/frames/ahoge_00029.png"
check "O: the orthographic orbit camera shows another picture" python3 "$work/pngcmp.py" differ "$work/ortho.png" "$work/orbit.png"

# L (--show-lod) shows each character's level of detail as `render --show-lod` does: on
# crowd-10k cut to 40 chibis with its `lod` on (camera 90 m out: every one posed, amber),
# following the scene camera (C), frame 29 in the window is render's frame 29 pixel for
# pixel; without L there is no amber dot. The status line counts the levels; --show-lod on
# a scene without characters is a usage error naming the scene.
python3 - "$src" "$work/crowd-40.json" <<'PY'
import json, os, sys
src, out = sys.argv[1], sys.argv[2]
scene = json.load(open(os.path.join(src, "scenes", "crowd-10k.json")))
scene["lod"]["enabled"] = True
scene["crowds"][0]["count"] = 40
scene["characters"][0]["gltf"] = os.path.join(src, "scenes", "characters", "chibi.glb")
json.dump(scene, open(out, "w"))
PY
view "$work/lod" "$work/crowd-40.json" --backend vulkan --size 200x150 --frames 30 --keys c,l --screenshot "$work/lod.png"
view "$work/nolod" "$work/crowd-40.json" --backend vulkan --size 200x150 --frames 30 --keys c --screenshot "$work/nolod.png"
"$bin" render "$work/crowd-40.json" --backend vulkan --size 200x150 --frames 0:30 --show-lod --out "$work/lod-frames" >/dev/null
check "L: the window shows the levels as render --show-lod does" python3 "$work/pngcmp.py" same "$work/lod.png" "$work/lod-frames/crowd-10k_00029.png"
check "L: posed characters' amber dots" python3 "$work/png.py" "$work/lod.png" 240,170,40
check "without L: no amber dot" bash -c "! python3 '$work/png.py' '$work/nolod.png' 240,170,40 >/dev/null"
check "L says what it shows" grep -q "levels of detail shown (green full, amber posed, blue hidden)" "$work/lod.out"
# --budget-ms: the end line says what the budget did at the last frame (a roomy one takes
# every character the projected-size rule makes full, whatever the measured scale).
view "$work/budget" "$work/crowd-40.json" --size 160x120 --frames 5 --budget-ms 100
check "--budget-ms: the end line says what the budget did" grep -q \
    "at the last frame, budget 100 ms (measured x[0-9.]*): every character the rule makes full" "$work/budget.out"
view "$work/nochars" scenes/flock.json --size 160x120 --frames 2 --show-lod
check "--show-lod without characters exits 2 naming the scene" bash -c "test $? -eq 2 && grep -q -- '--show-lod: scene .*flock.json has no characters' '$work/nochars.err'"

# Playing: 5 drawn frames are frames 0 .. 4; Q quits before the limit.
view "$work/play" scenes/ahoge.json --size 160x120 --frames 5
check "playing ends at frame 4" grep -q "view ended at frame 4 (t 0.067 s, playing)" "$work/play.out"
view "$work/quit" scenes/ahoge.json --size 160x120 --frames 50 --keys "space,right,q"
check "q quits" grep -q "view ended at frame 1 .* after 2 drawn frames" "$work/quit.out"

# Sketching by a scripted drag on a copy of the scene: orbit 0.8 rad round (between the
# scene's front and side examples, so the sketch adds one instead of replacing one), S
# (sketch mode, pauses), influence x1.25, a stroke from the strand's root (projected near
# (160, 100) at 320x240: the orbit turns round the head; the press picks the chain within
# 30 px) up and to the left, W saves. Undoing the saved sketch
# with `kodawari sketch --undo` gives back the original bytes.
cp scenes/ahoge.json "$work/ahoge.json"
view "$work/sketch" "$work/ahoge.json" --size 320x240 --frames 6 --keys "orbit:80:0,s,+,drag:160:100:120:50,w" --screenshot "$work/sketch.png"
rc=$?
check "sketch run exits 0" test $rc -eq 0
check "sketch picks the chain and adds an example" grep -q 'sketch .*: view example "sketch 1" added, influence 5,' "$work/sketch.out"
check "sketch is saved" bash -c "grep -q 'saved $work/ahoge.json' '$work/sketch.out' && grep -q '\"sketch 1\"' '$work/ahoge.json'"
chain=$(sed -n 's/^kodawari: sketch \([^:]*\): view example.*/\1/p' "$work/sketch.out" | head -1)
"$bin" sketch "$work/ahoge.json" --chain "$chain" --undo --out "$work/undone.json" >/dev/null
check "undoing the saved sketch gives the original bytes" cmp -s "$work/undone.json" scenes/ahoge.json

# K cycles what the next sketch makes (view, motion, pose example); the same drag after K K
# adds a pose example keyed by the head's pose at the frame shown (docs/sketch.md, "Keyed
# sketches"), saved with W; the command's --undo takes it back out, byte for byte.
cp scenes/ahoge.json "$work/ahoge-k.json"
view "$work/ksketch" "$work/ahoge-k.json" --size 320x240 --frames 8 --keys "orbit:80:0,s,k,k,drag:160:100:120:50,w"
rc=$?
check "keyed sketch run exits 0" test $rc -eq 0
check "K says the next sketch makes a motion example" grep -q 'the next sketch makes a motion example' "$work/ksketch.out"
check "K again: a pose example" grep -q 'the next sketch makes a pose example' "$work/ksketch.out"
check "the drag adds a pose example" grep -q 'sketch .*: pose example "sketch 1" added, head as now, influence 20 degrees' "$work/ksketch.out"
check "the pose example is saved" grep -q '"key": "pose", "pose": \[{"joint": "head"' "$work/ahoge-k.json"
kchain=$(sed -n 's/^kodawari: sketch \([^:]*\): pose example.*/\1/p' "$work/ksketch.out" | head -1)
"$bin" sketch "$work/ahoge-k.json" --chain "$kchain" --undo --out "$work/kundone.json" >/dev/null
check "undoing the keyed sketch gives the original bytes" cmp -s "$work/kundone.json" scenes/ahoge.json

# What the window shows (not the offscreen copy): an Xvfb whose screen is a file (-fbdir,
# XWD format), read while the viewer runs until the chain's colour appears there.
if command -v Xvfb >/dev/null 2>&1; then
    mkdir -p "$work/fb"
    exec 3>"$work/display"
    Xvfb -displayfd 3 -noreset -screen 0 640x480x24 -fbdir "$work/fb" >/dev/null 2>&1 &
    xvfb_pid=$!
    exec 3>&-
    for _ in $(seq 50); do test -s "$work/display" && break; sleep 0.2; done
    DISPLAY=":$(cat "$work/display")" "$bin" view scenes/ahoge.json --size 400x300 --frames 100000 >"$work/live.out" 2>"$work/live.err" &
    view_pid=$!
    check "the window shows the chain" python3 - "$work/fb/Xvfb_screen0" <<'PY'
import struct, sys, time
deadline = time.time() + 60
while time.time() < deadline:
    time.sleep(0.5)
    try:
        d = open(sys.argv[1], 'rb').read()
    except OSError:
        continue
    v = struct.unpack('>25I', d[:100])  # XWD header: size, ..., width, height, ..., bytes per line, ..., colours
    off, width, height, bpl = v[0] + v[19] * 12, v[4], v[5], v[12]
    px = {d[off + y * bpl + 4 * x:off + y * bpl + 4 * x + 3] for y in range(height) for x in range(width)}
    # A lit shade of kChainColor (235, 95, 20), stored as B, G, R: f times it, f in
    # [render::kAmbientLight, 1], within 2 per channel.
    for p in px:
        f = min(max((p[2] * 235 + p[1] * 95 + p[0] * 20) / (235 * 235 + 95 * 95 + 20 * 20), 0.45), 1.0)
        if max(abs(p[2] - f * 235), abs(p[1] - f * 95), abs(p[0] - f * 20)) <= 2:
            sys.exit(0)
sys.exit(1)
PY
    kill "$view_pid" 2>/dev/null
    wait "$view_pid" 2>/dev/null
    kill "$xvfb_pid" 2>/dev/null
    wait "$xvfb_pid" 2>/dev/null
fi

# Real input through the X server, not --keys: xdotool sends key presses and mouse moves and
# buttons with XTEST, as a keyboard and a mouse do (key and mousedown/mouseup without
# --window: with it xdotool would use XSendEvent, synthetic events straight to the window),
# to viewers on an Xvfb of their own. No window manager there: the window takes the focus
# itself and windowfocus makes sure. Each step waits for what the viewer shows (its window
# title is `kodawari view - STATUS LINE`) or prints (picks, sketches, screenshots), polling
# with one 60 s deadline per viewer. The viewers run in $work/x, where P's screenshots land.
# A press must reach the viewer before the drag's moves do: it reads the pointer's position
# now (glfwGetCursorPos) at the press, so a press and moves handled in one glfwPollEvents
# would lose the drag (seen here). The steps wait for the press's effect (a screenshot taken
# with the button down, or the pick) before moving.
if ! command -v xdotool >/dev/null 2>&1 || ! command -v Xvfb >/dev/null 2>&1; then
    echo "SKIPPED: real X input (xdotool or Xvfb not installed; scripts/setup installs both)"
else
    real_bin=$(realpath "$bin")
    mkdir -p "$work/x"
    exec 3>"$work/x-display"
    # -noreset: when its last client leaves, an X server resets and refuses connections for
    # a moment; the next viewer or xdotool call could come then.
    Xvfb -displayfd 3 -noreset -screen 0 640x480x24 >/dev/null 2>&1 &
    x_xvfb_pid=$!
    exec 3>&-
    for _ in $(seq 50); do test -s "$work/x-display" && break; sleep 0.2; done
    xdisplay=":$(cat "$work/x-display")"
    x() { DISPLAY=$xdisplay xdotool "$@"; }
    wait_for() {  # wait_for CMD...: until CMD succeeds; fails at the deadline or once the viewer has exited
        until "$@"; do
            if ((SECONDS >= deadline)) || ! kill -0 "$live_pid" 2>/dev/null; then "$@"; return; fi
            sleep 0.05
        done
    }
    title_has() { x getwindowname "$win" 2>/dev/null | grep -q -- "$1"; }
    printed() { grep -Eq -- "$1" "$live_out"; }
    screenshots() { test "$(grep -c '^kodawari: wrote screenshot ' "$live_out")" -ge "$1"; }
    screenshot() { echo "$work/x/$(sed -n 's/^kodawari: wrote screenshot //p' "$live_out" | sed -n "$1p")"; }
    live_start() {  # live_start NAME ARGS...: a viewer in the background, its window found and focused
        local name=$1; shift
        live_out=$work/$name.out
        live_err=$work/$name.err
        (cd "$work/x" && DISPLAY=$xdisplay exec "$real_bin" view "$@" >"$live_out" 2>"$live_err") &
        live_pid=$!
        deadline=$((SECONDS + 60))
        win=
        find_window() { win=$(x search --onlyvisible --name '^kodawari view' 2>/dev/null | head -1) && test -n "$win"; }
        wait_for find_window && timeout 10 env DISPLAY="$xdisplay" xdotool windowfocus --sync "$win"
    }
    live_quit() {  # Q, then the viewer's output and exit status (killed after 10 s: 124)
        local end=$((SECONDS + 10)) rc
        x key q
        while kill -0 "$live_pid" 2>/dev/null && ((SECONDS < end)); do sleep 0.05; done
        if kill -0 "$live_pid" 2>/dev/null; then
            kill "$live_pid"
            wait "$live_pid"
            rc=124
        else
            wait "$live_pid"
            rc=$?
        fi
        cat "$live_out" "$live_err"
        return $rc
    }

    # 1. Space pauses; 2. a left drag orbits: a screenshot (P) before the drag, one with the
    # button pressed but not moved yet (same camera, paused: the same picture, the renderer
    # is deterministic), one after dragging 80 px to the right (another picture).
    x_start=$SECONDS
    live_start x-orbit "$PWD/scenes/ahoge.json" --size 320x240 --frames 100000
    check "real input: the window plays" wait_for title_has '  playing  '
    x key space
    check "real input: Space pauses (the window title says so)" wait_for title_has '  paused  '
    x key p
    wait_for screenshots 1
    x mousemove --window "$win" 100 120 mousedown 1 key p
    wait_for screenshots 2
    x mousemove --window "$win" 120 120 mousemove --window "$win" 140 120 mousemove --window "$win" 160 120 \
        mousemove --window "$win" 180 120 mouseup 1 key p
    wait_for screenshots 3
    check "real input: P twice with no drag between, the same picture" python3 "$work/pngcmp.py" same "$(screenshot 1)" "$(screenshot 2)"
    check "real input: a left drag orbits (another picture)" python3 "$work/pngcmp.py" differ "$(screenshot 2)" "$(screenshot 3)"
    live_quit
    rc=$?
    check "real input: Q quits the orbit run (exit 0)" test $rc -eq 0

    # 3. Sketching on a copy of the scene with a real stroke: the orbit of the scripted sketch
    # test above by --keys (applied on the first frame), then S, a press on the strand's root
    # (near (160, 100): window pixels are image pixels at the window's first size), a drag up
    # and to the left to (120, 50) in 8 moves, the release (sketches), W (saves).
    cp scenes/ahoge.json "$work/x/ahoge.json"
    live_start x-sketch "$work/x/ahoge.json" --size 320x240 --frames 100000 --keys orbit:80:0
    wait_for title_has '  playing  '
    x key s
    check "real input: S sketches over a still frame" wait_for title_has '  paused  .*\[sketch: influence 4\]'
    x mousemove --window "$win" 160 100 mousedown 1
    wait_for printed '^kodawari: (picked|no chain)'
    check "real input: the press picks the chain" printed '^kodawari: picked '
    moves=()
    for i in 1 2 3 4 5 6 7 8; do moves+=(mousemove --window "$win" $((160 - 5 * i)) $((100 - 50 * i / 8))); done
    x "${moves[@]}" mouseup 1
    check "real input: the stroke adds a view example" wait_for printed '^kodawari: sketch [^:]*: view example "sketch 1" added, influence 4,'
    x key w
    wait_for printed '^kodawari: saved '
    check "real input: W saves it" grep -q '"sketch 1"' "$work/x/ahoge.json"
    live_quit
    rc=$?
    check "real input: Q quits the sketch run (exit 0)" test $rc -eq 0
    echo "real input: $((SECONDS - x_start)) s"
    kill "$x_xvfb_pid" 2>/dev/null
    wait "$x_xvfb_pid" 2>/dev/null
fi

# A bad scene is reported (exit 2) before any window: no display is needed to see it.
printf '{"name": "broken",' >"$work/bad.json"
env -u DISPLAY -u WAYLAND_DISPLAY "$bin" view "$work/bad.json" >"$work/bad.out" 2>"$work/bad.err"
rc=$?
cat "$work/bad.err"
check "bad scene exits 2" test $rc -eq 2
# Without a display server the viewer says so (exit 1) instead of crashing.
env -u DISPLAY -u WAYLAND_DISPLAY "$bin" view scenes/ahoge.json --frames 1 >"$work/nodisplay.out" 2>"$work/nodisplay.err"
rc=$?
cat "$work/nodisplay.err"
check "no display exits 1 with a reason" bash -c "test $rc -eq 1 && grep -q 'cannot open a window' '$work/nodisplay.err'"
# KODAWARI_VALIDATION=1 (CTest): Khronos + synchronization validation, teardown included.
check "no validation messages in any window run" bash -c "! cat '$work'/*.err | grep -q '\[vulkan validation\]'"
check "unknown key name is a usage error" bash -c "'$bin' view scenes/ahoge.json --keys space,bogus >/dev/null 2>&1; test \$? -eq 2"

echo "viewer: $passed passed, $failed failed"
test "$failed" -eq 0
