#!/usr/bin/env bash
# End-to-end checks of the `kodawari` command: real runs on the shipped scenes, exit
# codes, atomic outputs, the trace format and glTF-Validator on the export.
# usage: cli_test.sh KODAWARI_BINARY SOURCE_DIR
set -uo pipefail
bin=$1
src=$2
source "$(dirname "${BASH_SOURCE[0]}")/check.sh"

cd "$src"

# A run on the Vulkan backend writes the glb and the trace, and says where.
"$bin" run scenes/flock.json --backend vulkan --frames 120 --out "$work/flock.glb" --trace "$work/flock.jsonl" >"$work/run.out" 2>"$work/run.err"
rc=$?
cat "$work/run.out"
check "run exits 0" test $rc -eq 0
check "run names the output" grep -q "wrote $work/flock.glb" "$work/run.out"
check "run prints the backend" grep -q "backend vulkan on" "$work/run.out"

# auto on a machine whose best Vulkan device is a CPU (lavapipe) takes the cpu backend,
# several times faster there, and says why in one line; named, the device is obeyed
# (issue 38). On a GPU machine auto takes vulkan with no such line.
"$bin" run scenes/flock.json --frames 5 --no-export >"$work/auto.out" 2>"$work/auto.err"
rc=$?
"$bin" info >"$work/info.out" 2>&1
if grep -q "^backend auto: cpu (.* is a CPU" "$work/info.out"; then
  check "auto on a CPU-type device: the cpu backend" bash -c "test $rc -eq 0 && grep -q 'backend cpu on' '$work/auto.out'"
  check "auto on a CPU-type device: one line says why" bash -c \
    "test \$(grep -c 'backend auto runs on the CPU: .* is a CPU, not a GPU' '$work/auto.err') -eq 1"
  "$bin" run scenes/flock.json --frames 5 --no-export --device 0 >"$work/auto0.out" 2>"$work/auto0.err"
  rc=$?
  check "auto with the device named: runs on it" bash -c "test $rc -eq 0 && grep -q 'backend vulkan on' '$work/auto0.out' && ! grep -q 'runs on the CPU' '$work/auto0.err'"
else
  check "auto on a GPU: vulkan, no line about the CPU" bash -c "test $rc -eq 0 && grep -q 'backend vulkan on' '$work/auto.out' && ! grep -q 'runs on the CPU' '$work/auto.err'"
fi
check "glb exists" test -s "$work/flock.glb"
check "no temporary files left" bash -c "! ls '$work' | grep -q tmp"
check "trace header" bash -c "head -1 '$work/flock.jsonl' | grep -q '\"kind\":\"header\".*\"backend\":\"vulkan\"'"
birds=$(grep -c '"frame":0,' "$work/flock.jsonl")
lines=$(wc -l <"$work/flock.jsonl")
check "trace has 1 + frames x birds lines" test "$lines" -eq $((1 + 120 * birds))
check "glTF-Validator: 0 errors" node tests/tools/validate_gltf.mjs "$work/flock.glb"

# validate: the GPU against the CPU reference.
"$bin" validate scenes/flock.json --frames 600 >"$work/validate.out" 2>&1
rc=$?
cat "$work/validate.out"
check "validate flock passes" test $rc -eq 0

# Bad input: exit 2, the file and the JSON path named, nothing written.
printf '{"format":"kodawari-scene","version":1,"flocks":[{"wing_type":"pigeon","count":3,"colour":1}]}' >"$work/bad.json"
"$bin" run "$work/bad.json" --out "$work/bad.glb" >"$work/bad.out" 2>&1
rc=$?
check "bad scene exits 2" test $rc -eq 2
check "bad scene names file and path" grep -q "bad.json.*\$.flocks\[0\].colour" "$work/bad.out"
check "bad scene writes nothing" test ! -e "$work/bad.glb"
"$bin" run "$work/missing.json" >/dev/null 2>&1
check "missing scene fails" test $? -ne 0
"$bin" run scenes/flock.json --frames banana >/dev/null 2>&1
check "bad option exits 2" test $? -eq 2
"$bin" run scenes/flock.json --backend warp >/dev/null 2>&1
check "unknown backend exits 2" test $? -eq 2
"$bin" run scenes/flock.json --frames 0 >/dev/null 2>"$work/range.err"
check "a count out of range exits 2 naming the option and the range" bash -c "test $? -eq 2 && grep -q -- '--frames: expected an integer in \[1, 10000000\], got \"0\"' '$work/range.err'"
"$bin" run scenes/flock.json --frobnicate >/dev/null 2>"$work/unknown.err"
check "an unknown option exits 2 naming it" bash -c "test $? -eq 2 && grep -q -- '--frobnicate' '$work/unknown.err'"
"$bin" frobnicate >/dev/null 2>"$work/unknown-cmd.err"
check "an unknown command exits 2 naming it" bash -c "test $? -eq 2 && grep -q 'frobnicate' '$work/unknown-cmd.err'"
"$bin" run scenes/flock.json --frames >/dev/null 2>"$work/novalue.err"
check "an option without its value exits 2 naming it" bash -c "test $? -eq 2 && grep -q -- '--frames' '$work/novalue.err'"
"$bin" run scenes/flock.json --out= >/dev/null 2>"$work/empty.err"
check "--out= (an empty value) exits 2 naming it" bash -c "test $? -eq 2 && grep -q -- '--out: expected a value' '$work/empty.err'"
"$bin" >/dev/null 2>&1
check "no command exits 2" test $? -eq 2

# --help: the commands, and each command's options with their defaults; --version.
"$bin" --help >"$work/help.out" 2>&1
check "--help exits 0 and lists the commands" bash -c "test $? -eq 0 && grep -q '^  bench ' '$work/help.out' && grep -q '^  completion ' '$work/help.out' && grep -q '^  run ' '$work/help.out'"
"$bin" --version >"$work/version.out" 2>&1
check "--version" bash -c "test $? -eq 0 && grep -q '^kodawari [0-9]' '$work/version.out'"
"$bin" render --help >"$work/render-help.out" 2>&1
check "render --help lists --size with its default" bash -c "test $? -eq 0 && grep -q -- '--size WxH.*(default: 1280x720)' '$work/render-help.out'"
"$bin" bench chains --help >"$work/chains-help.out" 2>&1
check "bench chains --help: --frames with its default, --steps documented as the old spelling" bash -c \
    "grep -q -- '--frames N.*(default: 10)' '$work/chains-help.out' && grep -q -- '--steps N.*old spelling of --frames' '$work/chains-help.out'"
