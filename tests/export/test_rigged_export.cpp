// Tests of the rigged crowd export (export.hpp, RiggedGlbWriter): a round trip through
// our own loader against the source pose computed here independently, glTF-Validator on
// the outputs, sources with external buffers and images, and atomic writes. The export of
// a real simulation, and Blender's importer on it, are in scene/test_rigged_scene.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "kodawari/export/export.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/gltf/import.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

using testing_support::base64;

namespace fs = std::filesystem;
using testing_support::gltf_validator_command;
using testing_support::run_command;
using testing_support::shell_quote;
using testing_support::TempDir;

constexpr float kFps = 24.0f;

std::string asset(const std::string& relative) { return std::string(KODAWARI_SOURCE_DIR) + "/tests/assets/" + relative; }

glm::mat4 trs(const glm::vec3& t, const glm::quat& r, const glm::vec3& s) {
    return glm::translate(glm::mat4(1.0f), t) * glm::mat4_cast(r) * glm::scale(glm::mat4(1.0f), s);
}

glm::mat4 placement_matrix(const rods::Transform& p) {
    return glm::translate(glm::mat4(1.0f), p.position) * glm::mat4_cast(p.rotation);
}

/// A crowd of RiggedSimple: every node's TRS from the file's own clip at a time offset per
/// instance, the last two joints of its skin additionally turned every frame (standing
/// in for simulated hair).
struct RiggedSimpleCrowd {
    animation::Character character;
    std::vector<RiggedInstance> instances;
    std::vector<bool> animated;
    std::vector<int> perturbed;  // the two joints turned on top of the clip

    explicit RiggedSimpleCrowd(std::size_t count) {
        auto loaded = gltf::load_character(asset("khronos/RiggedSimple.gltf"));
        EXPECT_TRUE(loaded.ok()) << loaded.error().message;
        character = std::move(loaded).value();
        const std::vector<rods::Transform> placements = {
            {{0.0f, 0.0f, 0.0f}, glm::quat(1.0f, 0.0f, 0.0f, 0.0f)},
            {{3.0f, 0.0f, -1.0f}, glm::angleAxis(1.5707964f, glm::vec3(0.0f, 1.0f, 0.0f))},
            {{-2.0f, 1.0f, 4.0f}, glm::angleAxis(0.7f, glm::normalize(glm::vec3(1.0f, 1.0f, 0.0f)))},
        };
        for (std::size_t i = 0; i < count; ++i) {
            instances.push_back({"crowd" + std::to_string(i), placements[i % placements.size()]});
        }
        animated.assign(character.nodes.size(), false);
        for (const animation::Channel& channel : character.animations.at(0).channels) {
            animated[static_cast<std::size_t>(channel.node)] = true;
        }
        const std::vector<int>& joints = character.skins.at(0).joints;
        perturbed = {joints[joints.size() - 2], joints[joints.size() - 1]};
        for (const int j : perturbed) animated[static_cast<std::size_t>(j)] = true;
    }

    [[nodiscard]] std::size_t nodes() const { return character.nodes.size(); }

    /// Frame `f`'s local TRS of every node of every instance (instance-major).
    void frame(std::uint32_t f, std::vector<glm::vec3>& t, std::vector<glm::quat>& r, std::vector<glm::vec3>& s) const {
        const std::size_t n = nodes();
        t.resize(instances.size() * n);
        r.resize(instances.size() * n);
        s.resize(instances.size() * n);
        const animation::Animation& clip = character.animations.at(0);
        animation::Pose pose;
        for (std::size_t i = 0; i < instances.size(); ++i) {
            const float time = std::fmod(static_cast<float>(f) / kFps + 0.37f * static_cast<float>(i), clip.end);
            animation::evaluate(character, 0, time, pose);
            for (std::size_t k = 0; k < n; ++k) {
                t[i * n + k] = pose.translation[k];
                r[i * n + k] = pose.rotation[k];
                s[i * n + k] = pose.scale[k];
            }
            for (std::size_t p = 0; p < perturbed.size(); ++p) {
                const float angle = 0.4f * std::sin(0.3f * static_cast<float>(f) + static_cast<float>(i + p));
                const auto k = i * n + static_cast<std::size_t>(perturbed[p]);
                r[k] = glm::normalize(r[k] * glm::angleAxis(angle, glm::normalize(glm::vec3(1.0f, 0.5f, 0.2f))));
            }
        }
    }

