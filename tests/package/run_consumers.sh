#!/usr/bin/env bash
# The package as an application meets it (issue 11), the way vk-bootstrap tests itself:
# installs the built tree into a temporary prefix, then builds and runs programs against
# it. Any missing header, dependency or symbol fails a step.
#
#   1. `cmake --install BUILD --prefix TMP`; the installed tree has the libraries, the
#      headers as files (shared/ too, not a link), the package and kodawari.pc, and the
#      installed command prints the version.
#   2. kodawariConfigVersion.cmake accepts 0.3 requests only (check_version.cmake).
#   3. headers/: every installed header compiles alone against the prefix, -Werror.
#   4. find_package/: find_package(kodawari 0.3 CONFIG REQUIRED), kodawari::engine,
#      consumer.cpp (every component used, a real run of each).
#   4b. examples/own_domain/: a domain of the application's own (its kernel, the public
#      compute layer) built standalone against the prefix and run.
#   5. find_package_sim/: COMPONENTS sim, tests/consumers/sim_only.cpp on kodawari::sim alone.
#   6. pkg_config/: make and `pkg-config --cflags --libs kodawari` (--static for a static
#      build), consumer.cpp again.
#   6b. The C API as docs/install.md shows it: find_package_c/ (COMPONENTS c, kodawari::c,
#      a C-only project) and pkg_config_c/build.sh (`cc app.c $(pkg-config ... kodawari-c)`
#      with the rpath), each running examples/embed_cpu/main.c and printing what the build
#      tree's embed_cpu_c prints; without the rpath the program must not start, and with
#      LD_LIBRARY_PATH (the documented alternative) it must.
#   The C++ consumers set no C++ standard: the compiler's default must do, as the targets
#   carry cxx_std_20 (GCC 12 defaults to C++17, where <span> is missing).
#   7. add_subdirectory/: the source tree as a subproject (its tests, command and
#      install rules off), consumer.cpp again. Its build folder is kept in
#      BUILD/tests/package/add_subdirectory, so that a second run rebuilds only what
#      changed (the first builds the library once more).
#
#   bash tests/package/run_consumers.sh BUILD SOURCE CXX LAUNCHER SHARED GENERATOR BUILD_TYPE \
#        [CXX_FLAGS [EXE_LINKER_FLAGS]]
#
# CXX is the compiler and LAUNCHER the compiler launcher (ccache, or "") of the build,
# SHARED its BUILD_SHARED_LIBS (ON/OFF), CXX_FLAGS and EXE_LINKER_FLAGS its
# CMAKE_CXX_FLAGS and CMAKE_EXE_LINKER_FLAGS, which the programs are built with too (the
# asan preset's libraries need the sanitizers' runtime). ctest runs it as the test
# `package` (LABELS package). JOBS (default 2) is the parallelism of the consumer builds.
set -euo pipefail
build="$(cd "$1" && pwd)"
src="$(cd "$2" && pwd)"
cxx="$3"
launcher="$4"
shared="$5"
generator="$6"
build_type="${7:-Release}"
cxx_flags="${8:-}"
exe_linker_flags="${9:-}"
jobs="${JOBS:-2}"
here="$src/tests/package"

# A fixed place under the build tree rather than mktemp's: the consumers' compile lines
# are then the same on every run and in every clone (ccache's base directory is the
# clone's), so ccache serves the 71 headers-alone compiles and the consumers from its
# cache after the first run (61 s of compiling each time from a random folder).
work="$build/tests/package/work"
rm -rf "$work"
mkdir -p "$work"
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"
out="$work/out"
mkdir -p "$out"
start=$SECONDS
step_start=$SECONDS

fail() {
  echo "package: FAILED: $*" >&2
  exit 1
}
# Runs a command with its output in a log, shown only when it fails.
quiet() {
  local log="$work/log"
  if ! "$@" >"$log" 2>&1; then
    cat "$log" >&2
    fail "$*"
  fi
}
done_step() {
  echo "package: $1 ($((SECONDS - step_start)) s)"
  step_start=$SECONDS
}
is_on() {
  case "${1^^}" in ON | 1 | TRUE | YES | Y) return 0 ;; *) return 1 ;; esac
}
configure() {  # configure SOURCE BINARY ARGS...
  local s="$1" b="$2"
  shift 2
  local args=(-G "$generator" -DCMAKE_BUILD_TYPE="$build_type" -DCMAKE_CXX_COMPILER="$cxx"
    -DCMAKE_CXX_FLAGS="$cxx_flags" -DCMAKE_EXE_LINKER_FLAGS="$exe_linker_flags")
  [[ -n "$launcher" ]] && args+=(-DCMAKE_CXX_COMPILER_LAUNCHER="$launcher")
  quiet cmake -S "$s" -B "$b" "${args[@]}" "$@"
}

