#!/usr/bin/env bash
# The GPU machine's run (docs/gpu.md): one command that measures what a machine with a GPU
# is lent for (about 15 minutes, bare: no package registry, no build tools), so that its
# minutes go to measuring, not to installing or debugging.
#
#   scripts/gpu_run.sh --bundle [DIR]   on the developer machine: gather the built `kodawari`,
#                                       every shared library it and the Vulkan loader and
#                                       validation layer load (glibc left out), embed_vulkan,
#                                       the shipped scenes and this script into DIR (default
#                                       gpu-bundle/ at the checkout's root), under 64 MiB
#   bash gpu-bundle/gpu_run.sh [OUT]    on the GPU machine (or scripts/gpu_run.sh [OUT] in a
#                                       built tree): info, validate on vulkan for every shipped
#                                       scene, the benchmarks, embed_vulkan; at most 5 minutes
#   scripts/gpu_run.sh --quick [OUT]    the same steps at small sizes on whatever device there
#                                       is (lavapipe here), at most 2 minutes: ctest gpu_run_quick
#
# OUT (default gpu-results/<UTC date-time> under the current directory) receives run.log
# (every step's command and output, as they come), results.json (rewritten after every
# step: step name, command, exit status, seconds and the benchmark's --json) and the
# benchmarks' JSON files; the table of the benchmarks is printed last. The binary is
# $KODAWARI, else the bundle's bin/kodawari, else build/release/host/kodawari; embed_vulkan
# is $KODAWARI_EMBED_VULKAN, else (with $KODAWARI) the one beside it or in its build tree,
# else the bundle's, else build/release/examples/embed_vulkan/ (run.log says which).
# GPU_RUN_BUDGET and GPU_RUN_STEP_LIMIT are whole seconds, 5 or more; a bad one, or a
# $KODAWARI that is not there, exits 2 before OUT is made.
# Nothing is built. GPU_RUN_ONLY=REGEX runs only the steps whose names match (bash regex);
# GPU_RUN_BUDGET=SECONDS replaces the run's deadline (290 s, --quick 110 s).
# GPU_RUN_STEP_LIMIT=SECONDS replaces the limit of each validate and embed step (40 s,
# --quick 30 s).
# Exit status: 0 when every step that ran passed, 1 when one failed, timed out or was left
# out for lack of time, 2 for bad usage or a bundle that cannot be made.
#
# Only bash, coreutils (timeout, date, ...), grep, sed and a POSIX awk are used on the GPU
# machine: it has no Python. A failing step must not end the run: every step's status is
# taken with `|| rc=$?` under set -e.
set -euo pipefail
# Decimal points in printf and awk, whatever the GPU machine's locale.
export LC_ALL=C

