// The scene format's characters (docs/scene-format.md, version 2): what loads, and the loader's errors.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <kodawari/vulkan/gpu_info.hpp>
#include <kodawari/backends/rod_backend.hpp>
#include <kodawari/scene/scene.hpp>
#include <kodawari/rods/kinematics.hpp>
#include <kodawari/rods/solver.hpp>
#include <kodawari/rods/world.hpp>

#include "character_support.hpp"

using namespace kodawari::testing_support::characters;  // the character suites' shared helpers

// ---------------------------------------------------------------------------------------
// The scene format's characters (docs/scene-format.md, version 2)

TEST(CharacterScene, ValidSceneLoadsWithDefaults) {
    const auto loaded = kodawari::parse_scene(valid_character_scene().dump(), "test.json");
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const Scene& s = loaded.value();
    EXPECT_EQ(s.version, 2u);
    EXPECT_TRUE(s.flocks.empty());
    ASSERT_EQ(s.characters.size(), 1u);
    const kodawari::CharacterSpec& c = s.characters[0];
    EXPECT_EQ(c.skeleton.joints[c.skeleton.reference].name, "head");  // the default reference joint
    ASSERT_EQ(c.chains.size(), 2u);  // ear and its mirror image
    EXPECT_EQ(c.chains[1].name, "ear_r");
    EXPECT_EQ(c.chains[0].params.stiffness, rods::SolverParams{}.stiffness);
    EXPECT_EQ(c.chains[0].base.positions.size(), 8u);
    ASSERT_EQ(c.motion.oscillations.size(), 2u);
    EXPECT_EQ(c.motion.oscillations[0].joint, 0u);                   // sway: the root
    EXPECT_EQ(c.motion.oscillations[1].joint, c.skeleton.reference);  // head turn: the reference joint
    ASSERT_EQ(c.motion.locomotions.size(), 2u);
    EXPECT_EQ(c.motion.locomotions[1].ramp_out, 0.0f);  // a stop halts dead
    // Without "crowds": one instance of every character at the origin.
    ASSERT_EQ(s.crowds.size(), 1u);
    const auto built = kodawari::build_rod_scene(s);
    ASSERT_TRUE(built.ok()) << built.error().message;
    const RodScene& rs = built.value();
    EXPECT_EQ(rs.world.character_count, 1u);
    EXPECT_EQ(rs.character_names, std::vector<std::string>{"bunny#0"});
    EXPECT_EQ(rs.chain_names, (std::vector<std::string>{"bunny#0/ear", "bunny#0/ear_r"}));
    EXPECT_EQ(rs.world.templates[0].name, "bunny/ear");
    EXPECT_EQ(rs.world.joint_count, 16u);
    EXPECT_EQ(rs.frames, 600u);
    // Colliders follow their joint; a sphere is a capsule with a == b.
    const rods::RodFrame frame = rs.frame(0);
    ASSERT_EQ(frame.colliders.size(), 1u);
    EXPECT_EQ(frame.colliders[0].a, frame.colliders[0].b);
    EXPECT_EQ(frame.colliders[0].a, rs.joint_poses(0, 0)[1].position);
    EXPECT_EQ(frame.colliders[0].radius, 0.1f);
    EXPECT_EQ(rs.world.chains[0].collider_count, 1u);
    // "collide": false leaves a chain without colliders; a chain's physics overrides the
    // character's key by key.
    json doc = valid_character_scene();
    doc["characters"][0]["physics"] = {{"damping", 2.5}, {"stiffness", 0.7}};
    chain0(doc)["collide"] = false;
    chain0(doc)["physics"] = {{"stiffness", 0.9}, {"gravity", {0, 0, 0}}, {"rest_stiffness", 0.3}};
    const auto custom = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(custom.ok()) << custom.error().message;
    const RodScene crs = build(custom.value());
    EXPECT_EQ(crs.world.chains[0].collider_count, 0u);
    const rods::SolverParams& p = crs.world.templates[0].params;
    EXPECT_EQ(p.damping, 2.5f);
    EXPECT_EQ(p.stiffness, 0.9f);
    EXPECT_EQ(p.gravity, glm::vec3(0.0f));
    EXPECT_EQ(p.rest_stiffness, 0.3f);
    EXPECT_EQ(p.iterations, rods::SolverParams{}.iterations);
}

