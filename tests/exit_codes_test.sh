#!/usr/bin/env bash
# One exit-code policy for every command (issue 37; docs/command-line.md, "Exit codes"):
#   2  bad input or usage: a bad option, an input file that is missing or cannot be read,
#      content a loader refuses, a device asked for that is not there;
#   1  a runtime failure: an output that cannot be written, a failed check;
#   0  success.
# Every command of `kodawari --help` has rows here, printed as a table; each row also checks
# that the message names what was wrong and that nothing was written.
#   usage: exit_codes_test.sh KODAWARI_BINARY SOURCE_DIR
set -uo pipefail
bin=$(realpath "$1")  # absolute: some rows run from a folder of their own
src=$2
source "$(dirname "${BASH_SOURCE[0]}")/check.sh"
cd "$src"

# A folder that cannot be written: outputs under it fail at run time (exit 1), whoever runs
# the test (root ignores permission bits, so a file stands where a folder should be).
: >"$work/a-file"
unwritable="$work/a-file/sub"
printf '{"format":"kodawari-scene","version":1,"flocks":[{"wing_type":"pigeon","count":3,"colour":1}]}' >"$work/bad.json"
printf 'not a part file\n' >"$work/bad.kwpart"
printf '{"points": [[-900, -900], [-800, -850]]}' >"$work/offimage.json"
printf '{"points": [[640, 300], [660, 260], [700, 240], [740, 250]]}' >"$work/stroke.json"
printf '{"format":"kodawari-scene"' >"$work/truncated.json"
python3 -c 'import json, sys; d = json.load(open("scenes/ahoge.json")); d["lod"] = {"budget_ms": 0}; json.dump(d, open(sys.argv[1], "w"))' "$work/zero-budget.json"
"$bin" run scenes/flock.json --backend cpu --frames 3 --shard 0/1 --out "$work/ok.kwpart" >/dev/null 2>&1

commands_seen=()
printf '%-10s %-52s %-5s %s\n' "command" "case" "exit" "expected"
row() {  # row COMMAND CASE EXPECTED_EXIT MESSAGE_REGEX -- ARGS...
  local command=$1 case=$2 expected=$3 pattern=$4
  shift 5
  "$bin" "$@" >"$work/row.out" 2>"$work/row.err"
  local rc=$?
  printf '%-10s %-52s %-5s %s\n' "$command" "$case" "$rc" "$expected"
  commands_seen+=("$command")
  check "$command: $case exits $expected" test "$rc" -eq "$expected"
  if [[ -n "$pattern" ]]; then
    check "$command: $case: the message names it ($pattern)" grep -qE -- "$pattern" "$work/row.err"
  fi
}

row run "missing scene file" 2 "nosuch.json" -- run "$work/nosuch.json" --out "$work/x.glb"
row run "scene the loader refuses" 2 'bad.json.*\$\.flocks\[0\]\.colour' -- run "$work/bad.json" --out "$work/x.glb"
row run "truncated JSON" 2 "truncated.json" -- run "$work/truncated.json" --out "$work/x.glb"
row run "a device asked for that is not there" 2 'no usable Vulkan device matches "no-such-device"' -- \
  run scenes/ahoge.json --frames 2 --no-export --device no-such-device