    /// The world matrices of instance `i`'s nodes for one frame's values, computed from
    /// the source character alone: placement * (the file's hierarchy), where an animated
    /// node uses the frame's TRS and any other node its rest transform (its matrix when
    /// the file gives one).
    [[nodiscard]] std::vector<glm::mat4> world(std::size_t i, const std::vector<glm::vec3>& t,
                                               const std::vector<glm::quat>& r, const std::vector<glm::vec3>& s) const {
        const std::size_t n = nodes();
        std::vector<glm::mat4> out(n);
        for (const int index : character.order) {
            const auto k = static_cast<std::size_t>(index);
            const animation::Node& node = character.nodes[k];
            glm::mat4 local;
            if (animated[k]) {
                local = trs(t[i * n + k], r[i * n + k], s[i * n + k]);
            } else {
                local = node.matrix ? *node.matrix : trs(node.translation, node.rotation, node.scale);
            }
            out[k] = (node.parent >= 0 ? out[static_cast<std::size_t>(node.parent)] : placement_matrix(instances[i].placement)) *
                     local;
        }
        return out;
    }

    [[nodiscard]] RiggedGlbWriter writer() const {
        auto created = RiggedGlbWriter::create(asset("khronos/RiggedSimple.gltf"), character, instances, animated, kFps,
                                               "simulation");
        EXPECT_TRUE(created.ok()) << created.error().message;
        return std::move(created).value();
    }

    /// Writes `frames` frames to `path`.
    void write(const std::string& path, std::uint32_t frames) const {
        RiggedGlbWriter w = writer();
        std::vector<glm::vec3> t;
        std::vector<glm::quat> r;
        std::vector<glm::vec3> s;
        for (std::uint32_t f = 0; f < frames; ++f) {
            frame(f, t, r, s);
            ASSERT_TRUE(w.add_frame(t, r, s).ok());
        }
        const auto written = w.finish(path);
        ASSERT_TRUE(written.ok()) << written.error().message;
    }
};

float max_abs_difference(const glm::mat4& a, const glm::mat4& b) {
    float worst = 0.0f;
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) worst = std::max(worst, std::abs(a[c][r] - b[c][r]));
    }
    return worst;
}

// Reads back a GLB we wrote (image bytes kept undecoded: the tests look at the glTF
// structure); false, after a test failure saying why, when tinygltf cannot.
bool load_glb(const std::string& path, tinygltf::Model& model) {
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(
        [](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) { return true; },
        nullptr);
    std::string error, warning;
    const bool ok = loader.LoadBinaryFromFile(&model, &error, &warning, path);
    EXPECT_TRUE(ok) << path << ": " << error;
    return ok;
}

void expect_validates(const std::string& path) {
    std::string output;
    // node is a required test tool (scripts/setup installs it): missing is a failure.
    ASSERT_EQ(run_command("command -v node", output), 0) << "node is not on PATH; run scripts/setup";
    output.clear();
    EXPECT_EQ(run_command(gltf_validator_command(path), output), 0) << output;
    EXPECT_NE(output.find("glTF-Validator: 0 errors, 0 warnings"), std::string::npos) << output;
    std::cout << output;
}

