// Characters (SPEC A.1, A.3, C; docs/scene-format.md version 2): the loader's errors,
// the shipped rod scenes, the kinematics (skeleton, motions, camera), and the effect the
// seed asks for: an ahoge that reads as a sideways curl from every camera angle.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <kodawari/rod_scene.hpp>
#include <kodawari/rods/kinematics.hpp>
#include <kodawari/rods/solver.hpp>
#include <kodawari/rods/world.hpp>
#include <kodawari/scene.hpp>

namespace {

using kodawari::Error;
using kodawari::Result;
using kodawari::RodScene;
using kodawari::Scene;
using nlohmann::json;
namespace rods = kodawari::rods;

constexpr float kPi = std::numbers::pi_v<float>;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string source_path(const std::string& relative) { return std::string(KODAWARI_SOURCE_DIR) + "/" + relative; }

Scene load(const std::string& relative) {
    auto scene = kodawari::load_scene(source_path(relative));
    EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error().message);
    return scene.ok() ? scene.value() : Scene{};
}

RodScene build(const Scene& scene) {
    auto built = kodawari::build_rod_scene(scene);
    EXPECT_TRUE(built.ok()) << (built.ok() ? "" : built.error().message);
    return built.ok() ? std::move(built).value() : RodScene{};
}

// The CPU reference run of a RodScene, frame by frame, exactly as a backend would: the
// frame's kinematic input, each chain's view-blended rest shape, one solver step.
class Simulation {
public:
    explicit Simulation(const RodScene& scene) : scene_(scene) {
        scene_.frame(0, frame_);
        for (std::uint32_t c = 0; c < scene_.world.chains.size(); ++c) {
            const rods::RestShape rest = rods::rest_shape(scene_.world, c, frame_);
            states_.push_back(rods::initial_state(scene_.world.templ(scene_.world.chains[c]).chain, frame_.roots[c], rest.shape));
        }
    }

    /// Advances every chain to frame `index` (call with 1, 2, 3, ...).
    void step(std::uint32_t index) {
        scene_.frame(index, frame_);
        for (std::uint32_t c = 0; c < scene_.world.chains.size(); ++c) {
            const rods::ChainInstance& chain = scene_.world.chains[c];
            const rods::ChainTemplate& t = scene_.world.templ(chain);
            const rods::RestShape rest = rods::rest_shape(scene_.world, c, frame_);
            spheres_.clear();
            capsules_.clear();
            for (std::uint32_t k = chain.collider_begin; k < chain.collider_begin + chain.collider_count; ++k) {
                const rods::Capsule& cap = frame_.colliders[k];
                if (cap.a == cap.b) {
                    spheres_.push_back(rods::Sphere{cap.a, cap.radius});
                } else {
                    capsules_.push_back(cap);
                }
            }
            rods::step(t.chain, t.params, frame_.roots[c], rest.shape, spheres_, capsules_, frame_.dt, states_[c]);
        }
    }

    [[nodiscard]] const rods::ChainState& state(std::uint32_t chain) const { return states_[chain]; }
    [[nodiscard]] const rods::RodFrame& frame() const { return frame_; }

private:
    const RodScene& scene_;
    rods::RodFrame frame_;
    std::vector<rods::ChainState> states_;
    std::vector<rods::Sphere> spheres_;
    std::vector<rods::Capsule> capsules_;
};

// A look-at + perspective camera on a 1920 x 1080 picture, +Y up: what a viewer shows.
struct Projector {
    glm::mat4 view;
    glm::mat4 projection;
    float focal_px;  // pixels per metre at 1 m depth
    static constexpr float kWidth = 1920.0f;
    static constexpr float kHeight = 1080.0f;

    Projector(const rods::CameraPose& pose, float fov_deg)
        : view(glm::lookAt(pose.position, pose.target, glm::vec3(0.0f, 1.0f, 0.0f))),
          projection(glm::perspective(glm::radians(fov_deg), kWidth / kHeight, 0.01f, 1000.0f)),
          focal_px(0.5f * kHeight / std::tan(0.5f * glm::radians(fov_deg))) {}

    // Pixel coordinates, x to the right, y down.
    [[nodiscard]] glm::vec2 pixel(glm::vec3 p) const {
        const glm::vec4 clip = projection * view * glm::vec4(p, 1.0f);
        const glm::vec2 ndc(clip.x / clip.w, clip.y / clip.w);
        return glm::vec2(0.5f * (ndc.x + 1.0f) * kWidth, 0.5f * (1.0f - ndc.y) * kHeight);
    }
    // Pixels per metre at the depth of `p`.
    [[nodiscard]] float scale(glm::vec3 p) const { return focal_px / -(view * glm::vec4(p, 1.0f)).z; }
};

}  // namespace