for command in run merge validate "bench birds" "bench chains" "bench crowd" "bench flock" "bench view" rig sketch render view info schema completion; do
    # shellcheck disable=SC2086
    "$bin" $command --help >"$work/cmd-help.out" 2>&1
    # An option whose value name is longer than the column (--measure's choices) has its
    # description on the next line: joined to it first.
    check "$command --help: every option says its default" bash -c "test $? -eq 0 && ! sed -e :a -e '\$!N;s/\n   \{10,\}/ /;ta' -e 'P;D' '$work/cmd-help.out' | grep -- '^  --' | grep -v -e 'default' -e '^  --help' -e 'old spelling' -e 'required' -e 'instead of' -e '--undo' -e '--no-export'"
done
"$bin" help run >"$work/help-run.out" 2>&1
check "help run is run --help" bash -c "test $? -eq 0 && grep -q -- '--frames' '$work/help-run.out'"

# An output that cannot be written (a file stands where its folder should be): an error
# naming it, no partial file.
: >"$work/a-file"
"$bin" run scenes/flock.json --backend cpu --frames 5 --out "$work/a-file/dir/x.glb" >"$work/io.out" 2>&1
rc=$?
check "unwritable output fails" test $rc -ne 0
check "unwritable output is named" grep -q "a-file/dir/x.glb" "$work/io.out"
check "an output folder that cannot be made exits 1 (a runtime failure)" test $rc -eq 1

# No Vulkan driver: auto says so in one line and runs on the CPU; --backend vulkan fails clearly.
VK_ICD_FILENAMES=/nonexistent.json "$bin" run scenes/flock.json --frames 10 --no-export >"$work/nodev.out" 2>"$work/nodev.err"
rc=$?
check "no driver: auto runs on the cpu" bash -c "test $rc -eq 0 && grep -q 'backend cpu on' '$work/nodev.out'"
check "no driver: one line says why" bash -c "test \$(grep -c 'backend auto runs on the CPU' '$work/nodev.err') -eq 1 && grep -q 'no Vulkan driver found' '$work/nodev.err'"
VK_ICD_FILENAMES=/nonexistent.json "$bin" run scenes/flock.json --frames 10 --no-export --backend vulkan >/dev/null 2>"$work/nodev2.err"
rc=$?
check "no driver: --backend vulkan fails clearly" bash -c "test $rc -eq 1 && grep -q 'no Vulkan driver found' '$work/nodev2.err'"

# info lists the device it would choose.
"$bin" info >"$work/info.out" 2>&1
cat "$work/info.out"
check "info names the chosen device" grep -q "^chosen: " "$work/info.out"

# A device request that matches nothing: info and a run name each device and why it was
# passed over (Error::rejected_devices, GpuDeviceInfo::rejected), not just "none".
"$bin" info --device no-such-device >"$work/info-none.out" 2>&1
check "info: no device matches, says why for each" bash -c "grep -q '^chosen: none: no usable Vulkan device matches \"no-such-device\" (passed over: .*: does not match \"no-such-device\"' '$work/info-none.out' && grep -q '^      passed over: ' '$work/info-none.out'"
"$bin" run scenes/flock.json --frames 10 --no-export --backend vulkan --device no-such-device >/dev/null 2>"$work/nomatch.err"
rc=$?
check "run: no device matches, exits 2 (bad input) naming the devices" bash -c "test $rc -eq 2 && grep -q 'kodawari: error: no usable Vulkan device matches \"no-such-device\" (passed over: .*: does not match' '$work/nomatch.err'"

# The same input on the same backend gives the same bits.
"$bin" run scenes/flock.json --backend vulkan --frames 30 --out "$work/a.glb" >/dev/null 2>&1
"$bin" run scenes/flock.json --backend vulkan --frames 30 --out "$work/b.glb" >/dev/null 2>&1
check "vulkan runs are deterministic" cmp -s "$work/a.glb" "$work/b.glb"
# The vectorized cpu backend: chains are cpu-reference's bits; birds are within the
# reference's tolerances (the wings' sines are its own) and the same bits on every SIMD
# instruction set (KODAWARI_ISA or --isa forces a narrower one).
"$bin" run scenes/ahoge.json --backend cpu --frames 30 --out "$work/c.glb" >/dev/null 2>&1
"$bin" run scenes/ahoge.json --backend cpu-reference --frames 30 --out "$work/d.glb" >/dev/null 2>&1
check "cpu chains equal cpu-reference bit for bit" cmp -s "$work/c.glb" "$work/d.glb"
"$bin" run scenes/flock.json --backend cpu --frames 30 --out "$work/e.glb" >/dev/null 2>&1
KODAWARI_ISA=sse4 "$bin" run scenes/flock.json --backend cpu --frames 30 --out "$work/f.glb" >/dev/null 2>&1
check "cpu birds: the same bits on sse4 as on the widest instruction set" cmp -s "$work/e.glb" "$work/f.glb"
"$bin" validate scenes/flock.json --backend cpu --frames 300 >"$work/validate-cpu.out" 2>&1
check "validate: the cpu backend's birds pass against the reference" grep -q "validate: PASS" "$work/validate-cpu.out"
"$bin" info >"$work/info-simd.out" 2>&1
check "info names the SIMD instruction set and the available ones" grep -q '^SIMD: [a-z0-9]* (.*); available: .*scalar' "$work/info-simd.out"
KODAWARI_ISA=avx1024 "$bin" bench birds --count 10 --frames 1 --backends cpu >/dev/null 2>"$work/isa.err"
rc=$?
check "an unknown KODAWARI_ISA exits 2 naming it and the available ones" bash -c "test $rc -eq 2 && grep -q 'KODAWARI_ISA: SIMD instruction set \"avx1024\" is unknown.*available here: .*scalar' '$work/isa.err'"

