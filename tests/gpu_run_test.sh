#!/usr/bin/env bash
# ctest gpu_run_quick: scripts/gpu_run.sh, the GPU machine's run (docs/gpu.md), kept from
# rotting between the rare days a GPU is lent. It makes a bundle into a temporary folder,
# checks what is in it, runs the bundle's launcher with --quick from the bundle alone (an
# emptied environment, a PATH of only the tools the script may use on a bare machine:
# bash, coreutils, grep, sed, awk) and checks results.json and the table; then a broken
# step (a `kodawari` whose bench fails) must make the run exit 1 and the steps after it
# still run. Nothing is written to the source tree.
#
#   bash tests/gpu_run_test.sh KODAWARI SOURCE_DIR [EMBED_VULKAN]
set -euo pipefail
kodawari="$1"
src="$2"
embed="${3:-}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# The bundle.
KODAWARI="$kodawari" KODAWARI_EMBED_VULKAN="${embed:-/nonexistent}" \
  bash "$src/scripts/gpu_run.sh" --bundle "$work/bundle" >"$work/bundle.out" 2>&1 ||
  { cat "$work/bundle.out"; fail "--bundle exited $?"; }
cat "$work/bundle.out"
b="$work/bundle"
grep -q "^bundle $b: .* MiB" "$work/bundle.out" || fail "--bundle did not print the bundle's size"
for f in gpu_run.sh MANIFEST bin/kodawari lib/libvulkan.so.1 lib/compat/libstdc++.so.6 lib/compat/libgcc_s.so.1 \
  scenes/flock.json scenes/characters/chibi.glb; do
  [[ -e "$b/$f" ]] || fail "the bundle lacks $f"
