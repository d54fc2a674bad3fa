#!/usr/bin/env bash
# ctest's `schema` test (tests/schema/schema_test.mjs): the scene JSON Schema against the
# loader. Node.js is the one thing it may do without: then it skips (77) and says why.
# Everything else missing (Ajv not installed, the binary) is a failure, so a machine set
# up with scripts/setup never skips it silently.
set -euo pipefail
bin="$1"
root="$2"
if ! command -v node >/dev/null 2>&1; then
  echo "schema test skipped: node (Node.js) is not installed; scripts/setup installs it"
  exit 77
fi
exec node "$root/tests/schema/schema_test.mjs" "$bin" "$root"
