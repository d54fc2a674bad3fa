// glTF 2.0 character import (SPEC A.7, issue 4): a real rigged file, hand-written files
// whose interpolated values are known exactly, and one test per kind of bad input.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "kodawari/gltf/character.hpp"
#include "kodawari/gltf/import.hpp"
#include "test_support.hpp"

namespace kodawari {
namespace {

using testing_support::base64;

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kAssets = std::string(KODAWARI_SOURCE_DIR) + "/tests/assets";
const std::string kRiggedSimple = kAssets + "/khronos/RiggedSimple.gltf";

json read_json(const std::string& path) {
    std::ifstream in(path);
    return json::parse(in);
}

using testing_support::TempDir;

void write_bytes(const std::string& path, const std::vector<unsigned char>& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

void write_text(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
}

std::vector<unsigned char> read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A buffer of floats under construction; each add() returns the index of a new
// bufferView + accessor holding them.
struct Builder {
    json doc;
    std::vector<unsigned char> bytes;

    Builder() {
        doc["asset"] = {{"version", "2.0"}};
        doc["bufferViews"] = json::array();
        doc["accessors"] = json::array();
    }

    int add(const std::vector<float>& values, const std::string& type) {
        const std::size_t offset = bytes.size();
        bytes.resize(offset + values.size() * sizeof(float));
        std::memcpy(bytes.data() + offset, values.data(), values.size() * sizeof(float));
        const std::size_t comps = type == "SCALAR" ? 1 : type == "VEC3" ? 3 : type == "VEC4" ? 4 : 16;
        doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * 4}});
        doc["accessors"].push_back({{"bufferView", doc["bufferViews"].size() - 1},
                                    {"componentType", 5126},
                                    {"count", values.size() / comps},
                                    {"type", type}});
        return static_cast<int>(doc["accessors"].size() - 1);
    }

    // The document with its buffer as a data URI (§3.6.1).
    [[nodiscard]] json gltf() const {
        json d = doc;
        d["buffers"] = json::array({{{"byteLength", bytes.size()},
                                     {"uri", "data:application/octet-stream;base64," + base64(bytes)}}});
        return d;
    }