// A mirrored chain is the mirror image across its joint's X = 0 plane: x negated in its
// offset, shapes and view directions, and each rotation R turned into M R M.
TEST(CharacterScene, MirrorReflectsTheChain) {
    json doc = valid_character_scene();
    chain0(doc)["offset"] = {{"position", {0.05, 0.1, 0.02}}, {"rotation", {{"axis", {0, 0, 1}}, {"angle_deg", 20}}}};
    chain0(doc)["views"][0]["direction"] = {1, 0, 1};
    const auto loaded = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const kodawari::ChainSpec& a = loaded.value().characters[0].chains[0];
    const kodawari::ChainSpec& b = loaded.value().characters[0].chains[1];
    EXPECT_EQ(b.offset.position, glm::vec3(-0.05f, 0.1f, 0.02f));
    // The mirrored offset rotates the other way about Z: x' = M R M x.
    const glm::vec3 v(0.3f, 0.7f, -0.2f);
    const glm::vec3 m(-1.0f, 1.0f, 1.0f);
    EXPECT_LT(glm::length(b.offset.rotation * v - m * (a.offset.rotation * (m * v))), 1e-6f);
    for (std::size_t i = 0; i < a.base.positions.size(); ++i) {
        EXPECT_EQ(b.base.positions[i], m * a.base.positions[i]);
        EXPECT_LT(glm::length(b.base.orientations[i] * v - m * (a.base.orientations[i] * (m * v))), 1e-6f);
    }
    EXPECT_EQ(b.views[0].view.direction, m * a.views[0].view.direction);
}

// Joints may be listed in any order; they come out parents first.
TEST(CharacterScene, SkeletonIsOrderedParentsFirst) {
    json doc = valid_character_scene();
    doc["characters"][0]["skeleton"] = json::parse(R"([
        {"name": "head", "parent": "neck", "position": [0, 0.1, 0]},
        {"name": "neck", "parent": "body", "position": [0, 0.5, 0]},
        {"name": "body", "position": [0, 1, 0]}
    ])");
    const auto loaded = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const rods::Skeleton& sk = loaded.value().characters[0].skeleton;
    ASSERT_EQ(sk.joints.size(), 3u);
    EXPECT_EQ(sk.joints[0].name, "body");
    EXPECT_EQ(sk.joints[1].name, "neck");
    EXPECT_EQ(sk.joints[2].name, "head");
    EXPECT_EQ(sk.joints[0].parent, -1);
    EXPECT_EQ(sk.joints[1].parent, 0);
    EXPECT_EQ(sk.joints[2].parent, 1);
    EXPECT_EQ(sk.reference, 2u);
}

TEST(CharacterScene, VersionsAndTopLevel) {
    // Version 1 scenes describe birds only, and say what to change.
    json v1 = valid_character_scene();
    v1["version"] = 1;
    EXPECT_EQ(parse_error(v1), "test.json: $.characters: needs \"version\": 2 (version 1 scenes describe birds only)");
    json v3 = valid_character_scene();
    v3["version"] = 3;
    EXPECT_EQ(parse_error(v3), "test.json: $.version: expected 1 or 2 (the versions this build reads; 2 adds characters), got 3");
    json orbit_v1 = json::parse(R"({"format": "kodawari-scene", "version": 1, "camera": {"orbit": {}}, "flocks": []})");
    EXPECT_EQ(parse_error(orbit_v1), "test.json: $.camera.orbit: needs \"version\": 2 (version 1 scenes describe birds only)");
    json neither = valid_character_scene();
    neither.erase("characters");
    EXPECT_EQ(parse_error(neither), "test.json: $: expected \"flocks\", \"characters\" or both, got neither");
    json crowds_alone = neither;
    crowds_alone["flocks"] = json::parse(R"([{"wing_type": "gull", "count": 1, "generated_route": {}}])");
    crowds_alone["crowds"] = json::array();
    EXPECT_EQ(parse_error(crowds_alone), "test.json: $.crowds: needs \"characters\" (a crowd is made of a scene's characters)");
    json empty = valid_character_scene();
    empty["characters"] = json::array();
    EXPECT_EQ(parse_error(empty), "test.json: $.characters: expected a non-empty array of characters (at most 1024), got an empty array");
}