# bench writes the documented JSON.
"$bin" bench birds --count 1001 --frames 3 --json "$work/bench.json" >"$work/bench.out" 2>&1
rc=$?
check "bench exits 0" test $rc -eq 0
check "bench json has three backends" bash -c "node -e 'const r=require(\"$work/bench.json\"); if (r.benchmark!==\"birds\"||r.results.length!==3) process.exit(1)'"
# The GPU column (issue 37): in the JSON as gpu_ms_per_frame, null for the cpu kinds, a
# median like ms_per_frame and below it; the help and the table define it.
check "bench json: gpu_ms_per_frame, null for the cpu kinds, at most ms_per_frame for vulkan" bash -c "node -e 'const r=require(\"$work/bench.json\"); for (const m of r.results) { if (!(\"gpu_ms_per_frame\" in m)) process.exit(1); if (m.backend!==\"vulkan\" && m.gpu_ms_per_frame!==null) process.exit(2); if (m.backend===\"vulkan\" && !(m.gpu_ms_per_frame>0 && m.gpu_ms_per_frame<=m.ms_per_frame)) process.exit(3); }'"
check "bench's table says what GPU ms/frame is" grep -q "GPU ms/frame: the device's timestamps" "$work/bench.out"
"$bin" bench --help >"$work/bench-help.out" 2>&1
check "bench --help defines the columns" grep -q "GPU ms/frame, the device's timestamps" "$work/bench-help.out"
"$bin" bench birds --count 1001 --frames 2 --backend cpu --json "$work/bench-one.json" >/dev/null 2>&1
check "bench --backend cpu times cpu alone" bash -c "node -e 'const r=require(\"$work/bench-one.json\"); if (r.results.length!==1||r.results[0].backend!==\"cpu\") process.exit(1)'"

# Rod scenes (SPEC A): a run with a trace of chain records and a validator-clean export,
# validate against the CPU reference, and the chains benchmark's JSON.
"$bin" run scenes/ahoge.json --frames 60 --out "$work/ahoge.glb" --trace "$work/ahoge.jsonl" >"$work/ahoge.out" 2>&1
rc=$?
check "rod scene runs" test $rc -eq 0
check "rod trace: header + 60 chain records" bash -c "test \$(wc -l <'$work/ahoge.jsonl') -eq 61 && test \$(grep -c '\"kind\":\"chain\"' '$work/ahoge.jsonl') -eq 60"
check "rod trace records have the documented fields" bash -c "sed -n 2p '$work/ahoge.jsonl' | node -e 'const r=JSON.parse(require(\"fs\").readFileSync(0,\"utf8\")); for (const k of [\"frame\",\"time\",\"character\",\"chain\",\"view_dir\",\"weights\",\"rest\",\"joints\",\"orientations\"]) if (!(k in r)) process.exit(1); if (r.joints.length!==r.rest.length||r.orientations[0].length!==4) process.exit(1)'"
check "rod export passes glTF-Validator" node tests/tools/validate_gltf.mjs "$work/ahoge.glb"
"$bin" validate scenes/bunny.json --frames 120 >"$work/validate-bunny.out" 2>&1
check "validate passes on the bunny" grep -q "validate: PASS" "$work/validate-bunny.out"
"$bin" bench chains --count 130 --joints 9 --frames 2 --json "$work/bench-chains.json" >/dev/null 2>&1
check "bench chains json" bash -c "node -e 'const r=require(\"$work/bench-chains.json\"); if (r.benchmark!==\"chains\"||r.results.length!==3||!(r.results[0].per_second>0)) process.exit(1)'"
# The rod kernels side by side (issue 38, item 2), and the kernels' statistics where the
# driver offers them (lavapipe does not: the line says so).
"$bin" bench chains --count 130 --joints 9 --frames 2 --backends vulkan --rod-kernels per-chain,shared-constants,per-joint \
  --kernel-statistics --json "$work/bench-kernels.json" >"$work/bench-kernels.out" 2>&1
check "bench chains --rod-kernels times the three rod kernels" bash -c "node -e 'const r=require(\"$work/bench-kernels.json\"); if (r.results.length!==3||r.results[0].backend!==\"vulkan/per-chain\"||r.results[1].backend!==\"vulkan/shared-constants\"||r.results[2].backend!==\"vulkan/per-joint\"||!(r.results[2].per_second>0)) process.exit(1)'"
check "bench --kernel-statistics reports the kernels or why not" grep -q "^kernel statistics of vulkan" "$work/bench-kernels.out"
"$bin" bench chains --count 130 --frames 2 --backends vulkan --rod-kernels per-thread >/dev/null 2>"$work/bench-kernels.err"
check "bench chains --rod-kernels with an unknown kernel exits 2 naming it" bash -c "test $? -eq 2 && grep -q 'per-thread' '$work/bench-kernels.err'"
# bench flock: every backend on one flocking flock, in bird-steps/s, and where each
# backend's time went (the grid, the neighbour search, the rules).
"$bin" bench flock --count 301 --frames 2 --json "$work/bench-flock.json" >"$work/bench-flock.out" 2>&1
check "bench flock json" bash -c "node -e 'const r=require(\"$work/bench-flock.json\"); if (r.benchmark!==\"flock\"||r.count!==301||r.results.length!==3||!(r.results[1].per_second>0)) process.exit(1)'"
check "bench flock says the search's share" grep -q '^cpu-reference  *[0-9.]*  *[0-9.]*  *[0-9.]*  *[0-9.]*$' "$work/bench-flock.out"
# and the vulkan step's, timed apart (profile_flocking), with its device time per frame.
check "bench flock splits the vulkan step" grep -q '^vulkan  *[0-9.]*  *[0-9.]*  *[0-9.]*  *[0-9.]*$' "$work/bench-flock.out"
check "bench flock has the vulkan step's device time" bash -c "node -e 'const r=require(\"$work/bench-flock.json\"); const v=r.results.find(x=>x.backend===\"vulkan\"); if (!v||!(v.gpu_ms_per_frame>0)) process.exit(1)'"
check "bench flock's JSON has every backend's split" bash -c "node -e 'const r=require(\"$work/bench-flock.json\"); if (!r.results.every(x=>[x.grid_share,x.search_share,x.rules_share,x.search_ns_per_bird].every(v=>typeof v===\"number\"))) process.exit(1)'"
# The old spellings --chains and --steps still work for one release, saying so on stderr.
"$bin" bench chains --chains 130 --joints 9 --steps 2 --backends cpu --json "$work/bench-steps.json" >/dev/null 2>"$work/bench-steps.err"
check "bench chains --steps and --chains still work, deprecated" bash -c "test $? -eq 0 && grep -q -- '--steps is deprecated.*use --frames' '$work/bench-steps.err' && grep -q -- '--chains is deprecated.*use --count' '$work/bench-steps.err' && node -e 'const r=require(\"$work/bench-steps.json\"); if (r.chains!==130||r.steps!==2) process.exit(1)'"
"$bin" bench chains --steps 2 --frames 3 --backends cpu >/dev/null 2>"$work/bench-both.err"
check "bench chains --steps with --frames exits 2" bash -c "test $? -eq 2 && grep -q -- '--steps' '$work/bench-both.err'"
KODAWARI_ISA=sse4 "$bin" bench chains --count 130 --joints 9 --frames 2 --threads 2 --backends cpu-reference,cpu --json "$work/bench-isa.json" >"$work/bench-isa.out" 2>&1
check "bench: medians of 3 repetitions with min, max, ratios, the ISA and threads" bash -c "node -e 'const r=require(\"$work/bench-isa.json\"); const c=r.results[1]; if (r.isa!==\"sse4\"||r.threads!==2||r.repetitions!==3||c.backend!==\"cpu\"||c.isa!==\"sse4\"||c.threads!==2||!(c.min<=c.per_second&&c.per_second<=c.max)||!(c.vs_cpu_reference>0)||c.vs_cpu!==1||r.results[0].threads!==1||r.results[0].isa!==null) process.exit(1)' && grep -q 'cpu  *2 threads, sse4 .* sse4  *2\$' '$work/bench-isa.out'"

