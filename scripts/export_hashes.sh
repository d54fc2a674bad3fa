#!/usr/bin/env bash
# Bakes every shipped scene with `kodawari run` on the given backends (the first
# FRAMES frames, exported glTF and JSON Lines trace) and prints one line per file:
#   SCENE BACKEND KIND SHA256
# tests/export_identity.sh compares these lines with tests/export_hashes.txt, which this
# script wrote from the commit before a refactor: a change of structure must not change
# a single byte of what users bake.
#
#   bash scripts/export_hashes.sh KODAWARI [SOURCE_DIR] [FRAMES] [BACKENDS]
#
# BACKENDS defaults to "cpu-reference cpu": their bits depend on the compiler flags and
# the C library only, not on a Vulkan driver's code generation (lavapipe compiles for
# the host CPU's vector width), so the list holds on every x86-64 machine of this kind.
set -euo pipefail
kodawari="$1"
src="${2:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}"
frames="${3:-48}"
backends="${4:-cpu-reference cpu}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
for scene in "$src"/scenes/*.json; do
  name="$(basename "$scene" .json)"
  # crowd-10k is a benchmark scene: crowd-gltf's character 10 000 times (minutes on
  # cpu-reference), whose bytes crowd-gltf's lines already pin.
  [ "$name" = crowd-10k ] && continue
  for backend in $backends; do
    out="$work/$name-$backend"
    "$kodawari" run "$scene" --backend "$backend" --frames "$frames" --out "$out.glb" --trace "$out.jsonl" >/dev/null
    # A scene with rigged characters writes the character's own glTF under the out name;
    # list every file the bake wrote, in name order.
    for f in $(cd "$work" && ls "$name-$backend"* | sort); do
      printf '%s %s %s %s\n' "$name" "$backend" "${f#"$name-$backend"}" "$(sha256sum "$work/$f" | cut -d' ' -f1)"
    done
    rm -f "$out"*
  done
done
