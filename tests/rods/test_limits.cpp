// Angle limits (issue 36, item 2; VRMC_springBone_limit 1.0-draft): the limited direction
// against the draft's definitions and its table of singular directions
// (shaders/lib/spring_limit.glsl through rods::limit_direction), chains that come to rest
// on their limits where the closed form says on every backend, the scene format's
// `limit`, and every backend against the reference on scenes/limits.json.

#include <algorithm>
#include <fstream>
#include <functional>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include <kodawari/vulkan/backend_factory.hpp>
#include <kodawari/gltf/rig_scene.hpp>
#include <kodawari/backends/rod_backend.hpp>
#include <kodawari/rods/limits.hpp>
#include <kodawari/rods/solver.hpp>
#include <kodawari/rods/world.hpp>
#include <kodawari/scene/scene.hpp>

#include "character_support.hpp"
#include "test_support.hpp"

using namespace kodawari::testing_support::characters;

namespace {

constexpr float kDeg = kPi / 180.0f;

rods::AngleLimit cone(float deg) { return {rods::LimitKind::Cone, deg * kDeg, 0.0f, {1.0f, 0.0f, 0.0f, 0.0f}}; }
rods::AngleLimit hinge(float deg) { return {rods::LimitKind::Hinge, deg * kDeg, 0.0f, {1.0f, 0.0f, 0.0f, 0.0f}}; }
rods::AngleLimit spherical(float pitch_deg, float yaw_deg) {
    return {rods::LimitKind::Spherical, pitch_deg * kDeg, yaw_deg * kDeg, {1.0f, 0.0f, 0.0f, 0.0f}};
}

// Angle between two directions, rad.
float angle(glm::vec3 a, glm::vec3 b) {
    return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

glm::vec3 dir(float x, float y, float z) { return glm::normalize(glm::vec3(x, y, z)); }

bool same_bits(glm::vec3 a, glm::vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

}  // namespace

// The closed forms, in the limit's frame (+Y its axis): a direction inside comes back
// bit for bit; one outside goes to the nearest allowed one (a cone keeps its azimuth, a
// hinge drops its X and keeps its side, a spherical limit clamps pitch and yaw one by one
// as the draft's reference does); the draft's singular directions go where its table
// says. Bound 2e-6 rad: a few float roundings of a unit vector (1.2e-7 each).
TEST(Limits, DirectionsGoWhereTheDraftSays) {
    const float tol = 2e-6f;
    auto near = [&](glm::vec3 got, glm::vec3 want) { return angle(got, glm::normalize(want)) < tol; };
    // Cone of 30 degrees.
    const glm::vec3 inside = dir(std::sin(20 * kDeg), std::cos(20 * kDeg), 0.0f);
    EXPECT_TRUE(same_bits(rods::limit_direction(cone(30), inside), inside));
    const glm::vec3 out = dir(std::sin(70 * kDeg) * 0.6f, std::cos(70 * kDeg), std::sin(70 * kDeg) * 0.8f);
    EXPECT_TRUE(near(rods::limit_direction(cone(30), out), {0.5f * 0.6f, std::cos(30 * kDeg), 0.5f * 0.8f}));
    EXPECT_TRUE(near(rods::limit_direction(cone(30), {0, -1, 0}), {0, std::cos(30 * kDeg), std::sin(30 * kDeg)}))
        << "a cone's -Y goes to the boundary on the +Z side";
    EXPECT_TRUE(same_bits(rods::limit_direction(cone(180), glm::vec3(0, -1, 0)), glm::vec3(0, -1, 0)))
        << "a cone of pi allows every direction";
    // Hinge of 45 degrees: turns about X only.
    EXPECT_TRUE(near(rods::limit_direction(hinge(45), dir(0.6f, 0.8f, 0.0f)), {0, 1, 0}));
    EXPECT_TRUE(near(rods::limit_direction(hinge(45), dir(0.3f, 0.5f, 0.4f)), {0, 0.5f, 0.4f}));
    EXPECT_TRUE(near(rods::limit_direction(hinge(45), dir(0.3f, -0.5f, -0.8f)), {0, 1, -1}));
    EXPECT_TRUE(near(rods::limit_direction(hinge(45), {1, 0, 0}), {0, 1, 0})) << "a hinge's +-X goes to +Y";
    EXPECT_TRUE(near(rods::limit_direction(hinge(45), {-1, 0, 0}), {0, 1, 0}));
    EXPECT_TRUE(near(rods::limit_direction(hinge(45), {0, -1, 0}), {0, 1, 1})) << "a hinge's -Y: the +Z side";
    // Spherical, pitch 30 and yaw 20 degrees: (sin yaw, cos yaw cos pitch, cos yaw sin pitch).
    auto sph = [](float pitch, float yaw) {
        return glm::vec3(std::sin(yaw * kDeg), std::cos(yaw * kDeg) * std::cos(pitch * kDeg), std::cos(yaw * kDeg) * std::sin(pitch * kDeg));
    };
    EXPECT_TRUE(same_bits(rods::limit_direction(spherical(30, 20), sph(25, -15)), sph(25, -15)));
    EXPECT_TRUE(near(rods::limit_direction(spherical(30, 20), sph(50, 10)), sph(30, 10)));
    EXPECT_TRUE(near(rods::limit_direction(spherical(30, 20), sph(-50, -40)), sph(-30, -20)));
    EXPECT_TRUE(near(rods::limit_direction(spherical(30, 20), sph(10, 60)), sph(10, 20)));
    EXPECT_TRUE(near(rods::limit_direction(spherical(30, 20), {0, -1, 0}), sph(30, 0))) << "-Y: the +Z side";
    EXPECT_TRUE(near(rods::limit_direction(spherical(30, 20), {1, 0, 0}), sph(0, 20))) << "+X: the +Y side";
    EXPECT_TRUE(near(rods::limit_direction(spherical(30, 20), {-1, 0, 0}), sph(0, -20)));
    // The limit's frame: +Y turned onto the bone axis the shortest way, a half turn about
    // X for -Y (the draft's rule), then the limit's rotation.
    const glm::quat f = rods::limit_frame({1, 0, 0}, glm::quat(1, 0, 0, 0));
    EXPECT_LT(angle(f * glm::vec3(0, 1, 0), {1, 0, 0}), tol);
    EXPECT_LT(angle(f * glm::vec3(1, 0, 0), {0, -1, 0}), tol);
    const glm::quat down = rods::limit_frame({0, -1, 0}, glm::quat(1, 0, 0, 0));
    EXPECT_LT(angle(down * glm::vec3(0, 0, 1), {0, 0, -1}), tol) << "the half turn is about X";
}

TEST(Limits, OutOfRangeLimitsAreRefusedNamingTheField) {
    rods::AngleLimit bad = cone(30);
    bad.angle = 4.0f;
    ASSERT_FALSE(rods::validate(bad, "l").ok());
    EXPECT_TRUE(contains(rods::validate(bad, "l").error().message, "l.angle"));
    bad = spherical(30, 20);
    bad.yaw = 2.0f;
    EXPECT_TRUE(contains(rods::validate(bad, "l").error().message, "l.yaw"));
    bad = hinge(30);
    bad.rotation = glm::quat(2.0f, 0.0f, 0.0f, 0.0f);
    EXPECT_TRUE(contains(rods::validate(bad, "l").error().message, "l.rotation"));
    rods::ChainShape base;
    for (int i = 0; i < 3; ++i) base.positions.push_back(glm::vec3(0.1f * static_cast<float>(i), 0.0f, 0.0f));
    rods::default_orientations(base);
    rods::Chain chain = rods::make_chain(base, 0.005f, 0.002f).value();
    const std::vector<rods::AngleLimit> three(3, cone(10));
    const auto wrong = rods::set_limits(chain, three, "c.limit");
    ASSERT_FALSE(wrong.ok());
    EXPECT_TRUE(contains(wrong.error().message, "expected 2 limits")) << wrong.error().message;
}

namespace {

// A scene of one still character whose chain of `joints` joints and `length` m starts
// horizontal along +X (an arc along +Y turned by -90 degrees about Z), with no rest
// attraction, shape matching or colliders, so that gravity alone pulls it down and only
// its limits (`limit`, the scene format's) hold it: a pendulum.
json pendulum_scene(int joints, const json& limit) {
    json doc = json::parse(R"({
      "format": "kodawari-scene", "version": 2, "duration": 3,
      "characters": [{
        "name": "post", "skeleton": [{"name": "top", "position": [0, 1, 0]}], "reference_joint": "top",
        "chains": [{"name": "arm", "joint": "top",
                    "offset": {"rotation": {"axis": [0, 0, 1], "angle_deg": -90}},
                    "physics": {"stiffness": 0, "rest_stiffness": 0, "damping": 6}}]
      }]
    })");
    json& c = chain0(doc);
    c["shape"] = {{"arc", {{"joints", joints}, {"length", 0.1 * (joints - 1)}}}};
    c["limit"] = limit;
    return doc;
}

// Each segment's direction after `frames` frames on `kind`.
std::vector<glm::vec3> segment_directions(const kodawari::testing_support::BackendCase& kind, const json& doc,
                                          std::uint32_t frames) {
    auto scene = kodawari::parse_scene(doc.dump(), "pendulum.json");
    EXPECT_TRUE(scene.ok()) << scene.error().message;
    if (!scene.ok()) return {};
    const RodScene rs = build(scene.value());
    const auto snap = run_rod_frames(kind, rs, frames, [&](std::uint32_t f, rods::RodFrame& frame) { rs.frame(f, frame); });
    std::vector<glm::vec3> dirs;
    for (std::size_t i = 0; i + 1 < snap.positions.size(); ++i) dirs.push_back(glm::normalize(snap.positions[i + 1] - snap.positions[i]));
    return dirs;
}

class LimitBackends : public ::testing::TestWithParam<kodawari::testing_support::BackendCase> {};

// (cos a, -sin a, 0): a segment a below +X in the vertical XY plane.
glm::vec3 below(float deg) { return {std::cos(deg * kDeg), -std::sin(deg * kDeg), 0.0f}; }

}  // namespace

// Pendulums that gravity pulls straight down, on every backend, each coming to rest where
// its limit's closed form says (its frame: +Y along the bone, +X world -Y, +Z world +Z):
// - a cone of 30 degrees: 30 below horizontal;
// - a hinge (turning about the limit's X, world vertical): level, whatever gravity does;
// - the hinge turned 90 degrees about its axis (turning about world Z), 25 degrees: 25 below;
// - a spherical limit of pitch 20 and yaw 60 (gravity pulls along its yaw): 60 below;
//   turned 90 degrees about its axis (gravity along its pitch): 20 below;
// - a chain of 4 segments with a cone of 20 degrees on each joint, each measured from its
//   parent bone's turn (the draft's parent.worldRotation): 20, 40, 60 and 80 below.
// Bound 1e-3 rad: the damped swing's residue after 3 s (6/s damping leaves e^-18 of it)
// and float rounding; without the limit each hangs straight down, 90 degrees below.
TEST_P(LimitBackends, PendulumsRestOnTheirLimits) {
    if (GetParam() == kodawari::BackendKind::Vulkan) {
        if (const std::string why = kodawari::testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    }
    const json quarter_turn = {{"axis", {0, 1, 0}}, {"angle_deg", 90}};
    struct Case {
        const char* name;
        int joints;
        json limit;
        std::vector<float> expected_deg;  // each segment's angle below +X
        bool level = false;               // or: level, along +X
    };
    const std::vector<Case> cases = {
        {"cone 30", 2, {{"cone", {{"angle_deg", 30}}}}, {30}},
        {"hinge about the vertical", 2, {{"hinge", {{"angle_deg", 45}}}}, {0}, true},
        {"hinge turned", 2, {{"hinge", {{"angle_deg", 25}, {"rotation", quarter_turn}}}}, {25}},
        {"spherical yaw", 2, {{"spherical", {{"pitch_deg", 20}, {"yaw_deg", 60}}}}, {60}},
        {"spherical pitch", 2, {{"spherical", {{"pitch_deg", 20}, {"yaw_deg", 60}, {"rotation", quarter_turn}}}}, {20}},
        {"cone chain", 5, {{"cone", {{"angle_deg", 20}}}}, {20, 40, 60, 80}},
    };
    for (const Case& c : cases) {
        const std::vector<glm::vec3> dirs = segment_directions(GetParam(), pendulum_scene(c.joints, c.limit), 181);
        ASSERT_EQ(dirs.size(), c.expected_deg.size()) << c.name;
        float worst = 0.0f;
        for (std::size_t i = 0; i < dirs.size(); ++i) worst = std::max(worst, angle(dirs[i], below(c.expected_deg[i])));
        std::printf("[ measured ] %s on %s: %.2g rad from the closed form (bound 1e-3)\n", c.name,
                    kodawari::testing_support::case_name(GetParam()).c_str(), static_cast<double>(worst));
        EXPECT_LT(worst, 1e-3f) << c.name;
    }
    // With a limit that allows every direction (a cone of 180 degrees) the pendulum hangs
    // straight down: what holds it above is the limit, not the scene.
    if (GetParam() == kodawari::BackendKind::CpuReference) {
        json free = pendulum_scene(2, {{"cone", {{"angle_deg", 180}}}});
        const std::vector<glm::vec3> dirs = segment_directions(GetParam(), free, 181);
        ASSERT_EQ(dirs.size(), 1u);
        EXPECT_LT(angle(dirs[0], below(90)), 1e-3f);
    }
}

// Every backend against the reference on scenes/limits.json (a crowd whose chains carry
// every limit kind, against colliders, through the scene's motions): the CPU backends the
// reference's bits (the same limit in the same order), Vulkan within 1e-3 of the chain
// length (GLSL rounding a few ulp apart, compounded over 90 frames, as the other parity
// tests allow).
TEST_P(LimitBackends, LimitedCrowdMatchesTheReference) {
    if (GetParam() == kodawari::BackendKind::Vulkan) {
        if (const std::string why = kodawari::testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    }
    const RodScene rs = build(load("scenes/limits.json"));
    auto run = [&](const kodawari::testing_support::BackendCase& kind) {
        return run_rod_frames(kind, rs, 91, [&](std::uint32_t f, rods::RodFrame& frame) { rs.frame(f, frame); }).positions;
    };
    const std::vector<glm::vec3> ours = run(GetParam());
    const std::vector<glm::vec3> reference = run({kodawari::BackendKind::CpuReference, {}});
    ASSERT_EQ(ours.size(), reference.size());
    const float worst = worst_in_chain_lengths(rs, ours, reference);
    std::printf("[ measured ] limits.json on %s (%zu chains): max %.3g of the chain length from the reference\n",
                kodawari::testing_support::case_name(GetParam()).c_str(), rs.world.chains.size(), static_cast<double>(worst));
    if (GetParam() == kodawari::BackendKind::Vulkan) {
        EXPECT_LT(worst, 1e-3f);
    } else {
        EXPECT_EQ(worst, 0.0f) << "the CPU backends run the reference's code";
    }
}

// The closed-form conformance cases (tests/conformance/limits/, README "Angle limits"):
// VRM 1.0 files whose spring (chain-sag's: five joints along +X, gravityPower 1,
// stiffness 0) has a VRMC_springBone_limit on every joint, through `rig` (the extension
// read, the scene written) and the solver, on every backend. Gravity alone pulls the
// chain down; each joint's limit, measured from its parent bone's turn, holds it at
// - cone 20 degrees: 20, 40, 60, 80 below horizontal;
// - hinge 45 (turning about the limit frame's X, world vertical for a bone along +X): level;
// - the hinge turned a quarter about its axis (turning about world Z), 25: 25, 50, 75, then
//   straight down (90, inside its range);
// - spherical pitch 10, yaw 30 (gravity along the yaw): 30, 60, then straight down, 90, 90.
// The last joint's limit (a cone of 0, which would hold the chain level) is ignored, as
// the draft says it MUST be. Bound 1e-3 rad, as for the pendulums.
TEST_P(LimitBackends, VrmLimitsRestWhereTheClosedFormSays) {
    if (GetParam() == kodawari::BackendKind::Vulkan) {
        if (const std::string why = kodawari::testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    }
    const kodawari::testing_support::TempDir dir;
    const std::vector<std::pair<std::string, std::vector<float>>> cases = {
        {"limit-cone", {20, 40, 60, 80}},
        {"limit-hinge", {0, 0, 0, 0}},
        {"limit-hinge-turned", {25, 50, 75, 90}},
        {"limit-spherical", {30, 60, 90, 90}},
    };
    for (const auto& [name, expected] : cases) {
        const std::string scene_path = dir.file(name + ".json");
        auto rig = kodawari::gltf::make_rig_scene(source_path("tests/conformance/limits/" + name + ".gltf"), scene_path, {});
        ASSERT_TRUE(rig.ok()) << rig.error().message;
        const auto limits = json::parse(rig.value().json)["characters"][0]["chains"][0]["limit"];
        ASSERT_EQ(limits.size(), 4u) << name << ": one limit per bone, the tail's left out";
        auto scene = kodawari::parse_scene(rig.value().json, scene_path);
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        const RodScene rs = build(scene.value());
        const auto snap = run_rod_frames(GetParam(), rs, 61, [&](std::uint32_t f, rods::RodFrame& frame) { rs.frame(f, frame); });
        ASSERT_EQ(snap.positions.size(), 5u);
        float worst = 0.0f;
        for (std::size_t i = 0; i < 4; ++i) {
            const glm::vec3 d = glm::normalize(snap.positions[i + 1] - snap.positions[i]);
            worst = std::max(worst, angle(d, below(expected[i])));
        }
        std::printf("[ measured ] %s (VRM, through rig) on %s: %.2g rad from the closed form (bound 1e-3)\n", name.c_str(),
                    kodawari::testing_support::case_name(GetParam()).c_str(), static_cast<double>(worst));
        EXPECT_LT(worst, 1e-3f) << name;
    }
}

INSTANTIATE_TEST_SUITE_P(All, LimitBackends, kodawari::testing_support::all_backend_kinds(),
                         kodawari::testing_support::backend_test_name);

// The scene format's `limit`: one object for every segment or one per segment (null for
// none), each exactly one of cone, hinge, spherical, in degrees; everything else refused
// naming the field.
TEST(Limits, SceneLimitsAreReadAndBadOnesNamed) {
    json doc = valid_character_scene();  // ear: 8 joints, 7 segments, mirrored as ear_r
    chain0(doc)["limit"] = {{"cone", {{"angle_deg", 40}}}};
    auto scene = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const kodawari::ChainSpec& ear = scene.value().characters[0].chains[0];
    ASSERT_EQ(ear.limits.size(), 7u);
    EXPECT_EQ(ear.limits[3].kind, rods::LimitKind::Cone);
    EXPECT_NEAR(ear.limits[3].angle, 40 * kDeg, 1e-6f);
    EXPECT_EQ(scene.value().characters[0].chains[1].limits.size(), 7u) << "the mirror chain has them too";
    json per_joint = json::array();
    for (int i = 0; i < 7; ++i) per_joint.push_back(i == 2 ? json(nullptr) : json{{"spherical", {{"pitch_deg", 30}, {"yaw_deg", 10}}}});
    chain0(doc)["limit"] = per_joint;
    scene = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    EXPECT_EQ(scene.value().characters[0].chains[0].limits[2].kind, rods::LimitKind::None);
    EXPECT_EQ(scene.value().characters[0].chains[0].limits[3].kind, rods::LimitKind::Spherical);

    chain0(doc)["limit"] = {{"cone", {{"angle_deg", 200}}}};
    EXPECT_TRUE(contains(parse_error(doc), "$.characters[0].chains[0].limit.cone.angle_deg")) << parse_error(doc);
    chain0(doc)["limit"] = {{"spherical", {{"pitch_deg", 30}, {"yaw_deg", 100}}}};
    EXPECT_TRUE(contains(parse_error(doc), "limit.spherical.yaw_deg")) << parse_error(doc);
    chain0(doc)["limit"] = {{"cone", {{"angle_deg", 30}}}, {"hinge", {{"angle_deg", 30}}}};
    EXPECT_TRUE(contains(parse_error(doc), "exactly one of")) << parse_error(doc);
    chain0(doc)["limit"] = json::array({json{{"cone", {{"angle_deg", 30}}}}});
    EXPECT_TRUE(contains(parse_error(doc), "an array of 7 limits")) << parse_error(doc);
    chain0(doc)["limit"] = {{"twist", {{"angle_deg", 30}}}};
    EXPECT_TRUE(contains(parse_error(doc), "limit.twist")) << parse_error(doc);
    chain0(doc)["limit"] = {{"hinge", {{"angle_deg", 30}, {"rotation", {{"axis", {0, 0, 0}}, {"angle_deg", 10}}}}}};
    EXPECT_TRUE(contains(parse_error(doc), "limit.hinge.rotation.axis")) << parse_error(doc);
}

// A VRM file's bad limits are refused naming the file and the JSON path (a negative
// angle, two kinds in one limit, a rotation that is no quaternion); an angle past pi is
// read as pi, as the draft says implementations MUST.
TEST(Limits, BadVrmLimitsAreRefusedNamingThePath) {
    const kodawari::testing_support::TempDir dir;
    const json good = json::parse(kodawari::testing_support::file_bytes(source_path("tests/conformance/limits/limit-cone.gltf")));
    auto rig_error = [&](const std::function<void(json&)>& edit) {
        json doc = good;
        edit(doc["extensions"]["VRMC_springBone"]["springs"][0]["joints"][1]["extensions"]["VRMC_springBone_limit"]["limit"]);
        const std::string file = dir.file("bad.gltf");
        std::ofstream(file) << doc.dump();
        auto rig = kodawari::gltf::make_rig_scene(file, dir.file("bad.json"), {});
        return rig.ok() ? std::string("(no error)") : rig.error().message;
    };
    const std::string at = "$.extensions.VRMC_springBone.springs[0].joints[1].extensions.VRMC_springBone_limit.limit";
    std::string e = rig_error([](json& l) { l["cone"]["angle"] = -0.5; });
    EXPECT_TRUE(contains(e, at + ".cone.angle") && contains(e, "bad.gltf")) << e;
    e = rig_error([](json& l) { l["hinge"] = {{"angle", 0.5}}; });
    EXPECT_TRUE(contains(e, at) && contains(e, "more than one")) << e;
    e = rig_error([](json& l) { l["cone"]["rotation"] = {0, 0, 0}; });
    EXPECT_TRUE(contains(e, at + ".cone.rotation")) << e;
    e = rig_error([](json& l) { l["cone"]["angle"] = 7.0; });
    EXPECT_EQ(e, "(no error)") << "an angle past pi is read as pi";
}
