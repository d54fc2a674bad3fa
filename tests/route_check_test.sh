#!/usr/bin/env bash
# The route check of `kodawari run` and `validate` (issue 14, docs/command-line.md): a
# route beyond its bird's limits warns naming the flock, segment and limit; --strict exits
# 2 and writes nothing; --fit-routes lowers the speed and the run then has nothing to say;
# the shipped scenes pass without a warning.
# usage: route_check_test.sh KODAWARI_BINARY SOURCE_DIR
set -uo pipefail
bin=$1
src=$2
source "$(dirname "${BASH_SOURCE[0]}")/check.sh"
cd "$src"

# A gull flock at 12 m/s: a straight segment, then a 5 m hairpin (segment 1), then a
# straight 40 degree climb (segment 4).
cat >"$work/tight.json" <<'JSON'
{"format": "kodawari-scene", "version": 1, "name": "tight", "fps": 30, "duration": 1,
 "flocks": [{"name": "gulls", "wing_type": "gull", "count": 4, "seed": 5, "speed": 12,
   "route": {"points": [[0,20,0],[0,20,20],[0,20,40],[0,20,60],[0,20,68],[10,20,68],[10,20,60],
                        [10,20,40],[10,20,20],[10,20,0],[10,20,-20],[10,20,-40],[10,20,-60],
                        [10,36.8,-80],[10,53.6,-100],[10,70.4,-120]]}}]}
JSON

"$bin" run "$work/tight.json" --backend cpu-reference --out "$work/tight.glb" >"$work/warn.out" 2>"$work/warn.err"
rc=$?
cat "$work/warn.err"
check "a warning does not stop the run" test $rc -eq 0 -a -s "$work/tight.glb"
check "the turn warning names file, flock, segment and limit" \
    grep -q "warning: $work/tight.json: \$.flocks\[0\] \"gulls\": segment 1 (u = [0-9.]*): turn radius [0-9.]* m at 12 m/s is below the gull's minimum 8.47 m (max bank 60 deg)" "$work/warn.err"
check "the corner warning names the junction" \
    grep -q "segment 4 (u = 0): the route turns 40 deg at the junction with segment 3 (a corner" "$work/warn.err"
check "the climb warning names segment 4" \
    grep -q "segment 4 (u = [0-9.]*): climb 40 deg is above the gull's maximum 14.8 deg" "$work/warn.err"

"$bin" run "$work/tight.json" --backend cpu-reference --strict --out "$work/strict.glb" >"$work/strict.out" 2>"$work/strict.err"
rc=$?
check "--strict exits 2" test $rc -eq 2
check "--strict says why" grep -q "error: [0-9]* route limits exceeded (--strict" "$work/strict.err"
check "--strict writes nothing" bash -c "! ls '$work' | grep -q 'strict.glb\|tmp'"
"$bin" validate "$work/tight.json" --backend cpu --strict >/dev/null 2>"$work/vstrict.err"
check "validate --strict exits 2 too" test $? -eq 2

# --fit-routes smooths the kink where the climb starts (a corner), then lowers the speed
# until the hairpin and the bank jumps pass; the climb is the route's shape and still warns.
"$bin" run "$work/tight.json" --backend cpu-reference --fit-routes --out "$work/fit.glb" >"$work/fit.out" 2>"$work/fit.err"
rc=$?
cat "$work/fit.out" "$work/fit.err"
check "--fit-routes runs" test $rc -eq 0 -a -s "$work/fit.glb"
check "--fit-routes says what it changed" grep -q "fit: $work/tight.json: \$.flocks\[0\] \"gulls\": speed 12 -> [0-9.]* m/s" "$work/fit.out"
check "after the fit no turn warns" bash -c "! grep -q 'turn radius' '$work/fit.err'"
check "--fit-routes smooths the corner" grep -q "route points 11 and 13 turned onto one line through point 12 (a 40 deg corner)" "$work/fit.out"
check "after the fit no corner or bank jump warns" bash -c "! grep -q 'at the junction' '$work/fit.err'"
check "after the fit the climb still warns" grep -q "climb [0-9.]* deg is above the gull's maximum" "$work/fit.err"