    // The same as a .glb: header, JSON chunk, BIN chunk (§4 GLB File Format).
    [[nodiscard]] std::vector<unsigned char> glb() const {
        json d = doc;
        d["buffers"] = json::array({{{"byteLength", bytes.size()}}});
        std::string text = d.dump();
        while (text.size() % 4 != 0) text += ' ';
        std::vector<unsigned char> bin = bytes;
        while (bin.size() % 4 != 0) bin.push_back(0);
        std::vector<unsigned char> out;
        auto u32 = [&](std::uint32_t v) {
            for (int i = 0; i < 4; ++i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
        };
        u32(0x46546C67u);
        u32(2);
        u32(static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
        u32(static_cast<std::uint32_t>(text.size()));
        u32(0x4E4F534Au);
        out.insert(out.end(), text.begin(), text.end());
        u32(static_cast<std::uint32_t>(bin.size()));
        u32(0x004E4942u);
        out.insert(out.end(), bin.begin(), bin.end());
        return out;
    }
};

// Two nodes (root 0 with child 1), a skin of both, and three animations:
//   0: times {0, 1, 3} on node 1: LINEAR translation, STEP scale, LINEAR rotation
//   1: times {0, 2} CUBICSPLINE translation and rotation of node 1
Builder tiny_character() {
    Builder b;
    const int times = b.add({0.0f, 1.0f, 3.0f}, "SCALAR");
    const int translations = b.add({0, 0, 0, 2, 4, -6, 2, 0, 0}, "VEC3");
    const int scales = b.add({1, 1, 1, 2, 2, 2, 3, 3, 3}, "VEC3");
    // 0, 180 degrees about z, then (0, 0, -0.6, -0.8): the same rotation as
    // (0, 0, 0.6, 0.8), on the far side of the sphere, so the shorter arc needs a flip.
    const int rotations = b.add({0, 0, 0, 1, 0, 0, 1, 0, 0, 0, -0.6f, -0.8f}, "VEC4");
    const int cubic_times = b.add({0.0f, 2.0f}, "SCALAR");
    // Per key: in-tangent, value, out-tangent.
    const int cubic_translations = b.add({9, 9, 9, 0, 1, 0, 1, 0, 2, /**/ 3, -1, 0, 1, 3, -1, 9, 9, 9}, "VEC3");
    const int cubic_rotations = b.add({0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, /**/ 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0}, "VEC4");
    const int ibm = b.add({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, /**/ 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1},
                          "MAT4");
    b.doc["scene"] = 0;
    b.doc["scenes"] = json::array({{{"nodes", {0}}}});
    b.doc["nodes"] = json::array({{{"name", "root"}, {"children", {1}}, {"translation", {0, 1, 0}}},
                                  {{"name", "tip"}, {"translation", {0, 1, 0}}}});
    b.doc["skins"] = json::array({{{"joints", {0, 1}}, {"inverseBindMatrices", ibm}, {"skeleton", 0}}});
    b.doc["animations"] = json::array(
        {{{"name", "keys"},
          {"samplers",
           {{{"input", times}, {"output", translations}, {"interpolation", "LINEAR"}},
            {{"input", times}, {"output", scales}, {"interpolation", "STEP"}},
            {{"input", times}, {"output", rotations}, {"interpolation", "LINEAR"}}}},
          {"channels",
           {{{"sampler", 0}, {"target", {{"node", 1}, {"path", "translation"}}}},
            {{"sampler", 1}, {"target", {{"node", 1}, {"path", "scale"}}}},
            {{"sampler", 2}, {"target", {{"node", 1}, {"path", "rotation"}}}}}}},
         {{"name", "cubic"},
          {"samplers",
           {{{"input", cubic_times}, {"output", cubic_translations}, {"interpolation", "CUBICSPLINE"}},
            {{"input", cubic_times}, {"output", cubic_rotations}, {"interpolation", "CUBICSPLINE"}}}},
          {"channels",
           {{{"sampler", 0}, {"target", {{"node", 1}, {"path", "translation"}}}},
            {{"sampler", 1}, {"target", {{"node", 1}, {"path", "rotation"}}}}}}}});
    return b;
}

gltf::Character load_ok(const std::string& path) {
    auto loaded = gltf::load_character(path);
    EXPECT_TRUE(loaded.ok()) << (loaded.ok() ? "" : loaded.error().message);
    if (!loaded.ok()) return {};
    return std::move(loaded).value();
}

// The error of loading `doc` (written as `name`): it must fail with `kind`, and its
// message must start with the file and contain `expected_path` and `words`.
void expect_error(const std::string& file, const std::string& expected_path, const std::string& words,
                  Error::Kind kind = Error::Kind::InvalidInput) {
    const auto loaded = gltf::load_character(file);
    ASSERT_FALSE(loaded.ok()) << file << " loaded";
    const std::string& message = loaded.error().message;
    EXPECT_EQ(loaded.error().kind, kind) << message;
    EXPECT_EQ(message.rfind(file + ": " + expected_path + ": ", 0), 0u) << message;
    EXPECT_NE(message.find(words), std::string::npos) << message;
}

void expect_doc_error(const TempDir& dir, const json& doc, const std::string& expected_path, const std::string& words,
                      Error::Kind kind = Error::Kind::InvalidInput) {
    const std::string file = dir.file("bad.gltf");
    write_text(file, doc.dump());
    expect_error(file, expected_path, words, kind);
}

// Double-precision local matrix of a tinygltf node (§3.5.3), with the TRS overridden
// when given.
glm::dmat4 raw_local(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
        glm::dmat4 m(1.0);
        for (int c = 0; c < 4; ++c) {
            for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[static_cast<std::size_t>(4 * c + r)];
        }
        return m;
    }
    glm::dvec3 t(0.0);
    glm::dquat q(1.0, 0.0, 0.0, 0.0);
    glm::dvec3 s(1.0);
    if (node.translation.size() == 3) t = {node.translation[0], node.translation[1], node.translation[2]};
    if (node.rotation.size() == 4) q = glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
    if (node.scale.size() == 3) s = {node.scale[0], node.scale[1], node.scale[2]};
    glm::dmat4 m = glm::mat4_cast(q);
    for (int c = 0; c < 3; ++c) m[c] *= s[c];
    m[3] = glm::dvec4(t, 1.0);
    return m;
}

double max_abs_diff(const glm::mat4& a, const glm::dmat4& b) {
    double d = 0.0;
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) d = std::max(d, std::abs(static_cast<double>(a[c][r]) - b[c][r]));
    }
    return d;
}

// ---------------------------------------------------------------------------------------

