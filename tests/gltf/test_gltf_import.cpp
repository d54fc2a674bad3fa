// glTF 2.0 character import (SPEC A.7, issue 4): a real rigged file, and hand-written
// files whose interpolated values are known exactly. Bad input: test_gltf_import_errors.cpp.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "gltf_import_support.hpp"

namespace kodawari {
namespace {

using namespace gltf_import_test;  // its helpers, TempDir, json and fs

// ---------------------------------------------------------------------------------------

TEST(GltfImport, RiggedSimpleLoads) {
    const animation::Character c = load_ok(kRiggedSimple);
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
        const animation::Mesh::Triangles& t = c.meshes[0].triangles[0];
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
    const animation::Animation& a = c.animations[0];
    ASSERT_EQ(a.channels.size(), 3u);  // translation, rotation, scale of Bone.001
    for (const animation::Channel& ch : a.channels) EXPECT_EQ(ch.node, 4);
    for (const animation::Sampler& s : a.samplers) {
        EXPECT_EQ(s.times.size(), 50u);
        EXPECT_EQ(s.interpolation, animation::Interpolation::Linear);
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
    const animation::Character c = load_ok(kRiggedSimple);
    ASSERT_EQ(c.skins.size(), 1u);
    const animation::Pose pose = animation::rest_pose(c);
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
    const animation::Character c = load_ok(kRiggedSimple);
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
    animation::Pose pose;
    const std::vector<float> times = {-1.0f, 0.0f, static_cast<float>(first_time[0]), 0.3f, 0.5f, 0.77f,
                                      1.0f,  1.5f, 2.0f, 2.083333015441895f, 5.0f};
    for (const float t : times) {
        animation::evaluate(c, 0, t, pose);
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
        animation::evaluate(c, 0, t, pose);
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
        const animation::Character c = load_ok(kAssets + "/vrm-springbone/" + name);
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
    const animation::Character c = load_ok(file);
    ASSERT_EQ(c.animations.size(), 2u);
    animation::Pose pose;
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
        animation::evaluate(c, 0, e.t, pose);
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
    animation::evaluate(c, 0, 2.0f, pose);
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
    const animation::Character c = load_ok(file);
    ASSERT_EQ(c.animations.size(), 2u);
    animation::Pose pose;
    const glm::dvec3 v0(0, 1, 0), b0(1, 0, 2), a1(3, -1, 0), v1(1, 3, -1);
    const double td = 2.0;
    for (const double t : {0.5, 1.0, 1.5}) {
        const double u = t / td;
        const glm::dvec3 want = (2 * u * u * u - 3 * u * u + 1) * v0 + (u * u * u - 2 * u * u + u) * td * b0 +
                                (-2 * u * u * u + 3 * u * u) * v1 + (u * u * u - u * u) * td * a1;
        animation::evaluate(c, 1, static_cast<float>(t), pose);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(pose.translation[1][k], want[k], 1e-6) << "t " << t;
    }
    // By hand at the midpoint: 0.5 v0 + 0.25 b0 + 0.5 v1 - 0.25 a1 = (0, 2.25, 0).
    animation::evaluate(c, 1, 1.0f, pose);
    EXPECT_NEAR(pose.translation[1].y, 2.25f, 1e-6f);
    // Zero tangents between identity and 180 degrees about z: the midpoint (0,0,.5,.5)
    // normalizes to 90 degrees about z.
    const float h = std::sqrt(0.5f);
    EXPECT_NEAR(pose.rotation[1].z, h, 1e-6f);
    EXPECT_NEAR(pose.rotation[1].w, h, 1e-6f);
    EXPECT_NEAR(glm::length(pose.rotation[1]), 1.0f, 1e-6f);
    // Keys and clamping: the stored values, exactly.
    animation::evaluate(c, 1, 0.0f, pose);
    EXPECT_EQ(pose.translation[1], glm::vec3(0, 1, 0));
    animation::evaluate(c, 1, 2.0f, pose);
    EXPECT_EQ(pose.translation[1], glm::vec3(1, 3, -1));
    animation::evaluate(c, 1, 9.0f, pose);
    EXPECT_EQ(pose.translation[1], glm::vec3(1, 3, -1));
    EXPECT_EQ(pose.rotation[1], glm::quat(0, 0, 0, 1));
}

TEST(GltfImport, GlbLoadsLikeGltf) {
    TempDir dir;
    const std::string file = dir.file("tiny.glb");
    write_bytes(file, tiny_character().glb());
    const animation::Character c = load_ok(file);
    EXPECT_EQ(c.nodes.size(), 2u);
    ASSERT_EQ(c.skins.size(), 1u);
    EXPECT_EQ(c.skins[0].inverse_bind_matrices[1][3].y, -1.0f);
    EXPECT_EQ(c.animations.size(), 2u);
}

}  // namespace
}  // namespace kodawari