# 1. Install.
quiet cmake --install "$build" --prefix "$prefix"
libdir="$(cd "$prefix" && ls -d lib* | head -1)"
for f in include/kodawari/simulation/simulation.hpp include/kodawari/core/api.hpp include/kodawari/core/version.hpp \
  include/kodawari/shared/birds.h "$libdir/cmake/kodawari/kodawariConfig.cmake" \
  "$libdir/cmake/kodawari/kodawariConfigVersion.cmake" "$libdir/cmake/kodawari/kodawariTargets.cmake" \
  "$libdir/pkgconfig/kodawari.pc" "$libdir/pkgconfig/kodawari-c.pc" include/kodawari/kodawari.h \
  share/doc/kodawari/docs/command-line.md share/doc/kodawari/README.md share/doc/kodawari/docs/embedding.md \
  share/doc/kodawari/docs/scene.schema.json share/doc/kodawari/docs/images/crowd-gltf.png; do
  [[ -f "$prefix/$f" ]] || fail "$f not installed"
done
links="$(find "$prefix/include" -type l)"
[[ -z "$links" ]] || fail "links installed instead of headers: $links"
# No internal header: every installed header is one of the source tree's public ones, or
# a forwarding header at a 0.2 path (kodawari/<name>.hpp, moved into a component's folder
# in 0.3) that includes one of them and nothing else.
forwarding=0
while IFS= read -r header; do
  rel="${header#"$prefix/include/"}"
  [[ -f "$src/engine/include/$rel" || -f "$src/engine/include/$rel.in" ]] && continue
  target="$(sed -n 's/^#include "\(kodawari\/[a-z_]*\/[a-z_]*\.hpp\)"$/\1/p' "$header")"
  [[ "$rel" == kodawari/*.hpp && "$rel" != kodawari/*/* && -n "$target" &&
     ( -f "$src/engine/include/$target" || -f "$src/engine/include/$target.in" ) &&
     "$(grep -c '^#' "$header")" == 2 ]] || fail "$rel is installed but not a public header"
  forwarding=$((forwarding + 1))
done < <(find "$prefix/include" -type f)
# One forwarding header per header moved (engine/CMakeLists.txt, KODAWARI_MOVED_HEADERS).
moved="$(sed -n '/^set(KODAWARI_MOVED_HEADERS/,/)/p' "$src/engine/CMakeLists.txt" | grep -o '[a-z_]*/[a-z_]*\.hpp' | wc -l)"
[[ $moved -gt 0 && $forwarding == "$moved" ]] ||
  fail "$forwarding forwarding headers installed at the 0.2 paths; KODAWARI_MOVED_HEADERS lists $moved"
ls "$prefix/$libdir/libkodawari.so".* >/dev/null 2>&1 || fail "libkodawari.so.* (the C API) not installed"
for component in sim vulkan io render engine; do
  if is_on "$shared"; then
    ls "$prefix/$libdir/libkodawari_$component.so".* >/dev/null 2>&1 || fail "libkodawari_$component.so.* not installed"
  else
    [[ -f "$prefix/$libdir/libkodawari_$component.a" ]] || fail "libkodawari_$component.a not installed"
  fi
done
if [[ -x "$prefix/bin/kodawari" ]]; then
  version="$("$prefix/bin/kodawari" --version)"
  echo "package: installed command: $version"
  # Its help points at the reference page where the install put it (issue 37: it named
  # docs/command-line.md, which an install has only under share/doc).
  "$prefix/bin/kodawari" --help | tr -d '\n' | grep -qF "$prefix/share/doc/kodawari/docs/command-line.md" \
    || fail "the installed command's --help does not name $prefix/share/doc/kodawari/docs/command-line.md"
  # The default scenes come with it (<prefix>/share/kodawari/scenes): `validate` without a
  # scene and `bench crowd` (its rigged crowd and the chibi it loads) work from a folder
  # that has no scenes/ (a reviewer's `bench crowd` from an install: "cannot open the scene").
  (cd "$work" && "$prefix/bin/kodawari" validate --backend cpu --frames 2 >"$work/default-scene.log" 2>&1) \
    || { cat "$work/default-scene.log"; fail "the installed command's validate found no default scene outside the source tree"; }
  (cd "$work" && "$prefix/bin/kodawari" bench crowd --count 2 --frames 2 --backends cpu --repetitions 3 >"$work/bench-crowd.log" 2>&1) \
    || { cat "$work/bench-crowd.log"; fail "the installed command's bench crowd found no default scene outside the source tree"; }
fi
echo "package: installed into a temporary prefix: $(find "$prefix" -type f | wc -l) files," \
  "$(find "$prefix/include" -type f | wc -l) headers, libraries in $libdir"
done_step "install"

# 2. The version file.
quiet cmake -DVERSION_FILE="$prefix/$libdir/cmake/kodawari/kodawariConfigVersion.cmake" -P "$here/check_version.cmake"
grep -o 'kodawari .*' "$work/log" | sed 's/^/package: /'
done_step "version file"

# 3. Each installed header alone.
configure "$here/headers" "$work/headers" -DCMAKE_PREFIX_PATH="$prefix"
quiet cmake --build "$work/headers" -j "$jobs"
echo "package: $(find "$work/headers" -name '*.o' | wc -l) installed headers compiled alone, -Wall -Wextra -Wpedantic -Werror"
done_step "headers alone"

