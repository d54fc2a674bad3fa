// VRM spring bones as chains (SPEC A.7, issue 4): the shipped VRMC_springBone samples
// against their own JSON (read here independently), the documented parameter mapping,
// a hand-written VRM 0.x file, and the error and no-VRM cases.

#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "kodawari/gltf/import.hpp"
#include "kodawari/gltf/vrm.hpp"
#include "kodawari/rods/solver.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kAssets = std::string(KODAWARI_SOURCE_DIR) + "/tests/assets";
const std::string kSpringDir = kAssets + "/vrm-springbone";
const std::array<std::string, 3> kSpringFiles = {"inside-collider.gltf", "plane-collider.gltf", "sphere-collider.gltf"};

using testing_support::TempDir;

json read_json(const std::string& path) {
    std::ifstream in(path);
    return json::parse(in);
}

void write_text(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
}

animation::Character load(const std::string& path) {
    auto character = gltf::load_character(path);
    EXPECT_TRUE(character.ok()) << (character.ok() ? "" : character.error().message);
    return std::move(character).value();
}

gltf::VrmSprings read(const animation::Character& character) {
    auto springs = gltf::read_vrm_springs(character);
    EXPECT_TRUE(springs.ok()) << (springs.ok() ? "" : springs.error().message);
    return std::move(springs).value();
}

glm::vec3 vec3(const json& a) { return {a[0].get<float>(), a[1].get<float>(), a[2].get<float>()}; }

void expect_near(glm::vec3 a, glm::vec3 b, float tol) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

// The documented formulas (vrm.hpp), written out again here.
float expected_rest(float stiffness, float segment, float h) {
    const float a = 60.0f * h * h * stiffness;
    return a / (a + segment);
}
float expected_damping(float drag) { return -std::log(1.0f - drag) * 60.0f; }
// gravity = 60 p dir: the solver damps before adding gravity, as VRM does (issue 39; it
// was 60 p dir / exp(-damping h) while the solver damped after).
glm::vec3 expected_gravity(float power, glm::vec3 dir) { return 60.0f * power * dir; }

TEST(GltfVrm, SamplesYieldTheSpringsAndCollidersTheyDeclare) {
    for (const std::string& name : kSpringFiles) {
        SCOPED_TRACE(name);
        const std::string path = kSpringDir + "/" + name;
        const json doc = read_json(path);
        const json& ext = doc["extensions"]["VRMC_springBone"];
        const gltf::VrmSprings vrm = read(load(path));
        EXPECT_EQ(vrm.version, 2);

        ASSERT_EQ(vrm.colliders.size(), ext["colliders"].size());
        for (std::size_t i = 0; i < vrm.colliders.size(); ++i) {
            const json& c = ext["colliders"][i];
            // The extended shape, when present, replaces the base one (its fallback).
            json shape = c["shape"];
            bool extended = false;
            if (c.contains("extensions") && c["extensions"].contains("VRMC_springBone_extended_collider")) {
                shape = c["extensions"]["VRMC_springBone_extended_collider"]["shape"];
                extended = true;
            }
            const gltf::VrmCollider& got = vrm.colliders[i];
            EXPECT_EQ(got.node, c["node"].get<int>());
            if (shape.contains("plane")) {
                const json& p = shape["plane"];
                EXPECT_EQ(got.kind, rods::ColliderKind::Plane);
                expect_near(got.offset, p.contains("offset") ? vec3(p["offset"]) : glm::vec3(0.0f), 0.0f);
                expect_near(got.normal, glm::normalize(vec3(p["normal"])), 1e-7f);
                expect_near(got.tail, got.offset + got.normal, 1e-7f);
                continue;
            }
            const bool capsule = shape.contains("capsule");
            const json& s = capsule ? shape["capsule"] : shape["sphere"];
            EXPECT_EQ(got.capsule, capsule);
            EXPECT_FLOAT_EQ(got.radius, s["radius"].get<float>());
            expect_near(got.offset, s.contains("offset") ? vec3(s["offset"]) : glm::vec3(0.0f), 0.0f);
            const bool is_inside = extended && s.value("inside", false);
            EXPECT_EQ(got.kind, is_inside ? rods::ColliderKind::Inside : rods::ColliderKind::Outside);
        }
        // Every shape maps: no warnings.
        EXPECT_TRUE(vrm.warnings.empty()) << vrm.warnings.front();

        ASSERT_EQ(vrm.springs.size(), ext["springs"].size());
        for (std::size_t s = 0; s < vrm.springs.size(); ++s) {
            const json& joints = ext["springs"][s]["joints"];
            const gltf::VrmSpring& spring = vrm.springs[s];
            ASSERT_EQ(spring.chain.nodes.size(), joints.size());
            for (std::size_t j = 0; j < joints.size(); ++j) EXPECT_EQ(spring.chain.nodes[j], joints[j]["node"].get<int>());
            EXPECT_EQ(spring.chain.parent, -1);  // node 0 is a scene root in every sample
            std::vector<std::size_t> colliders;
            for (const json& g : ext["springs"][s]["colliderGroups"]) {
                for (const json& c : ext["colliderGroups"][g.get<std::size_t>()]["colliders"]) colliders.push_back(c.get<std::size_t>());
            }
            EXPECT_EQ(spring.colliders, colliders);
            EXPECT_TRUE(rods::validate(spring.params).ok());
            const auto chain = rods::make_chain(spring.chain.base, spring.physics.thickness, spring.physics.mass);
            EXPECT_TRUE(chain.ok()) << (chain.ok() ? "" : chain.error().message);
        }
    }
}

