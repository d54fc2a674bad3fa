// Rigged characters in scenes (issue 4, SPEC A.7): the scene format's `gltf` characters,
// crowds of them with clips and time offsets, the per-frame kinematic input they give
// the rod backends, a simulation of the project's own character, and `kodawari rig`'s
// scene writer on every shipped sample.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/vulkan/compute.hpp"
#include "kodawari/vulkan/crowd_animator.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/gltf/import.hpp"
#include "kodawari/gltf/rig_scene.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/scene/scene.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

using testing_support::gltf_validator_command;
using testing_support::run_command;
using testing_support::shell_quote;
using testing_support::TempDir;

const std::string kSource = KODAWARI_SOURCE_DIR;
const std::string kChibi = kSource + "/scenes/characters/chibi.glb";
const std::string kCrowdScene = kSource + "/scenes/crowd-gltf.json";

// The two runs the device-input tests compare, on one shared device with validation: the
// vulkan rod backend fed by a CrowdAnimator on the host (`host`), and one whose rigged
// input the animator writes on the device (`on_device`), both loaded at frame 0.
struct HostAndDeviceInput {
    struct Run {
        std::unique_ptr<RodBackend> rods;
        std::optional<CrowdAnimator> animator;
        rods::RodFrame frame;
    };
    std::shared_ptr<compute::Device> device;
    BackendOptions options;
    Run host, on_device;

    void start(const RodScene& scene) {
        options.validation = true;
        auto opened = open_shared_device(options);
        ASSERT_TRUE(opened.ok()) << opened.error().message;
        device = opened.value();
        options.context = device;
        for (Run* run : {&host, &on_device}) {
            auto backend = make_rod_backend(BackendKind::Vulkan, options);
            ASSERT_TRUE(backend.ok()) << backend.error().message;
            run->rods = std::move(backend).value();
            auto animator = CrowdAnimator::create(scene, BackendKind::Vulkan, options);
            ASSERT_TRUE(animator.ok()) << animator.error().message;
            run->animator.emplace(std::move(animator).value());
            ASSERT_TRUE(run->animator->frame(0, run->frame).ok());
            ASSERT_TRUE(run->rods->load(scene.world, run->frame).ok());
        }
        auto took = on_device.animator->write_inputs_on(*on_device.rods);
        ASSERT_TRUE(took.ok()) << took.error().message;
        ASSERT_TRUE(took.value()) << "the pose and rod backends share the device";
    }

    // The largest distance between a chain joint of one run and the same joint of the other (m).
    float joint_distance(const RodScene& scene) const {
        std::vector<rods::ChainState> a, b;
        EXPECT_TRUE(host.rods->read_states(a).ok());
        EXPECT_TRUE(on_device.rods->read_states(b).ok());
        EXPECT_EQ(a.size(), b.size());
        float worst = 0.0f;
        for (std::size_t c = 0; c < std::min(a.size(), b.size()); ++c) {
            const std::uint32_t n = scene.world.templ(scene.world.chains[c]).chain.joint_count;
            for (std::uint32_t i = 0; i < n; ++i) {
                worst = std::max(worst, glm::length((a[c].root.position + a[c].x[i]) - (b[c].root.position + b[c].x[i])));
            }
        }
        return worst;
    }
};

Scene load(const std::string& path) {
    auto scene = load_scene(path);
    EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error().message);
    return std::move(scene).value();
}

RodScene build(const Scene& scene) {
    auto built = build_rod_scene(scene);
    EXPECT_TRUE(built.ok()) << (built.ok() ? "" : built.error().message);
    return std::move(built).value();
}

// A scene text with one chibi character (its `gltf` path absolute) and `crowd` as the
// crowds array; `character_extra` is spliced into the character object.
std::string chibi_scene(const std::string& chains, const std::string& crowd = "", const std::string& character_extra = "") {
    return std::string(R"({"format": "kodawari-scene", "version": 2, "fps": 60, "duration": 1,
      "camera": {"position": [0, 1, 3], "target": [0, 1, 0]},
      "characters": [{"name": "chibi", "gltf": ")") +
           kChibi + R"(", )" + character_extra + R"("chains": )" + chains + "}]" +
           (crowd.empty() ? "" : ", \"crowds\": " + crowd) + "}";
}

std::string error_of(const std::string& text) {
    auto scene = parse_scene(text, "test.json");
    return scene.ok() ? std::string("(loaded)") : scene.error().message;
}

int node_named(const animation::Character& ch, const std::string& name) {
    for (std::size_t i = 0; i < ch.nodes.size(); ++i) {
        if (ch.nodes[i].name == name) return static_cast<int>(i);
    }
    ADD_FAILURE() << "no node " << name;
    return 0;
}

float max_difference(glm::vec3 a, glm::vec3 b) { return glm::length(a - b); }

TEST(RiggedScene, ShippedCrowdLoadsWithClipsAndOffsets) {
    const Scene scene = load(kCrowdScene);
    ASSERT_EQ(scene.characters.size(), 1u);
    ASSERT_TRUE(scene.characters[0].rig.has_value());
    const RodScene rods = build(scene);
    EXPECT_EQ(rods.instances.size(), 64u);
    EXPECT_EQ(rods.world.chains.size(), 64u * 7u);
    // The crowd picks from three clips: each must be played by someone, and the time
    // offsets must differ (a crowd that moves in lockstep would be a bug).
    std::set<std::int32_t> clips;
    std::set<float> offsets;
    for (const CharacterInstance& inst : rods.instances) {
        clips.insert(inst.clip);
        offsets.insert(inst.time_offset);
    }
    EXPECT_EQ(clips, (std::set<std::int32_t>{0, 1, 2}));
    EXPECT_GT(offsets.size(), 60u);
}