TEST(RiggedExport, RoundTripMatchesThePlacedSourcePose) {
    constexpr std::uint32_t kFrames = 40;
    const RiggedSimpleCrowd crowd(3);
    TempDir dir;
    const std::string path = dir.file("crowd.glb");

    RiggedGlbWriter writer = crowd.writer();
    std::vector<std::vector<std::vector<glm::mat4>>> expected(kFrames);  // [frame][instance][node]
    std::vector<glm::vec3> t;
    std::vector<glm::quat> r;
    std::vector<glm::vec3> s;
    for (std::uint32_t f = 0; f < kFrames; ++f) {
        crowd.frame(f, t, r, s);
        ASSERT_TRUE(writer.add_frame(t, r, s).ok());
        for (std::size_t i = 0; i < crowd.instances.size(); ++i) expected[f].push_back(crowd.world(i, t, r, s));
    }
    EXPECT_EQ(writer.frames(), kFrames);
    const auto written = writer.finish(path);
    ASSERT_TRUE(written.ok()) << written.error().message;

    auto reloaded = gltf::load_character(path);
    ASSERT_TRUE(reloaded.ok()) << reloaded.error().message;
    const animation::Character& out = reloaded.value();
    const animation::Character& source = crowd.character;

    // Structure: one animation, a skin per instance with the source's joints, the meshes
    // shared, the skinned mesh nodes at the scene root with their instance's skin.
    ASSERT_EQ(out.animations.size(), 1u);
    EXPECT_EQ(out.animations[0].name, "simulation");
    ASSERT_EQ(out.skins.size(), crowd.instances.size() * source.skins.size());
    for (const animation::Skin& skin : out.skins) EXPECT_EQ(skin.joints.size(), source.skins[0].joints.size());
    EXPECT_EQ(out.meshes.size(), source.meshes.size());
    std::set<int> skinned_mesh_nodes;
    for (std::size_t i = 0; i < crowd.instances.size(); ++i) {
        const int root = writer.output_node(i, -1);
        EXPECT_EQ(out.nodes.at(static_cast<std::size_t>(root)).name, crowd.instances[i].name);
        EXPECT_NE(std::find(out.roots.begin(), out.roots.end(), root), out.roots.end());
        for (std::size_t k = 0; k < source.nodes.size(); ++k) {
            const animation::Node& node = out.nodes.at(static_cast<std::size_t>(writer.output_node(i, static_cast<int>(k))));
            EXPECT_EQ(node.name, crowd.instances[i].name + "/" + source.nodes[k].name);
            if (source.nodes[k].skin < 0) continue;
            const int mesh_node = writer.skinned_mesh_node(i, static_cast<int>(k));
            skinned_mesh_nodes.insert(mesh_node);
            const animation::Node& holder = out.nodes.at(static_cast<std::size_t>(mesh_node));
            EXPECT_EQ(holder.parent, -1);
            EXPECT_NE(std::find(out.roots.begin(), out.roots.end(), mesh_node), out.roots.end());
            EXPECT_EQ(holder.mesh, source.nodes[k].mesh);
            ASSERT_GE(holder.skin, 0);
            const animation::Skin& skin = out.skins[static_cast<std::size_t>(holder.skin)];
            const animation::Skin& original = source.skins[static_cast<std::size_t>(source.nodes[k].skin)];
            for (std::size_t j = 0; j < skin.joints.size(); ++j) {
                EXPECT_EQ(skin.joints[j], writer.output_node(i, original.joints[j]));
            }
        }
    }
    EXPECT_EQ(skinned_mesh_nodes.size(), crowd.instances.size());
    EXPECT_EQ(out.roots.size(), 2 * crowd.instances.size());  // per instance its root and its skinned mesh

    // Every frame: the exported animation evaluated at the key's time against
    // placement * (the source pose), computed above from the source alone. The keys are
    // the frame's float32 values, so the difference is the rounding of composing ~5
    // transforms in another order (placement first, then the file's hierarchy) on
    // coordinates of a few units: a few ulps of ~5 (~5e-7 each), far below 1e-5.
    float worst = 0.0f;
    animation::Pose pose;
    std::size_t compared = 0;
    for (std::uint32_t f = 0; f < kFrames; ++f) {
        animation::evaluate(out, 0, static_cast<float>(f) / kFps, pose);
        for (std::size_t i = 0; i < crowd.instances.size(); ++i) {
            worst = std::max(worst, max_abs_difference(pose.world[static_cast<std::size_t>(writer.output_node(i, -1))],
                                                       placement_matrix(crowd.instances[i].placement)));
            for (std::size_t k = 0; k < source.nodes.size(); ++k) {
                const int node = writer.output_node(i, static_cast<int>(k));
                // A skinned mesh node moved to the scene root: skinning ignores its transform.
                if (skinned_mesh_nodes.count(node) != 0) continue;
                worst = std::max(worst, max_abs_difference(pose.world[static_cast<std::size_t>(node)], expected[f][i][k]));
                ++compared;
            }
        }
    }
    EXPECT_EQ(compared, kFrames * crowd.instances.size() * (source.nodes.size() - 1));
    EXPECT_LE(worst, 1e-5f);
    std::cout << "max |world difference| over " << compared << " node frames: " << worst << "\n";

    // The perturbed joints really move between frames (the test would pass vacuously
    // if the keys were constant).
    animation::evaluate(out, 0, 0.0f, pose);
    const glm::mat4 first = pose.world[static_cast<std::size_t>(writer.output_node(1, crowd.perturbed[1]))];
    animation::evaluate(out, 0, 5.0f / kFps, pose);
    EXPECT_GT(max_abs_difference(first, pose.world[static_cast<std::size_t>(writer.output_node(1, crowd.perturbed[1]))]), 1e-2f);
}