TEST(GltfImport, RiggedSimpleLoads) {
    const gltf::Character c = load_ok(kRiggedSimple);
    // From the file: Z_UP -> Armature -> {Bone -> Bone.001, Cylinder (mesh, skin)}.
    ASSERT_EQ(c.nodes.size(), 5u);
    EXPECT_EQ(c.nodes[0].name, "Z_UP");
    EXPECT_EQ(c.nodes[4].name, "Bone.001");
    EXPECT_EQ(c.nodes[0].parent, -1);
    EXPECT_EQ(c.nodes[1].parent, 0);
    EXPECT_EQ(c.nodes[2].parent, 1);
    EXPECT_EQ(c.nodes[3].parent, 1);
    EXPECT_EQ(c.nodes[4].parent, 3);
    EXPECT_EQ(c.nodes[1].children, (std::vector<int>{3, 2}));
    EXPECT_EQ(c.roots, std::vector<int>{0});
    EXPECT_EQ(c.order.size(), 5u);
    EXPECT_TRUE(c.nodes[0].matrix.has_value());
    EXPECT_FALSE(c.nodes[4].matrix.has_value());
    EXPECT_EQ(c.nodes[2].mesh, 0);
    EXPECT_EQ(c.nodes[2].skin, 0);
    ASSERT_EQ(c.meshes.size(), 1u);
    EXPECT_EQ(c.meshes[0].primitives, 1u);
    // The display geometry, against the file's own accessors (read independently here).
    ASSERT_EQ(c.meshes[0].triangles.size(), 1u);
    {
        const json doc = read_json(kRiggedSimple);
        const json& prim = doc["meshes"][0]["primitives"][0];
        const auto count = [&](const json& accessor) { return doc["accessors"][accessor.get<std::size_t>()]["count"].get<std::size_t>(); };
        const gltf::Mesh::Triangles& t = c.meshes[0].triangles[0];
        EXPECT_EQ(t.positions.size(), count(prim["attributes"]["POSITION"]));
        EXPECT_EQ(t.normals.size(), t.positions.size());
        EXPECT_EQ(t.joints.size(), t.positions.size());
        EXPECT_EQ(t.indices.size(), count(prim["indices"]));
        float worst = 0.0f;
        for (std::size_t v = 0; v < t.weights.size(); ++v) {
            worst = std::max(worst, std::abs(t.weights[v].x + t.weights[v].y + t.weights[v].z + t.weights[v].w - 1.0f));
            EXPECT_LT(std::max({t.joints[v].x, t.joints[v].y, t.joints[v].z, t.joints[v].w}), 2u);  // the skin has 2 joints
        }
        EXPECT_LT(worst, 1e-3f);  // glTF §3.7.3.3: weights sum to 1 (the file stores floats)
        for (const std::uint32_t i : t.indices) EXPECT_LT(i, t.positions.size());
    }
    ASSERT_EQ(c.skins.size(), 1u);
    EXPECT_EQ(c.skins[0].joints, (std::vector<int>{3, 4}));
    EXPECT_EQ(c.skins[0].skeleton, 3);
    EXPECT_EQ(c.skins[0].inverse_bind_matrices.size(), 2u);
    ASSERT_EQ(c.animations.size(), 1u);
    const gltf::Animation& a = c.animations[0];
    ASSERT_EQ(a.channels.size(), 3u);  // translation, rotation, scale of Bone.001
    for (const gltf::Channel& ch : a.channels) EXPECT_EQ(ch.node, 4);
    for (const gltf::Sampler& s : a.samplers) {
        EXPECT_EQ(s.times.size(), 50u);
        EXPECT_EQ(s.interpolation, gltf::Interpolation::Linear);
    }
    // Accessor 5's min / max in the file.
    EXPECT_FLOAT_EQ(a.start, 0.04166661947965622f);
    EXPECT_FLOAT_EQ(a.end, 2.083333015441895f);
}

// Skinning at rest (§3.7.3): world(joint) * IBM(joint) maps the mesh's bind space to the
// world, so when the rest pose is the bind pose it is the same matrix for every joint.
// RiggedSimple's exporter (COLLADA2GLTF) bound the mesh in the space under its root
// node "Z_UP", so that matrix is Z_UP's world matrix. Tolerance 1e-5: float matrices of
// magnitude ~4.
TEST(GltfImport, RiggedSimpleRestPoseIsBindPose) {
    const gltf::Character c = load_ok(kRiggedSimple);
    ASSERT_EQ(c.skins.size(), 1u);
    const gltf::Pose pose = gltf::rest_pose(c);
    const glm::dmat4 bind_space_inverse = glm::inverse(glm::dmat4(pose.world[0]));
    double worst = 0.0;
    for (std::size_t j = 0; j < c.skins[0].joints.size(); ++j) {
        const auto node = static_cast<std::size_t>(c.skins[0].joints[j]);
        const glm::dmat4 joint =
            bind_space_inverse * glm::dmat4(pose.world[node]) * glm::dmat4(c.skins[0].inverse_bind_matrices[j]);
        worst = std::max(worst, max_abs_diff(glm::mat4(1.0f), joint));
    }
    EXPECT_LT(worst, 1e-5);
    std::printf("RiggedSimple: rest joint matrices vs identity in bind space, worst %.3g\n", worst);
}