// The per-frame input of a rigged instance, recomputed here from animation::evaluate with the
// placement written out as translate * rotate-about-Y: reference joint, chain roots and
// the head collider, at frames where the clip time wraps.
TEST(RiggedScene, FrameInputFollowsTheClipAtTheInstanceTime) {
    const std::string chains = R"([{"name": "tail", "root": "tail_0"}, {"name": "bang", "root": "bang_C_0", "joints": 3}])";
    const std::string crowd = R"([{"character": "chibi", "instances": [
        {"position": [2, 0, -1], "yaw_deg": 90, "time_offset": 2.5, "animation": "walk"},
        {"position": [0, 0, 0], "animation": "turn"}]}])";
    const std::string colliders = R"("colliders": [{"type": "sphere", "joint": "head", "center": [0, 0.17, 0], "radius": 0.19}], )";
    auto parsed = parse_scene(chibi_scene(chains, crowd, colliders), "test.json");
    ASSERT_TRUE(parsed.ok()) << parsed.error().message;
    const RodScene rods = build(parsed.value());
    const animation::Character& ch = *rods.characters[0].rig;
    ASSERT_EQ(rods.world.chains.size(), 4u);
    EXPECT_EQ(rods.world.templ(rods.world.chains[0]).chain.joint_count, 8u);  // tail_0..tail_7, to the leaf
    EXPECT_EQ(rods.world.templ(rods.world.chains[1]).chain.joint_count, 3u);  // "joints": 3

    const int head = node_named(ch, "head");
    const int tail = node_named(ch, "tail_0");
    const int bang = node_named(ch, "bang_C_0");
    animation::Pose pose;
    for (const std::uint32_t frame : {0u, 37u, 59u}) {
        const rods::RodFrame input = rods.frame(frame);
        for (std::uint32_t c = 0; c < 2; ++c) {
            const CharacterInstance& inst = rods.instances[c];
            const animation::Animation& clip = ch.animations[static_cast<std::size_t>(inst.clip)];
            // Looping: the clip time is the instance time modulo the clip's length.
            const double t = static_cast<double>(frame) / 60.0 + static_cast<double>(inst.time_offset);
            const double d = static_cast<double>(clip.end - clip.start);
            const auto clip_t = static_cast<float>(static_cast<double>(clip.start) + std::fmod(t - static_cast<double>(clip.start), d));
            EXPECT_NEAR(rods.clip_time(c, frame), clip_t, 1e-5f);
            animation::evaluate(ch, static_cast<std::size_t>(inst.clip), clip_t, pose);
            const glm::mat4 placement = glm::rotate(glm::translate(glm::mat4(1.0f), inst.placement.position),
                                                    c == 0 ? glm::radians(90.0f) : 0.0f, glm::vec3(0, 1, 0));
            const auto world_of = [&](int node) { return animation::rigid_part(placement * pose.world[static_cast<std::size_t>(node)]); };
            // 1e-5 m: float matrices of a 1.2 m character, composed a few times.
            EXPECT_LT(max_difference(input.reference[c].position, world_of(head).position), 1e-5f) << "frame " << frame;
            EXPECT_LT(max_difference(input.roots[2 * c].position, world_of(tail).position), 1e-5f);
            EXPECT_LT(max_difference(input.roots[2 * c + 1].position, world_of(bang).position), 1e-5f);
            EXPECT_GT(std::abs(glm::dot(input.roots[2 * c].rotation, world_of(tail).rotation)), 1.0f - 1e-6f);
            const rods::Transform h = world_of(head);
            const glm::vec3 centre = h.position + h.rotation * glm::vec3(0, 0.17f, 0);
            EXPECT_LT(max_difference(input.colliders[c].a, centre), 1e-5f);
            EXPECT_FLOAT_EQ(input.colliders[c].radius, 0.19f);
        }
    }
    // Deterministic: the same frame gives the same bits.
    const rods::RodFrame a = rods.frame(37);
    const rods::RodFrame b = rods.frame(37);
    ASSERT_EQ(a.roots.size(), b.roots.size());
    for (std::size_t i = 0; i < a.roots.size(); ++i) {
        EXPECT_EQ(a.roots[i].position, b.roots[i].position);
        EXPECT_EQ(a.roots[i].rotation, b.roots[i].rotation);
    }
}

// The base shape is the rest pose in the root's frame: its joints' world positions.
TEST(RiggedScene, BaseShapeIsTheRestPose) {
    auto parsed = parse_scene(chibi_scene(R"([{"name": "tail", "nodes": ["tail_0", "tail_1", "tail_2", "tail_3"]}])", "",
                                          R"("animate": false, )"),
                              "test.json");
    ASSERT_TRUE(parsed.ok()) << parsed.error().message;
    const RodScene rods = build(parsed.value());
    const animation::Character& ch = *rods.characters[0].rig;
    EXPECT_EQ(rods.instances[0].clip, -1);
    const rods::RestShape rest = rods::rest_shape(rods.world, 0, rods.frame(0));
    const animation::Pose pose = animation::rest_pose(ch);
    const rods::Transform root = animation::rigid_part(pose.world[static_cast<std::size_t>(node_named(ch, "tail_0"))]);
    for (int i = 0; i < 4; ++i) {
        const glm::vec3 world = glm::vec3(pose.world[static_cast<std::size_t>(node_named(ch, "tail_" + std::to_string(i)))][3]);
        EXPECT_LT(max_difference(root.position + root.rotation * rest.shape.positions[static_cast<std::size_t>(i)], world), 1e-5f)
            << "joint " << i;
    }
}