TEST(RiggedExport, PassesGltfValidator) {
    const RiggedSimpleCrowd crowd(3);
    TempDir dir;
    const std::string path = dir.file("crowd.glb");
    crowd.write(path, 20);
    expect_validates(path);

    // The source's VRM-free, data-URI buffer ends up as the one GLB buffer.
    tinygltf::Model model;
    ASSERT_TRUE(load_glb(path, model));
    ASSERT_EQ(model.buffers.size(), 1u);
    EXPECT_TRUE(model.buffers[0].uri.empty());
    EXPECT_EQ(model.materials.size(), 1u);
    EXPECT_EQ(model.meshes.size(), 1u);
    ASSERT_EQ(model.animations.size(), 1u);
    // Per instance and animated node translation and rotation; scale only where it changes.
    std::size_t animated = 0;
    for (const bool a : crowd.animated) animated += a ? 1 : 0;
    EXPECT_GE(model.animations[0].channels.size(), 2 * animated * crowd.instances.size());
}

/// An animated skinned mesh node keeps its place (and channels) in the hierarchy; its
/// mesh moves to an extra node at the scene root.
TEST(RiggedExport, AnimatedSkinnedMeshNodeGetsAnExtraMeshNode) {
    RiggedSimpleCrowd crowd(2);
    int skinned = -1;
    for (std::size_t k = 0; k < crowd.nodes(); ++k) {
        if (crowd.character.nodes[k].skin >= 0) skinned = static_cast<int>(k);
    }
    ASSERT_GE(skinned, 0);
    crowd.animated[static_cast<std::size_t>(skinned)] = true;
    TempDir dir;
    const std::string path = dir.file("crowd.glb");
    crowd.write(path, 6);
    expect_validates(path);

    const RiggedGlbWriter writer = crowd.writer();  // the same layout, to look indices up
    auto reloaded = gltf::load_character(path);
    ASSERT_TRUE(reloaded.ok()) << reloaded.error().message;
    const animation::Character& out = reloaded.value();
    EXPECT_EQ(out.nodes.size(), crowd.instances.size() * (crowd.nodes() + 2));
    const int parent = crowd.character.nodes[static_cast<std::size_t>(skinned)].parent;
    for (std::size_t i = 0; i < crowd.instances.size(); ++i) {
        const animation::Node& kept = out.nodes.at(static_cast<std::size_t>(writer.output_node(i, skinned)));
        EXPECT_EQ(kept.mesh, -1);
        EXPECT_EQ(kept.skin, -1);
        EXPECT_EQ(kept.parent, parent < 0 ? writer.output_node(i, -1) : writer.output_node(i, parent));
        const int holder = writer.skinned_mesh_node(i, skinned);
        EXPECT_NE(holder, writer.output_node(i, skinned));
        const animation::Node& mesh_node = out.nodes.at(static_cast<std::size_t>(holder));
        EXPECT_EQ(mesh_node.name, kept.name + "/skinned mesh");
        EXPECT_EQ(mesh_node.parent, -1);
        EXPECT_GE(mesh_node.skin, 0);
        EXPECT_NE(std::find(out.roots.begin(), out.roots.end(), holder), out.roots.end());
        const bool has_channel = std::any_of(out.animations.at(0).channels.begin(), out.animations.at(0).channels.end(),
                                             [&](const animation::Channel& c) { return c.node == writer.output_node(i, skinned); });
        EXPECT_TRUE(has_channel);
    }
}