// The animation at keys, between keys and outside them: finite, unit rotations, and world
// matrices equal to an independent double-precision composition of the raw nodes walked
// up through tinygltf's children lists. At key times the animated values are read from
// the raw accessors. Tolerance 1e-5: float storage of values up to ~4.2 (float epsilon
// 1.2e-7 times a few products).
TEST(GltfImport, RiggedSimpleAnimationMatchesIndependentComposition) {
    const gltf::Character c = load_ok(kRiggedSimple);
    ASSERT_EQ(c.animations.size(), 1u);
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string err;
    std::string warn;
    ASSERT_TRUE(loader.LoadASCIIFromFile(&model, &err, &warn, kRiggedSimple)) << err;
    std::vector<int> parent(model.nodes.size(), -1);
    for (std::size_t i = 0; i < model.nodes.size(); ++i) {
        for (const int ch : model.nodes[i].children) parent[static_cast<std::size_t>(ch)] = static_cast<int>(i);
    }
    auto raw_floats = [&](int accessor_index, std::size_t element, std::size_t comps) {
        const tinygltf::Accessor& acc = model.accessors[static_cast<std::size_t>(accessor_index)];
        const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(acc.bufferView)];
        const std::size_t stride = view.byteStride ? view.byteStride : comps * 4;
        std::vector<double> out(comps);
        for (std::size_t k = 0; k < comps; ++k) {
            float f = 0.0f;
            std::memcpy(&f, model.buffers[0].data.data() + view.byteOffset + acc.byteOffset + element * stride + k * 4, 4);
            out[k] = f;
        }
        return out;
    };
    const tinygltf::Animation& raw = model.animations[0];
    const std::vector<double> first_time = raw_floats(raw.samplers[0].input, 0, 1);

    double worst = 0.0;
    gltf::Pose pose;
    const std::vector<float> times = {-1.0f, 0.0f, static_cast<float>(first_time[0]), 0.3f, 0.5f, 0.77f,
                                      1.0f,  1.5f, 2.0f, 2.083333015441895f, 5.0f};
    for (const float t : times) {
        gltf::evaluate(c, 0, t, pose);
        for (std::size_t i = 0; i < c.nodes.size(); ++i) {
            EXPECT_TRUE(std::isfinite(pose.translation[i].x + pose.translation[i].y + pose.translation[i].z));
            EXPECT_NEAR(glm::length(pose.rotation[i]), 1.0f, 1e-6f) << "t " << t << " node " << i;
        }
        for (std::size_t i = 0; i < model.nodes.size(); ++i) {
            glm::dmat4 world(1.0);
            for (int n = static_cast<int>(i); n >= 0; n = parent[static_cast<std::size_t>(n)]) {
                tinygltf::Node node = model.nodes[static_cast<std::size_t>(n)];
                if (n == 4) {  // the animated node: the pose's values
                    node.translation = {pose.translation[4].x, pose.translation[4].y, pose.translation[4].z};
                    node.rotation = {pose.rotation[4].x, pose.rotation[4].y, pose.rotation[4].z, pose.rotation[4].w};
                    node.scale = {pose.scale[4].x, pose.scale[4].y, pose.scale[4].z};
                }
                world = raw_local(node) * world;
            }
            worst = std::max(worst, max_abs_diff(pose.world[i], world));
        }
    }
    EXPECT_LT(worst, 1e-5);
    std::printf("RiggedSimple: world matrices vs independent composition, worst %.3g\n", worst);

    // At every key time the pose's animated values are the accessors' values, unchanged.
    const std::size_t keys = c.animations[0].samplers[0].times.size();
    for (std::size_t k = 0; k < keys; ++k) {
        const float t = static_cast<float>(raw_floats(raw.samplers[0].input, k, 1)[0]);
        gltf::evaluate(c, 0, t, pose);
        for (const tinygltf::AnimationChannel& ch : raw.channels) {
            const tinygltf::AnimationSampler& s = raw.samplers[static_cast<std::size_t>(ch.sampler)];
            if (ch.target_path == "rotation") {
                const std::vector<double> q = raw_floats(s.output, k, 4);
                EXPECT_EQ(pose.rotation[4].x, static_cast<float>(q[0]));
                EXPECT_EQ(pose.rotation[4].w, static_cast<float>(q[3]));
            } else {
                const std::vector<double> v = raw_floats(s.output, k, 3);
                const glm::vec3 got = ch.target_path == "translation" ? pose.translation[4] : pose.scale[4];
                EXPECT_EQ(got.z, static_cast<float>(v[2])) << ch.target_path << " key " << k;
            }
        }
    }
}