TEST(RiggedScene, BadInputNamesTheFileAndPath) {
    const std::string tail = R"([{"name": "tail", "root": "tail_0"}])";
    EXPECT_NE(error_of(chibi_scene(R"([{"name": "x", "root": "no_such_node"}])")).find("$.characters[0].chains[0].root"),
              std::string::npos);
    EXPECT_NE(error_of(chibi_scene(R"([{"name": "x", "nodes": ["tail_0", "tail_2"]}])")).find("a child of the node before it"),
              std::string::npos);
    EXPECT_NE(error_of(chibi_scene(R"([{"name": "x", "root": "tail_0", "joints": 9}])")).find("has 8 single-child joint(s)"),
              std::string::npos);
    EXPECT_NE(error_of(chibi_scene(R"([{"name": "a", "root": "tail_0"}, {"name": "b", "root": "tail_3"}])"))
                  .find("already simulated by chain \"a\""),
              std::string::npos);
    EXPECT_NE(error_of(chibi_scene(R"([{"name": "x", "root": "tail_0", "nodes": ["tail_0", "tail_1"]}])"))
                  .find("exactly one of \"root\" and \"nodes\""),
              std::string::npos);
    EXPECT_NE(error_of(chibi_scene(tail, "", R"("animation": "dance", )")).find("\"idle\", \"walk\", \"turn\""),
              std::string::npos);
    EXPECT_NE(error_of(chibi_scene(tail, "", R"("animate": false, "animation": "walk", )")).find("\"animate\": false"),
              std::string::npos);
    EXPECT_NE(error_of(chibi_scene(tail, "", R"("skeleton": [], )")).find("unknown key"), std::string::npos);
    EXPECT_NE(error_of(chibi_scene(tail, R"([{"character": "chibi", "count": 2, "animations": ["run"]}])"))
                  .find("$.crowds[0].animations[0]"),
              std::string::npos);
    // A missing file is bad input (issue 37: exit 2) that names the scene, the key and the file.
    std::string text = chibi_scene(tail);
    text.replace(text.find("chibi.glb"), 9, "missing.glb");
    auto missing = parse_scene(text, "test.json");
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(missing.error().message.find("test.json: $.characters[0].gltf"), std::string::npos) << missing.error().message;
    EXPECT_NE(missing.error().message.find("missing.glb"), std::string::npos);
    // Clips belong to rigged characters only.
    const std::string procedural = R"({"format": "kodawari-scene", "version": 2,
      "characters": [{"name": "b", "skeleton": [{"name": "head"}],
        "chains": [{"name": "c", "joint": "head", "shape": {"arc": {"joints": 3, "length": 0.2}}}]}],
      "crowds": [{"character": "b", "count": 1, "animations": ["walk"]}]})";
    EXPECT_NE(error_of(procedural).find("only rigged characters"), std::string::npos) << error_of(procedural);
}

// Where node names repeat (issue 18: exporters other than VRoid reuse names), the scene
// names a node by its path from a root or by its index; the repeated name alone is an
// error that says so. Built on three-vrm's sphere sample with "Spring B" renamed to
// "Spring A" (node 1, the child of node 0).
TEST(RiggedScene, NodesByPathOrIndexWhereNamesRepeat) {
    TempDir dir;
    std::ifstream in(kSource + "/tests/assets/vrm-springbone/sphere-collider.gltf");
    nlohmann::json doc = nlohmann::json::parse(in);
    doc["nodes"][1]["name"] = "Spring A";
    std::ofstream(dir.file("twins.gltf")) << doc.dump();
    std::filesystem::copy_file(kSource + "/tests/assets/vrm-springbone/sphere_mesh.bin", dir.file("sphere_mesh.bin"));
    const auto scene_with = [&](const std::string& chain) {
        return R"({"format": "kodawari-scene", "version": 2, "fps": 60, "duration": 1,
          "camera": {"position": [0, 1, 3], "target": [0, 1, 0]},
          "characters": [{"name": "s", "gltf": ")" + dir.file("twins.gltf") + R"(", "reference_joint": 5,
            "colliders": [{"name": "ball", "type": "sphere", "joint": "Collider", "radius": 0.5}],
            "chains": [)" + chain + "]}]}";
    };
    const std::string twice = error_of(scene_with(R"({"name": "c", "root": "Spring A"})"));
    EXPECT_NE(twice.find("\"Spring A\" names 2 nodes"), std::string::npos) << twice;
    EXPECT_NE(twice.find("by its index or by its path"), std::string::npos) << twice;
    EXPECT_NE(twice.find("$.characters[0].chains[0].root"), std::string::npos) << twice;
    for (const std::string& root : {std::string(R"("Spring A/Spring A")"), std::string("1")}) {
        SCOPED_TRACE(root);
        auto parsed = parse_scene(scene_with(R"({"name": "c", "root": )" + root + R"(, "colliders": ["ball"], "center": 0})"), "t.json");
        ASSERT_TRUE(parsed.ok()) << parsed.error().message;
        const ChainSpec& chain = parsed.value().characters[0].chains[0];
        EXPECT_EQ(chain.nodes, (std::vector<int>{1, 2, 3, 4}));
        EXPECT_EQ(chain.center, 0);
        EXPECT_EQ(chain.colliders, (std::vector<std::uint32_t>{0}));
        EXPECT_EQ(parsed.value().characters[0].skeleton.reference, 5u);
    }
    // A path step that is not there, an index past the last node, a collider name that is not there.
    EXPECT_NE(error_of(scene_with(R"({"name": "c", "root": "Spring A/Spring C"})")).find("path step \"Spring C\""), std::string::npos);
    EXPECT_NE(error_of(scene_with(R"({"name": "c", "root": 6})")).find("$.characters[0].chains[0].root"), std::string::npos);
    const std::string unknown = error_of(scene_with(R"({"name": "c", "root": 1, "colliders": ["bal"]})"));
    EXPECT_NE(unknown.find("$.characters[0].chains[0].colliders[0]"), std::string::npos) << unknown;
    EXPECT_NE(unknown.find("\"ball\""), std::string::npos) << unknown;
}