# Rigged characters (issue 4): `kodawari rig` on the project's character and on every
# shipped sample writes a scene that `kodawari run` simulates; bad input exits 2.
for f in scenes/characters/chibi.glb tests/assets/vrm-springbone/sphere-collider.gltf \
         tests/assets/vrm-springbone/inside-collider.gltf tests/assets/vrm-springbone/plane-collider.gltf; do
    base=$(basename "$f"); base=${base%.*}
    "$bin" rig "$f" --out "$work/rig-$base.json" >"$work/rig-$base.out" 2>&1
    check "rig $base exits 0" test $? -eq 0
    "$bin" run "$work/rig-$base.json" --frames 30 --out "$work/rig-$base.glb" >"$work/rig-run-$base.out" 2>&1
    check "rig scene of $base runs" test $? -eq 0
done
check "rig prints chains and joints" grep -q "7 chains from name patterns" "$work/rig-chibi.out"
check "rig prints each chain's joints" grep -q "tail_0 .* 8 joints" "$work/rig-chibi.out"
check "rig writes the plane collider (VRMC_springBone_extended_collider)" grep -q '"type": "plane"' "$work/rig-plane-collider.json"
check "rig writes the inside collider" grep -q '"inside": true' "$work/rig-inside-collider.json"
"$bin" rig tests/assets/khronos/RiggedSimple.gltf --roots Bone --out "$work/rig-rs.json" >/dev/null 2>&1 &&
    "$bin" run "$work/rig-rs.json" --frames 30 --out "$work/rig-rs.glb" >/dev/null 2>&1
check "rig --roots on RiggedSimple runs" test $? -eq 0
"$bin" rig tests/assets/khronos/RiggedSimple.gltf --out "$work/none.json" >"$work/rig-none.out" 2>&1
check "rig without chains exits 2 and says what to do" bash -c "test $? -eq 2 && grep -q -- '--roots' '$work/rig-none.out' && test ! -e '$work/none.json'"
"$bin" rig "$work/missing.glb" --out "$work/m.json" >"$work/rig-missing.out" 2>&1
check "rig on a missing file fails and names it" bash -c "test $? -ne 0 && grep -q 'missing.glb' '$work/rig-missing.out'"
"$bin" run scenes/crowd-gltf.json --frames 20 --out "$work/crowd-gltf.glb" >"$work/crowd-gltf.out" 2>&1
check "crowd-gltf runs" test $? -eq 0
check "crowd-gltf exports the character's own skeleton" grep -q "wrote $work/crowd-gltf.glb.*own skeleton" "$work/crowd-gltf.out"
check "crowd-gltf export passes glTF-Validator" node tests/tools/validate_gltf.mjs "$work/crowd-gltf.glb"

# --compact (docs/compact.md): the same scenes compacted at the default bounds are
# smaller, say what compaction did, and pass glTF-Validator (0 errors, 0 warnings); bad
# bounds exit 2 naming --compact and write nothing.
"$bin" run scenes/crowd-gltf.json --frames 20 --compact --out "$work/crowd-gltf-compact.glb" >"$work/crowd-gltf-compact.out" 2>&1
check "crowd-gltf --compact runs" test $? -eq 0
check "crowd-gltf --compact reports keys kept and the largest error" grep -q "compact: .* keys kept .*largest error .* mm, .* mrad" "$work/crowd-gltf-compact.out"
check "crowd-gltf --compact is smaller" test "$(stat -c %s "$work/crowd-gltf-compact.glb")" -lt "$(stat -c %s "$work/crowd-gltf.glb")"
check "crowd-gltf --compact passes glTF-Validator" bash -c "node tests/tools/validate_gltf.mjs '$work/crowd-gltf-compact.glb' | grep -q '0 errors, 0 warnings'"
"$bin" run scenes/flock.json --backend cpu --frames 120 --compact=0.002,0.005 --out "$work/flock-compact.glb" >"$work/flock-compact.out" 2>&1
check "flock --compact=0.002,0.005 runs" test $? -eq 0
check "flock --compact passes glTF-Validator" bash -c "node tests/tools/validate_gltf.mjs '$work/flock-compact.glb' | grep -q '0 errors, 0 warnings'"
"$bin" run scenes/ahoge.json --frames 30 --compact --out "$work/ahoge-compact.glb" >/dev/null 2>&1
check "ahoge --compact passes glTF-Validator" bash -c "node tests/tools/validate_gltf.mjs '$work/ahoge-compact.glb' | grep -q '0 errors, 0 warnings'"
for bad in "--compact=abc" "--compact=-1" "--compact=0.001,x" "--compact="; do
    "$bin" run scenes/ahoge.json --frames 3 "$bad" --out "$work/bad-compact.glb" >"$work/bad-compact.out" 2>&1
    check "run $bad exits 2 naming --compact" bash -c "test $? -eq 2 && grep -q -- '--compact: expected' '$work/bad-compact.out' && test ! -e '$work/bad-compact.glb'"