TEST(GltfImport, VrmSampleWithExternalBufferLoads) {
    for (const char* name : {"sphere-collider.gltf", "plane-collider.gltf", "inside-collider.gltf"}) {
        const gltf::Character c = load_ok(kAssets + "/vrm-springbone/" + name);
        EXPECT_EQ(c.nodes.size(), 6u) << name;
        EXPECT_EQ(c.order.size(), 6u) << name;
    }
}

// LINEAR and STEP (§3.11, Appendix C) on hand-written keys: exact at keys, expected
// values at midpoints. Tolerance at midpoints 1e-6: the expected values are rounded
// once to float (the evaluator works in double and rounds once too, so the actual error
// is at most one float ulp, ~1e-7 here).
TEST(GltfImport, LinearAndStepInterpolation) {
    TempDir dir;
    const std::string file = dir.file("tiny.gltf");
    write_text(file, tiny_character().gltf().dump());
    const gltf::Character c = load_ok(file);
    ASSERT_EQ(c.animations.size(), 2u);
    gltf::Pose pose;
    struct Expect {
        float t;
        glm::vec3 translation;
        glm::vec3 scale;
        glm::quat rotation;  // w, x, y, z
    };
    const float h = std::sqrt(0.5f);
    // Between keys 1 and 2 the far-side key (0,0,-0.6,-0.8) is flipped to (0,0,0.6,0.8);
    // the midpoint of two unit quaternions on the shorter arc is their normalized sum:
    // (0, 0, 1.6, 0.8) / |.| = (0, 0, 2, 1) / sqrt(5).
    const float s5 = 1.0f / std::sqrt(5.0f);
    const std::vector<Expect> expected = {
        {-1.0f, {0, 0, 0}, {1, 1, 1}, {1, 0, 0, 0}},          // before the first key: clamped
        {0.0f, {0, 0, 0}, {1, 1, 1}, {1, 0, 0, 0}},           // key 0
        {0.5f, {1, 2, -3}, {1, 1, 1}, {h, 0, 0, h}},          // midpoint 0-1: slerp = 90 degrees
        {0.999f, {1.998f, 3.996f, -5.994f}, {1, 1, 1}, {0, 0, 0, 0}},  // STEP holds key 0 until key 1
        {1.0f, {2, 4, -6}, {2, 2, 2}, {0, 0, 0, 1}},          // key 1
        {2.0f, {2, 2, -3}, {2, 2, 2}, {s5, 0, 0, 2 * s5}},    // midpoint 1-2
        {3.0f, {2, 0, 0}, {3, 3, 3}, {-0.8f, 0, 0, -0.6f}},   // key 2: the stored value, unflipped
        {7.0f, {2, 0, 0}, {3, 3, 3}, {-0.8f, 0, 0, -0.6f}},   // after the last key: clamped
    };
    for (const Expect& e : expected) {
        gltf::evaluate(c, 0, e.t, pose);
        const bool key = e.t <= 0.0f || e.t == 1.0f || e.t >= 3.0f;
        for (int k = 0; k < 3; ++k) {
            if (key) {
                EXPECT_EQ(pose.translation[1][k], e.translation[k]) << "t " << e.t;
            } else {
                EXPECT_NEAR(pose.translation[1][k], e.translation[k], 1e-6f) << "t " << e.t;
            }
            EXPECT_EQ(pose.scale[1][k], e.scale[k]) << "t " << e.t;  // STEP: always a key value
        }
        if (e.t == 0.999f) continue;  // the rotation there is checked only for being unit
        for (int k = 0; k < 4; ++k) {
            if (key) {
                EXPECT_EQ(pose.rotation[1][k], e.rotation[k]) << "t " << e.t;
            } else {
                EXPECT_NEAR(pose.rotation[1][k], e.rotation[k], 1e-6f) << "t " << e.t;
            }
        }
    }
    // World: root at (0,1,0), child local (2,2,-3) rotated/scaled nothing above: the
    // child's world translation is the sum (the root has no rotation).
    gltf::evaluate(c, 0, 2.0f, pose);
    EXPECT_NEAR(pose.world[1][3].x, 2.0f, 1e-6f);
    EXPECT_NEAR(pose.world[1][3].y, 3.0f, 1e-6f);
    EXPECT_NEAR(pose.world[1][3].z, -3.0f, 1e-6f);
}