TEST(CharacterScene, UnknownKeys) {
    json doc = valid_character_scene();
    doc["characters"][0]["skeletons"] = json::array();
    EXPECT_EQ(parse_error(doc),
              "test.json: $.characters[0].skeletons: unknown key (expected one of: name, skeleton, reference_joint, motions, "
              "colliders, physics, chains, wind)");
    json chain = valid_character_scene();
    chain0(chain)["stiffness"] = 0.5;
    EXPECT_EQ(parse_error(chain),
              "test.json: $.characters[0].chains[0].stiffness: unknown key (expected one of: name, joint, offset, shape, "
              "thickness, mass, physics, collide, colliders, center, mirror, views, keyed, limit)");
    // Keys depend on the motion's and the collider's type.
    json motion = valid_character_scene();
    motion["characters"][0]["motions"][1]["axis"] = {0, 1, 0};
    EXPECT_EQ(parse_error(motion),
              "test.json: $.characters[0].motions[1].axis: unknown key (expected one of: type, joint, amplitude_deg, "
              "frequency, phase_deg, sharpness, start, end, fade)");
    json stop = valid_character_scene();
    stop["characters"][0]["motions"][3]["end"] = 5;
    EXPECT_TRUE(contains(parse_error(stop), "test.json: $.characters[0].motions[3].end: unknown key (expected one of: type, "
                                            "speed, turn_rate_deg, start, stop_time,"));
    json collider = valid_character_scene();
    collider["characters"][0]["colliders"][0]["a"] = {0, 0, 0};
    EXPECT_EQ(parse_error(collider),
              "test.json: $.characters[0].colliders[0].a: unknown key (expected one of: name, type, joint, center, radius, inside)");
}

TEST(CharacterScene, BadShapes) {
    json many = valid_character_scene();
    chain0(many)["shape"]["arc"]["joints"] = 33;
    EXPECT_EQ(parse_error(many), "test.json: $.characters[0].chains[0].shape.arc.joints: expected an integer in [2, 32], got 33");
    json one = valid_character_scene();
    chain0(one)["shape"] = json::parse(R"({"positions": [[0, 0, 0]]})");
    EXPECT_EQ(parse_error(one),
              "test.json: $.characters[0].chains[0].shape.positions: expected an array of 2 to 32 joint positions [x, y, z], "
              "the first [0, 0, 0], got an array of 1 element");
    json both = valid_character_scene();
    chain0(both)["shape"]["positions"] = json::parse("[[0, 0, 0], [0, 1, 0]]");
    EXPECT_EQ(parse_error(both),
              "test.json: $.characters[0].chains[0].shape: expected exactly one of \"positions\" and \"arc\", got both");
    json origin = valid_character_scene();
    chain0(origin)["shape"] = json::parse(R"({"positions": [[0, 0.1, 0], [0, 0.2, 0]]})");
    EXPECT_EQ(parse_error(origin),
              "test.json: $.characters[0].chains[0].shape.positions[0]: expected [0, 0, 0] (joint 0 sits at the chain root; "
              "move the chain with \"offset\"), got [0, 0.1, 0]");
    json coincident = valid_character_scene();
    chain0(coincident)["shape"] = json::parse(R"({"positions": [[0, 0, 0], [0, 0.1, 0], [0, 0.1, 0]]})");
    chain0(coincident).erase("views");
    EXPECT_EQ(parse_error(coincident),
              "test.json: $.characters[0].chains[0].shape.positions[2]: expected a point at least 1e-6 m from the previous "
              "joint, got [0, 0.1, 0]");
    json quat = valid_character_scene();
    chain0(quat)["shape"] = json::parse(R"({"positions": [[0, 0, 0], [0, 0.1, 0]], "orientations": [[0, 0, 0, 1], [0, 0, 0, 2]]})");
    chain0(quat).erase("views");
    EXPECT_EQ(parse_error(quat),
              "test.json: $.characters[0].chains[0].shape.orientations[1]: expected a unit quaternion [x, y, z, w] (length "
              "within 1e-3 of 1), got [0, 0, 0, 2]");
    json count = valid_character_scene();
    chain0(count)["views"][0]["shape"]["arc"]["joints"] = 9;
    EXPECT_EQ(parse_error(count),
              "test.json: $.characters[0].chains[0].views[0].shape.arc.joints: expected 8 joints (as many as the chain's "
              "base shape), got 9");
    json parallel = valid_character_scene();
    chain0(parallel)["shape"]["arc"]["curl_deg"] = 10;
    chain0(parallel)["shape"]["arc"]["bend_axis"] = {0, 2, 0};
    EXPECT_EQ(parse_error(parallel),
              "test.json: $.characters[0].chains[0].shape.arc.bend_axis: expected a vector not parallel to \"direction\" (the "
              "arc bends about it), got [0, 2, 0]");
}