script_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# In a bundle the script sits beside bin/ and lib/; in a checkout it is scripts/gpu_run.sh.
if [[ -f "$script_dir/MANIFEST" && -f "$script_dir/bin/kodawari" && -d "$script_dir/lib" ]]; then
  in_bundle=1
  root="$script_dir"
  # A copy that dropped the modes (some transfers do) still runs.
  [[ -x "$root/bin/kodawari" ]] || chmod u+x "$root"/bin/* 2>/dev/null || true
else
  in_bundle=0
  root="$(cd "$script_dir/.." && pwd)"
fi
max_bundle_bytes=$((64 * 1024 * 1024))

usage() {
  sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed -e '$d' -e 's/^# \{0,1\}//'
}

# ---------------------------------------------------------------------------------------
# --bundle
# ---------------------------------------------------------------------------------------

# glibc's own libraries: the GPU machine's C library must load them (ld.so, libc and
# libm of one build go together), so they are never bundled. libstdc++ and libgcc_s are
# (lib/compat/): the machine's distribution may be older than this one; the launcher uses
# them only where the machine's own lack the versions the bundle needs.
is_glibc() {
  case "$1" in
    linux-vdso.so.* | ld-linux*.so.* | libc.so.* | libm.so.* | libdl.so.* | libpthread.so.* | \
      librt.so.* | libresolv.so.* | libutil.so.* | libanl.so.* | libmvec.so.* | libnsl.so.* | \
      libBrokenLocale.so.* | libthread_db.so.* | libnss_*.so.* | libc_malloc_debug.so.*)
      return 0 ;;
  esac
  return 1
}

# The path of a shared library by name, as the dynamic loader would find it.
find_lib() {
  local name="$1" path dir
  path="$( (/sbin/ldconfig -p 2>/dev/null || ldconfig -p 2>/dev/null || true) |
    awk -v n="$name" '$1 == n && /x86-64/ { print $NF; exit }')"
  if [[ -n "$path" && -e "$path" ]]; then
    printf '%s\n' "$path"
    return 0
  fi
  for dir in /usr/lib/x86_64-linux-gnu /lib/x86_64-linux-gnu /usr/lib64 /lib64 /usr/local/lib /usr/lib /lib; do
    if [[ -e "$dir/$name" ]]; then
      printf '%s\n' "$dir/$name"
      return 0
    fi
  done
  return 1
}

# The Khronos validation layer's manifest, where the loader would look for it.
find_layer_manifest() {
  local dir
  local -a dirs=()
  if [[ -n "${VK_LAYER_PATH:-}" ]]; then IFS=: read -r -a dirs <<<"$VK_LAYER_PATH"; fi
  dirs+=(/usr/local/share/vulkan/explicit_layer.d /usr/share/vulkan/explicit_layer.d /etc/vulkan/explicit_layer.d)
  for dir in "${dirs[@]}"; do
    if [[ -f "$dir/VkLayer_khronos_validation.json" ]]; then
      printf '%s\n' "$dir/VkLayer_khronos_validation.json"
      return 0
    fi
  done
  return 1
}

# The highest version of a symbol-version family (GLIBC_, GLIBCXX_, CXXABI_, GCC_) named
# in the files: what the machine's libraries must define for them to load.
max_version() {
  local prefix="$1"
  shift
  { grep -aoh "${prefix}_[0-9][0-9.]*[0-9]" "$@" 2>/dev/null || true; } | sort -u -V | tail -n 1
}

make_bundle() {
  local dest="$1"
  local kodawari="${KODAWARI:-$root/build/release/host/kodawari}"
  local embed="${KODAWARI_EMBED_VULKAN:-$root/build/release/examples/embed_vulkan/embed_vulkan}"
  if [[ "$in_bundle" == 1 ]]; then
    echo "gpu_run.sh --bundle: run it in a built checkout (scripts/gpu_run.sh), not in a bundle" >&2
    return 2
  fi
  if [[ ! -x "$kodawari" ]]; then
    echo "gpu_run.sh --bundle: no kodawari at $kodawari (build the tree: cmake --preset release && cmake --build build/release, or set KODAWARI)" >&2
    return 2
  fi
  if [[ -e "$dest" && ! -d "$dest" ]]; then
    echo "gpu_run.sh --bundle: $dest exists and is not a folder" >&2
    return 2
  fi
  # Written beside and renamed at the end: a failed bundle leaves no half-made folder.
  bundle_tmp="$dest.tmp-$$"
  local tmp="$bundle_tmp"
  rm -rf "$tmp"
  trap 'rm -rf "$bundle_tmp"' EXIT
  mkdir -p "$tmp/bin" "$tmp/lib/compat" "$tmp/layers"

  cp -L "$kodawari" "$tmp/bin/kodawari"
  local -a elves=("$kodawari")
  if [[ -x "$embed" ]]; then
    cp -L "$embed" "$tmp/bin/embed_vulkan"
    elves+=("$embed")
  else
    echo "gpu_run.sh --bundle: no embed_vulkan at $embed (its step will be skipped)" >&2
  fi
  # Loaded at run time with dlopen, which ldd does not see: the Vulkan loader, and the
  # validation layer (its manifest's library_path rewritten to point into the bundle).
  local loader
  if ! loader="$(find_lib libvulkan.so.1)"; then
    echo "gpu_run.sh --bundle: no libvulkan.so.1 on this machine (Debian package libvulkan1)" >&2
    return 2
  fi
  cp -L "$loader" "$tmp/lib/libvulkan.so.1"
  elves+=("$loader")
  local manifest layer_lib="" layer_name
  if manifest="$(find_layer_manifest)"; then
    layer_name="$(sed -n 's/.*"library_path"[[:space:]]*:[[:space:]]*"\([^"]*\)".*/\1/p' "$manifest" | head -n 1)"
    case "$layer_name" in
      /*) layer_lib="$layer_name" ;;
      */*) layer_lib="$(dirname "$manifest")/$layer_name" ;;
      ?*) layer_lib="$(find_lib "$layer_name" || true)" ;;
    esac
    if [[ -n "$layer_lib" && -f "$layer_lib" ]]; then
      cp -L "$layer_lib" "$tmp/lib/$(basename "$layer_lib")"
      # A library_path with a slash is relative to the manifest (the loader's rule).
      sed 's|\("library_path"[[:space:]]*:[[:space:]]*"\)[^"]*"|\1../lib/'"$(basename "$layer_lib")"'"|' \
        "$manifest" >"$tmp/layers/VkLayer_khronos_validation.json"
      elves+=("$layer_lib")
    else
      echo "gpu_run.sh --bundle: the validation layer's manifest $manifest names $layer_name, not found: bundled without it" >&2
    fi
  else
    echo "gpu_run.sh --bundle: no validation layer here (Debian package vulkan-validationlayers): bundled without it" >&2
  fi

  # Every library the binaries and those libraries load, to the end of the chain (ldd
  # resolves the whole tree), glibc left out.
  local elf line name path missing=""
  declare -A seen=()
  for elf in "${elves[@]}"; do
    while IFS= read -r line; do
      if [[ "$line" =~ ^[[:space:]]*([^[:space:]]+)[[:space:]]+=\>[[:space:]]+not\ found ]]; then
        missing+=" ${BASH_REMATCH[1]} (for $elf)"
        continue
      fi
      [[ "$line" =~ ^[[:space:]]*([^[:space:]]+)[[:space:]]+=\>[[:space:]]+([^[:space:]]+) ]] || continue
      name="${BASH_REMATCH[1]}"
      path="${BASH_REMATCH[2]}"
      is_glibc "$name" && continue
      [[ -n "${seen[$name]:-}" ]] && continue
      seen[$name]=1
      case "$name" in
        libstdc++.so.* | libgcc_s.so.*) cp -L "$path" "$tmp/lib/compat/$name" ;;
        *) [[ -e "$tmp/lib/$name" ]] || cp -L "$path" "$tmp/lib/$name" ;;
      esac
    done < <(ldd "$elf")
  done
  if [[ -n "$missing" ]]; then
    echo "gpu_run.sh --bundle: libraries not found:$missing" >&2
    return 2
  fi

  # The GL vendor-neutral dispatch libraries (glvnd) that the NVIDIA driver's Vulkan
  # library, libGLX_nvidia.so.0, links against: a CUDA-only image has the driver's
  # libraries mounted but not glvnd, and then the loader cannot open the driver (seen on
  # the first H200 lease: "no Vulkan driver found" with the driver's manifest present).
  # Used there only when the machine has none (setup_env).
  local glvnd
  mkdir -p "$tmp/lib/glvnd"
  for glvnd in libGLdispatch.so.0 libGLX.so.0; do
    if path="$(find_lib "$glvnd")"; then
      cp -L "$path" "$tmp/lib/glvnd/$glvnd"
    else
      echo "gpu_run.sh --bundle: no $glvnd here (Debian packages libglvnd0, libglx0): bundled without it" >&2
    fi
  done

  cp -R "$root/scenes" "$tmp/scenes"
  cp "$root/scripts/gpu_run.sh" "$tmp/gpu_run.sh"
  chmod +x "$tmp/gpu_run.sh"
  rmdir "$tmp/layers" 2>/dev/null || true

  # What the machine's own libraries must provide (the launcher checks these).
  local -a bundled_elves=("$tmp"/bin/* "$tmp"/lib/*.so*)
  local commit
  commit="$(git -C "$root" rev-parse --short=12 HEAD 2>/dev/null || echo unknown)"
  if [[ -n "$(git -C "$root" status --porcelain --untracked-files=no 2>/dev/null)" ]]; then commit+="+changes"; fi
  {
    echo "# The bundle of scripts/gpu_run.sh --bundle (docs/gpu.md); key=value lines read by gpu_run.sh."
    echo "commit=$commit"
    echo "made=$(date -u +%Y-%m-%dT%H:%M:%SZ)"
    echo "made_on=$(uname -srm) $(getconf GNU_LIBC_VERSION 2>/dev/null || true)"
    echo "needs_glibc=$(max_version GLIBC "${bundled_elves[@]}")"
    echo "compat_needs_glibc=$(max_version GLIBC "$tmp"/lib/compat/*)"
    echo "needs_glibcxx=$(max_version GLIBCXX "${bundled_elves[@]}")"
    echo "needs_cxxabi=$(max_version CXXABI "${bundled_elves[@]}")"
  } >"$tmp/MANIFEST"

  local bytes
  bytes="$(du -sb "$tmp" | cut -f1)"
  if ((bytes >= max_bundle_bytes)); then
    echo "gpu_run.sh --bundle: the bundle is $bytes bytes, over the 64 MiB a device machine takes" >&2
    return 2
  fi
  rm -rf "$dest"
  mv "$tmp" "$dest"
  echo "bundle $dest: $(awk -v b="$bytes" 'BEGIN { printf "%.1f MiB (%d bytes, limit 64 MiB)", b / 1048576, b }')"
  (cd "$dest" && find . -type f ! -path './scenes/*' -printf '%s\t%p\n' | sort -k2 |
    awk -F'\t' '{ printf "  %8.2f MiB  %s\n", $1 / 1048576, substr($2, 3) }')
  echo "  $(du -sb "$dest/scenes" | awk '{ printf "%8.2f MiB", $1 / 1048576 }')  scenes/ ($(find "$dest/scenes" -type f | wc -l) files)"
  local need f culprits=""
  need="$(sed -n 's/^needs_glibc=//p' "$dest/MANIFEST")"
  for f in "$dest"/bin/* "$dest"/lib/*.so*; do
    if grep -aqF "$need" "$f"; then culprits+="${culprits:+, }${f#"$dest"/}"; fi
  done
  echo "  commit $(sed -n 's/^commit=//p' "$dest/MANIFEST"); the GPU machine needs glibc >= ${need#GLIBC_} ($culprits)"
  # Open MPI's libevent is the usual culprit: Debian 12's needs glibc 2.36, past Ubuntu
  # 22.04's 2.35, while kodawari itself needs 2.34. `--mpi` is of no use on the GPU
  # machine, so a build without MPI makes a bundle that starts on more systems.
  if [[ "$(printf '%s\n%s\n' "${need#GLIBC_}" 2.35 | sort -V | tail -n 1)" != 2.35 ]]; then
    echo "  (past Ubuntu 22.04's glibc 2.35; a build without MPI needs less: docs/gpu.md, \"Older systems\")"
  fi
  echo "copy the folder to the GPU machine and run: bash $(basename "$dest")/gpu_run.sh [OUT]"
}

# ---------------------------------------------------------------------------------------
# The run
# ---------------------------------------------------------------------------------------

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }

# A JSON string of arbitrary text (control characters other than tab and newline dropped).
json_str() {
  local s
  s="$(printf '%s' "$1" | tr -d '\000-\010\013\014\016-\037')"
  s="${s//\\/\\\\}"
  s="${s//\"/\\\"}"
  s="${s//$'\t'/\\t}"
  s="${s//$'\n'/\\n}"
  printf '"%s"' "$s"
}

# The command as one line a shell would take back, quoting only what needs it.
quote_args() {
  local a line=""
  for a in "$@"; do
    if [[ "$a" =~ ^[A-Za-z0-9_./:=,+@%-]+$ ]]; then line+=" $a"; else line+=" $(printf '%q' "$a")"; fi
  done
  printf '%s' "${line# }"
}

log() { printf '%s\n' "$*" | tee -a "$log_file"; }

# The GPU machine's system: for results.json and the log.
host_json() {
  local cpu gpu="null" smi
  cpu="$(awk -F': ' '/^model name/ { print $2; exit }' /proc/cpuinfo 2>/dev/null || true)"
  if command -v nvidia-smi >/dev/null 2>&1; then
    smi="$(timeout 20 nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || true)"
    [[ -n "$smi" ]] && gpu="$(json_str "$smi")"
  fi
  printf '{"hostname":%s,"uname":%s,"cpu":%s,"cpus":%s,"memory":%s,"glibc":%s,"nvidia_smi":%s}' \
    "$(json_str "$(cat /proc/sys/kernel/hostname 2>/dev/null || true)")" \
    "$(json_str "$(uname -srm)")" "$(json_str "$cpu")" "$(nproc 2>/dev/null || echo 0)" \
    "$(json_str "$(awk '/^MemTotal/ { print $2 " " $3; exit }' /proc/meminfo 2>/dev/null || true)")" \
    "$(json_str "$(getconf GNU_LIBC_VERSION 2>/dev/null || true)")" "$gpu"
}

write_results() {
  local tmp="$out/results.json.tmp" i sep=""
  {
    printf '{"format":"kodawari-gpu-run","version":1,"mode":%s,"started":%s,"seconds":%s,"finished":%s,\n' \
      "$(json_str "$mode")" "$(json_str "$started_iso")" "$(elapsed "$t0" "$(now)")" "$1"
    printf ' "kodawari":%s,"embed_vulkan":%s,"bundle":%s,\n' "$(json_str "$bin")" "$(json_str "$embed")" "$bundle_json"
    printf ' "environment":%s,\n' "$env_json"
    printf ' "host":%s,\n' "$host"
    printf ' "device":%s,"driver":%s,"libstdcxx":%s,"glibc_warning":%s,\n' "$(json_str "$device")" \
      "$(json_str "$driver_note")" "$(json_str "$compat_note")" "$(json_str "$glibc_note")"
    printf ' "steps":['
    for i in ${steps_json[@]+"${!steps_json[@]}"}; do
      printf '%s\n  %s' "$sep" "${steps_json[$i]}"
      sep=","
    done
    printf '\n]}\n'
  } >"$tmp"
  mv "$tmp" "$out/results.json"
}

# run_step NAME LIMIT_S RESERVE_S KIND COMMAND...: runs COMMAND (in the bundle's
# environment, with the checkout or bundle as its folder) under timeout, for at most
# LIMIT_S and never past the run's deadline less RESERVE_S (time kept for the steps after
# it); appends its output to the log and its record to results.json. KIND: bench (the
# command writes $out/NAME.json), embed (77 means no device: skipped) or plain.
run_step() {
  local name="$1" limit="$2" reserve="$3" kind="$4"
  shift 4
  if [[ -n "${GPU_RUN_ONLY:-}" && ! "$name" =~ $GPU_RUN_ONLY ]]; then return 0; fi
  local left limit_now rc=0 result start end seconds command summary bench="null" status
  command="$(quote_args "$@")"
  left="$(awk -v d="$deadline" -v n="$(now)" -v r="$reserve" 'BEGIN { printf "%d", d - n - r }')"
  limit_now=$((left < limit ? left : limit))
  {
    echo
    echo "=== $name ($(date -u +%H:%M:%S), limit ${limit_now}s)"
    echo "\$ $command"
  } >>"$log_file"
  if ((limit_now < 5)); then
    result="skipped"
    summary="out of time: ${left}s left of the run's deadline (${reserve}s kept for the steps after it)"
    status="null"
    seconds=0
    failures+=("$name (out of time)")
  else
    start="$(now)"
    timeout -k 5 "$limit_now" env "${run_env[@]}" "$@" </dev/null >"$out/step.out" 2>&1 || rc=$?
    end="$(now)"
    seconds="$(elapsed "$start" "$end")"
    cat "$out/step.out" >>"$log_file"
    status="$rc"
    summary="$(grep -v '^[[:space:]]*$' "$out/step.out" | tail -n 1 || true)"
    if ((rc == 0)); then
      result="ok"
    elif ((rc == 124 || rc == 137)); then
      result="timeout"
      summary="timed out after ${limit_now}s; last line: $summary"
      failures+=("$name (timed out)")
    elif [[ "$kind" == embed && "$rc" == 77 ]]; then
      result="skipped"
    else
      result="failed"
      failures+=("$name (exit $rc)")
    fi
    if [[ "$kind" == bench && -s "$out/$name.json" ]]; then
      bench="$(cat "$out/$name.json")"
      bench_steps+=("$name")
      # `bench` skips a backend that cannot start (exit 0, the others timed): on this run
      # a missing vulkan result is the failure that matters most.
      # (The results only: a vulkan backend skipped is in the JSON's "skipped" too.)
      if [[ "$result" == ok && "$*" == *vulkan* ]] && ! sed 's/"skipped":\[.*//' "$out/$name.json" | grep -q '"backend":"vulkan'; then
        result="failed"
        summary="no vulkan result: $(grep -m 1 'skipped:' "$out/step.out" | sed 's/^ *//' || true)"
        failures+=("$name (no vulkan result)")
      fi
    fi
  fi
  echo "--- $name: $result, exit ${status/null/-}, ${seconds}s" >>"$log_file"
  printf '[%6.1fs] %-8s %-36s %6ss  %s\n' "$(elapsed "$t0" "$(now)")" "$result" "$name" "$seconds" \
    "$(printf '%s' "$summary" | cut -c1-90)"
  if [[ "$result" == failed || "$result" == timeout ]]; then
    tail -n 6 "$out/step.out" 2>/dev/null | sed 's/^/           | /' || true
  fi
  steps_json+=("$(printf '{"name":%s,"command":%s,"result":%s,"status":%s,"seconds":%s,"summary":%s,"bench":%s}' \
    "$(json_str "$name")" "$(json_str "$command")" "$(json_str "$result")" "$status" "$seconds" \
    "$(json_str "$summary")" "$bench")")
  rm -f "$out/step.out"
  write_results false
}

