#!/usr/bin/env bash
# Issue 32's measures of the shipped murmuration on the file a user gets: bake
# scenes/starlings.json (20 000 starlings and a falcon, 60 s at 30 fps) as the README's
# users do, compacted (2.2 GiB; uncompacted it would be 4.6 GiB of keys), and measure it
# with starlings_bake_check (tests/flocking/starlings_bake_check.cpp says what and why).
# About a minute to bake and a minute to measure on 2 cores; kept out of the sanitizer lane.
# usage: starlings_bake_test.sh KODAWARI CHECKER SOURCE_DIR WORK_DIR
set -euo pipefail
bin=$1
checker=$2
src=$3
work=$4
rm -rf "$work"
mkdir -p "$work"
trap 'rm -rf "$work"' EXIT
free_kib=$(df -Pk "$work" | awk 'NR == 2 {print $4}')
if [ "$free_kib" -lt $((3 * 1024 * 1024)) ]; then
    echo "FAIL: the bake needs 3 GiB free in $work; $((free_kib / 1024)) MiB are" >&2
    exit 1
fi
start=$(date +%s)
"$bin" run "$src/scenes/starlings.json" --backend cpu --compact --out "$work/starlings.glb"
baked=$(date +%s)
echo "baked in $((baked - start)) s"
"$checker" "$src/scenes/starlings.json" "$work/starlings.glb"
echo "measured in $(($(date +%s) - baked)) s"