done
# --meshopt compresses compacted keys: without --compact it exits 2 naming --meshopt, as
# a bad value of either option does, and writes nothing; merge likewise.
"$bin" run scenes/ahoge.json --frames 3 --meshopt --out "$work/bad-meshopt.glb" >"$work/bad-meshopt.out" 2>&1
check "run --meshopt without --compact exits 2 naming --meshopt" bash -c "test $? -eq 2 && grep -q -- '--meshopt: .*--compact' '$work/bad-meshopt.out' && test ! -e '$work/bad-meshopt.glb'"
"$bin" run scenes/ahoge.json --frames 3 --compact=abc --meshopt --out "$work/bad-meshopt.glb" >"$work/bad-meshopt.out" 2>&1
check "run --compact=abc --meshopt exits 2 naming --compact" bash -c "test $? -eq 2 && grep -q -- '--compact: expected' '$work/bad-meshopt.out' && test ! -e '$work/bad-meshopt.glb'"
"$bin" merge "$work/no-such-part.glb" --meshopt --out "$work/bad-meshopt.glb" >"$work/bad-meshopt.out" 2>&1
check "merge --meshopt without --compact exits 2 naming --meshopt" bash -c "test $? -eq 2 && grep -q -- '--meshopt: .*--compact' '$work/bad-meshopt.out' && test ! -e '$work/bad-meshopt.glb'"
"$bin" run scenes/ahoge.json --frames 10 --compact --meshopt --out "$work/ahoge-meshopt.glb" >"$work/ahoge-meshopt.out" 2>&1
check "ahoge --compact --meshopt passes glTF-Validator" bash -c "node tests/tools/validate_gltf.mjs '$work/ahoge-meshopt.glb' | grep -q '0 errors, 0 warnings'"
"$bin" bench crowd --count 13 --frames 2 --json "$work/bench-crowd.json" >/dev/null 2>&1
# Vulkan twice: the rod input made on the host, then written on the device.
check "bench crowd json" bash -c "node -e 'const r=require(\"$work/bench-crowd.json\"); if (r.benchmark!==\"crowd\"||r.instances!==13||r.results.length!==4||r.results[3].backend!==\"vulkan/dev-in\"||!(r.results[3].per_second>0)) process.exit(1)'"
# With levels of detail it prints the chains at each level and the share that kept their
# state (the rate), read back from each backend: the reference and cpu agree, and far
# characters keep (crowd-10k's camera starts 90 m out).
"$bin" bench crowd scenes/crowd-10k.json --count 40 --frames 11 --backends cpu-reference,cpu --lod --json "$work/bench-lod.json" >"$work/bench-lod.out" 2>&1
check "bench crowd --lod --json: the shares, the same on both backends, and the frame's split" bash -c "node -e 'const r=require(\"$work/bench-lod.json\").results; if (r.length!==2||!(r[0].kept_share>0)||r[0].kept_share!==r[1].kept_share||r[0].posed_share!==1||!(r[1].clip_ms>0)||!(r[1].chain_ms>0)) process.exit(1)'"
"$bin" bench crowd scenes/crowd-10k.json --count 40 --frames 11 --backends cpu-reference,cpu --lod --lod-reduced 24 --lod-bias 1 --json "$work/bench-reduced.json" >/dev/null 2>&1
check "bench crowd --lod-reduced: a reduced share, the same on both backends" bash -c "node -e 'const r=require(\"$work/bench-reduced.json\").results; if (r.length!==2||!(r[0].reduced_share>0)||r[0].reduced_share!==r[1].reduced_share) process.exit(1)'"
check "bench crowd json without levels of detail: null shares" bash -c "node -e 'const r=require(\"$work/bench-crowd.json\").results; if (r[0].kept_share!==null||!(r[0].clip_ms>0)) process.exit(1)'"
check "bench crowd --lod prints the kept share, the same on both backends" bash -c "test \$(grep -o 'kept their state [0-9.]*%' '$work/bench-lod.out' | sort -u | wc -l) -eq 1 && grep -c 'kept their state [1-9][0-9.]*%' '$work/bench-lod.out' | grep -qx 2"
"$bin" bench view scenes/ahoge.json --frames 3 --size 64x48 --json "$work/bench-view.json" >"$work/bench-view.out" 2>&1
check "bench view: three configurations, nothing read back when shared" bash -c "node -e 'const r=require(\"$work/bench-view.json\"); if (r.benchmark!==\"view\"||r.results.length!==3||r.results[0].configuration!==\"vulkan shared\"||r.results[0].read_back_bytes_per_frame!==0||!(r.results[1].read_back_bytes_per_frame>0)) process.exit(1)'"

