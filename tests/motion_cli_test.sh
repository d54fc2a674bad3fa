#!/usr/bin/env bash
# Motions from elsewhere (issue 18) through the command line: `kodawari rig AVATAR
# --motion ...` writes a scene that `run` and `validate` play; every bad motion exits 2
# naming the file and the JSON path, and writes nothing. The avatars and motions are
# written by tests/tools/make_motion_assets.py (docs/motions.md).
# usage: motion_cli_test.sh KODAWARI_BINARY SOURCE_DIR
set -uo pipefail
bin=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")  # absolute: the test runs in its scratch folder
src=$2
source "$(dirname "${BASH_SOURCE[0]}")/check.sh"

python3 "$src/tests/tools/make_motion_assets.py" "$work" || { echo "FAIL make_motion_assets.py"; exit 1; }
cd "$work"

# rig --motion: the motions listed and the first played; run and validate play it.
"$bin" rig avatar.vrm --motion walk.vrma --motion idle.vrma --out avatar.json >rig.out 2>&1
rc=$?
cat rig.out
check "rig --motion exits 0" test $rc -eq 0
check "rig plays the first motion" grep -q 'animation "walk"' rig.out
check "rig prints each motion" bash -c "grep -q 'motion \"walk\" .*walk.vrma: 13 bones, 31 keys, 1 s, hips displacement x0.812' rig.out &&
    grep -q 'motion \"idle\" .*idle.vrma' rig.out"
check "the scene lists the motions" node -e '
    const c = require(process.argv[1]).characters[0];
    if (c.animation !== "walk" || JSON.stringify(c.motions) !== JSON.stringify([{name: "walk", file: "walk.vrma"}, {name: "idle", file: "idle.vrma"}])) process.exit(1)' \
    "$work/avatar.json"
"$bin" run avatar.json --frames 30 --out avatar.glb >run.out 2>&1
rc=$?
cat run.out
check "run plays the retargeted motion" bash -c "test $rc -eq 0 && test -s avatar.glb"
check "glTF-Validator: 0 errors" node "$src/tests/tools/validate_gltf.mjs" avatar.glb
"$bin" validate avatar.json --frames 30 >validate.out 2>&1
check "validate passes" bash -c "test $? -eq 0 && grep -q 'validate: PASS' validate.out"
# A VRM 0.x avatar (facing -Z), a clip for another skeleton through --motion-map.
"$bin" rig avatar-vrm0.vrm --motion walk.vrma --motion run.gltf --motion-map mixamo-map.json --out vrm0.json >rig0.out 2>&1
rc=$?
cat rig0.out
check "rig --motion-map exits 0" test $rc -eq 0
check "rig says which motion went through the map" grep -q 'motion "run" .*(through --motion-map)' rig0.out
check "the scene names the map" grep -q '"map": "mixamo-map.json"' vrm0.json
"$bin" run vrm0.json --frames 30 --out vrm0.glb >/dev/null 2>&1
check "run plays the VRM 0.x scene" bash -c "test $? -eq 0 && test -s vrm0.glb"
"$bin" rig avatar.vrm --motion-map mixamo-map.json --out none.json >/dev/null 2>&1
check "rig --motion-map without --motion exits 2" bash -c "test $? -eq 2 && test ! -e none.json"

# Bad motions given to rig: exit 2, the file and the JSON path named, no scene.
bad_rig() {  # bad_rig NAME EXPECTED-TEXT RIG-ARGUMENTS...
    local name=$1 expected=$2; shift 2
    "$bin" rig "$@" --out bad.json >bad.out 2>&1
    local rc=$?
    check "rig: $name exits 2, says '$expected', writes nothing" bash -c \
        "test $rc -eq 2 && grep -qF -- '$expected' bad.out && test ! -e bad.json"
}
bad_rig "a .vrma without humanoid bones" "bones.vrma: \$.extensions.VRMC_vrm_animation.humanoid.humanBones: missing" \
    avatar.vrm --motion bones.vrma
bad_rig "a required bone the avatar lacks" "wave.vrma: \$.extensions.VRMC_vrm_animation.humanoid.humanBones.leftHand.node: the clip animates leftHand, a required VRM humanoid bone" \
    handless.vrm --motion wave.vrma
bad_rig "a map naming no node" "bad-map.json: \$.leftHand: no node of run.gltf is called \"mixamorig:LeftPalm\"" \
    avatar.vrm --motion run.gltf --motion-map bad-map.json