// ---------------------------------------------------------------------------------------
// The scene format's characters (docs/scene-format.md, version 2)

namespace {

// A small valid character scene that the error tests break one key at a time.
json valid_character_scene() {
    return json::parse(R"({
      "format": "kodawari-scene",
      "version": 2,
      "characters": [
        {
          "name": "bunny",
          "skeleton": [
            {"name": "body", "position": [0, 0.9, 0]},
            {"name": "head", "parent": "body", "position": [0, 0.6, 0]}
          ],
          "motions": [{"type": "sway"}, {"type": "head_turn"}, {"type": "walk", "end": 2}, {"type": "stop", "start": 3, "stop_time": 4}],
          "colliders": [{"type": "sphere", "joint": "head", "radius": 0.1}],
          "chains": [
            {
              "name": "ear", "joint": "head", "mirror": "ear_r",
              "shape": {"arc": {"joints": 8, "length": 0.2}},
              "views": [{"direction": [0, 0, 1], "shape": {"arc": {"joints": 8, "length": 0.2, "curl_deg": 30}}}]
            }
          ]
        }
      ]
    })");
}

std::string error_of(const Result<Scene>& result) {
    if (result.ok()) return "(no error)";
    EXPECT_EQ(result.error().kind, Error::Kind::InvalidInput);
    return result.error().message;
}

std::string parse_error(const json& scene) { return error_of(kodawari::parse_scene(scene.dump(), "test.json")); }

json& chain0(json& doc) { return doc["characters"][0]["chains"][0]; }

}  // namespace

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
              "colliders, physics, chains)");
    json chain = valid_character_scene();
    chain0(chain)["stiffness"] = 0.5;
    EXPECT_EQ(parse_error(chain),
              "test.json: $.characters[0].chains[0].stiffness: unknown key (expected one of: name, joint, offset, shape, "
              "thickness, mass, physics, collide, mirror, views)");
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
              "test.json: $.characters[0].colliders[0].a: unknown key (expected one of: type, joint, center, radius)");
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
              "move the chain with \"offset\"), got an array of 3 elements");
    json coincident = valid_character_scene();
    chain0(coincident)["shape"] = json::parse(R"({"positions": [[0, 0, 0], [0, 0.1, 0], [0, 0.1, 0]]})");
    chain0(coincident).erase("views");
    EXPECT_EQ(parse_error(coincident),
              "test.json: $.characters[0].chains[0].shape.positions[2]: expected a point at least 1e-6 m from the previous "
              "joint, got an array of 3 elements");
    json quat = valid_character_scene();
    chain0(quat)["shape"] = json::parse(R"({"positions": [[0, 0, 0], [0, 0.1, 0]], "orientations": [[0, 0, 0, 1], [0, 0, 0, 2]]})");
    chain0(quat).erase("views");
    EXPECT_EQ(parse_error(quat),
              "test.json: $.characters[0].chains[0].shape.orientations[1]: expected a unit quaternion [x, y, z, w] (length "
              "within 1e-3 of 1), got an array of 4 elements");
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
              "arc bends about it), got an array of 3 elements");
}

TEST(CharacterScene, BadViews) {
    json eight = valid_character_scene();
    for (int k = 0; k < 7; ++k) chain0(eight)["views"].push_back(chain0(eight)["views"][0]);
    EXPECT_EQ(parse_error(eight),
              "test.json: $.characters[0].chains[0].views: expected an array of at most 7 view examples, got an array of 8 "
              "elements");
    json zero = valid_character_scene();
    chain0(zero)["views"][0]["direction"] = {0, 0, 0};
    EXPECT_EQ(parse_error(zero),
              "test.json: $.characters[0].chains[0].views[0].direction: expected a non-zero vector [x, y, z], got an array of "
              "3 elements");
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
              "test.json: $.characters[0].chains[0].thickness: expected a finite number in (0, 1], got -0.01");
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
              "direction), got an array of 3 elements");
    json interpolation = valid_character_scene();
    interpolation["camera"] = json::parse(R"({"path": {"points": [[0, 1, 3], [1, 1, 3]], "target": [0, 1, 0], "interpolation": "cubic"}})");
    EXPECT_EQ(parse_error(interpolation),
              "test.json: $.camera.path.interpolation: expected one of \"catmull-rom\", \"linear\", got \"cubic\"");
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

// ---------------------------------------------------------------------------------------
// The ahoge (SPEC A; the seed's figure 7): "seen from any direction, the ahoge reads as a
// sideways curl".