row run "output folder cannot be made" 1 "a-file/sub" -- run scenes/ahoge.json --frames 2 --backend cpu --out "$unwritable/x.glb"
row run "unknown option" 2 "--frobnicate" -- run scenes/ahoge.json --frobnicate
row run "a misspelt option" 2 "run: no option --frame \(did you mean --frames\?\)" -- run scenes/ahoge.json --frame 10
row run "words it does not take, in their order" 2 "run: arguments it does not take: extra words" -- run scenes/ahoge.json --frames 3 extra words
row bench "a misspelt option of a benchmark" 2 "bench flock: no option --cunt \(did you mean --count\?\)" -- bench flock --cunt 5
row merge "missing part file" 2 "nosuch.kwpart" -- merge "$work/nosuch.kwpart" --out "$work/m.glb"
row merge "not a part file" 2 "bad.kwpart" -- merge "$work/bad.kwpart" --out "$work/m.glb"
row merge "output folder cannot be made" 1 "a-file/sub" -- merge "$work/ok.kwpart" --out "$unwritable/m.glb"
row validate "missing scene file" 2 "nosuch.json" -- validate "$work/nosuch.json"
row validate "scene the loader refuses" 2 "bad.json" -- validate "$work/bad.json"
row bench "missing crowd scene file" 2 "nosuch.json" -- bench crowd "$work/nosuch.json" --backends cpu
row bench "a count out of range" 2 "--count" -- bench birds --count 0
row bench "--backend and --backends together" 2 "--backends" -- bench chains --backend cpu --backends cpu
row bench "--backend auto" 2 "--backend" -- bench chains --backend auto
row bench "a workgroup size that is no power of two" 2 "--workgroup-size" -- bench chains --backends vulkan --workgroup-size 96
row bench "a workgroup size list with one out of range" 2 "--workgroup-sizes" -- bench chains --backends vulkan --workgroup-sizes 64,2048
row bench "a device asked for that is not there" 2 '--device no-such-device: no usable Vulkan device matches "no-such-device"' -- \
  bench chains --count 10 --frames 1 --backends vulkan --device no-such-device --json "$work/dev.json"
row bench "an empty --backends" 2 "--backends: .*an empty list" -- bench chains --count 10 --frames 1 --backends "" --json "$work/bench.json"
row bench "an unknown backend in --backends" 2 '--backends: unknown backend "gpu"' -- bench chains --count 10 --frames 1 --backends cpu,gpu
row bench "--json in a folder that does not exist" 2 "--json: .*nosuch-folder/b.json: the folder .* does not exist" -- \
  bench chains --count 10 --frames 1 --backends cpu --json "$work/nosuch-folder/b.json"
row bench "--json in a folder that cannot be written" 2 "--json: .*a-file/sub/b.json" -- bench chains --count 10 --frames 1 --backends cpu --json "$unwritable/b.json"
row bench "--json with an empty name" 2 "--json: expected a file name" -- bench chains --count 10 --frames 1 --backends cpu --json ""
row bench "--json -" 2 '--json: "-" is not taken' -- bench birds --count 10 --frames 1 --backends cpu --json -
row bench "--json a folder" 2 "--json: .* is a folder" -- bench flock --count 10 --frames 1 --backends cpu --json "$work"
row bench "--json in a missing folder, bench view" 2 "--json: .*nosuch-folder" -- bench view scenes/ahoge.json --frames 1 --json "$work/nosuch-folder/v.json"
row bench "an unknown bench" 2 'unknown bench "birdz": expected one of birds, chains, crowd, flock, view, ceilings' -- bench birdz
row bench "a bench named in capitals" 2 'unknown bench "BIRDS"' -- bench BIRDS --count 10
row bench "no bench named" 2 "bench: name one of birds, chains, crowd, flock, view, ceilings" -- bench --count 10
row bench "ceilings on 0 threads" 2 "--threads: expected an integer in \\[1, 1024\\]" -- bench ceilings --threads 0
row bench "--json given twice" 2 "--json: given 2 times; expected it once" -- bench birds --count 10 --json "$work/a.json" --json "$work/b.json"
row run "--frames with no value" 2 "--frames: expected a value \\(N\\) after it, got none" -- run scenes/flock.json --frames
row bench "ceilings on an unknown isa" 2 '--isa: SIMD instruction set "avx1024" is unknown' -- bench ceilings --isa avx1024 --repetitions 1
row bench "ceilings with a triad too small" 2 "--triad-mib" -- bench ceilings --triad-mib 1
row bench "ceilings' --json in a missing folder" 2 "--json: .*nosuch-folder" -- bench ceilings --json "$work/nosuch-folder/c.json"
KODAWARI_DEVICE=no-such-device "$bin" bench birds --count 10 --frames 1 >"$work/env-dev.out" 2>"$work/env-dev.err"
check "bench: KODAWARI_DEVICE that matches nothing exits 2 naming it" bash -c \
  "test $? -eq 2 && grep -q 'KODAWARI_DEVICE=no-such-device: no usable Vulkan device' '$work/env-dev.err' && ! grep -q 'bench birds:' '$work/env-dev.out'"
