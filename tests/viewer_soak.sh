#!/usr/bin/env bash
# A long viewer session under Xvfb with validation on (ctest sets KODAWARI_VALIDATION=1):
# CYCLES rounds of window resizes, backend switches (1 2 3: cpu-reference, cpu, vulkan),
# orbits, seeks, and sketches that are drawn and undone, one step per drawn frame. Passes
# when the viewer exits 0 (any validation message makes it exit 1), prints no validation
# message, and its memory does not grow: the resident set at the end is within BOUND_MB of
# the largest seen in the session's first quarter, sampled every 0.2 s from /proc. The
# bound: one backend switch remakes the simulation and its device buffers (a few MB for
# this scene) and the allocators keep freed blocks; a leak of one buffer per cycle would
# pass it within a few cycles. Exits 77 (CTest: skipped) where xvfb-run is not installed.
# usage: viewer_soak.sh KODAWARI_BINARY SOURCE_DIR [CYCLES]
set -uo pipefail
bin=$1
src=$2
cycles=${3:-60}
bound_mb=24
if ! command -v xvfb-run >/dev/null 2>&1; then
    echo "SKIPPED: no X server (xvfb-run not installed; scripts/setup installs xvfb)"
    exit 77
fi
source "$(dirname "${BASH_SOURCE[0]}")/check.sh"
cp "$src/scenes/ahoge.json" "$work/soak-scene.json"
cycle="resize:400:300,3,],right,resize:320:240,home,orbit:80:0,s,+,drag:160:100:120:50,u,-,s,orbit:-80:0,2,space,resize:480:360,1,space,resize:320:240,home,orbit:80:0,s,drag:160:100:120:50,u,s,orbit:-80:0,3,left"
keys=$cycle
for ((k = 1; k < cycles; ++k)); do keys+=",$cycle"; done
steps=$(($(tr -cd ',' <<<"$keys" | wc -c) + 1))
frames=$((steps + 10))
echo "viewer soak: $cycles cycles, $steps scripted steps, $frames frames"

xvfb-run -a -s "-screen 0 1024x768x24" "$bin" view "$work/soak-scene.json" --size 320x240 --frames "$frames" --keys "$keys" \
    >"$work/soak.out" 2>"$work/soak.err" &
runner=$!
# The viewer's own process (xvfb-run's child): its resident set, sampled until it exits.
pid=""
for ((t = 0; t < 100; ++t)); do
    [[ -n "$pid" ]] && break
    sleep 0.1
    pid=$(pgrep -f "^$bin view $work/soak-scene.json" | head -1)
done
: >"$work/rss.txt"
while [[ -n "$pid" ]] && kill -0 "$pid" 2>/dev/null; do
    awk '/^VmRSS:/ {print $2}' "/proc/$pid/status" 2>/dev/null >>"$work/rss.txt"
    sleep 0.2
done
wait "$runner"
rc=$?
tail -4 "$work/soak.out"
grep -v '^kodawari: sketch' "$work/soak.err" | tail -5
check "the viewer ran the whole session and exited 0" test "$rc" -eq 0
check "no validation message" bash -c "! grep -q '\\[vulkan validation\\]' '$work/soak.err'"
check "every sketch was drawn and undone" bash -c "test \$(grep -c 'view example \"sketch 1\" added' '$work/soak.out') -eq $((2 * cycles))"
samples=$(wc -l <"$work/rss.txt")
check "the resident set was sampled (>= 20 samples, got $samples)" test "$samples" -ge 20
if ((samples >= 20)); then
    quarter=$((samples / 4))
    early_kb=$(head -n "$quarter" "$work/rss.txt" | sort -n | tail -1)
    end_kb=$(tail -n 5 "$work/rss.txt" | sort -n | tail -1)
    peak_kb=$(sort -n "$work/rss.txt" | tail -1)
    echo "resident set: ${early_kb} kB at most in the first quarter, ${end_kb} kB at the end, ${peak_kb} kB at the peak"
    check "memory grew by at most $bound_mb MB over the session" test $((end_kb - early_kb)) -le $((bound_mb * 1024))
fi
echo "viewer soak: $passed passed, $failed failed"
test "$failed" -eq 0