# sketch (SPEC A.6): a stroke becomes a view example of ahoge, reported and loadable;
# --undo gives the file back byte for byte; bad strokes exit 2 naming file and path.
cp scenes/ahoge.json "$work/ahoge.json"
printf '{"points": [[640, 300], [660, 260], [700, 240], [740, 250]]}' >"$work/stroke.json"
"$bin" sketch "$work/ahoge.json" --in-place --chain girl/ahoge --stroke "$work/stroke.json" --influence 30 >"$work/sketch.out" 2>&1
rc=$?
cat "$work/sketch.out"
check "sketch exits 0" test $rc -eq 0
check "sketch prints the view direction" grep -q "^view direction \[" "$work/sketch.out"
check "sketch prints the reprojection error" grep -q "^reprojection error " "$work/sketch.out"
check "sketch names the example" grep -q 'view example [0-9] "sketch 1"' "$work/sketch.out"
check "sketched scene has the example" grep -q '"name": "sketch 1"' "$work/ahoge.json"
"$bin" run "$work/ahoge.json" --backend cpu --frames 10 --no-export >/dev/null 2>&1
check "sketched scene runs" test $? -eq 0
"$bin" sketch "$work/ahoge.json" --chain girl/ahoge --stroke "$work/stroke.json" --camera 0.85,2.3,0.85,0,1.62,0 --out "$work/ahoge2.json" >"$work/sketch2.out" 2>&1
check "sketch --camera --out" bash -c "test $? -eq 0 && grep -q '\"name\": \"sketch 2\"' '$work/ahoge2.json'"
"$bin" sketch "$work/ahoge2.json" --in-place --chain girl/ahoge --undo >/dev/null 2>&1
check "sketch --undo removes the last sketch" cmp -s "$work/ahoge.json" "$work/ahoge2.json"
cp scenes/bunny.json "$work/bunny.json"
"$bin" sketch "$work/bunny.json" --in-place --chain bunny/ear_l --stroke "$work/stroke.json" --camera 1.2,2.6,1.2,0,1.65,0 >/dev/null 2>&1
"$bin" sketch "$work/bunny.json" --in-place --chain bunny/ear_l --undo >/dev/null 2>&1
check "sketch then --undo gives the file back" cmp -s scenes/bunny.json "$work/bunny.json"
# A sketch within 20 degrees of an example replaces it, keeping it as "replaces"; --undo
# puts it back, byte for byte, and the next --undo finds nothing (issue 37).
printf '{"points": [[640, 300], [660, 260], [700, 240], [740, 250]]}' >"$work/front-stroke.json"
"$bin" sketch scenes/ahoge.json --chain girl/ahoge --stroke "$work/front-stroke.json" --out "$work/replaced.json" >"$work/replaced.out" 2>&1
check "a sketch near the front example replaces it and says it is kept" grep -q 'replaces "front" (within 20 degrees; kept in the file, --undo brings it back)' "$work/replaced.out"
check "the replaced example is in the file as \"replaces\"" grep -q '"replaces": {' "$work/replaced.json"
"$bin" sketch "$work/replaced.json" --chain girl/ahoge --undo --in-place >"$work/restored.out" 2>&1
check "--undo puts back the replaced example" grep -q 'putting back "front", which it had replaced' "$work/restored.out"
# (Written in another folder, the copy's "$schema" names the same schema file from there.)
check "--undo after a replacing sketch gives the scene back byte for byte, but its \$schema" \
  cmp -s <(grep -v '"\$schema"' scenes/ahoge.json) <(grep -v '"\$schema"' "$work/replaced.json")
schema_ref=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["$schema"])' "$work/replaced.json")
check "the sketched copy's \$schema ($schema_ref) is docs/scene.schema.json from its folder" \
  cmp -s docs/scene.schema.json "$work/$schema_ref"
cp scenes/ahoge.json "$work/ahoge-before-noout.json"
"$bin" sketch scenes/ahoge.json --chain girl/ahoge --stroke "$work/front-stroke.json" >/dev/null 2>&1
check "sketch without --out or --in-place exits 2" test $? -eq 2
check "... and leaves the scene alone" cmp -s scenes/ahoge.json "$work/ahoge-before-noout.json"
printf '{"points": [[640, 300]]}' >"$work/short.json"
cp "$work/ahoge.json" "$work/before.json"
"$bin" sketch "$work/ahoge.json" --in-place --chain girl/ahoge --stroke "$work/short.json" >"$work/short.out" 2>&1
check "sketch with a 1-point stroke exits 2" test $? -eq 2
check "sketch error names the stroke file and path" grep -q 'short.json: \$.points' "$work/short.out"
check "failed sketch leaves the scene" cmp -s "$work/ahoge.json" "$work/before.json"
printf '{"points": [[640, 300], [1, "x"]]}' >"$work/nan.json"
"$bin" sketch "$work/ahoge.json" --in-place --chain girl/ahoge --stroke "$work/nan.json" >"$work/nan.out" 2>&1
check "sketch with a non-number exits 2" bash -c "test $? -eq 2 && grep -q 'points\[1\]\[1\]' '$work/nan.out'"
"$bin" sketch "$work/ahoge.json" --in-place --chain girl/tail --stroke "$work/stroke.json" >"$work/chain.out" 2>&1
check "sketch of an unknown chain exits 2" bash -c "test $? -eq 2 && grep -q 'no chain' '$work/chain.out'"
"$bin" sketch "$work/bunny.json" --in-place --chain bunny/ear_r --stroke "$work/stroke.json" >"$work/mirror.out" 2>&1
check "sketch of a mirrored chain exits 2" bash -c "test $? -eq 2 && grep -q 'mirror' '$work/mirror.out'"
# Keyed sketches (docs/sketch.md): --key motion at the ponytail's sprint writes the head's
# measured speed; --key pose on nod's bangs the head's rotation; --undo takes the keyed
# example back out, byte for byte; bad options and the limits exit 2, writing nothing.
cp scenes/ponytail.json "$work/ponytail.json"
"$bin" sketch "$work/ponytail.json" --in-place --chain runner/ponytail --stroke "$work/stroke.json" --frame 330 --key motion >"$work/kmotion.out" 2>&1
rc=$?
cat "$work/kmotion.out"
check "sketch --key motion exits 0" test $rc -eq 0
check "sketch --key motion prints the measured speed" grep -Eq '^motion key: head speed [4-9][.0-9]* m/s \(magnitude, smoothed over 0.25 s\), influence ' "$work/kmotion.out"
check "sketch --key motion names the keyed example" grep -q '^keyed example 1 "sketch 1" added' "$work/kmotion.out"
check "the motion example is in the chain's keyed array" grep -q '"name": "sketch 1", "key": "motion", "joint": "head", "measure": "speed", "frame": "magnitude", "value": ' "$work/ponytail.json"
"$bin" run "$work/ponytail.json" --backend cpu --frames 10 --no-export >/dev/null 2>&1
check "the scene with the motion example runs" test $? -eq 0
"$bin" sketch "$work/ponytail.json" --in-place --chain runner/ponytail --undo >"$work/kundo.out" 2>&1
check "sketch --undo says it removed the keyed example" grep -q '^removed keyed example 1 "sketch 1" of runner/ponytail' "$work/kundo.out"
check "sketch --key motion then --undo gives the file back" cmp -s scenes/ponytail.json "$work/ponytail.json"
cp scenes/nod.json "$work/nod.json"
"$bin" sketch "$work/nod.json" --in-place --chain girl/bang_l1 --stroke "$work/stroke.json" --frame 150 --key pose --influence 15 >"$work/kpose.out" 2>&1
rc=$?
cat "$work/kpose.out"
check "sketch --key pose exits 0" test $rc -eq 0
check "sketch --key pose prints the rotation" grep -q '^pose key: head rotation \[.*influence 15 degrees' "$work/kpose.out"
check "the pose example is written with a rotation" grep -q '"key": "pose", "pose": \[{"joint": "head", "rotation": \[' "$work/nod.json"
"$bin" sketch "$work/nod.json" --in-place --chain girl/bang_l1 --undo >/dev/null 2>&1
check "sketch --key pose then --undo gives the file back" cmp -s scenes/nod.json "$work/nod.json"
cp "$work/ponytail.json" "$work/pony-before.json"
kbad() {  # kbad NAME EXPECTED-MESSAGE ARGS...: exit 2, the message, the scene untouched
    local name=$1 expected=$2; shift 2
    "$bin" sketch "$work/ponytail.json" --in-place --chain runner/ponytail --stroke "$work/stroke.json" "$@" >"$work/kbad.out" 2>&1
    local rc=$?
    check "sketch $name exits 2" test $rc -eq 2
    check "sketch $name says: $expected" grep -qF -- "$expected" "$work/kbad.out"
    check "sketch $name writes nothing" cmp -s "$work/ponytail.json" "$work/pony-before.json"
}
kbad "--key sideways" '--key: expected motion or pose, got "sideways"' --key sideways
kbad "--measure jerk" '--measure: expected speed, acceleration or angular_speed, got "jerk"' --frame 330 --key motion --measure jerk
kbad "--joint tail" '--joint: joint "tail": character "runner" has no such joint' --frame 330 --key motion --joint tail
kbad "--influence nan" '--influence: expected a finite number, got "nan"' --frame 330 --key motion --influence nan
kbad "--influence -1" '--influence: expected a number in (0, 1e4]' --frame 330 --key motion --influence -1
kbad "--smoothing -0.5" '--smoothing: expected seconds in [0, 60], got "-0.5"' --frame 330 --key motion --smoothing -0.5
kbad "--smoothing nan" '--smoothing: expected a finite number, got "nan"' --frame 330 --key motion --smoothing nan
kbad "--measure without --key" '--joint, --measure and --smoothing need --key motion|pose' --measure speed
kbad "--key motion at rest" 'character "runner" does not move at frame 0' --key motion
kbad "--key pose --smoothing" '--measure and --smoothing need --key motion' --key pose --smoothing 1
# The limits: a chain with 4 keyed examples takes no fifth (exit 2, naming file and chain).
for i in 1 2 3; do
    "$bin" sketch "$work/ponytail.json" --in-place --chain runner/ponytail --stroke "$work/stroke.json" --frame $((200 + 40 * i)) --key motion >/dev/null 2>&1