// The project's own character simulated for 4 s walking and turning: the strands keep
// their lengths, stay out of the head, and swing.
TEST(RiggedScene, ChibiSimulatesOnTheCpu) {
    const Scene scene = load(kCrowdScene);
    Scene small = scene;
    small.crowds[0].count = 3;
    small.crowds[0].clips = {1, 2, 1};
    const RodScene rods = build(small);
    auto backend = make_rod_backend(BackendKind::Cpu, BackendOptions{});
    ASSERT_TRUE(backend.ok());
    ASSERT_TRUE(backend.value()->load(rods.world, rods.frame(0)).ok());
    ChainSnapshot snap;
    float worst_stretch = 0.0f;
    float worst_depth = 0.0f;
    float lag = 0.0f;  // tip's distance from where the rest shape puts it, in chain lengths
    for (std::uint32_t f = 1; f <= 240; ++f) {
        const rods::RodFrame input = rods.frame(f);
        ASSERT_TRUE(backend.value()->step(input).ok());
        ASSERT_TRUE(backend.value()->read(snap).ok());
        for (std::size_t c = 0; c < rods.world.chains.size(); ++c) {
            const rods::ChainInstance& ci = rods.world.chains[c];
            const rods::Chain& chain = rods.world.templ(ci).chain;
            for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) {
                const float length = glm::length(snap.positions[ci.joint_begin + i + 1] - snap.positions[ci.joint_begin + i]);
                ASSERT_TRUE(std::isfinite(length));
                worst_stretch = std::max(worst_stretch, std::abs(length / chain.segment_length[i] - 1.0f));
            }
            for (std::uint32_t i = 1; i < chain.joint_count; ++i) {
                const rods::Collider& head = input.colliders[ci.collider_begin];
                const float depth = head.radius + chain.thickness - glm::length(snap.positions[ci.joint_begin + i] - head.a);
                worst_depth = std::max(worst_depth, depth);
            }
            const std::uint32_t t = ci.joint_begin + chain.joint_count - 1;
            float length = 0.0f;
            for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) length += chain.segment_length[i];
            lag = std::max(lag, glm::length(snap.positions[t] - snap.rest[t]) / length);
        }
    }
    RecordProperty("worst_stretch", std::to_string(worst_stretch));
    RecordProperty("worst_depth_m", std::to_string(worst_depth));
    std::printf("chibi x3, 240 frames: worst stretch %.3g, deepest contact %.3g m, largest tip lag %.3g L\n",
                static_cast<double>(worst_stretch), static_cast<double>(worst_depth), static_cast<double>(lag));
    // Collisions are projected last (rods/solver.hpp), so a strand pressed into the head
    // may stretch by a few percent; 5% of a segment is the bound the rods tests measured.
    EXPECT_LT(worst_stretch, 0.05f);
    // Colliders are the last projection: joints end each step outside, up to float error.
    EXPECT_LT(worst_depth, 1e-4f);
    // Secondary motion: the tips swing off the rest shape the animation carries (a
    // strand glued to its rest shape would give 0), but stay near it (no blow-up).
    EXPECT_GT(lag, 0.02f);
    EXPECT_LT(lag, 0.5f);
}

// `kodawari rig`'s scene writer on the project's character and every shipped sample:
// each written scene loads and builds.
TEST(RiggedScene, RigWritesScenesThatLoad) {
    TempDir dir;
    struct Case {
        std::string file;
        std::optional<gltf::ChainSearch> search;
        std::size_t chains;
        std::uint32_t colliders;
        std::string source;
    };
    gltf::ChainSearch bone;
    bone.roots = {"Bone"};
    const std::vector<Case> cases = {
        {kChibi, std::nullopt, 7, 0, "name patterns"},
        {kSource + "/tests/assets/vrm-springbone/sphere-collider.gltf", std::nullopt, 1, 1, "VRM 1.0 spring bones"},
        {kSource + "/tests/assets/vrm-springbone/inside-collider.gltf", std::nullopt, 1, 1, "VRM 1.0 spring bones"},
        {kSource + "/tests/assets/vrm-springbone/plane-collider.gltf", std::nullopt, 1, 1, "VRM 1.0 spring bones"},
        {kSource + "/tests/assets/khronos/RiggedSimple.gltf", bone, 1, 0, "named roots"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.file);
        gltf::RigOptions options;
        options.search = c.search;
        const std::string out = dir.file("scene.json");
        auto rig = gltf::make_rig_scene(c.file, out, options);
        ASSERT_TRUE(rig.ok()) << rig.error().message;
        EXPECT_EQ(rig.value().chains.size(), c.chains);
        EXPECT_EQ(rig.value().colliders, c.colliders);
        EXPECT_EQ(rig.value().source, c.source);
        std::ofstream(out) << rig.value().json;
        const Scene scene = load(out);
        const RodScene rods = build(scene);
        EXPECT_EQ(rods.world.chains.size(), c.chains);
        EXPECT_EQ(rods.world.collider_count, c.colliders);
        if (c.source == "VRM 1.0 spring bones") {
            // The mapping's parameters reach the scene whole: shape matching off (vrm.hpp),
            // not the loader's default 0.5 that a scene without `stiffness` gets.
            for (const auto& t : rods.world.templates) EXPECT_EQ(t.params.stiffness, 0.0f);
        }
    }
    // The extended colliders replace their fallback shapes (the plane's is a sphere 10 km
    // away): a plane through the collider node with its normal, and an inside sphere, both
    // without warnings about colliders. The collider node "Collider" is at (0, 1, 0); in
    // the inside sample it is scaled by 1.35, which scales the radius (as UniVRM does).
    auto plane = gltf::make_rig_scene(kSource + "/tests/assets/vrm-springbone/plane-collider.gltf", dir.file("p.json"), {});
    ASSERT_TRUE(plane.ok()) << plane.error().message;
    for (const std::string& w : plane.value().warnings) EXPECT_EQ(w.find("collider 0"), std::string::npos) << w;
    const auto plane_json = nlohmann::json::parse(plane.value().json)["characters"][0]["colliders"][0];
    EXPECT_EQ(plane_json["type"], "plane");
    EXPECT_EQ(plane_json["normal"], nlohmann::json::array({0, 0, 1}));
    EXPECT_EQ(plane_json["point"], nlohmann::json::array({0, 0, 0}));
    auto inside = gltf::make_rig_scene(kSource + "/tests/assets/vrm-springbone/inside-collider.gltf", dir.file("i.json"), {});
    ASSERT_TRUE(inside.ok()) << inside.error().message;
    const auto inside_json = nlohmann::json::parse(inside.value().json)["characters"][0]["colliders"][0];
    EXPECT_EQ(inside_json["type"], "sphere");
    EXPECT_EQ(inside_json["inside"], true);
    EXPECT_NEAR(inside_json["radius"].get<double>(), 1.25 * 1.35, 1e-5);
    // No pattern matches RiggedSimple's "Bone": a clear error that says what to do.
    auto none = gltf::make_rig_scene(kSource + "/tests/assets/khronos/RiggedSimple.gltf", dir.file("r.json"), {});
    ASSERT_FALSE(none.ok());
    EXPECT_NE(none.error().message.find("--roots"), std::string::npos) << none.error().message;
    // A clip that does not exist.
    gltf::RigOptions dance;
    dance.clip = "dance";
    auto bad_clip = gltf::make_rig_scene(kChibi, dir.file("c.json"), dance);
    ASSERT_FALSE(bad_clip.ok());
    EXPECT_NE(bad_clip.error().message.find("\"idle\", \"walk\", \"turn\""), std::string::npos) << bad_clip.error().message;
    // Nodes whose rest places overflow (3e38 m each side: a span of infinity) would aim the
    // camera at no finite distance (fuzz_gltf, CI stop 49): refused, naming the node.
    const std::string far = kSource + "/tests/fuzz/regressions/gltf/named-joints-overflowing-the-camera-range.gltf";
    auto overflow = gltf::make_rig_scene(far, dir.file("f.json"), {});
    ASSERT_FALSE(overflow.ok());
    EXPECT_NE(overflow.error().message.find("nodes[4] (\"far_a\") is at (3e+38, 0, 0)"), std::string::npos)
        << overflow.error().message;
    EXPECT_NE(overflow.error().message.find(far), std::string::npos) << overflow.error().message;
}