# A backend named twice is timed once, as a size named twice in --workgroup-sizes.
"$bin" bench chains --count 10 --frames 1 --backends cpu,cpu --json "$work/twice.json" >/dev/null 2>&1
check "bench: --backends cpu,cpu times cpu once" python3 -c "
import json, sys; r = json.load(open(sys.argv[1])); assert [m['backend'] for m in r['results']] == ['cpu'], r" "$work/twice.json"
rm -f "$work/twice.json"
# Options for a backend the bench does not time are said to be ignored; the header's cpu
# ISA and threads only when cpu is timed.
"$bin" bench chains --count 10 --frames 1 --backends cpu-reference --workgroup-sizes 32,64 --rod-kernels per-joint --threads 2 \
  >"$work/ignored.out" 2>"$work/ignored.err"
check "bench: vulkan-only and cpu-only options without their backend: warned as ignored" bash -c "test $? -eq 0 &&
  grep -q 'warning: --workgroup-sizes is ignored' '$work/ignored.err' && grep -q 'warning: --rod-kernels is ignored' '$work/ignored.err' &&
  grep -q 'warning: --threads is ignored' '$work/ignored.err' && ! grep -q '^medians.*cpu:' '$work/ignored.out'"
# Every bench's JSON has count and frames; bench view's cpu read-back bytes are null
# where its table says '-'.
"$bin" bench view scenes/ahoge.json --frames 2 --size 16x16 --json "$work/view.json" >"$work/view.out" 2>&1
check "bench view: cpu's read-back bytes null in the JSON, '-' in the table" bash -c "python3 -c \"
import json, sys; r = json.load(open(sys.argv[1])); c = r['results'][2]
assert c['configuration'] == 'cpu' and c['read_back_bytes_per_frame'] is None and r['count'] == 3 and r['frames'] == 2, r\" '$work/view.json' &&
  grep -qE '^cpu +[0-9.e+]+ +[0-9.]+ +- ' '$work/view.out'"
"$bin" bench chains --count 12 --frames 2 --backends cpu --json "$work/chains.json" >/dev/null 2>&1
check "bench chains: count and frames in the JSON beside chains and steps" python3 -c "
import json, sys; r = json.load(open(sys.argv[1])); assert (r['count'], r['frames'], r['chains'], r['steps']) == (12, 2, 12, 2), r" "$work/chains.json"
rm -f "$work/view.json" "$work/chains.json"
# --help: each --count's range, bench's backends without auto, bench view's own columns.
check "bench --help: the counts' ranges, no auto, no --compact" bash -c "'$bin' bench birds --help | grep -q '1 to 20000000' &&
  '$bin' bench chains --help | grep -q '1 to 2000000 ' && '$bin' bench crowd --help | grep -q '1 to 100000 ' &&
  '$bin' bench flock --help | grep -q '1 to 4000000 ' && ! '$bin' bench birds --help | grep -qE 'auto\||--compact'"
check "bench view --help: its own columns, not the medians and ratios" bash -c "'$bin' bench view --help | grep -q 'vs vulkan readback, the' &&
  ! '$bin' bench view --help | grep -q 'vs c-ref'"
