#!/usr/bin/env bash
# ctest's `three_vrm_comparison` (tests/three_vrm/compare.mjs): our VRM spring-bone
# mapping measured against three-vrm's own spring bones on every backend (issue 18;
# docs/rigged-characters.md, "Measured against three-vrm"). Node.js is the one thing it
# may do without: then it skips (77) and says why. Everything else missing (three and
# three-vrm not installed in .tools/npm, the binary, a backend) is a failure, so a machine
# set up with scripts/setup never skips it silently.
#
#   bash three_vrm_test.sh KODAWARI_BINARY SOURCE_DIR [compare.mjs options]
set -euo pipefail
bin="$1"
root="$2"
shift 2
if ! command -v node >/dev/null 2>&1; then
  echo "three_vrm_comparison skipped: node (Node.js) is not installed; scripts/setup installs it"
  exit 77
fi
exec node "$root/tests/three_vrm/compare.mjs" "$bin" "$root" "$@"