// The shipped crowd cut to `count` instances, simulated on the CPU for `frames` frames
// and exported with RiggedCrowdExport; the joints of every frame are kept.
struct SimulatedChibi {
    RodScene rods;
    std::vector<std::vector<glm::vec3>> positions;  // per frame, ChainSnapshot::positions
    std::vector<std::vector<int>> output_nodes;     // per instance, file node -> exported node
};

SimulatedChibi simulate_and_export(std::uint32_t count, std::uint32_t frames, const std::string& path,
                                   const GlbCompaction& compaction = {}) {
    Scene scene = load(kCrowdScene);
    scene.crowds[0].count = count;
    SimulatedChibi out{build(scene), {}, {}};
    auto backend = make_rod_backend(BackendKind::Cpu, BackendOptions{});
    EXPECT_TRUE(backend.ok());
    auto exporter = RiggedCrowdExport::create(out.rods, 0, {}, compaction);
    EXPECT_TRUE(exporter.ok()) << (exporter.ok() ? "" : exporter.error().message);
    ChainSnapshot snap;
    for (std::uint32_t f = 0; f < frames; ++f) {
        const rods::RodFrame input = out.rods.frame(f);
        EXPECT_TRUE((f == 0 ? backend.value()->load(out.rods.world, input) : backend.value()->step(input)).ok());
        EXPECT_TRUE(backend.value()->read(snap).ok());
        out.positions.push_back(snap.positions);
        EXPECT_TRUE(exporter.value().add_frame(f, snap).ok());
    }
    const std::size_t nodes = out.rods.characters[0].rig->nodes.size();
    for (std::size_t i = 0; i < count; ++i) {
        std::vector<int> map(nodes);
        for (std::size_t n = 0; n < nodes; ++n) map[n] = exporter.value().writer().output_node(i, static_cast<int>(n));
        out.output_nodes.push_back(std::move(map));
    }
    const auto finished = exporter.value().finish(path);
    EXPECT_TRUE(finished.ok()) << (finished.ok() ? "" : finished.error().message);
    return out;
}

// Issue 4: re-importing the export of a simulated crowd reproduces the simulated chain
// joints and the clip-posed skeleton, and glTF-Validator finds nothing wrong.
TEST(RiggedScene, ExportRoundTripsTheSimulation) {
    TempDir dir;
    const std::string path = dir.file("chibi.glb");
    constexpr std::uint32_t kFrames = 45;
    const SimulatedChibi sim = simulate_and_export(3, kFrames, path);
    std::string output;
    ASSERT_EQ(run_command(gltf_validator_command(path), output), 0) << output;
    EXPECT_NE(output.find("glTF-Validator: 0 errors, 0 warnings"), std::string::npos) << output;

    auto reloaded = gltf::load_character(path);
    ASSERT_TRUE(reloaded.ok()) << reloaded.error().message;
    const animation::Character& exported = reloaded.value();
    ASSERT_EQ(exported.animations.size(), 1u);
    const animation::Character& source = *sim.rods.characters[0].rig;
    const int head = node_named(source, "head");
    animation::Pose pose;
    animation::Pose clip;
    float worst_chain = 0.0f;
    float worst_head = 0.0f;
    for (std::uint32_t f = 0; f < kFrames; ++f) {
        animation::evaluate(exported, 0, sim.rods.time(f), pose);
        for (std::uint32_t c = 0; c < 3; ++c) {
            const CharacterInstance& inst = sim.rods.instances[c];
            // Every simulated joint (joint 0 follows the clip) where the solver put it.
            for (std::size_t k = 0; k < sim.rods.characters[0].chain_nodes.size(); ++k) {
                const std::vector<int>& nodes = sim.rods.characters[0].chain_nodes[k];
                const rods::ChainInstance& ci = sim.rods.world.chains[inst.chain_begin + k];
                for (std::size_t i = 0; i < nodes.size(); ++i) {
                    const int out_node = sim.output_nodes[c][static_cast<std::size_t>(nodes[i])];
                    const glm::vec3 got = glm::vec3(pose.world[static_cast<std::size_t>(out_node)][3]);
                    worst_chain = std::max(worst_chain, glm::length(got - sim.positions[f][ci.joint_begin + i]));
                }
            }
            // The skeleton where the instance's clip puts it.
            animation::evaluate(source, static_cast<std::size_t>(inst.clip), sim.rods.clip_time(c, f), clip);
            const glm::vec3 expected = inst.placement.position + inst.placement.rotation * glm::vec3(clip.world[static_cast<std::size_t>(head)][3]);
            const int out_head = sim.output_nodes[c][static_cast<std::size_t>(head)];
            worst_head = std::max(worst_head, glm::length(glm::vec3(pose.world[static_cast<std::size_t>(out_head)][3]) - expected));
        }
    }
    std::printf("re-imported export, 3 chibis x %u frames: chain joints within %.3g m, head within %.3g m\n", kFrames,
                static_cast<double>(worst_chain), static_cast<double>(worst_head));
    // 1e-5 m (1e-5 of the character's 1.4 m size, as the issue asks): float32 keys, and
    // the joints' transforms composed through ~12 parents on re-import.
    EXPECT_LT(worst_chain, 1e-5f);
    EXPECT_LT(worst_head, 1e-5f);
}