TEST(CharacterScene, BadViews) {
    json eight = valid_character_scene();
    for (int k = 0; k < 7; ++k) chain0(eight)["views"].push_back(chain0(eight)["views"][0]);
    EXPECT_EQ(parse_error(eight),
              "test.json: $.characters[0].chains[0].views: expected an array of at most 7 view examples, got an array of 8 "
              "elements");
    // Seven views leave no room for a keyed example: said so, not "at most 0 keyed examples".
    json full = valid_character_scene();
    for (int k = 0; k < 6; ++k) chain0(full)["views"].push_back(chain0(full)["views"][0]);
    chain0(full)["keyed"] = json::array({{{"key", "motion"}, {"value", 2}, {"shape", chain0(full)["views"][0]["shape"]}}});
    EXPECT_EQ(parse_error(full), "test.json: $.characters[0].chains[0].keyed: the chain's 7 view examples leave no room for a "
                                 "keyed one (at most 7 examples in all): expected an empty array, got 1");
    json zero = valid_character_scene();
    chain0(zero)["views"][0]["direction"] = {0, 0, 0};
    EXPECT_EQ(parse_error(zero),
              "test.json: $.characters[0].chains[0].views[0].direction: expected a non-zero vector [x, y, z], got [0, 0, 0]");
    json influence = valid_character_scene();
    chain0(influence)["views"][0]["influence"] = 0;
    EXPECT_EQ(parse_error(influence),
              "test.json: $.characters[0].chains[0].views[0].influence: expected a finite number in (0, 1000], got 0");
    json infinite = valid_character_scene();
    chain0(infinite)["views"][0]["influence"] = 2.5;
    std::string text = infinite.dump();
    text.replace(text.find("2.5"), 3, "1e999");
    EXPECT_EQ(error_of(kodawari::parse_scene(text, "test.json")),
              "test.json: $.characters[0].chains[0].views[0].influence: expected a finite number, got 1e999 (beyond the range "
              "of a double)");
}

TEST(CharacterScene, BadSkeletons) {
    json unknown = valid_character_scene();
    unknown["characters"][0]["skeleton"][1]["parent"] = "torso";
    EXPECT_EQ(parse_error(unknown),
              "test.json: $.characters[0].skeleton[1].parent: expected the name of another joint of this skeleton (\"body\"), "
              "got \"torso\"");
    json cycle = valid_character_scene();
    cycle["characters"][0]["skeleton"] = json::parse(R"([
        {"name": "body"}, {"name": "a", "parent": "b"}, {"name": "b", "parent": "c"}, {"name": "c", "parent": "a"}])");
    EXPECT_EQ(parse_error(cycle),
              "test.json: $.characters[0].skeleton[1].parent: expected a parent chain that reaches the root joint, got a cycle: "
              "\"a\" -> \"b\" -> \"c\" -> \"a\"");
    json roots = valid_character_scene();
    roots["characters"][0]["skeleton"][1].erase("parent");
    EXPECT_EQ(parse_error(roots),
              "test.json: $.characters[0].skeleton[1].parent: expected the name of the parent joint (a skeleton has one root, "
              "and joint 0 \"body\" already is it), got nothing (required key missing)");
    json twice = valid_character_scene();
    twice["characters"][0]["skeleton"][1]["name"] = "body";
    EXPECT_EQ(parse_error(twice),
              "test.json: $.characters[0].skeleton[1].name: expected a name no other joint has (joint 0 is also \"body\"), got "
              "\"body\"");
    json no_head = valid_character_scene();
    no_head["characters"][0]["skeleton"][1]["name"] = "skull";
    no_head["characters"][0]["chains"][0]["joint"] = "skull";
    no_head["characters"][0]["colliders"][0]["joint"] = "skull";
    EXPECT_EQ(parse_error(no_head),
              "test.json: $.characters[0].reference_joint: no joint is called \"head\" (the default reference joint); name the "
              "joint that view directions are measured in");
    json joint = valid_character_scene();
    chain0(joint)["joint"] = "tail";
    EXPECT_EQ(parse_error(joint),
              "test.json: $.characters[0].chains[0].joint: expected the name of a joint of this character's skeleton "
              "(\"body\", \"head\"), got \"tail\"");
    json separator = valid_character_scene();
    chain0(separator)["name"] = "ear/left";
    EXPECT_EQ(parse_error(separator),
              "test.json: $.characters[0].chains[0].name: expected a non-empty name without '#' or '/', got \"ear/left\"");
    json taken = valid_character_scene();
    chain0(taken)["mirror"] = "ear";
    EXPECT_EQ(parse_error(taken), "test.json: $.characters[0].chains[0].mirror: expected a name other than the chain's own, got \"ear\"");
    json clash = valid_character_scene();
    chain0(clash)["name"] = "ear_r";
    chain0(clash)["mirror"] = "ear_l";
    clash["characters"][0]["chains"].push_back(chain0(clash));
    EXPECT_EQ(parse_error(clash),
              "test.json: $.characters[0].chains[1].name: expected a chain name this character does not use yet (\"ear_r\" is "
              "taken), got \"ear_r\"");
}