row run "a level-of-detail bias out of range" 2 "--lod-bias" -- run scenes/crowd-gltf.json --frames 1 --no-export --lod-bias 9
row render "a level-of-detail bias out of range" 2 "--lod-bias" -- render scenes/crowd-gltf.json --out "$work/lod-frames" --frames 1 --lod-bias 9
row render "levels of detail shown on a scene without characters" 2 "--show-lod: scene" -- render scenes/flock.json --out "$work/lod-frames" --frames 1 --show-lod
row run "a reduced level at or above full_pixels" 2 "--lod-reduced: expected 0 .off. or a number of pixels below the scene's lod.full_pixels .24., got 24" -- run scenes/crowd-gltf.json --frames 1 --no-export --lod-reduced 24
row run "a frame budget of zero" 2 "--budget-ms: expected a positive number of milliseconds" -- run scenes/crowd-gltf.json --frames 1 --no-export --budget-ms 0
row bench "a frame budget that is not a number" 2 "--budget-ms: expected a finite number" -- bench crowd --count 2 --frames 1 --budget-ms nan
row run "a scene's budget of zero" 2 "lod.budget_ms" -- run "$work/zero-budget.json" --frames 1 --no-export
row rig "missing character file" 2 "nosuch.glb" -- rig "$work/nosuch.glb" --out "$work/r.json"
row rig "missing bird file" 2 "nosuch.glb" -- rig "$work/nosuch.glb" --bird --out "$work/r.json"
row rig "missing bird map file" 2 "nosuch-map.json" -- rig scenes/characters/chibi.glb --bird --map "$work/nosuch-map.json" --out "$work/r.json"
row rig "missing motion file" 2 "nosuch.vrma" -- rig scenes/characters/avatar.vrm --motion "$work/nosuch.vrma" --out "$work/r.json"
row rig "a scene file given as a character" 2 "bad.json" -- rig "$work/bad.json" --out "$work/r.json"
row rig "output folder cannot be written" 1 "a-file/sub" -- rig scenes/characters/chibi.glb --out "$unwritable/r.json"
row sketch "missing scene file" 2 "nosuch.json" -- sketch "$work/nosuch.json" --chain girl/ahoge --stroke "$work/stroke.json" --out "$work/s.json"
row sketch "missing stroke file" 2 "nosuch-stroke.json: cannot open the stroke file" -- \
  sketch scenes/ahoge.json --chain girl/ahoge --stroke "$work/nosuch-stroke.json" --out "$work/s.json"
row sketch "stroke wholly off the image" 2 'offimage.json: \$\.points' -- \
  sketch scenes/ahoge.json --chain girl/ahoge --stroke "$work/offimage.json" --out "$work/s.json"
row sketch "neither --out nor --in-place" 2 "--in-place" -- sketch scenes/ahoge.json --chain girl/ahoge --stroke "$work/stroke.json"
row sketch "output folder cannot be written" 1 "a-file/sub" -- \
  sketch scenes/ahoge.json --chain girl/ahoge --stroke "$work/stroke.json" --out "$unwritable/s.json"
row render "missing scene file" 2 "nosuch.json" -- render "$work/nosuch.json" --out "$work/frames" --frames 1
row render "--animation not named .png" 2 "a.gif" -- render scenes/ahoge.json --out "$work/frames" --frames 1 --animation "$work/a.gif"
row render "--contact-sheet folder cannot be made" 1 "a-file/sub" -- \
  render scenes/ahoge.json --out "$work/frames" --frames 1 --contact-sheet "$unwritable/sheet.png"
# A bake never replaces a file its scene reads: a model in out/ named as its scene (what
# `rig` makes by default) is the default output's path.
cp scenes/characters/chibi.glb "$work/chibi.glb"
"$bin" rig "$work/chibi.glb" --out "$work/chibi.json" >/dev/null 2>&1
model_sum=$(md5sum <"$work/chibi.glb")
row run "--out the character model its scene reads" 2 "chibi.glb: --out is the model of character .chibi. of the scene .*chibi.json" -- \
  run "$work/chibi.json" --frames 2 --backend cpu --out "$work/chibi.glb"
row run "--out the scene file itself" 2 "--out is the scene file itself" -- run "$work/chibi.json" --frames 2 --backend cpu --shard 0/1 --out "$work/chibi.json"
row run "--out not named .glb" 2 "a.gltf: the bake is a binary glTF file: name it .glb" -- run scenes/ahoge.json --frames 2 --backend cpu --out "$work/a.gltf"
row merge "--out not named .glb" 2 "m.gltf: the bake is a binary glTF file" -- merge "$work/ok.kwpart" --out "$work/m.gltf"
row run "--trace the model its scene reads" 2 "--trace is the model of character .chibi. of the scene.*--trace .*chibi-bake.jsonl" -- \
  run "$work/chibi.json" --frames 2 --backend cpu --no-export --trace "$work/chibi.glb"
row rig "--out the model being rigged" 2 "--out is the model of character .chibi., which the scene reads" -- rig "$work/chibi.glb" --out "$work/chibi.glb"
row sketch "--out the model its scene reads" 2 "chibi.glb: is the model of character .chibi., which the scene reads, so nothing was written" -- \
  sketch "$work/chibi.json" --chain chibi/ahoge_0 --stroke "$work/stroke.json" --out "$work/chibi.glb"