# The benchmarks' table, from their JSON files: per benchmark and backend the rate's
# median, min and max, ms/frame, GPU ms/frame, the ratio to cpu of the same run and the
# device (and bench flock's split of the step), and each backend the benchmark skipped with
# why. POSIX awk: the JSON is the flat one `kodawari bench --json` writes (result and
# skipped objects of strings, numbers and null).
print_table() {
  local name
  for name in "$@"; do
    printf '%s\t' "$name"
    tr -d '\n' <"$out/$name.json"
    printf '\n'
  done | awk -F'\t' '
    function field(obj, key,   v) {
      if (!match(obj, "\"" key "\":(\"[^\"]*\"|[^,}]*)")) return ""
      v = substr(obj, RSTART + length(key) + 3, RLENGTH - length(key) - 3)
      gsub(/^"|"$/, "", v)
      return v
    }
    function num(v, f) { return (v == "" || v == "null") ? "-" : sprintf(f, v) }
    BEGIN {
      printf "%-22s %-24s %9s %11s %11s %11s %9s %9s %8s  %s\n", "bench", "backend", "count", "median/s",
        "min/s", "max/s", "ms/frame", "GPU ms", "vs cpu", "device"
    }
    {
      json = $2
      kind = field(json, "benchmark")
      # Every benchmark writes "count" (before it, chains wrote "chains" and crowd "instances").
      count = field(json, "count")
      if (count == "") count = field(json, kind == "chains" ? "chains" : "instances")
      unit = kind == "chains" ? "joint-steps" : (kind == "birds" ? "bird-frames" : (kind == "flock" ? "bird-steps" : "frames"))
      rest = substr(json, index(json, "\"results\":[") + 11)
      skipped = ""
      if (index(rest, "],\"skipped\":[") > 0) {
        skipped = substr(rest, index(rest, "],\"skipped\":[") + 13)
        rest = substr(rest, 1, index(rest, "],\"skipped\":["))
      }
      n = split(rest, objs, "},")
      for (i = 1; i <= n; ++i) {
        o = objs[i]
        if (field(o, "backend") == "") continue
        # bench flock: the split of the flocking step (grid, search, rules), after the device.
        shares = ""
        if (field(o, "search_share") != "" && field(o, "search_share") != "null")
          shares = sprintf("  [grid %.0f%%, search %.0f%%, rules %.0f%%]", 100 * field(o, "grid_share"),
                          100 * field(o, "search_share"), 100 * field(o, "rules_share"))
        printf "%-22s %-24s %9s %11s %11s %11s %9s %9s %8s  %s%s\n", $1, field(o, "backend"), count,
          num(field(o, "per_second"), "%.4g"), num(field(o, "min"), "%.4g"), num(field(o, "max"), "%.4g"),
          num(field(o, "ms_per_frame"), "%.3f"), num(field(o, "gpu_ms_per_frame"), "%.3f"),
          num(field(o, "vs_cpu"), "%.2fx"), field(o, "device"), shares
      }
      n = split(skipped, objs, "},")
      for (i = 1; i <= n; ++i) {
        if (field(objs[i], "backend") == "") continue
        printf "%-22s %-24s skipped: %s\n", $1, field(objs[i], "backend"), field(objs[i], "reason")
      }
      if (!(kind in seen)) units = units (units == "" ? "" : ", ") kind ": " unit "/s"
      seen[kind] = 1
    }
    END { if (NR == 0) print "(no benchmark wrote its results)"; else print "(rates: " units "; medians of the repetitions, min and max beside them; GPU ms: the device timestamps per frame)" }
  '
}