done
check "three more keyed sketches fill the ponytail" test "$(grep -c '"key": "motion"' "$work/ponytail.json")" -eq 4
cp "$work/ponytail.json" "$work/pony-full.json"
"$bin" sketch "$work/ponytail.json" --in-place --chain runner/ponytail --stroke "$work/stroke.json" --frame 330 --key pose >"$work/kfull.out" 2>&1
check "a fifth keyed sketch exits 2" test $? -eq 2
check "the limit names the file, the chain and the most" grep -qF "ponytail.json: \$.characters[0].chains[0].keyed: chain \"runner/ponytail\" already has 4 keyed examples, the most a chain may have (4)" "$work/kfull.out"
check "the refused sketch writes nothing" cmp -s "$work/ponytail.json" "$work/pony-full.json"
# The offscreen renderer (issue 5): PNG files per frame, a contact sheet, bad input exits 2.
"$bin" render scenes/ahoge.json --frames 10:40:10 --size 161x97 --contact-sheet "$work/render/sheet.png" --columns 2 \
    --out "$work/render" >"$work/render.out" 2>&1
check "render exits 0" test $? -eq 0
check "render writes one PNG per frame (10, 20, 30; 40 is exclusive)" bash -c \
    "test -s '$work/render/ahoge_00010.png' && test -s '$work/render/ahoge_00020.png' && test -s '$work/render/ahoge_00030.png' && test ! -e '$work/render/ahoge_00040.png'"
check "render names what it wrote" grep -q "wrote $work/render/ahoge_00030.png" "$work/render.out"
check "render PNG has the asked size" python3 -c "import struct,sys; d=open(sys.argv[1],'rb').read(24); sys.exit(d[:8]!=b'\\x89PNG\\r\\n\\x1a\\n' or struct.unpack('>II', d[16:24])!=(161, 97))" "$work/render/ahoge_00010.png"
check "render contact sheet exists" grep -q "wrote contact sheet $work/render/sheet.png" "$work/render.out"
"$bin" render scenes/ahoge.json --frames 5:5 --out "$work/render-bad" >"$work/render-bad.out" 2>&1
check "render with an empty --frames range exits 2 and says why" bash -c "test $? -eq 2 && grep -q 'empty' '$work/render-bad.out'"
"$bin" render scenes/ahoge.json --frames 0:100000 --out "$work/render-bad" >"$work/render-bad2.out" 2>&1
check "render past the scene's end exits 2" test $? -eq 2
"$bin" render scenes/ahoge.json --size 0x10 --out "$work/render-bad" >"$work/render-bad3.out" 2>&1
check "render with a bad --size exits 2" test $? -eq 2
# --show-lod (issue 35): a dot over each of the 64 characters in its level's colour, and the
# counts per level printed; the picture differs from the one without the dots.
"$bin" render scenes/crowd-gltf.json --backend cpu --frames 30 --size 160x90 --show-lod --out "$work/render-lod" \
    >"$work/render-lod.out" 2>&1
check "render --show-lod exits 0" test $? -eq 0
check "render --show-lod counts every character once" bash -c \
    "grep -E 'frame 30: characters full [0-9]+, posed [0-9]+, hidden [0-9]+' '$work/render-lod.out' | awk '{ n = \$6 + \$8 + \$10; exit (n != 64) }'"
