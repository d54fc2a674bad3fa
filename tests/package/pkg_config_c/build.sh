#!/usr/bin/env bash
# A C application built with pkg-config and nothing else, with the exact command line of
# docs/install.md ("The C API"): the library's folder is given to the loader as an rpath,
# since a prefix outside the loader's path is what this test installs into.
#   bash build.sh OUT_DIR      (PKG_CONFIG_PATH points at the prefix's lib/pkgconfig)
set -euo pipefail
out="$1"
cd "$(dirname "$0")/../../../examples/embed_cpu"
cp main.c "$out/app.c"
cd "$out"
cc app.c $(pkg-config --cflags --libs kodawari-c) -Wl,-rpath,$(pkg-config --variable=libdir kodawari-c) -o app