// CUBICSPLINE (Appendix C): p(u) = (2u^3-3u^2+1) v_k + (u^3-2u^2+u) t_d b_k
// + (-2u^3+3u^2) v_k+1 + (u^3-u^2) t_d a_k+1, rotations normalized. Exact at keys;
// tolerance 1e-6 elsewhere (one float rounding of values of magnitude <= 3).
TEST(GltfImport, CubicSplineInterpolation) {
    TempDir dir;
    const std::string file = dir.file("tiny.gltf");
    write_text(file, tiny_character().gltf().dump());
    const gltf::Character c = load_ok(file);
    ASSERT_EQ(c.animations.size(), 2u);
    gltf::Pose pose;
    const glm::dvec3 v0(0, 1, 0), b0(1, 0, 2), a1(3, -1, 0), v1(1, 3, -1);
    const double td = 2.0;
    for (const double t : {0.5, 1.0, 1.5}) {
        const double u = t / td;
        const glm::dvec3 want = (2 * u * u * u - 3 * u * u + 1) * v0 + (u * u * u - 2 * u * u + u) * td * b0 +
                                (-2 * u * u * u + 3 * u * u) * v1 + (u * u * u - u * u) * td * a1;
        gltf::evaluate(c, 1, static_cast<float>(t), pose);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(pose.translation[1][k], want[k], 1e-6) << "t " << t;
    }
    // By hand at the midpoint: 0.5 v0 + 0.25 b0 + 0.5 v1 - 0.25 a1 = (0, 2.25, 0).
    gltf::evaluate(c, 1, 1.0f, pose);
    EXPECT_NEAR(pose.translation[1].y, 2.25f, 1e-6f);
    // Zero tangents between identity and 180 degrees about z: the midpoint (0,0,.5,.5)
    // normalizes to 90 degrees about z.
    const float h = std::sqrt(0.5f);
    EXPECT_NEAR(pose.rotation[1].z, h, 1e-6f);
    EXPECT_NEAR(pose.rotation[1].w, h, 1e-6f);
    EXPECT_NEAR(glm::length(pose.rotation[1]), 1.0f, 1e-6f);
    // Keys and clamping: the stored values, exactly.
    gltf::evaluate(c, 1, 0.0f, pose);
    EXPECT_EQ(pose.translation[1], glm::vec3(0, 1, 0));
    gltf::evaluate(c, 1, 2.0f, pose);
    EXPECT_EQ(pose.translation[1], glm::vec3(1, 3, -1));
    gltf::evaluate(c, 1, 9.0f, pose);
    EXPECT_EQ(pose.translation[1], glm::vec3(1, 3, -1));
    EXPECT_EQ(pose.rotation[1], glm::quat(0, 0, 0, 1));
}

TEST(GltfImport, GlbLoadsLikeGltf) {
    TempDir dir;
    const std::string file = dir.file("tiny.glb");
    write_bytes(file, tiny_character().glb());
    const gltf::Character c = load_ok(file);
    EXPECT_EQ(c.nodes.size(), 2u);
    ASSERT_EQ(c.skins.size(), 1u);
    EXPECT_EQ(c.skins[0].inverse_bind_matrices[1][3].y, -1.0f);
    EXPECT_EQ(c.animations.size(), 2u);
}

// --- bad input -------------------------------------------------------------------------

TEST(GltfImportErrors, UnreadableFileIsIo) {
    TempDir dir;
    const auto loaded = gltf::load_character(dir.file("absent.gltf"));
    ASSERT_FALSE(loaded.ok());
    EXPECT_EQ(loaded.error().kind, Error::Kind::Io);
    EXPECT_NE(loaded.error().message.find("absent.gltf"), std::string::npos) << loaded.error().message;
}

TEST(GltfImportErrors, TruncatedGltf) {
    TempDir dir;
    const std::vector<unsigned char> whole = read_all(kRiggedSimple);
    const std::string file = dir.file("RiggedSimple.gltf");
    write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(whole.size() / 2)));
    expect_error(file, "$", "invalid JSON");
    // Every cut must fail cleanly (none is a complete document); steps of 97 bytes keep
    // the test fast while hitting every part of the file.
    for (std::size_t n = 0; n < whole.size(); n += 97) {
        write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(n)));
        const auto loaded = gltf::load_character(file);
        ASSERT_FALSE(loaded.ok()) << n;
        EXPECT_EQ(loaded.error().message.rfind(file + ": ", 0), 0u) << loaded.error().message;
    }
}