# The bundle's environment for the steps: its libraries first, its layer manifest, and
# the machine's NVIDIA driver file when the loader finds no GPU by itself.
setup_env() {
  run_env=()
  local lib_path=""
  if [[ "$in_bundle" == 1 ]]; then
    lib_path="$root/lib"
    # libstdc++ and libgcc_s from the bundle only where the machine's own lack the
    # versions the bundle's binaries need (a newer machine keeps its own, which the GPU
    # driver may need in turn).
    local need_cxx need_abi sys_cxx compat=0
    need_cxx="$(sed -n 's/^needs_glibcxx=//p' "$root/MANIFEST" 2>/dev/null || true)"
    need_abi="$(sed -n 's/^needs_cxxabi=//p' "$root/MANIFEST" 2>/dev/null || true)"
    if sys_cxx="$(find_lib libstdc++.so.6)" && [[ -n "$(find_lib libgcc_s.so.1 || true)" ]]; then
      if [[ -n "$need_cxx" ]] && ! grep -qaF "$need_cxx" "$sys_cxx"; then compat=1; fi
      if [[ -n "$need_abi" ]] && ! grep -qaF "$need_abi" "$sys_cxx"; then compat=1; fi
    else
      compat=1
    fi
    if ((compat)); then
      lib_path+=":$root/lib/compat"
      compat_note="the bundle's libstdc++ (lib/compat: the machine's lacks ${need_cxx:-?} or is absent)"
    else
      compat_note="the machine's libstdc++ ($sys_cxx, has ${need_cxx:-?})"
    fi
    run_env+=("LD_LIBRARY_PATH=$lib_path${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}")
    if [[ -f "$root/layers/VkLayer_khronos_validation.json" ]]; then
      run_env+=("VK_LAYER_PATH=$root/layers")
    fi
    local need_glibc have_glibc
    need_glibc="$(sed -n 's/^needs_glibc=GLIBC_//p' "$root/MANIFEST" 2>/dev/null || true)"
    have_glibc="$(getconf GNU_LIBC_VERSION 2>/dev/null | awk '{ print $2 }' || true)"
    if ((compat)); then
      local compat_glibc
      compat_glibc="$(sed -n 's/^compat_needs_glibc=GLIBC_//p' "$root/MANIFEST" 2>/dev/null || true)"
      if [[ -n "$compat_glibc" && "$(printf '%s\n%s\n' "$need_glibc" "$compat_glibc" | sort -V | tail -n 1)" == "$compat_glibc" ]]; then
        need_glibc="$compat_glibc"
      fi
    fi
    if [[ -n "$need_glibc" && -n "$have_glibc" &&
      "$(printf '%s\n%s\n' "$need_glibc" "$have_glibc" | sort -V | head -n 1)" != "$need_glibc" ]]; then
      glibc_note="WARNING: the bundle needs glibc >= $need_glibc, this machine has $have_glibc: its programs will not start (docs/gpu.md, \"Older systems\")"
    fi
  fi
  run_env+=(KODAWARI_VALIDATION=0)
}