"$bin" render scenes/crowd-gltf.json --backend cpu --frames 30 --size 160x90 --lod --out "$work/render-nolod" >/dev/null 2>&1
# --lod-reduced: the reduced level between full and posed, counted on its own line.
"$bin" render scenes/crowd-gltf.json --backend cpu --frames 30 --size 160x90 --show-lod --lod-reduced 12 \
    --out "$work/render-reduced" >"$work/render-reduced.out" 2>&1
check "render --show-lod --lod-reduced counts the reduced level too" bash -c \
    "grep -E 'frame 30: characters full [0-9]+, reduced [1-9][0-9]*, posed [0-9]+, hidden [0-9]+' '$work/render-reduced.out' | awk '{ n = \$6 + \$8 + \$10 + \$12; exit (n != 64) }'"
check "render --show-lod draws the dots" bash -c "! cmp -s '$work/render-lod/crowd-gltf_00030.png' '$work/render-nolod/crowd-gltf_00030.png'"

# --zoom: the scene camera's field of view narrowed about its target; a different picture
# of the same frame, and a bad value is a usage error.
"$bin" render scenes/ahoge.json --frames 0 --size 64x40 --out "$work/zoom1" >/dev/null 2>&1
"$bin" render scenes/ahoge.json --frames 0 --size 64x40 --out "$work/zoom2" --zoom 2 >/dev/null 2>&1
check "render --zoom 2 draws a different picture of the frame" bash -c "test -s '$work/zoom2/ahoge_00000.png' && ! cmp -s '$work/zoom1/ahoge_00000.png' '$work/zoom2/ahoge_00000.png'"
"$bin" render scenes/ahoge.json --frames 0 --out "$work/zoom3" --zoom 0 >"$work/zoom-bad.out" 2>&1
check "render --zoom 0 exits 2 naming the option and the range" bash -c "test $? -eq 2 && grep -q -- '--zoom: expected a number in \\[0.1, 100\\]' '$work/zoom-bad.out'"

# --camera: another eye and target for the picture (the simulation keeps the scene's
# camera); a different picture of the same frame, and a bad value or an eye on the target
# is a usage error that writes nothing.
"$bin" render scenes/ahoge.json --frames 0 --size 64x40 --out "$work/camera1" --camera 0.8,1.6,0.8,0,1.57,0 >/dev/null 2>&1
check "render --camera draws a different picture of the frame" bash -c "test -s '$work/camera1/ahoge_00000.png' && ! cmp -s '$work/zoom1/ahoge_00000.png' '$work/camera1/ahoge_00000.png'"
"$bin" render scenes/ahoge.json --frames 0 --out "$work/camera2" --camera 1,2,3 >"$work/camera-bad.out" 2>&1
check "render --camera with 3 numbers exits 2 naming the option" bash -c "test $? -eq 2 && grep -q -- '--camera: expected EYE_X' '$work/camera-bad.out' && test ! -e '$work/camera2'"
"$bin" render scenes/ahoge.json --frames 0 --out "$work/camera3" --camera 1,2,3,1,2,3 >"$work/camera-bad2.out" 2>&1
check "render --camera with the eye on the target exits 2" bash -c "test $? -eq 2 && grep -q 'the target equals the eye' '$work/camera-bad2.out'"

# --joints: dots at the strands' joints on request only (tests/render checks where).
# (Dots are drawn only where the chain is long enough on screen for them to stay apart.)
"$bin" render scenes/ahoge.json --frames 0 --size 320x180 --zoom 2 --out "$work/nojoints" >/dev/null 2>&1
"$bin" render scenes/ahoge.json --frames 0 --size 320x180 --zoom 2 --out "$work/joints" --joints >/dev/null 2>&1
check "render --joints draws a different picture of the frame" bash -c "test -s '$work/joints/ahoge_00000.png' && test -s '$work/nojoints/ahoge_00000.png' && ! cmp -s '$work/nojoints/ahoge_00000.png' '$work/joints/ahoge_00000.png'"

# --animation (an APNG of the drawn frames; tests/render/test_apng.cpp decodes it frame by
# frame): here what the command line adds, the signature and acTL (5 frames, forever),
# and the failures.
"$bin" render scenes/ahoge.json --frames 0:50:10 --size 64x40 --out "$work/anim" --animation "$work/anim.png" \
    --animation-size 32x20 >"$work/anim.out" 2>&1
check "render --animation exits 0" test $? -eq 0
check "render --animation names the file, frames, size and delay" \
    grep -q "wrote animation $work/anim.png (5 frames, 32x20, 1/6 s each, looping)" "$work/anim.out"
check "render --animation writes an APNG of 5 frames that loops" python3 -c "import struct,sys; d=open(sys.argv[1],'rb').read(); \
i=d.find(b'acTL'); sys.exit(d[:8]!=b'\\x89PNG\\r\\n\\x1a\\n' or i!=37 or struct.unpack('>II', d[i+4:i+12])!=(5, 0))" "$work/anim.png"
"$bin" render scenes/ahoge.json --frames 0:50:10 --size 64x40 --out "$work/anim-bad" --animation "$work/a-file/a.png" \
    >"$work/anim-bad.out" 2>&1
check "render --animation into a folder that cannot be made exits 1" test $? -eq 1
check "render --animation names the folder it cannot make" grep -q -- "--animation $work/a-file: cannot create the directory" "$work/anim-bad.out"
check "... found before any frame is drawn" bash -c "! grep -q 'wrote .*anim-bad/' '$work/anim-bad.out'"
check "render --animation that fails leaves no frames directory" test ! -e "$work/anim-bad"
"$bin" render scenes/ahoge.json --frames 0 --out "$work/anim-bad" --animation-size 32x20 >"$work/anim-bad2.out" 2>&1
check "--animation-size without --animation exits 2" bash -c "test $? -eq 2 && grep -q 'goes with --animation' '$work/anim-bad2.out'"
"$bin" render scenes/ahoge.json --frames 0 --size 64x40 --out "$work/anim-bad" --animation "$work/a.png" --animation-size 65x20 \
    >"$work/anim-bad3.out" 2>&1
check "--animation-size larger than --size exits 2" bash -c "test $? -eq 2 && grep -q 'animation-size' '$work/anim-bad3.out'"

echo "cli: $passed passed, $failed failed"
test $failed -eq 0
