#!/usr/bin/env bash
# ctest's `spring_conformance` (tests/conformance/conformance.mjs, README.md): our VRM
# spring bones against the stored three-vrm conformance vectors, on every backend (issue
# 36). Node.js is the one thing it may do without: then it skips (77) and says why.
# Without three and three-vrm in .tools/npm it still compares with the stored vectors, but
# cannot make them again: it then ends with 77 too (when every check it could run passed),
# saying so. A missing binary or a run that fails is a failure (2).
#
#   bash conformance_test.sh KODAWARI_BINARY SOURCE_DIR [conformance.mjs options]
set -euo pipefail
bin="$1"
root="$2"
shift 2
if ! command -v node >/dev/null 2>&1; then
  echo "spring_conformance skipped: node (Node.js) is not installed; scripts/setup installs it"
  exit 77
fi
exec node "$root/tests/conformance/conformance.mjs" "$bin" "$root" "$@"