# Does the loader, as set up so far, see a GPU? `kodawari info` lists each device's type.
# (Read whole, then searched: `info | grep -q` could end info with SIGPIPE once grep has
# its match, and pipefail would call that a miss.)
sees_gpu() {
  local listing
  listing="$(timeout 60 env "${run_env[@]}" "$@" "$bin" info 2>&1 || true)"
  grep -qE '^ +type (discrete|integrated)' <<<"$listing"
}

# The NVIDIA driver's Vulkan manifest, or one written for its library when the machine
# has the driver but no manifest (a container started without the graphics capability
# of the NVIDIA container toolkit mounts libGLX_nvidia.so.0 alone, or nothing).
nvidia_icd() {
  local f lib
  for f in /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json /usr/share/vulkan/icd.d/nvidia_icd.json /etc/vulkan/icd.d/nvidia_icd.json \
    /usr/local/share/vulkan/icd.d/nvidia_icd.json /usr/share/vulkan/icd.d/nvidia_icd.x86_64.json \
    /etc/vulkan/icd.d/nvidia_icd.x86_64.json; do
    if [[ -f "$f" ]]; then
      printf '%s\n' "$f"
      return 0
    fi
  done
  if lib="$(find_lib libGLX_nvidia.so.0)"; then
    printf '{"file_format_version":"1.0.0","ICD":{"library_path":"%s","api_version":"1.3.0"}}\n' "$lib" \
      >"$out/nvidia_icd.json"
    printf '%s\n' "$out/nvidia_icd.json"
    return 0
  fi
  return 1
}