/// A .gltf whose buffer is an external .bin file (VRMC_springBone sample): the export is
/// one self-contained .glb, without the VRM extension, that validates.
TEST(RiggedExport, ExternalBinSourceBecomesSelfContainedGlb) {
    const std::string source = asset("vrm-springbone/sphere-collider.gltf");
    auto character = gltf::load_character(source);
    ASSERT_TRUE(character.ok()) << character.error().message;
    const std::size_t n = character.value().nodes.size();
    std::vector<bool> animated(n, false);
    for (std::size_t k = 0; k < n; ++k) animated[k] = character.value().nodes[k].name.rfind("Spring", 0) == 0;
    const std::vector<RiggedInstance> instances = {{"left", {{-2.0f, 0.0f, 0.0f}, glm::quat(1.0f, 0.0f, 0.0f, 0.0f)}},
                                                   {"right", {{2.0f, 0.0f, 0.0f}, glm::quat(1.0f, 0.0f, 0.0f, 0.0f)}}};
    auto created = RiggedGlbWriter::create(source, character.value(), instances, animated, kFps, "springs");
    ASSERT_TRUE(created.ok()) << created.error().message;
    RiggedGlbWriter& writer = created.value();
    const animation::Pose rest = animation::rest_pose(character.value());
    for (std::uint32_t f = 0; f < 12; ++f) {
        std::vector<glm::vec3> t;
        std::vector<glm::quat> r;
        std::vector<glm::vec3> s;
        for (std::size_t i = 0; i < instances.size(); ++i) {
            for (std::size_t k = 0; k < n; ++k) {
                t.push_back(rest.translation[k]);
                s.push_back(rest.scale[k]);
                const float angle = animated[k] ? 0.2f * std::sin(0.5f * static_cast<float>(f + k + i)) : 0.0f;
                r.push_back(rest.rotation[k] * glm::angleAxis(angle, glm::vec3(0.0f, 0.0f, 1.0f)));
            }
        }
        ASSERT_TRUE(writer.add_frame(t, r, s).ok());
    }
    TempDir dir;
    const std::string path = dir.file("springs.glb");
    const auto written = writer.finish(path);
    ASSERT_TRUE(written.ok()) << written.error().message;
    expect_validates(path);

    tinygltf::Model model;
    ASSERT_TRUE(load_glb(path, model));
    ASSERT_EQ(model.buffers.size(), 1u);
    EXPECT_TRUE(model.buffers[0].uri.empty());  // the BIN chunk: no sphere_mesh.bin needed
    EXPECT_EQ(model.extensions.count("VRMC_springBone"), 0u);
    EXPECT_EQ(std::count(model.extensionsUsed.begin(), model.extensionsUsed.end(), "VRMC_springBone"), 0);
    EXPECT_EQ(model.meshes.size(), 2u);
    EXPECT_EQ(model.nodes.size(), instances.size() * (1 + n));
    EXPECT_EQ(model.nodes.at(static_cast<std::size_t>(writer.output_node(1, 0))).name, "right/Spring A");
    // The non-skinned mesh nodes keep their place in the hierarchy.
    EXPECT_EQ(model.scenes.at(0).nodes, (std::vector<int>{writer.output_node(0, -1), writer.output_node(1, -1)}));
}

// A 1x1 RGB PNG.
const std::vector<unsigned char> kPng = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00,
    0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x08, 0x02, 0x00, 0x00, 0x00, 0x90, 0x77, 0x53, 0xde, 0x00, 0x00, 0x00,
    0x0c, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0xf8, 0xdf, 0xa0, 0x00, 0x00, 0x04, 0x21, 0x01, 0xa0, 0x4d,
    0xbf, 0x32, 0x90, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};