done
[[ -z "$embed" || -x "$b/bin/embed_vulkan" ]] || fail "the bundle lacks bin/embed_vulkan"
for f in "$b"/lib/*; do
  case "$(basename "$f")" in
    libc.so.* | libm.so.* | ld-linux* | libdl.so.* | libpthread.so.*) fail "glibc bundled: $f" ;;
  esac
done
bytes="$(du -sb "$b" | cut -f1)"
((bytes < 64 * 1024 * 1024)) || fail "the bundle is $bytes bytes, 64 MiB or more"
# The validation layer when this machine has it, its manifest pointing into the bundle.
if [[ -f /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json ]]; then
  grep -q '"library_path": *"\.\./lib/libVkLayer_khronos_validation\.so"' "$b/layers/VkLayer_khronos_validation.json" ||
    fail "the layer manifest's library_path does not point into the bundle"
  [[ -f "$b/lib/libVkLayer_khronos_validation.so" ]] || fail "the bundle lacks the validation layer's library"
fi
# Every library the bundle's programs and libraries need resolves into the bundle, glibc
# aside.
for f in "$b"/bin/* "$b"/lib/*.so*; do
  LD_LIBRARY_PATH="$b/lib:$b/lib/compat" ldd "$f" | awk -v b="$b" '
    /=>/ && $3 !~ "^" b "/" && $1 !~ /^(linux-vdso|ld-linux|libc|libm|libdl|libpthread|librt)\./ { print; bad = 1 }
    END { exit bad }' || fail "$f loads the libraries above from outside the bundle"
done

# The bundle's launcher, alone: no inherited environment, a PATH of the tools a bare
# machine has (the script must not need Python or anything else), and the dynamic
# loader's record of every library each process loads.
mkdir -p "$work/path" "$work/ld"
for tool in bash env dirname sed awk grep sort tail head cut date tr cat tee mkdir rm mv uname getconf nproc timeout; do
  ln -s "$(command -v "$tool")" "$work/path/$tool"
done
rc=0
# The run's deadline: 300 s instead of --quick's 110 (GPU_RUN_BUDGET), and 90 s for each
# validate step instead of 30 (GPU_RUN_STEP_LIMIT). Here every step runs on lavapipe under
# the loader's logging, beside whatever else ctest runs on the two cores of a VM with 20%
# of its time stolen: the steps alone took 100 s, so 110 s left the last validate steps
# out, and CI's run of stop 58 saw `validate crowd.json --frames 3` run past its 30 s (lavapipe
# compiling the crowd's kernels). This test checks that the steps run and report, not how
# fast (ctest's limit is 420 s).
(cd "$work" && env -i PATH="$work/path" HOME="${HOME:-$work}" GPU_RUN_BUDGET="${GPU_RUN_BUDGET:-300}" \
  GPU_RUN_STEP_LIMIT="${GPU_RUN_STEP_LIMIT:-90}" LD_DEBUG=libs \
  LD_DEBUG_OUTPUT="$work/ld/p" bash "$b/gpu_run.sh" --quick "$work/out") >"$work/quick.out" 2>&1 || rc=$?
cat "$work/quick.out"
((rc == 0)) || fail "the bundle's gpu_run.sh --quick exited $rc"
grep -q '^bench  *backend  *count  *median/s' "$work/quick.out" || fail "no table printed"
tail -n 1 "$work/quick.out" | grep -q 'steps passed' || fail "the last line does not say the steps passed"
[[ -s "$work/out/run.log" ]] || fail "no run.log"
python3 - "$work/out/results.json" "$src" "${embed:+1}" <<'EOF'
import glob, json, os, sys
results, src, embed = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
d = json.load(open(results))
def check(cond, what):
    if not cond:
        sys.exit(f"FAIL: results.json: {what}")
check(d["format"] == "kodawari-gpu-run" and d["mode"] == "quick" and d["finished"] is True, "header")
check(d["environment"]["LD_LIBRARY_PATH"].split(":")[0].endswith("/bundle/lib"), "the bundle's libraries first")
check(d["bundle"] is not None and d["bundle"]["commit"], "the bundle's commit")
steps = {s["name"]: s for s in d["steps"]}
for s in d["steps"]:
    check(s["result"] == "ok" and s["status"] == 0 and s["seconds"] >= 0 and s["command"], f"step {s}")
scenes = sorted(os.path.relpath(p, os.path.join(src, "scenes"))[:-5].replace("/", "-")
                for p in glob.glob(os.path.join(src, "scenes", "*.json")) + glob.glob(os.path.join(src, "scenes", "*", "*.json"))
                if not p.endswith("crowd-10k.json"))  # the benchmark scene: gpu_run.sh says why
expected = ["info", "ceilings"] + [f"validate-{s}" for s in scenes] + (["embed_vulkan"] if embed else [])
for name in expected:
    check(name in steps, f"no step {name}")
# The host's ceilings, beside the results.
ceilings = json.load(open(os.path.join(os.path.dirname(results), "ceilings.json")))
check(ceilings["benchmark"] == "ceilings" and 0 < ceilings["fp32_flops"]["min"] <= ceilings["fp32_flops"]["median"]
      and ceilings["triad_bytes_per_second"]["median"] > 0, f"ceilings.json: {ceilings}")
benches = [s for s in d["steps"] if s["name"].startswith("bench-")]
check(len(benches) == 10, f"{len(benches)} bench steps, not 10")
# One character, the embedding's case, on every backend.
check("bench-crowd-1" in steps, "no step bench-crowd-1")
# The levels of detail's crowd: the shares of each level and of the kept state per result.
check("bench-crowd-lod-5" in steps, "no step bench-crowd-lod-5")
for r in steps["bench-crowd-lod-5"]["bench"]["results"]:
    check(r.get("posed_share") is not None and r.get("kept_share") is not None and r["clip_ms"] >= 0,
          f"bench-crowd-lod-5: {r}")
for s in benches:
    backends = {r["backend"].split("/")[0] for r in s["bench"]["results"]}
    check({"cpu", "vulkan"} <= backends, f"{s['name']}: backends {backends}")
# The large sizes time the vulkan kernels at every workgroup size of --workgroup-sizes.
for name in ("bench-chains-1001", "bench-birds-10001", "bench-flock-3001"):
    check(name in steps, f"no step {name}")
    labels = {r["backend"] for r in steps[name]["bench"]["results"]}
    check({"vulkan/wg32", "vulkan/wg64"} <= labels, f"{name}: backends {labels}, not vulkan/wg32 and vulkan/wg64")
    for r in s["bench"]["results"]:
        check(r["per_second"] > 0 and r["min"] <= r["per_second"] <= r["max"], f"{s['name']}: {r}")
EOF
# Every library of the bundle that a process loaded came from the bundle (the Vulkan
# loader and the validation layer, which ldd does not list, included).
grep -h 'calling init:' "$work"/ld/p.* | awk '{ print $NF }' | sort -u >"$work/loaded"
grep -q "^$b/lib/libvulkan.so.1\$" "$work/loaded" || fail "the bundle's libvulkan.so.1 was never loaded"
for f in "$b"/lib/*.so*; do
  name="$(basename "$f")"
  if grep "/$name\$" "$work/loaded" | grep -v "^$b/" | grep -q .; then
    fail "$name loaded from outside the bundle: $(grep "/$name\$" "$work/loaded" | grep -v "^$b/" | head -n 1)"
  fi
done

# A broken step: the run goes on after it, records it and exits 1.
cat >"$work/broken" <<EOF
#!/bin/sh
if [ "\$1" = bench ]; then echo "broken on purpose" >&2; exit 2; fi
exec "$kodawari" "\$@"
EOF
chmod +x "$work/broken"
rc=0
(cd "$work" && env -i PATH="$work/path" HOME="${HOME:-$work}" KODAWARI="$work/broken" \
  GPU_RUN_ONLY='^(info|bench-chains-301|validate-flock)$' bash "$b/gpu_run.sh" --quick "$work/broken-out") \
  >"$work/broken.out" 2>&1 || rc=$?
cat "$work/broken.out"
((rc == 1)) || fail "a failed step gave exit $rc, not 1"
python3 - "$work/broken-out/results.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
got = [(s["name"], s["result"], s["status"]) for s in d["steps"]]
want = [("info", "ok", 0), ("bench-chains-301", "failed", 2), ("validate-flock", "ok", 0)]
if got != want or d["finished"] is not True or "broken on purpose" not in d["steps"][1]["summary"]:
    sys.exit(f"FAIL: the broken run's steps {got}, not {want}")
EOF
# Bad usage exits 2 before OUT or its run.log is made: a budget or step limit that is no
# number of seconds, a KODAWARI that is not there.
for setting in GPU_RUN_BUDGET=abc GPU_RUN_BUDGET=2 GPU_RUN_STEP_LIMIT=abc KODAWARI=/nonexistent; do
  rc=0
  env KODAWARI="$kodawari" "$setting" bash "$src/scripts/gpu_run.sh" --quick "$work/bad-usage" >"$work/bad.out" 2>&1 || rc=$?
  [[ $rc -eq 2 ]] || { cat "$work/bad.out"; fail "$setting: exit $rc, not 2"; }
  grep -q "${setting%%=*}" "$work/bad.out" || { cat "$work/bad.out"; fail "$setting: the message does not name it"; }
  [[ ! -e "$work/bad-usage" ]] || fail "$setting: $work/bad-usage made before exiting 2"
done
echo "gpu_run_quick: ok"