TEST(GltfVrm, MappedParametersFollowTheDocumentedFormulas) {
    // sphere-collider.gltf: joints 0..4, each 2 units below the last under a root scaled
    // by 0.25 (so 0.5 m segments), stiffness 1, gravityPower 0, dragForce 0.4,
    // hitRadius 0.25 on every bone.
    const std::string path = kSpringDir + "/sphere-collider.gltf";
    const json joint = read_json(path)["extensions"]["VRMC_springBone"]["springs"][0]["joints"][0];
    const gltf::VrmSprings vrm = read(load(path));
    ASSERT_EQ(vrm.springs.size(), 1u);
    const gltf::VrmSpring& spring = vrm.springs[0];
    const float segment = 2.0f * 0.25f;
    EXPECT_NEAR(spring.chain.length, 4.0f * segment, 1e-5f);
    EXPECT_NEAR(spring.params.rest_stiffness, expected_rest(joint["stiffness"].get<float>(), segment, rods::kReferenceSubstep), 1e-6f);
    EXPECT_NEAR(spring.params.rest_stiffness, 0.008264f, 1e-5f);  // 60/14400 / (60/14400 + 0.5)
    EXPECT_NEAR(spring.params.damping, expected_damping(joint["dragForce"].get<float>()), 1e-4f);
    EXPECT_NEAR(spring.params.damping, 30.649f, 1e-2f);  // -ln(0.6) * 60
    expect_near(spring.params.gravity, glm::vec3(0.0f), 0.0f);
    EXPECT_EQ(spring.params.stiffness, 0.0f);  // VRM has no shape matching
    EXPECT_FLOAT_EQ(spring.hit_radius, joint["hitRadius"].get<float>());
    EXPECT_NEAR(spring.physics.thickness, 0.25f * 0.25f, 1e-6f);  // hitRadius times the root's world scale
    EXPECT_GT(spring.physics.mass, 0.0f);
}

// A VRM 0.x file: a strand that branches (node 2 has children 3 and 4), a leaf branch
// of one joint (skipped), a collider group on the head.
const char* kVrm0 = R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["VRM"],
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [
    {"name": "root", "children": [1, 6]},
    {"name": "hairA", "translation": [0, -0.1, 0], "children": [2]},
    {"name": "hairA2", "translation": [0, -0.1, 0], "children": [3, 4]},
    {"name": "leafL", "translation": [0.05, -0.1, 0], "children": [5]},
    {"name": "leafR", "translation": [-0.05, -0.1, 0]},
    {"name": "leafL2", "translation": [0, -0.2, 0]},
    {"name": "head", "translation": [0, 1, 0]}
  ],
  "extensions": {"VRM": {"secondaryAnimation": {
    "boneGroups": [{"stiffiness": 2.0, "gravityPower": 0.5, "gravityDir": {"x": 0, "y": -1, "z": 0},
                    "dragForce": 0.2, "hitRadius": 0.01, "center": -1, "bones": [1], "colliderGroups": [0]}],
    "colliderGroups": [{"node": 6, "colliders": [{"offset": {"x": 0.1, "y": 0.2, "z": 0.3}, "radius": 0.09}]}]
  }}}
})";