/// Images given by URI (an external file and a data URI) move into the GLB's buffer
/// unchanged; KHR_texture_transform stays, VRM extensions go, VRM's meta is kept.
TEST(RiggedExport, ImagesByUriMoveIntoTheGlb) {
    TempDir dir;
    // One textured triangle, its vertices in an external .bin.
    const std::vector<float> vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1};  // 3 positions, 3 uvs
    {
        std::ofstream bin(dir.file("tri.bin"), std::ios::binary);
        bin.write(reinterpret_cast<const char*>(vertices.data()), static_cast<std::streamsize>(vertices.size() * sizeof(float)));
        std::ofstream png(dir.file("albedo.png"), std::ios::binary);
        png.write(reinterpret_cast<const char*>(kPng.data()), static_cast<std::streamsize>(kPng.size()));
    }
    const nlohmann::json doc = {
        {"asset", {{"version", "2.0"}}},
        {"extensionsUsed", {"KHR_texture_transform", "VRMC_vrm", "VRMC_materials_mtoon"}},
        {"extensions", {{"VRMC_vrm", {{"specVersion", "1.0"}, {"meta", {{"name", "tri"}, {"authors", {"someone"}}}}}}}},
        {"buffers", {{{"uri", "tri.bin"}, {"byteLength", 60}}}},
        {"bufferViews", {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}, {"target", 34962}},
                         {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 24}, {"target", 34962}}}},
        {"accessors", {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"},
                        {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
                       {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}}}},
        {"images", {{{"uri", "albedo.png"}}, {{"uri", "data:image/png;base64," + base64(kPng)}}}},
        {"samplers", {{{"magFilter", 9729}}}},
        {"textures", {{{"source", 0}, {"sampler", 0}}, {{"source", 1}}}},
        {"materials",
         {{{"name", "skin"},
           {"pbrMetallicRoughness",
            {{"baseColorTexture", {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"scale", {2, 2}}}}}}}}}},
           {"emissiveTexture", {{"index", 1}}},
           {"emissiveFactor", {1, 1, 1}},
           {"extensions", {{"VRMC_materials_mtoon", {{"specVersion", "1.0"}}}}}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}}}, {"material", 0}}}}}}},
        {"nodes", {{{"name", "body"}, {"children", {1}}}, {{"name", "tri"}, {"mesh", 0}}}},
        {"scenes", {{{"nodes", {0}}}}},
        {"scene", 0},
    };
    const std::string source = dir.file("tri.gltf");
    {
        std::ofstream out(source);
        out << doc.dump(1);
    }
    auto character = gltf::load_character(source);
    ASSERT_TRUE(character.ok()) << character.error().message;
    const std::vector<RiggedInstance> instances = {{"a", {}}, {"b", {{1.0f, 0.0f, 0.0f}, glm::quat(1.0f, 0.0f, 0.0f, 0.0f)}}};
    auto created = RiggedGlbWriter::create(source, character.value(), instances, {false, true}, kFps, "spin");
    ASSERT_TRUE(created.ok()) << created.error().message;
    for (std::uint32_t f = 0; f < 3; ++f) {
        const glm::quat q = glm::angleAxis(0.3f * static_cast<float>(f), glm::vec3(0.0f, 0.0f, 1.0f));
        const std::vector<glm::vec3> t(4, glm::vec3(0.0f));
        const std::vector<glm::quat> r(4, q);
        const std::vector<glm::vec3> s(4, glm::vec3(1.0f));
        ASSERT_TRUE(created.value().add_frame(t, r, s).ok());
    }
    fs::create_directories(dir.path() / "out");
    const std::string path = (dir.path() / "out" / "tri.glb").string();
    const auto written = created.value().finish(path);
    ASSERT_TRUE(written.ok()) << written.error().message;
    expect_validates(path);

    tinygltf::Model model;
    ASSERT_TRUE(load_glb(path, model));
    ASSERT_EQ(model.images.size(), 2u);
    for (const tinygltf::Image& image : model.images) {
        EXPECT_TRUE(image.uri.empty());
        EXPECT_EQ(image.mimeType, "image/png");
        ASSERT_GE(image.bufferView, 0);
        const tinygltf::BufferView& view = model.bufferViews.at(static_cast<std::size_t>(image.bufferView));
        ASSERT_EQ(view.byteLength, kPng.size());
        const auto* begin = model.buffers.at(0).data.data() + view.byteOffset;
        EXPECT_TRUE(std::equal(kPng.begin(), kPng.end(), begin));
    }
    EXPECT_EQ(model.extensionsUsed, std::vector<std::string>{"KHR_texture_transform"});
    EXPECT_EQ(model.extensions.count("VRMC_vrm"), 0u);
    EXPECT_EQ(model.materials.at(0).extensions.count("VRMC_materials_mtoon"), 0u);
    EXPECT_EQ(model.materials.at(0).pbrMetallicRoughness.baseColorTexture.extensions.count("KHR_texture_transform"), 1u);
    ASSERT_TRUE(model.asset.extras.Has("vrmMeta"));
    EXPECT_EQ(model.asset.extras.Get("vrmMeta").Get("name").Get<std::string>(), "tri");
}