TEST(CharacterScene, BadPhysicsAndMotions) {
    json stiff = valid_character_scene();
    chain0(stiff)["physics"] = {{"stiffness", 1.5}};
    EXPECT_EQ(parse_error(stiff),
              "test.json: $.characters[0].chains[0].physics.stiffness: expected a finite number in [0, 1], got 1.5");
    json iterations = valid_character_scene();
    iterations["characters"][0]["physics"] = {{"iterations", 0}};
    EXPECT_EQ(parse_error(iterations),
              "test.json: $.characters[0].physics.iterations: expected an integer in [1, 64], got 0");
    json substep = valid_character_scene();
    chain0(substep)["physics"] = {{"max_substep", 0.1}};
    EXPECT_EQ(parse_error(substep),
              "test.json: $.characters[0].chains[0].physics.max_substep: expected a finite number in (0, 0.05], got 0.1");
    json thickness = valid_character_scene();
    chain0(thickness)["thickness"] = -0.01;
    EXPECT_EQ(parse_error(thickness),
              "test.json: $.characters[0].chains[0].thickness: expected a finite number in [1e-05, 1], got -0.01");
    // Issue 39: at most half the shortest segment (8 joints over 0.2 m: 0.0286 m segments).
    json overlapping = valid_character_scene();
    chain0(overlapping)["thickness"] = 0.02;
    EXPECT_EQ(parse_error(overlapping),
              "test.json: $.characters[0].chains[0].thickness: thickness 0.020000 m is more than half the chain's shortest "
              "segment (0.028571 m); at most 0.014286 m");
    chain0(overlapping)["thickness"] = 0.014;
    EXPECT_TRUE(kodawari::parse_scene(overlapping.dump(), "test.json").ok());
    // Issue 39: no root inside a collider (the ear's root sits on the head sphere's top).
    json buried = valid_character_scene();
    chain0(buried)["offset"] = {{"position", {0, 0.05, 0}}};
    EXPECT_EQ(parse_error(buried), "test.json: $.characters[0].chains[0]: the chain's root is 0.050000 m inside collider 0 in "
                                   "the rest pose; move the root onto or outside its surface");
    chain0(buried)["collide"] = false;
    EXPECT_TRUE(kodawari::parse_scene(buried.dump(), "test.json").ok());
    json end = valid_character_scene();
    end["characters"][0]["motions"][0]["start"] = 2;
    end["characters"][0]["motions"][0]["end"] = 1;
    EXPECT_EQ(parse_error(end),
              "test.json: $.characters[0].motions[0].end: expected a finite number in (2, 100000], got 1");
    json stop = valid_character_scene();
    stop["characters"][0]["motions"][3].erase("stop_time");
    EXPECT_EQ(parse_error(stop),
              "test.json: $.characters[0].motions[3].stop_time: expected a finite number in (3, 100000], got nothing "
              "(required key missing)");
    json ramps = valid_character_scene();
    ramps["characters"][0]["motions"][2]["ramp_out"] = 1.8;
    EXPECT_EQ(parse_error(ramps),
              "test.json: $.characters[0].motions[2].ramp_out: expected ramps with ramp_in + ramp_out <= end - start (2 s), "
              "got 1.8");
    json type = valid_character_scene();
    type["characters"][0]["motions"][0]["type"] = "dance";
    EXPECT_EQ(parse_error(type),
              "test.json: $.characters[0].motions[0].type: expected one of \"sway\", \"head_turn\", \"walk\", \"stop\", got "
              "\"dance\"");
    json nan = valid_character_scene();
    nan["characters"][0]["motions"][0]["frequency"] = "NaN";
    EXPECT_EQ(parse_error(nan), "test.json: $.characters[0].motions[0].frequency: expected a finite number in [0, 100], got \"NaN\"");
    // A character may have 256 colliders, a chain touch 16: one without a `colliders`
    // list takes all of them, which is an error at the chain past 16.
    json many = valid_character_scene();
    for (int k = 0; k < 16; ++k) many["characters"][0]["colliders"].push_back(many["characters"][0]["colliders"][0]);
    EXPECT_EQ(parse_error(many),
              "test.json: $.characters[0].chains[0]: collides with all 17 colliders of its character, and one chain may "
              "touch at most 16; give it a \"colliders\" list of collider names");
    json too_many = valid_character_scene();
    for (int k = 0; k < 256; ++k) too_many["characters"][0]["colliders"].push_back(too_many["characters"][0]["colliders"][0]);
    EXPECT_EQ(parse_error(too_many),
              "test.json: $.characters[0].colliders: expected an array of colliders (at most 256), got an array of 257 elements");
    json listed = many;
    listed["characters"][0]["colliders"][16]["name"] = "last";
    for (json& c : listed["characters"][0]["chains"]) c["colliders"] = json::array({"last"});
    EXPECT_EQ(parse_error(listed), "(no error)");
    json collider = valid_character_scene();
    collider["characters"][0]["colliders"][0]["radius"] = 0;
    EXPECT_EQ(parse_error(collider),
              "test.json: $.characters[0].colliders[0].radius: expected a finite number in (0, 1000], got 0");
}