TEST(GltfVrm, Vrm0BoneGroupsBecomeChains) {
    const TempDir dir;
    const std::string path = dir.file("vrm0.gltf");
    write_text(path, kVrm0);
    const gltf::VrmSprings vrm = read(load(path));
    EXPECT_EQ(vrm.version, 1);

    ASSERT_EQ(vrm.colliders.size(), 1u);
    EXPECT_EQ(vrm.colliders[0].node, 6);
    EXPECT_FALSE(vrm.colliders[0].capsule);
    expect_near(vrm.colliders[0].offset, glm::vec3(0.1f, 0.2f, -0.3f), 0.0f);  // z negated back
    EXPECT_FLOAT_EQ(vrm.colliders[0].radius, 0.09f);

    ASSERT_EQ(vrm.springs.size(), 2u);
    EXPECT_EQ(vrm.springs[0].chain.nodes, (std::vector<int>{1, 2}));
    EXPECT_EQ(vrm.springs[0].chain.parent, 0);
    EXPECT_EQ(vrm.springs[1].chain.nodes, (std::vector<int>{3, 5}));
    EXPECT_EQ(vrm.springs[1].chain.parent, 2);
    ASSERT_EQ(vrm.warnings.size(), 1u);  // leafR: one joint, no bone
    EXPECT_NE(vrm.warnings[0].find("$.extensions.VRM.secondaryAnimation.boneGroups[0].bones[0]"), std::string::npos)
        << vrm.warnings[0];
    EXPECT_NE(vrm.warnings[0].find("node 4"), std::string::npos) << vrm.warnings[0];

    const std::array<float, 2> segments = {0.1f, 0.2f};
    for (std::size_t s = 0; s < 2; ++s) {
        const gltf::VrmSpring& spring = vrm.springs[s];
        EXPECT_EQ(spring.colliders, (std::vector<std::size_t>{0}));
        EXPECT_NEAR(spring.params.rest_stiffness, expected_rest(2.0f, segments[s], rods::kReferenceSubstep), 1e-6f);
        EXPECT_NEAR(spring.params.damping, expected_damping(0.2f), 1e-4f);
        // 60 * 0.5 * (0, -1, 0) = (0, -30, 0), whatever the drag.
        expect_near(spring.params.gravity, expected_gravity(0.5f, glm::vec3(0.0f, -1.0f, 0.0f)), 1e-4f);
        EXPECT_NEAR(spring.params.gravity.y, -30.0f, 1e-3f);
        EXPECT_FLOAT_EQ(spring.hit_radius, 0.01f);
        EXPECT_NEAR(spring.physics.thickness, 0.01f, 1e-7f);
        EXPECT_TRUE(rods::make_chain(spring.chain.base, spring.physics.thickness, spring.physics.mass).ok());
    }
}