// The frame input with the clips on each pose backend (CrowdAnimator) against
// RodScene::frame's CPU evaluation: the CPU backends give the same bits; the GPU within
// 1e-5 m (its interpolation runs in float, in another order: about 1e-6 of the size,
// backends/test_pose_backends.cpp). 37 instances: not a multiple of the workgroup size.
TEST(RiggedScene, CrowdAnimatorMatchesTheCpuFrames) {
    Scene scene = load(kCrowdScene);
    scene.crowds[0].count = 37;
    const RodScene rods = build(scene);
    for (const BackendKind kind : {BackendKind::CpuReference, BackendKind::Cpu, BackendKind::Vulkan}) {
        SCOPED_TRACE(std::string(backend_name(kind)));
        if (kind == BackendKind::Vulkan) {
            if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) {
                std::printf("SKIPPED the vulkan case: %s\n", why.c_str());
                continue;
            }
        }
        BackendOptions options;
        options.validation = true;
        auto animator = CrowdAnimator::create(rods, kind, options);
        ASSERT_TRUE(animator.ok()) << animator.error().message;
        rods::RodFrame got;
        float worst = 0.0f;
        for (const std::uint32_t f : {0u, 1u, 61u, 239u, 479u}) {
            ASSERT_TRUE(animator.value().frame(f, got).ok());
            const rods::RodFrame expected = rods.frame(f);
            ASSERT_EQ(got.roots.size(), expected.roots.size());
            for (std::size_t i = 0; i < got.roots.size(); ++i) {
                worst = std::max(worst, glm::length(got.roots[i].position - expected.roots[i].position));
                worst = std::max(worst, glm::length(glm::vec3(got.roots[i].rotation.x, got.roots[i].rotation.y, got.roots[i].rotation.z) -
                                                    glm::vec3(expected.roots[i].rotation.x, expected.roots[i].rotation.y,
                                                              expected.roots[i].rotation.z)));
            }
            for (std::size_t i = 0; i < got.reference.size(); ++i) {
                worst = std::max(worst, glm::length(got.reference[i].position - expected.reference[i].position));
            }
            for (std::size_t i = 0; i < got.colliders.size(); ++i) {
                worst = std::max(worst, glm::length(got.colliders[i].a - expected.colliders[i].a));
            }
        }
        std::printf("%s: frame input within %.3g of the CPU's\n", std::string(backend_name(kind)).c_str(), static_cast<double>(worst));
        if (kind == BackendKind::Vulkan) {
            EXPECT_LT(worst, 1e-5f);
            EXPECT_EQ(animator.value().validation_messages(), 0u);
        } else {
            EXPECT_EQ(worst, 0.0f);
        }
    }
}

// The rigged characters' rod input written on the device (CrowdAnimator::write_inputs_on,
// shaders/rod_inputs.comp) against the same input computed on the host from the same
// pose matrices read back: the vulkan rod backend stepped 60 frames both ways from the
// same start must end in nearly the same state. The two inputs differ by float rounding
// only (rigid_part in GLSL against glm, about 1e-7 m), which the solver carries: 1e-5 m
// (the project's bound for GPU against CPU poses) is far below a visible difference (a
// joint is 1 to 3 cm from the next) and far below what a wrong or stale root or collider
// gives (millimetres to centimetres). The
// device run must read nothing back after frame 0. 37 instances: not a multiple of the
// workgroup size.
void check_rod_input_on_device(const RodScene& rods, const char* what);

TEST(RiggedScene, RodInputWrittenOnTheDeviceMatchesTheHosts) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    Scene scene = load(kCrowdScene);
    scene.crowds[0].count = 37;
    check_rod_input_on_device(build(scene), "37 chibis");
    // Issue 18's avatars: per-chain collider runs and a chain with a center frame, whose
    // pose rod_inputs.comp writes too (RodFrame::centers).
    Scene avatars = load(kSource + "/scenes/avatars.json");
    avatars.crowds[0].count = 12;
    avatars.crowds[1].count = 11;
    const RodScene avatar_rods = build(avatars);
    ASSERT_GT(avatar_rods.world.center_count, 0u);
    check_rod_input_on_device(avatar_rods, "23 avatars");
}