TEST(CharacterScene, BadCrowds) {
    json unknown = valid_character_scene();
    unknown["crowds"] = json::parse(R"([{"character": "cat", "count": 4}])");
    EXPECT_EQ(parse_error(unknown), "test.json: $.crowds[0].character: expected the name of a character of this scene (\"bunny\"), got \"cat\"");
    json none = valid_character_scene();
    none["crowds"] = json::parse(R"([{"character": "bunny"}])");
    EXPECT_EQ(parse_error(none), "test.json: $.crowds[0]: expected \"count\" >= 1 or a non-empty \"instances\", got no instances");
    json columns = valid_character_scene();
    columns["crowds"] = json::parse(R"([{"character": "bunny", "count": 4, "layout": "ring", "columns": 2}])");
    EXPECT_EQ(parse_error(columns), "test.json: $.crowds[0].columns: only used by \"layout\": \"grid\"");
    json many = valid_character_scene();
    many["crowds"] = json::parse(R"([{"character": "bunny", "count": 60000}, {"character": "bunny", "count": 50000}])");
    EXPECT_EQ(parse_error(many),
              "test.json: $.crowds[1]: too many instances: a scene holds at most 100000 characters and 1000000 chains in all");
    json offset = valid_character_scene();
    offset["crowds"] = json::parse(R"([{"character": "bunny", "instances": [{"position": [0, 0, 0], "time_offset": -1}]}])");
    EXPECT_EQ(parse_error(offset),
              "test.json: $.crowds[0].instances[0].time_offset: expected a finite number in [0, 3600], got -1");
}