TEST(GltfImportErrors, TruncatedGlb) {
    TempDir dir;
    const std::vector<unsigned char> whole = tiny_character().glb();
    const std::string file = dir.file("tiny.glb");
    write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.end() - 10));
    expect_error(file, "GLB header", "truncated");
    write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.begin() + 7));
    expect_error(file, "GLB header", "fewer than the 12-byte header");
    // Cuts every 7 bytes (7 is coprime with the 4-byte alignment of headers and chunks,
    // so every offset within a word is hit), each one a clean error.
    for (std::size_t n = 0; n < whole.size(); n += 7) {
        write_bytes(file, std::vector<unsigned char>(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(n)));
        const auto loaded = gltf::load_character(file);
        ASSERT_FALSE(loaded.ok()) << n;
        EXPECT_EQ(loaded.error().kind, Error::Kind::InvalidInput) << n;
        EXPECT_EQ(loaded.error().message.rfind(file + ": GLB ", 0), 0u) << loaded.error().message;
    }
}

TEST(GltfImportErrors, WrongMagic) {
    TempDir dir;
    std::vector<unsigned char> bytes = tiny_character().glb();
    bytes[1] = 'L';  // "gLTF"
    const std::string file = dir.file("tiny.glb");
    write_bytes(file, bytes);
    expect_error(file, "GLB header", "magic is \"gLTF\", expected \"glTF\"");
    // A JSON file named .glb is not a GLB either.
    write_text(file, tiny_character().gltf().dump());
    expect_error(file, "GLB header", "magic is \"{\\x22ac\"");
}

TEST(GltfImportErrors, AccessorOutOfRange) {
    TempDir dir;
    {
        Builder b = tiny_character();
        b.doc["accessors"][1]["count"] = 4;  // 4 VEC3 = 48 bytes in a 36-byte view
        expect_doc_error(dir, b.gltf(), "$.accessors[1]", "run past the end of bufferView 1 (36 bytes)");
    }
    {
        Builder b = tiny_character();
        b.doc["accessors"][1]["byteOffset"] = 4;
        expect_doc_error(dir, b.gltf(), "$.accessors[1]", "from byteOffset 4 run past the end");
    }
    {
        Builder b = tiny_character();
        b.doc["bufferViews"][1]["byteLength"] = 100000;  // past the buffer
        expect_doc_error(dir, b.gltf(), "$.bufferViews[1]", "run past the end of buffer 0");
    }
    {
        Builder b = tiny_character();
        b.doc["animations"][0]["samplers"][0]["output"] = 42;
        expect_doc_error(dir, b.gltf(), "$.animations[0].samplers[0].output", "accessor 42 does not exist");
    }
}