TEST(RiggedExport, MissingDirectoryIsAnErrorAndLeavesNothing) {
    const RiggedSimpleCrowd crowd(2);
    RiggedGlbWriter writer = crowd.writer();
    std::vector<glm::vec3> t;
    std::vector<glm::quat> r;
    std::vector<glm::vec3> s;
    crowd.frame(0, t, r, s);
    ASSERT_TRUE(writer.add_frame(t, r, s).ok());
    TempDir dir;
    const std::string path = dir.file("no-such-dir/crowd.glb");
    const auto written = writer.finish(path);
    ASSERT_FALSE(written.ok());
    EXPECT_EQ(written.error().kind, Error::Kind::Io);
    EXPECT_NE(written.error().message.find(path), std::string::npos) << written.error().message;
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(dir.entries().empty());
    // Failing to open the file leaves the writer usable.
    const auto retried = writer.finish(dir.file("crowd.glb"));
    ASSERT_TRUE(retried.ok()) << retried.error().message;
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"crowd.glb"});
}

TEST(RiggedExport, SourceThatDoesNotLoadIsAnError) {
    const RiggedSimpleCrowd crowd(1);
    TempDir dir;
    const std::string missing = dir.file("missing.gltf");
    auto created = RiggedGlbWriter::create(missing, crowd.character, crowd.instances, crowd.animated, kFps, "x");
    ASSERT_FALSE(created.ok());
    EXPECT_EQ(created.error().kind, Error::Kind::InvalidInput);  // a missing input file: bad input (issue 37)
    EXPECT_NE(created.error().message.find(missing), std::string::npos) << created.error().message;

    // Another file than the character's: the node counts differ.
    const std::string other = asset("vrm-springbone/sphere-collider.gltf");
    created = RiggedGlbWriter::create(other, crowd.character, crowd.instances, crowd.animated, kFps, "x");
    ASSERT_FALSE(created.ok());
    EXPECT_EQ(created.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(created.error().message.find(other), std::string::npos) << created.error().message;
}

TEST(RiggedExport, NonFiniteFrameIsAnError) {
    const RiggedSimpleCrowd crowd(2);
    RiggedGlbWriter writer = crowd.writer();
    std::vector<glm::vec3> t;
    std::vector<glm::quat> r;
    std::vector<glm::vec3> s;
    crowd.frame(0, t, r, s);
    t[crowd.nodes() + static_cast<std::size_t>(crowd.perturbed[1])].x = std::nanf("");
    const auto added = writer.add_frame(t, r, s);
    ASSERT_FALSE(added.ok());
    EXPECT_EQ(added.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(added.error().message.find("crowd1"), std::string::npos) << added.error().message;
    EXPECT_EQ(writer.frames(), 0u);
    TempDir dir;
    const auto written = writer.finish(dir.file("x.glb"));
    ASSERT_FALSE(written.ok());  // no frames
    EXPECT_TRUE(dir.entries().empty());
}

}  // namespace
}  // namespace kodawari
