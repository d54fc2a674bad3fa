#!/usr/bin/env bash
# ctest's `meshopt_readers` (docs/compact.md, "--meshopt"): `--compact --meshopt` files of
# the three writers (the birds of flock.json at the default bounds and at loose ones, the
# chains of ahoge.json, the rigged crowd of crowd-gltf.json) pass glTF-Validator with 0
# errors and 0 warnings, and two readers that decode EXT_meshopt_compression, three.js
# (GLTFLoader + MeshoptDecoder) and gltf-transform, give back every frame of the
# uncompacted bake within the bounds (tests/meshopt/readers.mjs). Node.js is the one
# thing it may do without: then it skips (77) and says why; three, gltf-transform or the
# validator missing from .tools/npm is a failure.
#
#   bash meshopt_test.sh KODAWARI_BINARY SOURCE_DIR
set -uo pipefail
bin="$1"
root="$2"
tools="${KODAWARI_NODE_TOOLS:-$root/.tools/npm}"
if ! command -v node >/dev/null 2>&1; then
  echo "meshopt_readers skipped: node (Node.js) is not installed; scripts/setup installs it"
  exit 77
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
failures=0
check() {
  local name="$1"
  shift
  if "$@"; then echo "ok: $name"; else echo "FAIL: $name"; failures=$((failures + 1)); fi
}

# NAME SCENE BOUNDS(METRES,RADIANS) RUN-OPTIONS...
case_of() {
  local name="$1" scene="$2" metres="$3" radians="$4"
  shift 4
  "$bin" run "$root/scenes/$scene" "$@" --out "$work/$name-full.glb" >"$work/$name-full.out" 2>&1
  check "$name: uncompacted bake" test $? -eq 0
  "$bin" run "$root/scenes/$scene" "$@" --compact="$metres,$radians" --meshopt --out "$work/$name.glb" >"$work/$name.out" 2>&1
  check "$name: --compact=$metres,$radians --meshopt bake" test $? -eq 0
  cat "$work/$name.out" | grep "compact:"
  node "$root/tests/tools/validate_gltf.mjs" "$work/$name.glb" >"$work/$name.validator" 2>&1
  tail -n 1 "$work/$name.validator"
  check "$name: glTF-Validator 0 errors, 0 warnings" grep -q "0 errors, 0 warnings" "$work/$name.validator"
  check "$name: EXT_meshopt_compression required" python3 -c "
import json, struct, sys
data = open(sys.argv[1], 'rb').read()
gltf = json.loads(data[20:20 + struct.unpack_from('<I', data, 12)[0]])
sys.exit(0 if gltf.get('extensionsRequired') == ['EXT_meshopt_compression'] else 1)" "$work/$name.glb"
  node "$root/tests/meshopt/readers.mjs" "$work/$name-full.glb" "$work/$name.glb" "$metres" "$radians" "$tools"
  check "$name: three.js and gltf-transform read it within the bounds" test $? -eq 0
}

# 240 frames of flock.json: every wing beats a dozen times, the body turns along its route,
# tails spread (a scale channel).
case_of flock flock.json 0.001 0.001 --backend cpu --frames 240
case_of flock-loose flock.json 0.005 0.02 --backend cpu --frames 120
case_of ahoge ahoge.json 0.001 0.001 --frames 60
case_of crowd crowd-gltf.json 0.001 0.001 --frames 30

if ((failures > 0)); then
  echo "meshopt_readers: $failures check(s) failed"
  exit 1
fi
echo "meshopt_readers: all checks passed"