TEST(GltfImportErrors, NonInvertibleInverseBindMatrix) {
    TempDir dir;
    {
        Builder b = tiny_character();
        // A matrix scaling z by 0.
        const int singular = b.add({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, /**/ 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                                   "MAT4");
        b.doc["skins"][0]["inverseBindMatrices"] = singular;
        expect_doc_error(dir, b.gltf(), "$.skins[0].inverseBindMatrices[0]", "joint node 0 is not invertible");
    }
    {
        Builder b = tiny_character();
        const float nan = std::nanf("");
        const int bad = b.add({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, /**/ nan, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                              "MAT4");
        b.doc["skins"][0]["inverseBindMatrices"] = bad;
        expect_doc_error(dir, b.gltf(), "$.skins[0].inverseBindMatrices[1]", "is not a finite number");
    }
    {
        // Nearly singular relative to its size: columns of length 1, 1, 1 with the
        // third almost parallel to the first (|det| = 1e-8).
        Builder b = tiny_character();
        const float e = 1e-8f;
        const int bad = b.add({1, 0, 0, 0, 0, 1, 0, 0, 1, 0, e, 0, 0, 0, 0, 1, /**/ 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                              "MAT4");
        b.doc["skins"][0]["inverseBindMatrices"] = bad;
        expect_doc_error(dir, b.gltf(), "$.skins[0].inverseBindMatrices[0]", "not invertible");
    }
    {
        // A small but proper scale (1e-3 on every axis, det 1e-9) is accepted: the test is
        // relative to the matrix's size.
        Builder b = tiny_character();
        const float s = 1e-3f;
        const int small = b.add({s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0, 0, 0, 0, 1, /**/ 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                                "MAT4");
        b.doc["skins"][0]["inverseBindMatrices"] = small;
        const std::string file = dir.file("small.gltf");
        write_text(file, b.gltf().dump());
        const auto loaded = gltf::load_character(file);
        EXPECT_TRUE(loaded.ok()) << loaded.error().message;
    }
}

TEST(GltfImportErrors, SkinJoints) {
    TempDir dir;
    {
        Builder b = tiny_character();
        b.doc["skins"][0]["joints"] = json::array();
        b.doc["skins"][0].erase("inverseBindMatrices");
        expect_doc_error(dir, b.gltf(), "$.skins[0].joints", "at least one joint");
    }
    {
        Builder b = tiny_character();
        b.doc["skins"][0]["joints"] = {0, 17};
        expect_doc_error(dir, b.gltf(), "$.skins[0].joints[1]", "node 17 does not exist");
    }
    {
        Builder b = tiny_character();
        b.doc["skins"][0]["joints"] = {0, 1, 0};  // three joints, two matrices
        expect_doc_error(dir, b.gltf(), "$.skins[0].inverseBindMatrices", "2 matrices for 3 joints");
    }
}

TEST(GltfImportErrors, NodeTreeCycles) {
    TempDir dir;
    {
        Builder b = tiny_character();
        b.doc["nodes"][0]["children"] = {0};
        expect_doc_error(dir, b.gltf(), "$.nodes[0].children[0]", "node 0 is its own child");
    }
    {
        Builder b = tiny_character();
        b.doc["nodes"][1]["children"] = {0};  // 0 -> 1 -> 0
        expect_doc_error(dir, b.gltf(), "$.nodes[1].children[0]", "node 0 is its own ancestor (cycle 0 -> 1 -> 0)");
    }
    {
        Builder b = tiny_character();
        b.doc["nodes"].push_back({{"name", "second parent"}, {"children", {1}}});
        expect_doc_error(dir, b.gltf(), "$.nodes[2].children[0]", "node 1 already has parent node 0");
    }
    {
        Builder b = tiny_character();
        b.doc["nodes"][1]["children"] = {5};
        expect_doc_error(dir, b.gltf(), "$.nodes[1].children[0]", "node 5 does not exist");
    }
}

TEST(GltfImportErrors, MissingExternalBuffer) {
    TempDir dir;
    const std::string file = dir.file("sphere-collider.gltf");
    fs::copy_file(kAssets + "/vrm-springbone/sphere-collider.gltf", file);
    expect_error(file, "$.buffers[0].uri", "external buffer \"sphere_mesh.bin\" not found");
    // Present but shorter than declared.
    write_bytes(dir.file("sphere_mesh.bin"), std::vector<unsigned char>(100, 0));
    expect_error(file, "$.buffers[0]", "has 100 bytes (truncated)");
}

TEST(GltfImportErrors, AnimationProblems) {
    TempDir dir;
    {
        Builder b = tiny_character();
        b.doc["animations"][0]["channels"][0]["target"]["node"] = 9;
        expect_doc_error(dir, b.gltf(), "$.animations[0].channels[0].target.node", "node 9 does not exist");
    }
    {
        Builder b = tiny_character();
        b.doc["animations"][0]["samplers"][0]["interpolation"] = "SMOOTH";
        // tinygltf may reject the value itself; either way the error names the sampler.
        const std::string file = dir.file("bad.gltf");
        write_text(file, b.gltf().dump());
        const auto loaded = gltf::load_character(file);
        ASSERT_FALSE(loaded.ok());
        EXPECT_EQ(loaded.error().message.rfind(file + ": ", 0), 0u) << loaded.error().message;
    }
    {
        Builder b = tiny_character();
        const int times = b.add({0.0f, 1.0f, 1.0f}, "SCALAR");
        b.doc["animations"][0]["samplers"][0]["input"] = times;
        expect_doc_error(dir, b.gltf(), "$.animations[0].samplers[0].input", "key times must increase");
    }
    {
        Builder b = tiny_character();
        b.doc["animations"][0]["channels"][0]["sampler"] = 2;  // a VEC4 rotation sampler on translation
        b.doc["animations"][0]["channels"][2]["sampler"] = 0;
        expect_doc_error(dir, b.gltf(), "$.animations[0].samplers[2].output", "translation or scale needs VEC3");
    }
    {
        Builder b = tiny_character();
        b.doc["nodes"][1].erase("translation");
        b.doc["nodes"][1]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        expect_doc_error(dir, b.gltf(), "$.animations[0].channels[0].target.node", "has a matrix");
    }
}

}  // namespace
}  // namespace kodawari
