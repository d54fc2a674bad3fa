#!/usr/bin/env bash
# The shipped scenes bake to the very bytes they baked to before the engine was
# restructured (issue 19: one Simulation facade, one compute layer): every exported glTF
# and trace of scripts/export_hashes.sh on the CPU backends matches tests/export_hashes.txt.
#   bash tests/export_identity.sh KODAWARI SOURCE_DIR
set -euo pipefail
kodawari="$1"
src="$2"
expected="$src/tests/export_hashes.txt"
actual="$(mktemp)"
trap 'rm -f "$actual"' EXIT
bash "$src/scripts/export_hashes.sh" "$kodawari" "$src" 24 "cpu-reference cpu" >"$actual"
if ! diff -u "$expected" "$actual"; then
  echo "export_identity: the lines above differ from $expected (- expected, + now)" >&2
  echo "export_identity: $(diff "$expected" "$actual" | grep -c '^>' || true) of $(wc -l <"$expected") files changed" >&2
  exit 1
fi
echo "export_identity: $(wc -l <"$expected") files byte-identical to $expected"
