#!/usr/bin/env bash
# Faults while writing (issue 16): every output the commands write (run's .glb and trace,
# render's PNG folder and contact sheet, rig's scene, sketch's scene rewritten in place)
# to a full disk, to a directory that cannot be written and to /dev/full must fail with
# status 1 and an error naming the file and why, and leave neither output nor temporary
# file (sketch: the scene byte for byte as it was). And a scene larger than the Vulkan
# device can bind: --backend vulkan fails naming the buffer and the sizes, auto runs on
# the CPU saying why in one line.
# usage: faults_test.sh KODAWARI_BINARY SOURCE_DIR
set -uo pipefail
bin=$1
src=$2
source "$(dirname "${BASH_SOURCE[0]}")/check.sh"

cd "$src"

mounts=()
cleanup() {
  for m in "${mounts[@]}"; do umount "$m" 2>/dev/null || umount -l "$m"; done
  chmod -R u+w "$work" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
root=0
[[ $(id -u) -eq 0 ]] && root=1

# mount_tmpfs DIR OPTIONS: a fresh tmpfs at DIR (unmounted at exit); 1 when it cannot be.
mount_tmpfs() {
  mkdir -p "$1"
  [[ $root -eq 1 ]] && mount -t tmpfs -o "$2" tmpfs "$1" 2>/dev/null || return 1
  mounts+=("$1")
}
# fill DIR: fills the file system of DIR to the last block.
fill() { dd if=/dev/zero of="$1/filler" bs=4k >/dev/null 2>&1; sync; }

printf '{"points": [[640, 300], [660, 260], [700, 240], [740, 250]]}' >"$work/stroke.json"
cp scenes/ahoge.json "$work/ahoge.orig.json"

# expect_failure CASE DIR FILE WHY COMMAND...: COMMAND exits 1, its error names FILE and
# says WHY (the strerror text), and DIR holds exactly what it held before.
expect_failure() {
  local name=$1 dir=$2 file=$3 why=$4
  shift 4
  local before after rc
  before=$(ls -A "$dir")
  "$@" >"$work/case.out" 2>"$work/case.err"
  rc=$?
  after=$(ls -A "$dir")
  sed 's/^/    /' "$work/case.err"
  check "$name: exits 1" test $rc -eq 1
  check "$name: the error names ${file##*/}" grep -qF "kodawari: error: $file" "$work/case.err"
  check "$name: ... and says why ($why)" grep -qF "($why)" "$work/case.err"
  check "$name: no output, no temporary file left" test "$before" = "$after"
}
# The sketch cases: the scene in DIR is rewritten in place (or at --out).
sketch_in() {  # in place unless --out is among the arguments
  local where=(--in-place)
  [[ " ${*:2} " == *" --out "* ]] && where=()
  "$bin" sketch "$1/ahoge.json" --chain girl/ahoge --stroke "$work/stroke.json" --influence 30 "${where[@]}" "${@:2}"
}
scene_unchanged() { cmp -s "$1/ahoge.json" "$work/ahoge.orig.json"; }

# 1. A full disk: a 256 KiB tmpfs, outputs of several MiB (and a filled one for the small files).
nospace='No space left on device'
if mount_tmpfs "$work/full" size=256k; then
  d="$work/full"
  # The .glb's keys wait in a spill file beside it, which fills the disk first.
  expect_failure "full disk, run .glb (birds)" "$d" "$d/flock.glb" "$nospace" \
    "$bin" run scenes/flock.json --backend cpu --frames 60 --out "$d/flock.glb"
  expect_failure "full disk, run .glb (chains)" "$d" "$d/crowd.glb" "$nospace" \
    "$bin" run scenes/crowd.json --backend cpu --frames 3 --out "$d/crowd.glb"
  expect_failure "full disk, run --trace" "$d" "$d/flock.jsonl" "$nospace" \
    "$bin" run scenes/flock.json --backend cpu --frames 10 --no-export --trace "$d/flock.jsonl"
  # render: frames are written until the disk is full; those go too, and the folder it made.
  expect_failure "full disk, render" "$d" "$d/frames/flock_000" "$nospace" \
    "$bin" render scenes/flock.json --frames 0:12 --out "$d/frames"
  check "full disk, render: it failed part-way (frames were written, then removed)" bash -c \
    "grep -q 'wrote .*flock_00000.png' '$work/case.out' && grep -q 'render failed: removed the [0-9]* files\? it wrote' '$work/case.err'"
else
  echo "SKIP: the full-disk cases: mounting a tmpfs needs root (running as uid $(id -u)) or failed here"
fi
# The small outputs on a disk of their own (so that no earlier case's leftovers matter),
# filled to the last block.
if mount_tmpfs "$work/filled" size=256k; then
  d="$work/filled"
  cp scenes/ahoge.json "$d/ahoge.json"
  fill "$d"
  expect_failure "full disk, rig" "$d" "$d/chibi.json" "$nospace" \
    "$bin" rig scenes/characters/chibi.glb --out "$d/chibi.json"
  expect_failure "full disk, sketch (in place)" "$d" "$d/ahoge.json" "$nospace" sketch_in "$d"
  check "full disk, sketch: the scene is byte for byte as it was" scene_unchanged "$d"
else
  echo "SKIP: the full-disk cases of rig and sketch: mounting a tmpfs needs root (running as uid $(id -u)) or failed here"
fi

# 1b. The .glb itself overflowing (its spill file fits; the two together do not): the
# atomic file's own write fails, not the spill's.
if mount_tmpfs "$work/full4m" size=4m; then
  expect_failure "full disk after the spill, run .glb" "$work/full4m" "$work/full4m/flock.glb: write failed" "$nospace" \
    "$bin" run scenes/flock.json --backend cpu --frames 60 --out "$work/full4m/flock.glb"
else
  echo "SKIP: the .glb overflowing after its spill file: mounting a tmpfs needs root or failed here"
fi

# 2. A directory that cannot be written: read-only as root (which ignores permission
# bits), chmod 555 otherwise.
d="$work/ro"
if mount_tmpfs "$d" size=4m; then
  cp scenes/ahoge.json "$d/ahoge.json"
  mount -o remount,ro "$d"
  denied='Read-only file system'
else
  mkdir -p "$d"
  cp scenes/ahoge.json "$d/ahoge.json"
  chmod 555 "$d"
  denied='Permission denied'
  [[ $root -eq 1 ]] && echo "SKIP: root ignores chmod 555 and no read-only tmpfs could be mounted: the cases below cannot fail"
fi
if [[ $root -eq 0 || "$denied" == 'Read-only file system' ]]; then
  expect_failure "unwritable directory, run .glb" "$d" "$d/flock.glb" "$denied" \
    "$bin" run scenes/flock.json --backend cpu --frames 5 --out "$d/flock.glb"
  expect_failure "unwritable directory, run --trace" "$d" "$d/flock.jsonl" "$denied" \
    "$bin" run scenes/flock.json --backend cpu --frames 5 --no-export --trace "$d/flock.jsonl"
  expect_failure "unwritable directory, render into it" "$d" "$d/flock_00000.png" "$denied" \
    "$bin" render scenes/flock.json --frames 0:2 --size 64x36 --out "$d"
  expect_failure "unwritable directory, render a folder in it" "$d" "--out $d/frames: cannot create the directory" "$denied" \
    "$bin" render scenes/flock.json --frames 0:2 --size 64x36 --out "$d/frames"
  expect_failure "unwritable directory, rig" "$d" "$d/chibi.json" "$denied" \
    "$bin" rig scenes/characters/chibi.glb --out "$d/chibi.json"
  expect_failure "unwritable directory, sketch (in place)" "$d" "$d/ahoge.json" "$denied" sketch_in "$d"
  check "unwritable directory, sketch: the scene is byte for byte as it was" scene_unchanged "$d"
fi

# 3. /dev/full: a device is written in place (an atomic writer would rename a file over it:
# as root that replaced the device node), and its ENOSPC is the error. As root, a private
# node of the same device, so that a regression cannot replace the machine's /dev/full.
d="$work/dev"
mkdir -p "$d"
full=/dev/full
if [[ $root -eq 1 ]] && mknod "$d/full" c 1 7 2>/dev/null; then full="$d/full"; fi
if [[ -c "$full" ]]; then
  cp scenes/ahoge.json "$d/ahoge.json"
  expect_failure "/dev/full, run .glb" "$d" "$full: write failed" "$nospace" \
    "$bin" run scenes/flock.json --backend cpu --frames 5 --out "$full"
  check "/dev/full, run .glb: still the device" test -c "$full"
  expect_failure "/dev/full, run --trace" "$d" "$full: write failed" "$nospace" \
    "$bin" run scenes/flock.json --backend cpu --frames 5 --no-export --trace "$full"
  check "/dev/full, run --trace: still the device" test -c "$full"
  expect_failure "/dev/full, render --contact-sheet" "$d" "$full: write failed" "$nospace" \
    "$bin" render scenes/flock.json --frames 0:2 --size 64x36 --out "$d/frames" --contact-sheet "$full"
  expect_failure "/dev/full, rig" "$d" "$full: write failed" "$nospace" \
    "$bin" rig scenes/characters/chibi.glb --out "$full"
  expect_failure "/dev/full, sketch --out" "$d" "$full: write failed" "$nospace" sketch_in "$d" --out "$full"
  check "/dev/full, sketch: the scene is byte for byte as it was" scene_unchanged "$d"
  check "/dev/full: still the device after every case" test -c "$full"
else
  echo "SKIP: the /dev/full cases: no /dev/full here"
fi

# 4. A scene larger than the Vulkan device can bind: one flock whose poses of a single
# frame (64 bytes a bird) exceed the chosen device's maxStorageBufferRange (lavapipe:
# 128 MiB, so 2.1 million birds: 0.2 s and 170 MB to build host-side). The buffer every
# other route to "too large" would need (gigabytes of chains, or the ring of frames) costs
# far more host memory; the pose ring itself shrinks to fit and is not a failure.
range_mib=$(KODAWARI_VALIDATION=0 "$bin" info 2>/dev/null | awk '
  /^chosen: \[/ { match($0, /\[[0-9]+\]/); chosen = substr($0, RSTART, RLENGTH) }
  /^  \[[0-9]+\] / { current = $1 }
  /storage buffer range/ { for (i = 1; i <= NF; ++i) if ($i == "range") range[current] = $(i + 1) }
  END { if (chosen != "") print range[chosen] }')
if [[ -z "$range_mib" ]]; then
  echo "SKIP: the device-limit cases: no Vulkan device here"
else
  # Above the printed range (rounded to 0.1 MiB) for sure.
  birds=$(awk -v r="$range_mib" 'BEGIN { printf "%d", (r + 0.1) * 1048576 / 96 + 1 }')
  if (( birds > 10000000 )); then
    echo "SKIP: the device-limit cases: this device's storage buffer range ($range_mib MiB) holds the largest scene (10 million birds)"
  else
    python3 - "$work/toobig.json" "$birds" <<'EOF'
import json, sys
scene = json.load(open("scenes/flock.json"))
scene["name"] = "toobig"
scene["flocks"] = scene["flocks"][:1]
scene["flocks"][0]["count"] = int(sys.argv[2])
json.dump(scene, open(sys.argv[1], "w"))
EOF
    bytes=$((birds * 96))
    "$bin" run "$work/toobig.json" --backend vulkan --frames 1 --no-export >"$work/big.out" 2>"$work/big.err"
    rc=$?
    cat "$work/big.err"
    check "too large for the device, --backend vulkan: exits 1 (no crash, no lost device)" test $rc -eq 1
    check "too large for the device, --backend vulkan: names the buffer and both sizes" grep -q \
      "kodawari: error: .* cannot hold $birds birds: the poses need a storage buffer of $bytes bytes (96 bytes per bird, one frame); the device allows [0-9]* (maxStorageBufferRange)" \
      "$work/big.err"
    # The device named, so that auto runs on it although it may be a CPU (issue 38).
    "$bin" run "$work/toobig.json" --frames 1 --no-export --device 0 >"$work/big-auto.out" 2>"$work/big-auto.err"
    rc=$?
    cat "$work/big-auto.out" "$work/big-auto.err"
    check "too large for the device, auto: runs on the cpu" bash -c "test $rc -eq 0 && grep -q 'backend cpu on' '$work/big-auto.out'"
    check "too large for the device, auto: one line says why, naming the buffer and the sizes" bash -c \
      "test \$(cat '$work/big-auto.out' '$work/big-auto.err' | grep -ciE 'vulkan|fall|runs on the cpu') -eq 1 &&
       grep -q 'backend auto runs on the CPU: .* cannot hold $birds birds: the poses need a storage buffer of $bytes bytes.*maxStorageBufferRange)' '$work/big-auto.err'"
  fi
fi

echo "passed $passed, failed $failed"
[[ $failed -eq 0 ]]