# 4. find_package.
configure "$here/find_package" "$work/find_package" -DCMAKE_PREFIX_PATH="$prefix"
quiet cmake --build "$work/find_package" -j "$jobs"
"$work/find_package/consumer" "$src" "$out" || fail "the find_package consumer"
done_step "find_package consumer"

# 4b. A domain of the application's own on the installed compute layer
# (examples/own_domain, standalone: its kernel compiled by its own CMakeLists), run with
# a scene's domains on cpu and, where a device exists, vulkan.
configure "$src/examples/own_domain" "$work/own_domain" -DCMAKE_PREFIX_PATH="$prefix"
quiet cmake --build "$work/own_domain" -j "$jobs"
"$work/own_domain/own_domain" "$src/scenes/birds-closeup.json" --frames 30 | sed 's/^/package: /' \
  || fail "the own_domain example on the installed package"
done_step "find_package own_domain example"

# 5. find_package, COMPONENTS sim.
configure "$here/find_package_sim" "$work/find_package_sim" -DCMAKE_PREFIX_PATH="$prefix"
quiet cmake --build "$work/find_package_sim" -j "$jobs"
"$work/find_package_sim/sim_only" || fail "the sim-only consumer"
done_step "find_package COMPONENTS sim consumer"

# 6. pkg-config.
export PKG_CONFIG_PATH="$prefix/$libdir/pkgconfig"
if is_on "$shared"; then
  pc_libs=""
  ldflags="-Wl,-rpath,$prefix/$libdir"
else
  pc_libs="--static"
  ldflags=""
fi
echo "package: pkg-config --cflags --libs $pc_libs kodawari: $(pkg-config --cflags --libs $pc_libs kodawari)"
compiler="$cxx"
[[ -n "$launcher" ]] && compiler="$launcher $cxx"
quiet make -C "$here/pkg_config" OUT="$work" CXX="$compiler" PKG_CONFIG_LIBS="$pc_libs" CXXFLAGS="$cxx_flags" \
  LDFLAGS="$exe_linker_flags $ldflags"
"$work/consumer" "$src" "$out" || fail "the pkg-config consumer"
done_step "pkg-config consumer"

# 6b. The C API, with CMake and with pkg-config, as docs/install.md shows it.
expected_c="$("$build/tests/embed_cpu/embed_cpu_c")" || fail "the build tree's embed_cpu_c"
cc_launcher=()
[[ -n "$launcher" ]] && cc_launcher=(-DCMAKE_C_COMPILER_LAUNCHER="$launcher")
quiet cmake -S "$here/find_package_c" -B "$work/find_package_c" -G "$generator" -DCMAKE_BUILD_TYPE="$build_type" \
  -DCMAKE_C_FLAGS="$cxx_flags" -DCMAKE_EXE_LINKER_FLAGS="$exe_linker_flags" -DCMAKE_PREFIX_PATH="$prefix" "${cc_launcher[@]}"
quiet cmake --build "$work/find_package_c" -j "$jobs"
[[ "$("$work/find_package_c/app")" == "$expected_c" ]] || fail "the find_package(COMPONENTS c) consumer printed other tips than embed_cpu_c"
done_step "find_package COMPONENTS c consumer (C, kodawari::c)"
mkdir -p "$work/c"
quiet bash "$here/pkg_config_c/build.sh" "$work/c"
[[ "$("$work/c/app")" == "$expected_c" ]] || fail "the pkg-config kodawari-c consumer printed other tips than embed_cpu_c"
# Without the rpath the loader cannot find libkodawari.so in a prefix of its own; with
# LD_LIBRARY_PATH, the alternative docs/install.md gives, it can.
(cd "$work/c" && quiet cc app.c $(pkg-config --cflags --libs kodawari-c) $exe_linker_flags -o app_norpath)
if "$work/c/app_norpath" >/dev/null 2>&1; then fail "a program without the rpath started: the test's prefix is on the loader's path"; fi
[[ "$(LD_LIBRARY_PATH="$(pkg-config --variable=libdir kodawari-c)" "$work/c/app_norpath")" == "$expected_c" ]] \
  || fail "LD_LIBRARY_PATH=\$(pkg-config --variable=libdir kodawari-c) did not let the program run"
echo "package: pkg-config --cflags --libs kodawari-c: $(pkg-config --cflags --libs kodawari-c)"
done_step "pkg-config kodawari-c consumer (C, rpath and LD_LIBRARY_PATH)"

# 7. add_subdirectory, in a build folder kept between runs.
sub="$build/tests/package/add_subdirectory"
configure "$here/add_subdirectory" "$sub" -DKODAWARI_SOURCE_DIR="$src" -DBUILD_SHARED_LIBS="$shared"
quiet nice cmake --build "$sub" -j "$jobs"
"$sub/consumer" "$src" "$out" || fail "the add_subdirectory consumer"
done_step "add_subdirectory consumer"

echo "package: ok: installed, found with find_package and pkg-config, built with add_subdirectory ($((SECONDS - start)) s)"