bad_rig "a glTF clip without a map" "run.gltf: \$.extensions.VRMC_vrm_animation: missing" avatar.vrm --motion run.gltf
bad_rig "a missing motion file" "gone.vrma: no such file" avatar.vrm --motion gone.vrma

# Bad motions in a scene: run and validate exit 2 naming the scene, the key's JSON path
# and the problem inside the motion file; run writes nothing.
scene() {  # scene FILE CHARACTER MOTIONS-JSON
    cat >"$1" <<EOF
{"format": "kodawari-scene", "version": 2, "name": "bad", "fps": 30, "duration": 1,
 "characters": [{"name": "a", "gltf": "$2", "animation": "walk", "motions": $3,
                 "chains": [{"name": "hair", "root": "hair_0"}]}]}
EOF
}
bad_scene() {  # bad_scene NAME EXPECTED-TEXT CHARACTER MOTIONS-JSON
    local name=$1 expected=$2
    scene bad-scene.json "$3" "$4"
    "$bin" run bad-scene.json --out bad.glb >bad.out 2>&1
    local rc=$?
    check "run: $name exits 2, says '$expected', writes nothing" bash -c \
        "test $rc -eq 2 && grep -qF -- 'bad-scene.json: $expected' bad.out && test ! -e bad.glb"
    "$bin" validate bad-scene.json >bad.out 2>&1
    rc=$?
    check "validate: $name exits 2" bash -c "test $rc -eq 2 && grep -qF -- 'bad-scene.json: $expected' bad.out"
}
bad_scene "a .vrma without humanoid bones" \
    "\$.characters[0].motions[0].file: bones.vrma: \$.extensions.VRMC_vrm_animation.humanoid.humanBones: missing" \
    avatar.vrm '[{"name": "walk", "file": "bones.vrma"}]'
bad_scene "a required bone the avatar lacks" \
    "\$.characters[0].motions[0].file: wave.vrma: \$.extensions.VRMC_vrm_animation.humanoid.humanBones.leftHand.node:" \
    handless.vrm '[{"name": "walk", "file": "wave.vrma"}]'
bad_scene "no bone in common" "\$.characters[0].motions[0].file: toes.vrma: \$.extensions.VRMC_vrm_animation.humanoid.humanBones: no humanoid bone in common" \
    avatar.vrm '[{"name": "walk", "file": "toes.vrma", "target_map": "hips-map.json"}]'
bad_scene "a map naming no node" "\$.characters[0].motions[0].map: bad-map.json: \$.leftHand: no node of" \
    avatar.vrm '[{"name": "walk", "file": "run.gltf", "clip": "Run", "map": "bad-map.json"}]'
bad_scene "a name clashing with a clip" "\$.characters[0].motions[1].name: \"walk\" is already the name of an earlier motion" \
    avatar.vrm '[{"name": "walk", "file": "walk.vrma"}, {"name": "walk", "file": "idle.vrma"}]'
bad_scene "a missing motion file" "\$.characters[0].motions[0].file: gone.vrma: no such file" \
    avatar.vrm '[{"name": "walk", "file": "gone.vrma"}]'

# The VRM collider model's bad input (issue 18), in the generated VRoid-class avatar's
# variants (scenes/characters/make_avatar.py --variant): a collider group naming a
# collider the file lacks, a plane collider with a zero normal. rig exits 2, names the
# file and the JSON path, and writes nothing.
for variant in vrm-missing-collider vrm-zero-plane; do
    python3 "$src/scenes/characters/make_avatar.py" --variant $variant --out $variant.vrm >/dev/null ||
        { echo "FAIL make_avatar.py --variant $variant"; exit 1; }
done
bad_rig "a collider group naming a missing collider"     "vrm-missing-collider.vrm: \$.extensions.VRMC_springBone.colliderGroups[" vrm-missing-collider.vrm
check "  ...and says which collider" grep -q "collider 16 does not exist (16 of them)" bad.out
bad_rig "a plane with a zero normal"     ".shape.plane.normal: a plane" vrm-zero-plane.vrm
check "  ...and names the file and says what was expected" bash -c "grep -q 'vrm-zero-plane.vrm: [$].extensions.VRMC_springBone.colliders.0.' bad.out && grep -q 'must be a non-zero vector' bad.out"

echo "motion cli: $passed passed, $failed failed"
test $failed -eq 0