namespace {

struct AhogeRun {
    float min_ratio = 1e9f;                  // worst sideways offset, in strand lengths
    int failing_frames = 0;                  // frames below the margin
    int frames = 0;
    std::array<float, 24> bin_min{};         // worst ratio per 15-degree bin of the view azimuth
    std::array<int, 24> bin_frames{};
};

// The criterion: on screen, the tip lies to the camera's right of the root by at least
// `margin` of the strand's length (as projected at the root's depth). That is what "reads
// as a sideways curl" means for a strand that stands up from the top of the head: the
// curl shows in profile, always opening the same way.
AhogeRun run_ahoge(const RodScene& scene, float margin, float warmup_s) {
    AhogeRun out;
    out.bin_min.fill(1e9f);
    Simulation sim(scene);
    const rods::ChainTemplate& t = scene.world.templates[0];
    float length = 0.0f;
    for (std::uint32_t i = 0; i + 1 < t.chain.joint_count; ++i) length += t.chain.segment_length[i];
    const std::uint32_t last = t.chain.joint_count - 1;
    const auto first_checked = static_cast<std::uint32_t>(std::lround(warmup_s * scene.fps));
    for (std::uint32_t f = 1; f < scene.frames; ++f) {
        sim.step(f);
        if (f < first_checked) continue;
        const Projector cam(scene.camera_pose(f), scene.fov_deg);
        const rods::ChainState& s = sim.state(0);
        const float sideways = (cam.pixel(s.x[last]).x - cam.pixel(s.x[0]).x) / (length * cam.scale(s.x[0]));
        const glm::vec3 d = rods::rest_shape(scene.world, 0, sim.frame()).view_direction;
        float azimuth = std::atan2(d.x, d.z) * 180.0f / kPi;  // 0 = the head's front, 90 = its left
        if (azimuth < 0.0f) azimuth += 360.0f;
        const auto bin = static_cast<std::size_t>(std::min(23.0f, azimuth / 15.0f));
        out.bin_min[bin] = std::min(out.bin_min[bin], sideways);
        ++out.bin_frames[bin];
        out.min_ratio = std::min(out.min_ratio, sideways);
        if (sideways < margin) ++out.failing_frames;
        ++out.frames;
    }
    return out;
}

}  // namespace

TEST(Characters, AhogeReadsSidewaysFromEveryAngle) {
    Scene scene = load("scenes/ahoge.json");
    ASSERT_EQ(scene.characters.size(), 1u);
    const RodScene with_views = build(scene);
    ASSERT_EQ(with_views.world.chains.size(), 1u);
    const float margin = 0.25f;
    const AhogeRun run = run_ahoge(with_views, margin, 2.0f);
    for (std::size_t b = 0; b < 24; ++b) {
        std::printf("[ measured ] azimuth %3zu-%3zu deg: %3d frames, min sideways %.3f L\n", 15 * b, 15 * b + 15,
                    run.bin_frames[b], static_cast<double>(run.bin_min[b]));
    }
    std::printf("[ measured ] with view examples: min sideways offset %.3f of the strand length over %d frames\n",
                static_cast<double>(run.min_ratio), run.frames);
    scene.characters[0].chains[0].views.clear();
    const RodScene base_only = build(scene);
    const AhogeRun control = run_ahoge(base_only, margin, 2.0f);
    std::printf("[ measured ] base shape only: min sideways offset %.3f, %d of %d frames below %.2f\n",
                static_cast<double>(control.min_ratio), control.failing_frames, control.frames, static_cast<double>(margin));
    EXPECT_EQ(run.failing_frames, 0);
    EXPECT_GT(control.failing_frames, 0);
}