void check_rod_input_on_device(const RodScene& rods, const char* what) {
    SCOPED_TRACE(what);
    HostAndDeviceInput runs;
    ASSERT_NO_FATAL_FAILURE(runs.start(rods));
    auto& [device, options, host, on_device] = runs;
    EXPECT_TRUE(on_device.animator->writes_inputs_on_device());
    EXPECT_FALSE(host.animator->writes_inputs_on_device());
    // A CPU rod backend cannot take device input.
    auto cpu = make_rod_backend(BackendKind::Cpu, {});
    ASSERT_TRUE(cpu.ok());
    auto cpu_animator = CrowdAnimator::create(rods, BackendKind::Vulkan, options);
    ASSERT_TRUE(cpu_animator.ok());
    auto refused = cpu_animator.value().write_inputs_on(*cpu.value());
    ASSERT_TRUE(refused.ok());
    EXPECT_FALSE(refused.value());

    constexpr std::uint32_t kFrames = 60;
    std::uint64_t device_read_back = 0;
    for (std::uint32_t f = 1; f <= kFrames; ++f) {
        ASSERT_TRUE(host.animator->frame(f, host.frame).ok());
        ASSERT_TRUE(host.rods->step(host.frame).ok());
        const std::uint64_t before = device->read_back_bytes();
        ASSERT_TRUE(on_device.animator->frame(f, on_device.frame).ok());
        ASSERT_TRUE(on_device.rods->step(on_device.frame).ok());
        device_read_back += device->read_back_bytes() - before;
    }
    float worst = 0.0f;
    ASSERT_NO_FATAL_FAILURE(worst = runs.joint_distance(rods));
    std::printf("rod input on the device, %s x %u frames: chain joints within %.3g m of the host-input run; "
                "%llu bytes read back\n",
                what, kFrames, static_cast<double>(worst), static_cast<unsigned long long>(device_read_back));
    EXPECT_LT(worst, 1e-5f);
    EXPECT_EQ(device_read_back, 0u);
    EXPECT_EQ(device->validation_messages(), 0u);
}

// The key sources of keyed examples (docs/keyed-examples.md K.1) written on the device
// with the rest of the rigged input (rod_inputs.comp) against RodScene::rigged_frame's on
// the host: each chain of the crowd's chibis reads its head's world pose (motion), the
// head's rotation relative to its parent node and its root node's world rotation (pose,
// the second with no parent: KeyJoint::parent -1). The scene format cannot say so yet, so
// the key joints and keyed examples are set by hand on the built scene: a speed example
// (key 0 m/s, so its weight follows the walk) and a pose example keyed on instance 0's
// first-frame pose. The combined weights W of every chain (ChainSnapshot::weights), which
// depend on every key source through the smoothed measures, must agree within 1e-4
// between the two runs every 10 frames (the inputs differ by rigid_part's rounding, about
// 1e-7, which the weights' slopes of order 1 keep far below that; a missing, stale or
// mis-parented key moves a weight by 0.1 or more), and the chains within 1e-3 m after 60
// frames. Not the 1e-5 m of the test above: the weights differ by up to 9e-6 here, and
// hair lying on the head amplifies what its rest shape gets (issue 39's solver keeps the
// energy the old sweep drained, and does not give back to a parent what the head's
// collider undid): 3.2e-4 m after 60 frames (3e-6 with contacts given back; the hair's
// second differences were the same, 10.4 mm/frame^2, so nothing visible changed). A
// mis-parented key still moves the hair by centimetres. The keyed weights must move, or a key left at its
// first value would pass. 37 instances: not a multiple of the workgroup size.
TEST(RiggedScene, KeySourcesWrittenOnTheDeviceMatchTheHosts) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    Scene scene = load(kCrowdScene);
    scene.crowds[0].count = 37;
    // The scene's own keyed examples (the tail's) make way for this test's, on every chain.
    for (kodawari::CharacterSpec& ch : scene.characters) {
        for (kodawari::ChainSpec& chain : ch.chains) {
            chain.keyed.clear();
            chain.key_sources.clear();
        }
    }
    RodScene rods = build(scene);
    std::vector<std::uint32_t> keyed_templates;
    for (CharacterKinematics& k : rods.characters) {
        if (!k.rig) continue;
        const std::uint32_t head = k.skeleton.reference;
        const int head_parent = k.rig->nodes[head].parent;
        ASSERT_GE(head_parent, 0);
        for (std::size_t c = 0; c < k.chains.size(); ++c) {
            ChainAttachment& a = k.chains[c];
            a.keys = {KeyJoint{head, -1, rods::KeySourceKind::Motion}, KeyJoint{head, head_parent, rods::KeySourceKind::Pose},
                      KeyJoint{a.joint, -1, rods::KeySourceKind::Pose}};
            const std::uint32_t t = k.first_template + static_cast<std::uint32_t>(c);
            if (std::find(keyed_templates.begin(), keyed_templates.end(), t) != keyed_templates.end()) continue;
            keyed_templates.push_back(t);
            rods::ChainTemplate& tpl = rods.world.templates[t];
            // Keyed shapes: the base turned about X, one way and the other (same segment lengths).
            const rods::ChainShape base = rods::to_positions(tpl.basis, tpl.shapes[0]);
            auto turned = [&](float angle) {
                rods::ChainShape s = base;
                const glm::quat r = glm::angleAxis(angle, glm::vec3(1, 0, 0));
                for (glm::vec3& p : s.positions) p = r * p;
                for (glm::quat& o : s.orientations) o = glm::normalize(r * o);
                return s;
            };
            const rods::KeySourceKind sources[] = {rods::KeySourceKind::Motion, rods::KeySourceKind::Pose, rods::KeySourceKind::Pose};
            const rods::ChainShape shapes[] = {turned(0.6f), turned(-0.6f)};
            rods::KeyedExample still;
            still.kind = rods::KeyKind::Motion;
            still.source = 0;
            still.measure = rods::MotionMeasure::Speed;
            still.value = glm::vec3(0.0f);
            still.influence = 0.5f;
            still.smoothing = 0.1f;
            rods::KeyedExample pose;  // key rotations set below, from the first frame
            pose.kind = rods::KeyKind::Pose;
            pose.source_mask = 0b110;
            pose.influence = 0.15f;
            pose.rotations[1] = pose.rotations[2] = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
            const rods::KeyedExample keyed[] = {still, pose};
            ASSERT_LE(tpl.views.size() + 2, rods::kMaxViewExamples);
            const auto added = rods::add_keyed_examples(tpl, sources, shapes, keyed);
            ASSERT_TRUE(added.ok()) << added.error().message;
        }
    }
    ASSERT_FALSE(keyed_templates.empty());
    ASSERT_TRUE(rods.world.finalize().ok());
    {
        // The pose example's key: instance 0's pose at frame 0 (so its weight starts near 1
        // there and moves as the clips play).
        const rods::RodFrame first = rods.frame(0);
        std::vector<bool> done(rods.world.templates.size(), false);
        for (std::size_t c = 0; c < rods.world.chains.size(); ++c) {
            const std::uint32_t t = rods.world.chains[c].template_index;
            rods::ChainTemplate& tpl = rods.world.templates[t];
            if (tpl.keyed.size() != 2 || done[t]) continue;
            done[t] = true;
            const std::uint32_t k = rods.world.chains[c].key_begin;
            tpl.keyed[1].rotations[1] = first.keys[k + 1].rotation;
            tpl.keyed[1].rotations[2] = first.keys[k + 2].rotation;
        }
    }
    HostAndDeviceInput runs;
    ASSERT_NO_FATAL_FAILURE(runs.start(rods));
    auto& [device, options, host, on_device] = runs;

    constexpr std::uint32_t kFrames = 60;
    constexpr std::size_t kWeights = rods::kMaxViewExamples + 1;
    float worst_weight = 0.0f, low = 1.0f, high = 0.0f;
    for (std::uint32_t f = 1; f <= kFrames; ++f) {
        ASSERT_TRUE(host.animator->frame(f, host.frame).ok());
        ASSERT_TRUE(host.rods->step(host.frame).ok());
        ASSERT_TRUE(on_device.animator->frame(f, on_device.frame).ok());
        ASSERT_TRUE(on_device.rods->step(on_device.frame).ok());
        if (f % 10 != 0) continue;
        ChainSnapshot a, b;
        ASSERT_TRUE(host.rods->read(a).ok());
        ASSERT_TRUE(on_device.rods->read(b).ok());
        ASSERT_EQ(a.weights.size(), b.weights.size());
        for (std::size_t k = 0; k < a.weights.size(); ++k) worst_weight = std::max(worst_weight, std::abs(a.weights[k] - b.weights[k]));
        for (std::size_t c = 0; c < rods.world.chains.size(); ++c) {
            const rods::ChainTemplate& tpl = rods.world.templ(rods.world.chains[c]);
            for (std::size_t j = 1; j <= tpl.keyed.size(); ++j) {
                const float w = a.weights[c * kWeights + tpl.views.size() + j];
                low = std::min(low, w);
                high = std::max(high, w);
            }
        }
    }
    float worst = 0.0f;
    ASSERT_NO_FATAL_FAILURE(worst = runs.joint_distance(rods));
    std::printf("key sources on the device, 37 chibis x %u frames: W within %.3g of the host-input run (keyed W from %.3f "
                "to %.3f), chain joints within %.3g m\n",
                kFrames, static_cast<double>(worst_weight), static_cast<double>(low), static_cast<double>(high),
                static_cast<double>(worst));
    EXPECT_GT(high - low, 0.2f) << "the keyed weights must move";
    EXPECT_LT(worst_weight, 1e-4f);
    EXPECT_LT(worst, 1e-3f);
    EXPECT_EQ(device->validation_messages(), 0u);
}

