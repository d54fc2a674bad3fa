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

gltf::Character load(const std::string& path) {
    auto character = gltf::load_character(path);
    EXPECT_TRUE(character.ok()) << (character.ok() ? "" : character.error().message);
    return std::move(character).value();
}

gltf::VrmSprings read(const gltf::Character& character) {
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

TEST(GltfVrm, SamplesYieldTheSpringsAndCollidersTheyDeclare) {
    for (const std::string& name : kSpringFiles) {
        SCOPED_TRACE(name);
        const std::string path = kSpringDir + "/" + name;
        const json doc = read_json(path);
        const json& ext = doc["extensions"]["VRMC_springBone"];
        const gltf::VrmSprings vrm = read(load(path));
        EXPECT_EQ(vrm.version, 2);

        ASSERT_EQ(vrm.colliders.size(), ext["colliders"].size());
        bool plane = false, inside = false;
        for (std::size_t i = 0; i < vrm.colliders.size(); ++i) {
            const json& c = ext["colliders"][i];
            // The extended shape wins unless it is a plane (then the base shape stays).
            json shape = c["shape"];
            bool extended = false;
            if (c.contains("extensions") && c["extensions"].contains("VRMC_springBone_extended_collider")) {
                const json& es = c["extensions"]["VRMC_springBone_extended_collider"]["shape"];
                if (es.contains("plane")) {
                    plane = true;
                } else {
                    shape = es;
                    extended = true;
                }
            }
            const gltf::VrmCollider& got = vrm.colliders[i];
            EXPECT_EQ(got.node, c["node"].get<int>());
            const bool capsule = shape.contains("capsule");
            const json& s = capsule ? shape["capsule"] : shape["sphere"];
            EXPECT_EQ(got.capsule, capsule);
            EXPECT_FLOAT_EQ(got.radius, s["radius"].get<float>());
            expect_near(got.offset, s.contains("offset") ? vec3(s["offset"]) : glm::vec3(0.0f), 0.0f);
            const bool is_inside = extended && s.value("inside", false);
            EXPECT_EQ(got.inside, is_inside);
            inside = inside || is_inside;
        }
        // One warning per unmapped kind, none otherwise.
        EXPECT_EQ(vrm.warnings.size(), static_cast<std::size_t>(plane) + static_cast<std::size_t>(inside));
        for (const std::string& w : vrm.warnings) {
            EXPECT_NE(w.find(path), std::string::npos) << w;
            EXPECT_NE(w.find("$.extensions.VRMC_springBone.colliders[0]"), std::string::npos) << w;
            EXPECT_NE(w.find(plane ? "plane" : "inside"), std::string::npos) << w;
        }

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
    const rods::SolverParams defaults;
    EXPECT_NEAR(spring.params.rest_stiffness, expected_rest(joint["stiffness"].get<float>(), segment, defaults.max_substep), 1e-6f);
    EXPECT_NEAR(spring.params.rest_stiffness, 0.008264f, 1e-5f);  // 60/14400 / (60/14400 + 0.5)
    EXPECT_NEAR(spring.params.damping, expected_damping(joint["dragForce"].get<float>()), 1e-4f);
    EXPECT_NEAR(spring.params.damping, 30.649f, 1e-2f);  // -ln(0.6) * 60
    expect_near(spring.params.gravity, glm::vec3(0.0f), 0.0f);
    EXPECT_FLOAT_EQ(spring.params.stiffness, defaults.stiffness);
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

    const rods::SolverParams defaults;
    const std::array<float, 2> segments = {0.1f, 0.2f};
    for (std::size_t s = 0; s < 2; ++s) {
        const gltf::VrmSpring& spring = vrm.springs[s];
        EXPECT_EQ(spring.colliders, (std::vector<std::size_t>{0}));
        EXPECT_NEAR(spring.params.rest_stiffness, expected_rest(2.0f, segments[s], defaults.max_substep), 1e-6f);
        EXPECT_NEAR(spring.params.damping, expected_damping(0.2f), 1e-4f);
        expect_near(spring.params.gravity, glm::vec3(0.0f, -30.0f, 0.0f), 1e-5f);  // 60 * 0.5 * (0, -1, 0)
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
    const gltf::Character character = load(path);
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

TEST(GltfVrm, FileWithoutVrmIsVersionZero) {
    const gltf::VrmSprings vrm = read(load(kAssets + "/khronos/RiggedSimple.gltf"));
    EXPECT_EQ(vrm.version, 0);
    EXPECT_TRUE(vrm.springs.empty());
    EXPECT_TRUE(vrm.colliders.empty());
    EXPECT_TRUE(vrm.warnings.empty());
}

}  // namespace
}  // namespace kodawari