# The loader found no GPU by itself: try the NVIDIA driver's manifest, then the bundle's
# glvnd libraries (lib/glvnd) behind the machine's own libraries, each alone and both;
# keep the first that shows a GPU. When none does, keep the loader's own account of why
# (VK_LOADER_DEBUG) for run.log.
find_driver() {
  local icd="" glvnd_lib="" e
  icd="$(nvidia_icd || true)"
  if [[ -d "$root/lib/glvnd" && -z "$(find_lib libGLdispatch.so.0 || true)" ]]; then
    for e in "${run_env[@]}"; do
      [[ "$e" == LD_LIBRARY_PATH=* ]] && glvnd_lib="${e#LD_LIBRARY_PATH=}:"
    done
    glvnd_lib="LD_LIBRARY_PATH=$glvnd_lib$root/lib/glvnd"
  fi
  # Each try is its variables joined by the unit separator (paths may hold spaces).
  local sep=$'\x1f'
  local -a tries=()
  [[ -n "$icd" ]] && tries+=("VK_DRIVER_FILES=$icd${sep}VK_ICD_FILENAMES=$icd")
  [[ -n "$glvnd_lib" ]] && tries+=("$glvnd_lib")
  [[ -n "$icd" && -n "$glvnd_lib" ]] && tries+=("VK_DRIVER_FILES=$icd${sep}VK_ICD_FILENAMES=$icd${sep}$glvnd_lib")
  local try
  local -a vars
  for try in "${tries[@]}"; do
    IFS="$sep" read -r -a vars <<<"$try"
    if sees_gpu "${vars[@]}"; then
      # (a later LD_LIBRARY_PATH would win in env anyway; one is clearer in run.log)
      local -a kept=()
      for e in "${run_env[@]}"; do
        [[ "$try" == *LD_LIBRARY_PATH=* && "$e" == LD_LIBRARY_PATH=* ]] || kept+=("$e")
      done
      run_env=("${kept[@]}" "${vars[@]}")
      driver_note="the loader found no GPU by itself; found with ${vars[*]}"
      [[ "$try" == *LD_LIBRARY_PATH=* ]] && driver_note+=" (the bundle's glvnd: the machine has no libGLdispatch.so.0)"
      return 0
    fi
  done
  if [[ -n "$icd" ]]; then
    driver_note="no GPU from the loader's own search, nor with the NVIDIA manifest $icd${glvnd_lib:+ and the glvnd of the bundle}"
  else
    driver_note="no GPU from the loader's own search (no NVIDIA driver manifest or libGLX_nvidia.so.0 here)"
  fi
  # Why, in the loader's words, with the last combination tried (none tried: nothing of
  # NVIDIA's here, as on a machine with lavapipe alone, and nothing to explain).
  ((${#tries[@]} > 0)) || return 0
  IFS="$sep" read -r -a vars <<<"${tries[${#tries[@]}-1]}"
  loader_debug="$(timeout 60 env "${run_env[@]}" "${vars[@]}" VK_LOADER_DEBUG=error,warn,driver "$bin" info 2>&1 | tail -n 40 || true)"
  local lib
  if [[ -n "$icd" ]]; then
    lib="$(sed -n 's/.*"library_path"[[:space:]]*:[[:space:]]*"\([^"]*\)".*/\1/p' "$icd" | head -n 1)"
    [[ "$lib" != /* ]] && lib="$(find_lib "$lib" || echo "$lib")"
    loader_debug+=$'\n'"ldd $lib:"$'\n'"$(ldd "$lib" 2>&1 | head -n 30 || true)"
  fi
}

run_all() {
  local quick="$1"
  out="$2"
  mode="full"
  ((quick)) && mode="quick"
  # The whole run's deadline: 5 minutes on the GPU machine, 2 for --quick (less a margin
  # for starting and the table). Checked, as the binary is, before OUT and run.log are
  # made: bad usage leaves nothing behind.
  local budget=290
  ((quick)) && budget=110
  budget="${GPU_RUN_BUDGET:-$budget}"
  [[ "$budget" =~ ^[0-9]+$ && "$budget" -ge 5 ]] ||
    { echo "gpu_run.sh: GPU_RUN_BUDGET is '$budget'; expected whole seconds, 5 or more" >&2; return 2; }
  if [[ -n "${GPU_RUN_STEP_LIMIT:-}" ]] && ! [[ "$GPU_RUN_STEP_LIMIT" =~ ^[0-9]+$ && "$GPU_RUN_STEP_LIMIT" -ge 5 ]]; then
    echo "gpu_run.sh: GPU_RUN_STEP_LIMIT is '$GPU_RUN_STEP_LIMIT'; expected whole seconds, 5 or more" >&2
    return 2
  fi

  if [[ -n "${KODAWARI:-}" ]]; then
    bin="$KODAWARI"
  elif [[ "$in_bundle" == 1 ]]; then
    bin="$root/bin/kodawari"
  else
    bin="$root/build/release/host/kodawari"
  fi
  if [[ "$bin" != */* ]]; then bin="$(command -v "$bin" || echo "$bin")"; fi
  if [[ ! -x "$bin" ]]; then
    echo "gpu_run.sh: no kodawari at $bin (set KODAWARI, or build the tree, or run the bundle's gpu_run.sh)" >&2
    return 2
  fi
  # embed_vulkan: $KODAWARI_EMBED_VULKAN, else beside $KODAWARI (a bundle's bin/, or the
  # build tree kodawari came from), else the bundle's or build/release's; run.log says which.
  local bin_dir
  bin_dir="$(cd "$(dirname "$bin")" && pwd)"
  if [[ -n "${KODAWARI_EMBED_VULKAN:-}" ]]; then
    embed="$KODAWARI_EMBED_VULKAN" embed_note="\$KODAWARI_EMBED_VULKAN"
  elif [[ -n "${KODAWARI:-}" && -x "$bin_dir/embed_vulkan" ]]; then
    embed="$bin_dir/embed_vulkan" embed_note="beside \$KODAWARI"
  elif [[ -n "${KODAWARI:-}" ]]; then
    embed="$(dirname "$bin_dir")/examples/embed_vulkan/embed_vulkan" embed_note="the build tree of \$KODAWARI"
  elif [[ "$in_bundle" == 1 ]]; then
    embed="$root/bin/embed_vulkan" embed_note="the bundle's"
  else
    embed="$root/build/release/examples/embed_vulkan/embed_vulkan" embed_note="build/release's"
  fi
  mkdir -p "$out"
  out="$(cd "$out" && pwd)"
  log_file="$out/run.log"
  : >"$log_file"
  t0="$(now)"
  started_iso="$(date -u +%Y-%m-%dT%H:%M:%SZ)"
  deadline="$(awk -v t="$t0" -v b="$budget" 'BEGIN { printf "%.3f", t + b }')"
  log "embed_vulkan: $embed ($embed_note)"
  # Scenes are named relative to the checkout or the bundle; the steps run there.
  cd "$root"

  compat_note=""
  glibc_note=""
  setup_env
  driver_note="the loader's own search"
  loader_debug=""
  if ! sees_gpu; then
    find_driver
  fi
  device="$(timeout 60 env "${run_env[@]}" "$bin" info 2>/dev/null | sed -n 's/^chosen: \[[0-9]*\] \(.*\), because.*/\1/p' | head -n 1 || true)"
  [[ -z "$device" ]] && device="none"

  local e env_parts=""
  for e in "${run_env[@]}"; do
    env_parts+="${env_parts:+,}$(json_str "${e%%=*}"):$(json_str "${e#*=}")"
  done
  [[ -n "${KODAWARI_FORCE_STAGING:-}" ]] && env_parts+=",\"KODAWARI_FORCE_STAGING\":$(json_str "$KODAWARI_FORCE_STAGING")"
  env_json="{$env_parts}"
  bundle_json="null"
  if [[ "$in_bundle" == 1 ]]; then
    bundle_json="{\"commit\":$(json_str "$(sed -n 's/^commit=//p' "$root/MANIFEST")"),\"made\":$(json_str "$(sed -n 's/^made=//p' "$root/MANIFEST")")}"
  fi
  host="$(host_json)"
  steps_json=()
  bench_steps=()
  failures=()

  {
    echo "gpu_run.sh $mode: $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(uname -n), into $out"
    echo "kodawari: $bin"
    echo "device: $device"
    echo "driver: $driver_note"
    [[ -n "$compat_note" ]] && echo "libstdc++: $compat_note"
    [[ -n "$glibc_note" ]] && echo "$glibc_note"
    echo "environment: ${run_env[*]}"
  } | tee -a "$log_file"
  if ((!quick)) && [[ "$device" == none || "$device" == llvmpipe* ]]; then
    log "WARNING: no GPU is visible to Vulkan: the vulkan figures will be the CPU device's or missing"
  fi
  if [[ -n "$loader_debug" ]]; then
    { echo "the Vulkan loader's account (VK_LOADER_DEBUG=error,warn,driver, last lines):"; echo "$loader_debug"; } | tee -a "$log_file"
  fi
  write_results false

  # Sizes. The GPU machine's: issue 38's (chains 100k and 1M x 16 joints x 4 iterations,
  # birds 1M and 10M, crowds of 1 000 and 10 000 chibis); cpu-reference only at the small
  # ones, where it takes seconds (its 1M chains would take minutes). --quick: the same
  # steps at sizes lavapipe on two loaded cores runs in seconds, counts not multiples of
  # a workgroup.
  # The large sizes (cpu and vulkan alone) take more repetitions: a GPU step of 1M chains
  # is a few milliseconds, and cpu-reference no longer sets the pace (the cpu backend's 1M
  # chains took 1.55 s a frame on the 2-core machine, so 10 frames). validate's 20 frames:
  # crowd.json's cpu-reference takes about 0.45 s a frame.
  local chains_s=100000 chains_l=1000000 chains_frames_s=5 chains_frames_l=10
  local birds_s=1000000 birds_l=10000000 birds_frames_s=10 birds_frames_l=20
  local crowd_s=1000 crowd_l=10000 crowd_frames=30 crowd_lod_frames=60 crowd_one_frames=600
  # The flock: 10 000 birds (issue 32's size beside Blender's boids) and a million.
  local flock_s=10000 flock_l=1000000 flock_frames_s=60 flock_frames_l=5
  # The vulkan kernels' workgroup sizes timed side by side at the large sizes (issue 38,
  # item 2; `bench --workgroup-sizes`): the first GPU run picks the default from them.
  local workgroups=32,64,128,256
  local triad_mib=1536 reps_s=3 reps_l=5 validate_frames=20 embed_frames=120 bench_limit=90 step_limit=40
  local bench_reserve=75
  if ((quick)); then
    chains_s=301 chains_l=1001 chains_frames_s=2 chains_frames_l=2
    birds_s=1001 birds_l=10001 birds_frames_s=3 birds_frames_l=3
    crowd_s=2 crowd_l=5 crowd_frames=3 crowd_lod_frames=11 crowd_one_frames=5 reps_l=3
    flock_s=1001 flock_l=3001 flock_frames_s=2 flock_frames_l=2
    # Two sizes keep the option's path run; each is a pipeline lavapipe compiles.
    workgroups=32,64
    triad_mib=48 validate_frames=3 embed_frames=12 bench_limit=40 step_limit=30 bench_reserve=30
  fi
  step_limit="${GPU_RUN_STEP_LIMIT:-$step_limit}"
  [[ "$step_limit" =~ ^[0-9]+$ && "$step_limit" -ge 5 ]] ||
    { echo "gpu_run.sh: GPU_RUN_STEP_LIMIT is '$step_limit'; expected whole seconds, 5 or more" >&2; exit 2; }
  local all=cpu-reference,cpu,vulkan fast=cpu,vulkan
  local has_layer=0
  if [[ "$in_bundle" == 1 && -f "$root/layers/VkLayer_khronos_validation.json" ]] ||
    { [[ "$in_bundle" == 0 ]] && find_layer_manifest >/dev/null; }; then
    has_layer=1
  fi

  run_step info 60 0 plain "$bin" info
  # The host's fp32 peak and memory rate, which the cpu rows of the benches are set against
  # (docs/performance.md); a few seconds.
  run_step ceilings 30 0 plain "$bin" bench ceilings --repetitions 3 --triad-mib "$triad_mib" --json "$out/ceilings.json"
  # Benchmarks first: their figures are what the machine is lent for. Each keeps
  # bench_reserve seconds of the deadline for validate and embed_vulkan.
  # The rod kernels side by side: a chain per invocation (its template's constants in
  # registers or in shared memory) and a joint per invocation (docs/performance.md, "The
  # GPU-first variant"). The first bench of each kind also
  # prints its kernels' registers and spills (--kernel-statistics).
  run_step "bench-chains-$chains_s" "$bench_limit" "$bench_reserve" bench "$bin" bench chains --count "$chains_s" \
    --joints 16 --iterations 4 --frames "$chains_frames_s" --repetitions "$reps_s" --backends "$all" \
    --rod-kernels per-chain,shared-constants,per-joint --kernel-statistics --json "$out/bench-chains-$chains_s.json"
  # The poses as records and as fields side by side (docs/performance.md, "Birds").
  run_step "bench-birds-$birds_s" "$bench_limit" "$bench_reserve" bench "$bin" bench birds --count "$birds_s" \
    --frames "$birds_frames_s" --repetitions "$reps_s" --backends "$all" --pose-layouts records,fields \
    --kernel-statistics --json "$out/bench-birds-$birds_s.json"
  run_step "bench-crowd-$crowd_s" "$bench_limit" "$bench_reserve" bench "$bin" bench crowd --count "$crowd_s" \
    --frames "$crowd_frames" --repetitions "$reps_s" --backends "$all" --kernel-statistics --json "$out/bench-crowd-$crowd_s.json"
  # One character, an embedding's case: a frame's latency on the card (a submission and
  # its wait) beside the cpu backend's on all the machine's threads (docs/performance.md,
  # "One character, and other small scenes").
  run_step "bench-crowd-1" "$bench_limit" "$bench_reserve" bench "$bin" bench crowd --count 1 \
    --frames "$crowd_one_frames" --repetitions "$reps_s" --backends "$all" --json "$out/bench-crowd-1.json"
  run_step "bench-chains-$chains_l" "$bench_limit" "$bench_reserve" bench "$bin" bench chains --count "$chains_l" \
    --joints 16 --iterations 4 --frames "$chains_frames_l" --repetitions "$reps_l" --backends "$fast" \
    --workgroup-sizes "$workgroups" --json "$out/bench-chains-$chains_l.json"
  run_step "bench-birds-$birds_l" "$bench_limit" "$bench_reserve" bench "$bin" bench birds --count "$birds_l" \
    --frames "$birds_frames_l" --repetitions "$reps_l" --backends "$fast" --workgroup-sizes "$workgroups" \
    --json "$out/bench-birds-$birds_l.json"
  run_step "bench-crowd-$crowd_l" "$bench_limit" "$bench_reserve" bench "$bin" bench crowd --count "$crowd_l" \
    --frames "$crowd_frames" --repetitions "$reps_l" --backends "$fast" --workgroup-sizes "$workgroups" \
    --json "$out/bench-crowd-$crowd_l.json"
  # The levels of detail on crowd-10k (issue 35: the camera's first second, 90 m out;
  # `--lod`), so that a GPU's figures stand beside the cpu backend's 94 frames/s on 2 cores.
  run_step "bench-crowd-lod-$crowd_l" "$bench_limit" "$bench_reserve" bench "$bin" bench crowd scenes/crowd-10k.json \
    --count "$crowd_l" --frames "$crowd_lod_frames" --lod --repetitions "$reps_l" --backends "$fast" \
    --json "$out/bench-crowd-lod-$crowd_l.json"
  run_step "bench-flock-$flock_s" "$bench_limit" "$bench_reserve" bench "$bin" bench flock --count "$flock_s" \
    --frames "$flock_frames_s" --repetitions "$reps_s" --backends "$all" --kernel-statistics --json "$out/bench-flock-$flock_s.json"
  run_step "bench-flock-$flock_l" "$bench_limit" "$bench_reserve" bench "$bin" bench flock --count "$flock_l" \
    --frames "$flock_frames_l" --repetitions "$reps_l" --backends "$fast" --workgroup-sizes "$workgroups" \
    --json "$out/bench-flock-$flock_l.json"

  # Every shipped scene, vulkan against cpu-reference, but crowd-10k: the benchmark scene
  # (crowd-gltf's character 10 000 times, which cpu-reference takes minutes to settle);
  # crowd-gltf's validation covers its kernels.
  local scene base
  for scene in scenes/*.json scenes/*/*.json; do
    [[ -f "$scene" ]] || continue
    base="${scene#scenes/}"
    base="${base%.json}"
    [[ "$base" == crowd-10k ]] && continue
    run_step "validate-${base//\//-}" "$step_limit" 10 plain "$bin" validate "$scene" --backend vulkan \
      --frames "$validate_frames"
  done
  # Under the validation layer (synchronization validation on), a rod scene and a flock:
  # the discrete GPU's paths (staging copies, real asynchrony) that lavapipe never takes.
  if ((has_layer)); then
    run_step validate-layers-crowd-gltf "$step_limit" 10 plain "$bin" validate scenes/crowd-gltf.json \
      --backend vulkan --frames "$validate_frames" --validation
    run_step validate-layers-flock "$step_limit" 10 plain "$bin" validate scenes/flock.json \
      --backend vulkan --frames "$validate_frames" --validation
  fi
  if [[ -x "$embed" ]]; then
    if ((has_layer)); then
      run_step embed_vulkan "$step_limit" 0 embed "$embed" --validation --frames "$embed_frames"
    else
      run_step embed_vulkan "$step_limit" 0 embed "$embed" --frames "$embed_frames"
    fi
  else
    log "embed_vulkan: not built ($embed), skipped"
  fi

  write_results true
  {
    echo
    echo "=== table ($device)"
    print_table ${bench_steps[@]+"${bench_steps[@]}"}
    echo
    if ((${#failures[@]} == 0)); then
      echo "gpu_run.sh $mode: ${#steps_json[@]} steps passed in $(elapsed "$t0" "$(now)") s; results.json and run.log in $out"
    else
      echo "gpu_run.sh $mode: ${#failures[@]} of ${#steps_json[@]} steps did not pass: ${failures[*]}"
      echo "  in $(elapsed "$t0" "$(now)") s; results.json and run.log in $out"
    fi
  } | tee -a "$log_file"
  ((${#failures[@]} == 0))
}

case "${1:-}" in
  -h | --help)
    usage
    exit 0
    ;;
  --bundle)
    if (($# > 2)); then
      usage >&2
      exit 2
    fi
    make_bundle "${2:-$root/gpu-bundle}"
    ;;
  --quick)
    if (($# > 2)); then
      usage >&2
      exit 2
    fi
    run_all 1 "${2:-gpu-results/quick-$(date -u +%Y%m%d-%H%M%S)}"
    ;;
  -*)
    echo "gpu_run.sh: unknown option $1" >&2
    usage >&2
    exit 2
    ;;
  *)
    if (($# > 1)); then
      usage >&2
      exit 2
    fi
    run_all 0 "${1:-gpu-results/$(date -u +%Y%m%d-%H%M%S)}"
    ;;
esac