TEST(GltfVrm, BrokenJointPathNamesFileAndJsonPath) {
    const TempDir dir;
    json doc = read_json(kSpringDir + "/sphere-collider.gltf");
    doc["extensions"]["VRMC_springBone"]["springs"][0]["joints"][2]["node"] = 4;  // skips node 3
    const std::string path = dir.file("broken.gltf");
    write_text(path, doc.dump());
    fs::copy_file(kSpringDir + "/sphere_mesh.bin", dir.file("sphere_mesh.bin"));
    const animation::Character character = load(path);
    const auto vrm = gltf::read_vrm_springs(character);
    ASSERT_FALSE(vrm.ok());
    EXPECT_EQ(vrm.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(vrm.error().message.find(path), std::string::npos) << vrm.error().message;
    EXPECT_NE(vrm.error().message.find("$.extensions.VRMC_springBone.springs[0].joints[2]"), std::string::npos)
        << vrm.error().message;
}

TEST(GltfVrm, ColliderGroupOutOfRangeIsAnError) {
    const TempDir dir;
    json doc = read_json(kSpringDir + "/sphere-collider.gltf");
    doc["extensions"]["VRMC_springBone"]["springs"][0]["colliderGroups"][0] = 3;
    const std::string path = dir.file("group.gltf");
    write_text(path, doc.dump());
    fs::copy_file(kSpringDir + "/sphere_mesh.bin", dir.file("sphere_mesh.bin"));
    const auto vrm = gltf::read_vrm_springs(load(path));
    ASSERT_FALSE(vrm.ok());
    EXPECT_NE(vrm.error().message.find("$.extensions.VRMC_springBone.springs[0].colliderGroups[0]"), std::string::npos)
        << vrm.error().message;
}

// The bad input of issue 18: a collider group naming a collider the file lacks, and a
// plane whose normal is zero. Each names the file and the JSON path.
TEST(GltfVrm, MissingColliderAndZeroNormalAreErrors) {
    const TempDir dir;
    fs::copy_file(kSpringDir + "/plane_mesh.bin", dir.file("plane_mesh.bin"));
    fs::copy_file(kSpringDir + "/sphere_mesh.bin", dir.file("sphere_mesh.bin"));
    json doc = read_json(kSpringDir + "/plane-collider.gltf");
    json missing = doc;
    missing["extensions"]["VRMC_springBone"]["colliderGroups"][0]["colliders"][0] = 1;  // one collider: index 0
    write_text(dir.file("missing.gltf"), missing.dump());
    const auto a = gltf::read_vrm_springs(load(dir.file("missing.gltf")));
    ASSERT_FALSE(a.ok());
    EXPECT_NE(a.error().message.find(dir.file("missing.gltf")), std::string::npos) << a.error().message;
    EXPECT_NE(a.error().message.find("$.extensions.VRMC_springBone.colliderGroups[0].colliders[0]"), std::string::npos)
        << a.error().message;
    EXPECT_NE(a.error().message.find("collider 1 does not exist"), std::string::npos) << a.error().message;

    json zero = doc;
    zero["extensions"]["VRMC_springBone"]["colliders"][0]["extensions"]["VRMC_springBone_extended_collider"]["shape"]["plane"]
        ["normal"] = json::array({0, 0, 0});
    write_text(dir.file("zero.gltf"), zero.dump());
    const auto b = gltf::read_vrm_springs(load(dir.file("zero.gltf")));
    ASSERT_FALSE(b.ok());
    EXPECT_NE(b.error().message.find(
                  "$.extensions.VRMC_springBone.colliders[0].extensions.VRMC_springBone_extended_collider.shape.plane.normal"),
              std::string::npos)
        << b.error().message;
    EXPECT_NE(b.error().message.find("non-zero"), std::string::npos) << b.error().message;
}

// `center`: VRM 1.0's node index and VRM 0.x's (where -1 is none) become VrmSpring::center;
// an index out of range is an error at its path.
TEST(GltfVrm, CenterNodesAreRead) {
    const TempDir dir;
    fs::copy_file(kSpringDir + "/sphere_mesh.bin", dir.file("sphere_mesh.bin"));
    json doc = read_json(kSpringDir + "/sphere-collider.gltf");
    doc["extensions"]["VRMC_springBone"]["springs"][0]["center"] = 5;
    write_text(dir.file("center.gltf"), doc.dump());
    const gltf::VrmSprings vrm = read(load(dir.file("center.gltf")));
    ASSERT_EQ(vrm.springs.size(), 1u);
    EXPECT_EQ(vrm.springs[0].center, 5);
    EXPECT_TRUE(vrm.warnings.empty());

    doc["extensions"]["VRMC_springBone"]["springs"][0]["center"] = 6;
    write_text(dir.file("far.gltf"), doc.dump());
    const auto far = gltf::read_vrm_springs(load(dir.file("far.gltf")));
    ASSERT_FALSE(far.ok());
    EXPECT_NE(far.error().message.find("$.extensions.VRMC_springBone.springs[0].center"), std::string::npos) << far.error().message;

    write_text(dir.file("vrm0.gltf"), kVrm0);
    EXPECT_EQ(read(load(dir.file("vrm0.gltf"))).springs[0].center, -1);
    json vrm0 = json::parse(kVrm0);
    vrm0["extensions"]["VRM"]["secondaryAnimation"]["boneGroups"][0]["center"] = 0;
    write_text(dir.file("vrm0-center.gltf"), vrm0.dump());
    const gltf::VrmSprings with_center = read(load(dir.file("vrm0-center.gltf")));
    ASSERT_EQ(with_center.springs.size(), 2u);
    EXPECT_EQ(with_center.springs[0].center, 0);
    EXPECT_EQ(with_center.springs[1].center, 0);
}

TEST(GltfVrm, FileWithoutVrmIsVersionZero) {
    const gltf::VrmSprings vrm = read(load(kAssets + "/khronos/RiggedSimple.gltf"));
    EXPECT_EQ(vrm.version, 0);
    EXPECT_TRUE(vrm.springs.empty());
    EXPECT_TRUE(vrm.colliders.empty());
    EXPECT_TRUE(vrm.warnings.empty());
}

}  // namespace
}  // namespace kodawari