# A flyable copy (the climb removed): the fit makes --strict pass.
python3 - "$work/tight.json" "$work/level.json" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
points = scene["flocks"][0]["route"]["points"]
scene["flocks"][0]["route"]["points"] = [[p[0], 20, p[2]] for p in points]
json.dump(scene, open(sys.argv[2], "w"))
PY
"$bin" run "$work/level.json" --backend cpu-reference --strict --fit-routes --no-export >"$work/level.out" 2>"$work/level.err"
check "--strict --fit-routes passes a route whose only fault was the speed" test $? -eq 0 -a ! -s "$work/level.err"

# A user's bird (issue 37): `rig --bird` writes a scene its own checks pass, at the bird's
# own cruise speed; its flock is held to the bird's derived limits under the bird's name,
# and --fit-routes starts from that cruise speed, not a built-in type's.
PYTHONDONTWRITEBYTECODE=1 python3 scripts/make_test_bird.py "$work/mybird.glb" >/dev/null
"$bin" rig "$work/mybird.glb" --bird --out "$work/mybird.json" >"$work/rigbird.out" 2>&1
check "rig --bird exits 0 and says how big a route it made" bash -c "test $? -eq 0 && grep -q 'route: a generated loop [0-9]* m across' '$work/rigbird.out'"
"$bin" run "$work/mybird.json" --backend cpu-reference --frames 1 --no-export --strict >/dev/null 2>"$work/rigbird.err"
check "rig --bird's scene passes --strict (no route warning)" test $? -eq 0 -a ! -s "$work/rigbird.err"
# The same flock on the example's small route: warnings name the user's bird and its own
# minimum radius, and the fit starts from its cruise speed (11.2 m/s).
python3 - "$work/mybird.json" "$work/small.json" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["flocks"][0]["generated_route"]["extent"] = [45, 8, 45]
json.dump(scene, open(sys.argv[2], "w"))
PY
"$bin" run "$work/small.json" --backend cpu-reference --frames 1 --no-export >/dev/null 2>"$work/small.err"
check "a user's bird's warnings name it, not a built-in type" bash -c "grep -q \"below the mybird's minimum\" '$work/small.err' && ! grep -q pigeon '$work/small.err'"
"$bin" run "$work/small.json" --backend cpu-reference --frames 1 --no-export --fit-routes >"$work/small-fit.out" 2>/dev/null
check "--fit-routes starts from the user's bird's cruise speed" grep -q 'speed 11.2 -> [0-9.]* m/s so its turns, bank jumps and speed changes are within the mybird' "$work/small-fit.out"

# A generated route in a 1 m box at a pigeon's speed is beyond it everywhere: 8 lines for
# the flock, then how many more, rather than one per segment, limit and variant.
cat >"$work/tiny.json" <<'JSON'
{"format": "kodawari-scene", "version": 1, "name": "tiny", "fps": 30, "duration": 1,
 "flocks": [{"name": "tiny", "wing_type": "pigeon", "count": 10,
             "generated_route": {"extent": [1, 1, 1], "segments": 64, "loop": true}}]}
JSON
"$bin" validate "$work/tiny.json" --backend cpu --frames 2 >/dev/null 2>"$work/tiny.err"
check "a flock's route warnings stop at 8 lines and a count" bash -c "
    test \$(grep -c 'warning: .*\\\$.flocks\\[0\\] \"tiny\": segment' '$work/tiny.err') -eq 8 &&
    grep -q 'warning: $work/tiny.json: \\\$.flocks\\[0\\] \"tiny\": [0-9]* more like these ([0-9]* in all)' '$work/tiny.err'"

for scene in scenes/*.json; do
    grep -q '"flocks"' "$scene" || continue
    "$bin" run "$scene" --backend cpu-reference --frames 1 --no-export --strict >/dev/null 2>"$work/shipped.err"
    check "$scene: no route warnings" test $? -eq 0 -a ! -s "$work/shipped.err"
done

echo "route_check: $passed passed, $failed failed"
test $failed -eq 0