row run "--trace the same file as --out" 2 "--trace .*both.glb is also --out" -- \
  run scenes/ahoge.json --frames 2 --backend cpu --out "$work/both.glb" --trace "$work/both.glb"
cp "$work/ok.kwpart" "$work/part-named.glb"
row merge "--out a part being merged" 2 "a part being merged" -- merge "$work/part-named.glb" --out "$work/part-named.glb"
mkdir -p "$work/cwd/out" && cp scenes/characters/chibi.glb "$work/cwd/out/chibi.glb"
rigged=$(cd "$work/cwd" && "$bin" rig out/chibi.glb --out out/chibi.json 2>/dev/null)
check "rig: the run it suggests names an --out of its own when the default is the model (got: $rigged)" \
  grep -qF "(kodawari run out/chibi.json --out out/chibi-bake.glb)" <<<"$rigged"
(cd "$work/cwd" && "$bin" run out/chibi.json --frames 2 --backend cpu >/dev/null 2>"$work/default.err")
check "run: the default output over the model exits 2" test $? -eq 2
check "run: the default output over the model: the message says so" grep -qF "the default output is the model of character" "$work/default.err"
check "the refused runs left the models as they were" bash -c \
  "test \"\$(md5sum <'$work/chibi.glb')\" = '$model_sum' && test \"\$(md5sum <'$work/cwd/out/chibi.glb')\" = '$model_sum'"
check "the refused merge left its part" cmp -s "$work/ok.kwpart" "$work/part-named.glb"
# A sketch written to another folder, made as run's --out is, names the scene's files
# from there (move_scene_text).
"$bin" sketch "$work/chibi.json" --chain chibi/ahoge_0 --stroke "$work/stroke.json" --out "$work/moved/chibi.json" >/dev/null 2>"$work/moved.err"
moved_rc=$?
check "sketch --out another folder exits 0 ($(head -c 300 "$work/moved.err"))" test "$moved_rc" -eq 0
check "sketch --out another folder: the scene names its model from there" grep -qF '"gltf": "../chibi.glb"' "$work/moved/chibi.json"
# --no-export writes nothing: not even run's default out/ folder.
mkdir -p "$work/noexport" && cp scenes/ahoge.json "$work/noexport/"
(cd "$work/noexport" && "$bin" run ahoge.json --backend cpu --frames 2 --no-export >/dev/null 2>&1)
check "run --no-export makes no out/ folder" test ! -e "$work/noexport/out"
# No scene given, outside the source tree: the default is not there.
(cd "$work/cwd" && "$bin" run --backend cpu --frames 2 >/dev/null 2>"$work/noscene.err")
check "run: no scene and no default here exits 2" test $? -eq 2
check "run: no scene and no default here: the message says no scene was given" grep -qF "no scene given" "$work/noscene.err"
row view "missing scene file" 2 "nosuch.json" -- view "$work/nosuch.json"
row info "an instruction set that is no name" 2 "" -- info --isa pentium
row info "a device asked for that is not there" 2 "" -- info --device no-such-device
row schema "an argument it does not take" 2 "" -- schema extra
row completion "a shell it does not know" 2 "" -- completion fish
row kodawari "unknown command" 2 "lists the commands" -- frobnicate

check "nothing written by the failing rows" bash -c "! ls '$work' | grep -qE '^(x\.glb|m\.glb|m\.gltf|a\.gltf|both\.glb|r\.json|s\.json|frames|a\.gif|dev\.json|bench\.json|nosuch-folder)$'"
check "the folder that cannot be written is untouched" test -f "$work/a-file"
# Writing to a closed stdout is a runtime failure, not bad input.
"$bin" schema >&- 2>/dev/null
check "schema: stdout closed exits 1" test $? -eq 1

# Every command of the help has a row.
help_commands=$("$bin" --help | awk '/^Subcommands:/{f=1;next} f && !NF {exit} f {print $1}')
check "the help lists commands" test -n "$help_commands"
for command in $help_commands; do
  check "the table has rows for \`$command\`" bash -c "printf '%s\n' ${commands_seen[*]} | grep -qx '$command'"
done

echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