TEST(CharacterScene, BadCameras) {
    json both = valid_character_scene();
    both["camera"] = json::parse(R"({"orbit": {"target": [0, 1, 0], "radius": 2}, "path": {}})");
    EXPECT_EQ(parse_error(both),
              "test.json: $.camera.path: expected at most one of \"orbit\", \"path\" and \"keyframes\", got \"orbit\" and "
              "\"path\"");
    json position = valid_character_scene();
    position["camera"] = json::parse(R"({"position": [0, 1, 5], "orbit": {"target": [0, 1, 0], "radius": 2}})");
    EXPECT_EQ(parse_error(position), "test.json: $.camera.position: not used with \"orbit\" (it places and aims the camera itself)");
    json radius = valid_character_scene();
    radius["camera"] = json::parse(R"({"orbit": {"target": [0, 1, 0], "radius": 0}})");
    EXPECT_EQ(parse_error(radius), "test.json: $.camera.orbit.radius: expected a finite number in (0, 500000], got 0");
    json rate = valid_character_scene();
    rate["camera"] = json::parse(R"({"orbit": {"target": [0, 1, 0], "radius": 2, "period": 5, "degrees_per_second": 10}})");
    EXPECT_EQ(parse_error(rate),
              "test.json: $.camera.orbit.period: expected at most one of \"degrees_per_second\" and \"period\", got both");
    json keys = valid_character_scene();
    keys["camera"] = json::parse(R"({"keyframes": {"keys": [
        {"time": 0, "position": [0, 1, 3], "target": [0, 1, 0]},
        {"time": 0, "position": [1, 1, 3], "target": [0, 1, 0]}]}})");
    EXPECT_EQ(parse_error(keys),
              "test.json: $.camera.keyframes.keys[1].time: expected a time after the previous key's (0 s), got 0");
    json looking = valid_character_scene();
    looking["camera"] = json::parse(R"({"path": {"points": [[0, 1, 3], [0, 1, 0]], "target": [0, 1, 0]}})");
    EXPECT_EQ(parse_error(looking),
              "test.json: $.camera.path.points[1]: expected a point other than the path's target (the camera needs a "
              "direction), got [0, 1, 0]");
    json interpolation = valid_character_scene();
    interpolation["camera"] = json::parse(R"({"path": {"points": [[0, 1, 3], [1, 1, 3]], "target": [0, 1, 0], "interpolation": "cubic"}})");
    EXPECT_EQ(parse_error(interpolation),
              "test.json: $.camera.path.interpolation: expected one of \"catmull-rom\", \"linear\", got \"cubic\"");
}

// Every JSON example in docs/scene-format.md loads (and builds, where it has characters).
TEST(CharacterScene, DocumentationExamplesLoad) {
    std::FILE* file = std::fopen(source_path("docs/scene-format.md").c_str(), "rb");
    ASSERT_NE(file, nullptr);
    std::string text;
    std::array<char, 4096> buffer{};
    for (std::size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), file)) > 0;) text.append(buffer.data(), n);
    std::fclose(file);
    int examples = 0;
    for (std::size_t at = text.find("```json\n"); at != std::string::npos; at = text.find("```json\n", at)) {
        at += 8;
        const std::size_t end = text.find("```", at);
        ASSERT_NE(end, std::string::npos);
        const auto scene = kodawari::parse_scene(text.substr(at, end - at), "docs/scene-format.md");
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        if (!scene.value().characters.empty()) {
            EXPECT_TRUE(kodawari::build_rod_scene(scene.value()).ok());
        }
        ++examples;
    }
    EXPECT_GE(examples, 2);
}

// Bird scenes still load as they did, and a scene may hold birds and characters.
TEST(CharacterScene, BirdScenesAndMixedScenes) {
    const Scene flock = load("scenes/flock.json");
    EXPECT_EQ(flock.version, 1u);
    EXPECT_TRUE(flock.characters.empty());
    const auto empty = kodawari::build_rod_scene(flock);
    ASSERT_TRUE(empty.ok()) << empty.error().message;
    EXPECT_TRUE(empty.value().world.chains.empty());
    json mixed = valid_character_scene();
    mixed["flocks"] = json::parse(R"([{"wing_type": "gull", "count": 3, "generated_route": {"seed": 2}}])");
    const auto scene = kodawari::parse_scene(mixed.dump(), "test.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    EXPECT_EQ(scene.value().flocks.size(), 1u);
    EXPECT_EQ(scene.value().characters.size(), 1u);
    const auto birds = kodawari::build_bird_world(scene.value());
    ASSERT_TRUE(birds.ok()) << birds.error().message;
    EXPECT_EQ(birds.value().birds.size(), 3u);
}