// Blender's own glTF importer (tests/tools/blender_check.py) on the export of a
// simulated crowd, when Blender is installed (bash scripts/setup --with-blender), and on
// its compact export (--compact: fewer keys, rotations as shorts) with the same counts.
// Two Blender runs.
TEST(RiggedScene, BlenderImportsTheExport) {
    std::string output;
    if (run_command("command -v blender", output) != 0) {
        GTEST_SKIP() << "SKIPPED: blender not installed (bash scripts/setup --with-blender installs it)";
    }
    for (const bool compact : {false, true}) {
        SCOPED_TRACE(compact ? "compact" : "uncompacted");
        TempDir dir;
        const std::string path = dir.file("chibi.glb");
        constexpr std::uint32_t kInstances = 2;
        const SimulatedChibi sim = simulate_and_export(kInstances, 20, path, GlbCompaction{.enabled = compact});
        const std::string line = testing_support::blender_report_line(path, output);
        ASSERT_FALSE(line.empty()) << output;
        const nlohmann::json report = nlohmann::json::parse(line);
        std::cout << report.dump().substr(0, 400) << "...\n";

        // Blender 3.4 makes each skin an armature and one action per animated object, bone
        // channels going to their armature: one action per instance, whose animated bones
        // are the nodes the clips animate plus every chain joint.
        const animation::Character& source = *sim.rods.characters[0].rig;
        std::set<int> animated;
        for (const animation::Animation& a : source.animations) {
            for (const animation::Channel& ch : a.channels) animated.insert(ch.node);
        }
        for (const std::vector<int>& nodes : sim.rods.characters[0].chain_nodes) animated.insert(nodes.begin(), nodes.end());
        EXPECT_EQ(report.at("actions").get<std::size_t>(), kInstances);
        EXPECT_EQ(report.at("armature_count").get<std::size_t>(), kInstances);
        std::set<std::string> expected;
        for (std::uint32_t c = 0; c < kInstances; ++c) {
            for (const int n : animated) expected.insert(sim.rods.character_names[c] + "/" + source.nodes[static_cast<std::size_t>(n)].name);
        }
        std::set<std::string> bones;
        for (const auto& [armature, names] : report.at("armatures").items()) {
            EXPECT_EQ(names.size(), animated.size()) << armature;
            for (const auto& bone : names) bones.insert(bone.get<std::string>());
        }
        EXPECT_EQ(bones, expected);
    }
}

}  // namespace
}  // namespace kodawari