namespace {

// 2D distance from p to the segment [a, b].
float segment_distance(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
    const glm::vec2 ab = b - a;
    const float len2 = glm::dot(ab, ab);
    const float t = len2 > 0.0f ? std::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
    return glm::length(p - (a + t * ab));
}

// Seen from a fixed camera in front of the face, the smallest on-screen distance from
// either eye to any bang over the last second of a 3 s run, in head radii.
float eye_clearance(Scene scene) {
    scene.camera.motion.kind = rods::CameraMotion::Kind::Fixed;
    scene.camera.motion.position = glm::vec3(0.0f, 1.57f, 1.0f);
    scene.camera.motion.target = glm::vec3(0.0f, 1.57f, 0.0f);
    scene.duration = 3.0f;
    const RodScene rs = build(scene);
    Simulation sim(rs);
    float clearance = 1e9f;
    const glm::vec3 centre(0.0f, 0.1f, 0.0f);
    const float radius = 0.11f;
    for (std::uint32_t f = 1; f < rs.frames; ++f) {
        sim.step(f);
        if (rs.time(f) < 2.0f) continue;
        const Projector cam(rs.camera_pose(f), rs.fov_deg);
        const rods::Transform& head = sim.frame().reference[0];
        const float head_px = radius * cam.scale(head.position + head.rotation * centre);
        for (const float side : {-1.0f, 1.0f}) {
            const float az = side * 20.0f * kPi / 180.0f;
            const float el = 5.0f * kPi / 180.0f;
            const glm::vec3 eye_local = centre + radius * glm::vec3(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
            const glm::vec2 eye = cam.pixel(head.position + head.rotation * eye_local);
            for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
                const rods::ChainState& st = sim.state(c);
                const std::uint32_t n = rs.world.templ(rs.world.chains[c]).chain.joint_count;
                for (std::uint32_t i = 0; i + 1 < n; ++i) {
                    clearance = std::min(clearance, segment_distance(eye, cam.pixel(st.x[i]), cam.pixel(st.x[i + 1])) / head_px);
                }
            }
        }
    }
    return clearance;
}

}  // namespace

TEST(Characters, BangsPartFromTheFront) {
    Scene scene = load("scenes/bangs.json");
    const float with_views = eye_clearance(scene);
    for (kodawari::ChainSpec& chain : scene.characters[0].chains) chain.views.clear();
    const float base_only = eye_clearance(scene);
    std::printf("[ measured ] eye clearance seen from the front: %.3f head radii with the view example, %.3f with the base shape only\n",
                static_cast<double>(with_views), static_cast<double>(base_only));
}

namespace {

// Seen from a fixed camera at `azimuth_deg` round the head (0 = in front, 90 = the
// character's left), the smallest on-screen horizontal distance between the two ear tips
// over the last second of a 3 s run, in ear lengths. The head turn is left out so that
// the camera alone sets the view.
float ear_tip_separation(Scene scene, float azimuth_deg) {
    auto& oscillations = scene.characters[0].motion.oscillations;
    oscillations.erase(std::remove_if(oscillations.begin(), oscillations.end(),
                                      [](const rods::Oscillation& o) { return o.axis == glm::vec3(0.0f, 1.0f, 0.0f); }),
                       oscillations.end());
    const float a = azimuth_deg * kPi / 180.0f;
    scene.camera.motion.kind = rods::CameraMotion::Kind::Fixed;
    scene.camera.motion.target = glm::vec3(0.0f, 1.65f, 0.0f);
    scene.camera.motion.position = scene.camera.motion.target + 1.6f * glm::vec3(std::sin(a), 0.0f, std::cos(a));
    scene.duration = 3.0f;
    const RodScene rs = build(scene);
    Simulation sim(rs);
    const rods::Chain& ear = rs.world.templates[0].chain;
    float length = 0.0f;
    for (std::uint32_t i = 0; i + 1 < ear.joint_count; ++i) length += ear.segment_length[i];
    float separation = 1e9f;
    for (std::uint32_t f = 1; f < rs.frames; ++f) {
        sim.step(f);
        if (rs.time(f) < 2.0f) continue;
        const Projector cam(rs.camera_pose(f), rs.fov_deg);
        const glm::vec3 left = sim.state(0).x[ear.joint_count - 1];
        const glm::vec3 right = sim.state(1).x[ear.joint_count - 1];
        separation = std::min(separation, std::abs(cam.pixel(left).x - cam.pixel(right).x) / (length * cam.scale(0.5f * (left + right))));
    }
    return separation;
}

}  // namespace

TEST(Characters, BunnyEarsSplayPerView) {
    Scene scene = load("scenes/bunny.json");
    ASSERT_EQ(scene.characters[0].chains.size(), 2u);
    const float front = ear_tip_separation(scene, 0.0f);
    const float side = ear_tip_separation(scene, 90.0f);
    const float other_side = ear_tip_separation(scene, -90.0f);
    for (kodawari::ChainSpec& chain : scene.characters[0].chains) chain.views.clear();
    const float front_base = ear_tip_separation(scene, 0.0f);
    const float side_base = ear_tip_separation(scene, 90.0f);
    std::printf("[ measured ] ear tips apart on screen: front %.3f, left side %.3f, right side %.3f ear lengths; base shape only: front %.3f, side %.3f\n",
                static_cast<double>(front), static_cast<double>(side), static_cast<double>(other_side), static_cast<double>(front_base), static_cast<double>(side_base));
}

