// The same test bodies against every pose backend: cpu-reference, cpu and vulkan (on
// lavapipe where there is no GPU, with validation and synchronization validation on:
// ctest sets KODAWARI_VALIDATION=1 and any message fails the test). cpu-reference is
// checked against hand-computed values; cpu must match it bit for bit, vulkan within a
// stated bound.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include <kodawari/shared/poses.h>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/animation/character.hpp"
#include "kodawari/gltf/import.hpp"
#include "kodawari/backends/pose_backend.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

using namespace kodawari;
using nlohmann::json;
using testing_support::TempDir;

namespace {

using testing_support::base64;

const std::string kRiggedSimple = std::string(KODAWARI_SOURCE_DIR) + "/tests/assets/khronos/RiggedSimple.gltf";

// 203 instances: 3 full workgroups and a partial one.
constexpr std::size_t kInstances = 203;

// The vulkan bound, as a fraction of the character's size (below), on the largest
// difference of a world-matrix entry from cpu-reference. Both sides pick the same keys
// (the key search and the clip time are exact on both), so only rounding differs: the
// CPU interpolates in double and rounds once, the kernel interpolates in float (the
// parameter u, lerp, slerp's atan and polynomial, the Hermite weights: a few ulp, ~1e-7
// relative) and composes parent * local in a different association with the placement
// (one more rounding per level and entry). Placements up to 10 sizes away scale the
// absolute rounding of the translation column by 10. So ~1e-6 of the size is expected;
// 1e-5 leaves a 10x margin and still fails for any wrong key, wrap, arc or formula
// (those move entries by 1e-3 or more of the size).
constexpr double kVulkanBound = 1e-5;

// A small deterministic generator (the same numbers on every platform, unlike the
// standard distributions).
struct Lcg {
    std::uint64_t state;
    // Uniform in [0, 1).
    double next() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * (1.0 / 9007199254740992.0);
    }
    float between(double lo, double hi) { return static_cast<float>(lo + (hi - lo) * next()); }
};

// The largest distance between two node origins at rest (1 when all coincide): what
// the errors are measured against.
double character_size(const animation::Character& c) {
    const animation::Pose rest = animation::rest_pose(c);
    double size = 0.0;
    for (const glm::mat4& a : rest.world) {
        for (const glm::mat4& b : rest.world) size = std::max(size, static_cast<double>(glm::length(glm::vec3(a[3] - b[3]))));
    }
    return size > 0.0 ? size : 1.0;
}

// A crowd: every fifth instance at rest, the others on clip (i % clips); every third
// without a time offset (so that scene times on keys and wraps are sampled exactly
// there), every seventh not looping; placements up to 10 sizes away, turned anyhow.
std::vector<PoseInstance> crowd(const animation::Character& c, std::size_t count, std::uint64_t seed) {
    Lcg random{seed};
    const double size = character_size(c);
    std::vector<PoseInstance> out(count);
    for (std::size_t i = 0; i < count; ++i) {
        PoseInstance& p = out[i];
        p.placement.position = glm::vec3(random.between(-10 * size, 10 * size), random.between(-10 * size, 10 * size),
                                         random.between(-10 * size, 10 * size));
        p.placement.rotation = glm::normalize(glm::quat(random.between(-1, 1), random.between(-1, 1), random.between(-1, 1),
                                                        random.between(-1, 1)));
        p.clip = i % 5 == 0 ? -1 : static_cast<std::int32_t>(i % c.animations.size());
        p.time_offset = i % 3 == 0 ? 0.0f : random.between(-3.0, 3.0);
        p.loop = i % 7 != 3;
    }
    return out;
}

double max_abs_difference(const glm::mat4& a, const glm::mat4& b) {
    double d = 0.0;
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) d = std::max(d, std::abs(static_cast<double>(a[c][r]) - static_cast<double>(b[c][r])));
    }
    return d;
}

// ---- a tiny glTF written by the test ----------------------------------------------------

// Float accessors in one buffer; add() returns the new accessor's index.
struct GltfWriter {
    json doc = {{"asset", {{"version", "2.0"}}}, {"bufferViews", json::array()}, {"accessors", json::array()}};
    std::vector<unsigned char> bytes;

    int add(const std::vector<float>& values, const std::string& type) {
        const std::size_t offset = bytes.size();
        bytes.resize(offset + values.size() * sizeof(float));
        std::memcpy(bytes.data() + offset, values.data(), values.size() * sizeof(float));
        const std::size_t comps = type == "SCALAR" ? 1 : type == "VEC3" ? 3 : 4;
        doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * 4}});
        json accessor = {{"bufferView", doc["bufferViews"].size() - 1},
                         {"componentType", 5126},
                         {"count", values.size() / comps},
                         {"type", type}};
        if (type == "SCALAR") {  // animation inputs need min and max (§3.11)
            accessor["min"] = {*std::min_element(values.begin(), values.end())};
            accessor["max"] = {*std::max_element(values.begin(), values.end())};
        }
        doc["accessors"].push_back(accessor);
        return static_cast<int>(doc["accessors"].size() - 1);
    }

    // Writes the document with its buffer as a data URI (§3.6.1) and returns the path.
    std::string write(const TempDir& dir, const std::string& name) {
        doc["buffers"] = json::array({{{"byteLength", bytes.size()},
                                       {"uri", "data:application/octet-stream;base64," + base64(bytes)}}});
        const std::string path = dir.file(name);
        std::ofstream(path, std::ios::binary) << doc.dump();
        return path;
    }
};

const float kS45 = std::sqrt(0.5f);  // sin 45 degrees = cos 45 degrees

// Four nodes: "root" (0) given by a matrix (translation (1, 2, 3), 90 degrees about z,
// scale 2), its child "arm" (1) with child "hand" (2), and a second root "free" (3).
// Clip 0 "mixed", keys at 0.5, 1.5, 2.5 (d = 2):
//   arm:  STEP translation (0,0,1) (1,0,1) (1,2,1); CUBICSPLINE rotation identity,
//         90 degrees about y, 180 about y with zero tangents but an in-tangent on key 2
//   hand: CUBICSPLINE translation (0,1,0) out (2,0,0); (0,1,4) in (0,0,-2), out (1,1,1);
//         (3,0,0) in (0,0,0). CUBICSPLINE scale (1,1,1) out (1,0,0); (3,1,1) in (-1,0,0);
//         (1,1,2). STEP rotation 90 degrees about x, identity, 90 about z.
//   free: LINEAR translation (0,0,0) (2,0,0) (4,8,0) -- not seamless, so a wrong wrap shows
// Clip 1 "turns", keys at 0.1, 0.4, 0.7 (d = 0.6, not a power of two):
//   arm:  LINEAR rotation identity, 170 degrees about x, then 200 degrees about x written
//         as -q (15 degrees on along the shorter arc, which needs the flip); STEP scale
//         with one key only (at 0.4): (0.5, 1, 1)
//   free: STEP rotation identity, 90 about y, 45 about z
std::string write_tiny(const TempDir& dir) {
    GltfWriter w;
    const int times0 = w.add({0.5f, 1.5f, 2.5f}, "SCALAR");
    const int times1 = w.add({0.1f, 0.4f, 0.7f}, "SCALAR");
    const int one_key = w.add({0.4f}, "SCALAR");
    const float s85 = std::sin(glm::radians(85.0f));
    const float c85 = std::cos(glm::radians(85.0f));
    const float s100 = std::sin(glm::radians(100.0f));
    const float c100 = std::cos(glm::radians(100.0f));
    const float s225 = std::sin(glm::radians(22.5f));
    const float c225 = std::cos(glm::radians(22.5f));
    const int arm_t = w.add({0, 0, 1, 1, 0, 1, 1, 2, 1}, "VEC3");
    const int arm_r = w.add({0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0,            // key 0: in, value, out
                             0, 0, 0, 0, 0, kS45, 0, kS45, 0, 0, 0, 0,      // key 1
                             0, 0.5f, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0},        // key 2
                            "VEC4");
    const int hand_t = w.add({0, 0, 0, 0, 1, 0, 2, 0, 0,  //
                              0, 0, -2, 0, 1, 4, 1, 1, 1,  //
                              0, 0, 0, 3, 0, 0, 0, 0, 0},
                             "VEC3");
    const int hand_s = w.add({0, 0, 0, 1, 1, 1, 1, 0, 0,  //
                              -1, 0, 0, 3, 1, 1, 0, 0, 0,  //
                              0, 0, 0, 1, 1, 2, 0, 0, 0},
                             "VEC3");
    const int hand_r = w.add({kS45, 0, 0, kS45, 0, 0, 0, 1, 0, 0, kS45, kS45}, "VEC4");
    const int free_t = w.add({0, 0, 0, 2, 0, 0, 4, 8, 0}, "VEC3");
    const int turn_r = w.add({0, 0, 0, 1, s85, 0, 0, c85, -s100, 0, 0, -c100}, "VEC4");
    const int arm_s = w.add({0.5f, 1, 1}, "VEC3");
    const int free_r = w.add({0, 0, 0, 1, 0, kS45, 0, kS45, 0, 0, s225, c225}, "VEC4");
    w.doc["scene"] = 0;
    w.doc["scenes"] = json::array({{{"nodes", {0, 3}}}});
    w.doc["nodes"] = json::array({{{"name", "root"},
                                   {"children", {1}},
                                   {"matrix", {0, 2, 0, 0, -2, 0, 0, 0, 0, 0, 2, 0, 1, 2, 3, 1}}},
                                  {{"name", "arm"}, {"children", {2}}, {"translation", {0, 1, 0}}},
                                  {{"name", "hand"}, {"translation", {0, 1, 0}}},
                                  {{"name", "free"}, {"translation", {5, 0, 0}}, {"scale", {1, 2, 1}}}});
    auto sampler = [](int input, int output, const char* interpolation) {
        return json{{"input", input}, {"output", output}, {"interpolation", interpolation}};
    };
    auto channel = [](int s, int node, const char* path) {
        return json{{"sampler", s}, {"target", {{"node", node}, {"path", path}}}};
    };
    w.doc["animations"] = json::array(
        {{{"name", "mixed"},
          {"samplers",
           {sampler(times0, arm_t, "STEP"), sampler(times0, arm_r, "CUBICSPLINE"), sampler(times0, hand_t, "CUBICSPLINE"),
            sampler(times0, hand_s, "CUBICSPLINE"), sampler(times0, hand_r, "STEP"), sampler(times0, free_t, "LINEAR")}},
          // Not in node order, so the backends' sorting is exercised.
          {"channels",
           {channel(5, 3, "translation"), channel(2, 2, "translation"), channel(0, 1, "translation"), channel(3, 2, "scale"),
            channel(1, 1, "rotation"), channel(4, 2, "rotation")}}},
         {{"name", "turns"},
          {"samplers", {sampler(times1, turn_r, "LINEAR"), sampler(one_key, arm_s, "STEP"), sampler(times1, free_r, "STEP")}},
          {"channels", {channel(2, 3, "rotation"), channel(0, 1, "rotation"), channel(1, 1, "scale")}}}});
    return w.write(dir, "tiny.gltf");
}

animation::Character load(const std::string& path) {
    auto loaded = gltf::load_character(path);
    EXPECT_TRUE(loaded.ok()) << (loaded.ok() ? "" : loaded.error().message);
    if (!loaded.ok()) return {};
    return std::move(loaded).value();
}

glm::mat4 trs(glm::vec3 t, glm::quat r, glm::vec3 s) {
    return glm::translate(glm::mat4(1.0f), t) * glm::mat4_cast(r) * glm::scale(glm::mat4(1.0f), s);
}

class PoseBackends : public ::testing::TestWithParam<testing_support::BackendCase> {
protected:
    void SetUp() override {
        if (GetParam() == BackendKind::Vulkan) {
            if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
        }
        auto made = make_pose_backend(GetParam(), testing_support::backend_options(GetParam()));
        ASSERT_TRUE(made.ok()) << made.error().message;
        backend_ = std::move(made).value();
    }
    void TearDown() override {
        if (backend_) {
            EXPECT_EQ(backend_->validation_messages(), 0u) << "Vulkan validation reported problems (see stderr)";
        }
    }

    static std::vector<glm::mat4> evaluate(PoseBackend& backend, float time) {
        std::vector<glm::mat4> world;
        const auto evaluated = backend.evaluate(time);
        EXPECT_TRUE(evaluated.ok()) << evaluated.error().message;
        const auto read = backend.read(world);
        EXPECT_TRUE(read.ok()) << read.error().message;
        // Where the backend lends its matrices in place, they are read()'s, byte for byte.
        const std::span<const glm::mat4> lent = backend.host_world();
        if (!lent.empty()) {
            EXPECT_EQ(lent.size(), world.size());
            EXPECT_EQ(std::memcmp(lent.data(), world.data(), world.size() * sizeof(glm::mat4)), 0) << "host_world() differs from read()";
        } else if (!world.empty()) {
            EXPECT_EQ(backend.name(), "vulkan") << "the cpu kinds keep their matrices on the host";
        }
        return world;
    }

    // Loads `instances` of `c` on this backend and on cpu-reference and compares them at
    // every time: bit for bit for cpu, within kVulkanBound of the size for vulkan.
    void expect_matches_reference(const animation::Character& c, const std::vector<PoseInstance>& instances,
                                  const std::vector<float>& times, const char* what) {
        auto reference = make_pose_backend(BackendKind::CpuReference, {});
        ASSERT_TRUE(reference.ok());
        ASSERT_TRUE(reference.value()->load(c, instances).ok());
        const auto loaded = backend_->load(c, instances);
        ASSERT_TRUE(loaded.ok()) << loaded.error().message;
        const double size = character_size(c);
        double worst = 0.0;
        for (const float t : times) {
            const std::vector<glm::mat4> want = evaluate(*reference.value(), t);
            const std::vector<glm::mat4> got = evaluate(*backend_, t);
            ASSERT_EQ(got.size(), instances.size() * c.nodes.size());
            ASSERT_EQ(want.size(), got.size());
            double at_t = 0.0;
            std::size_t where = 0;
            for (std::size_t k = 0; k < want.size(); ++k) {
                const double d = max_abs_difference(want[k], got[k]) / size;
                ASSERT_TRUE(std::isfinite(d)) << "t " << t << ", matrix " << k;
                if (d > at_t) {
                    at_t = d;
                    where = k;
                }
            }
            EXPECT_LE(at_t, kVulkanBound) << what << ": t " << t << ", instance " << where / c.nodes.size() << ", node "
                                          << where % c.nodes.size();
            if (GetParam() != BackendKind::Vulkan) {
                EXPECT_EQ(std::memcmp(want.data(), got.data(), want.size() * sizeof(glm::mat4)), 0)
                    << what << ": t " << t << ": the CPU backends run the same code";
            }
            worst = std::max(worst, at_t);
        }
        std::printf("[ measured ] %s, %s: %zu instances x %zu nodes at %zu times: max %.3g of the size (%.3g)\n",
                    testing_support::case_name(GetParam()).c_str(), what, instances.size(), c.nodes.size(), times.size(), worst, size);
    }

    std::unique_ptr<PoseBackend> backend_;
};

}  // namespace

// RiggedSimple (LINEAR translation, rotation and scale of one bone, two matrix nodes above
// it): a crowd at times before the clip, on its first and last key, on keys in between,
// after it and on exact wrap points (start + k d), and at arbitrary times.
TEST_P(PoseBackends, RiggedSimpleCrowdMatchesTheReference) {
    const animation::Character c = load(kRiggedSimple);
    ASSERT_EQ(c.animations.size(), 1u);
    ASSERT_NE(kInstances % KW_POSES_WORKGROUP_SIZE, 0u) << "must exercise a partial workgroup";
    const animation::Animation& clip = c.animations[0];
    const std::vector<float>& keys = clip.samplers[0].times;
    const float d = clip.end - clip.start;
    const std::vector<float> times = {-5.0f,     0.0f,       clip.start,          keys[1],      keys[17],
                                      keys[48],  clip.end,   clip.start + d,      clip.start + 3.0f * d,
                                      0.3f,      0.77f,      1.5f,                2.0f,         3.1f,
                                      10.0f,     -123.456f};
    expect_matches_reference(c, crowd(c, kInstances, 1), times, "RiggedSimple");
}

// STEP and CUBICSPLINE on translation, rotation and scale, a matrix node, a LINEAR
// rotation across the far side of the sphere, a one-key channel and loop wraps (clip 1's
// d = 0.6 is not a power of two, so its wrap count needs a real division).
TEST_P(PoseBackends, StepAndCubicSplineMatchTheReference) {
    const TempDir dir;
    const animation::Character c = load(write_tiny(dir));
    ASSERT_EQ(c.animations.size(), 2u);
    std::vector<float> times = {-7.3f, 0.0f, 0.1f, 0.5f, 0.7f, 1.0f, 1.3f, 1.5f, 2.2f, 2.5f, 4.5f, 5.0f, 100.25f};
    Lcg random{7};
    for (int k = 0; k < 12; ++k) times.push_back(random.between(-4.0, 8.0));
    expect_matches_reference(c, crowd(c, kInstances, 2), times, "tiny STEP/CUBICSPLINE");
}

// More nodes than the kernel's uniform block holds (KW_POSES_UNIFORM_NODES): RiggedSimple
// with short chains added below its animated bone and below its root, so that nodes
// past the block are read from the storage buffer, animated ancestors and all.
TEST_P(PoseBackends, ManyNodesMatchTheReference) {
    animation::Character c = load(kRiggedSimple);
    ASSERT_EQ(c.animations.size(), 1u);
    const int animated = c.animations[0].channels[0].node;
    const int root = c.order[0];
    const int added = static_cast<int>(KW_POSES_UNIFORM_NODES) + 40;
    for (int k = 0; k < added; ++k) {
        const int index = static_cast<int>(c.nodes.size());
        animation::Node node;
        node.name = "added_" + std::to_string(k);
        // Chains of 3: a fresh start below the bone (or, every 4th chain, the root), then
        // below the node added just before.
        node.parent = k % 3 != 0 ? index - 1 : (k % 12 == 0 ? root : animated);
        node.translation = {0.01f * static_cast<float>(k % 5), 0.02f, -0.01f};
        node.rotation = glm::angleAxis(0.05f * static_cast<float>(k % 7), glm::normalize(glm::vec3(1.0f, static_cast<float>(k % 3), 0.5f)));
        node.scale = glm::vec3(1.0f + 0.01f * static_cast<float>(k % 4));
        c.nodes[static_cast<std::size_t>(node.parent)].children.push_back(index);
        c.nodes.push_back(node);
        c.order.push_back(index);
    }
    ASSERT_GT(c.nodes.size(), std::size_t{KW_POSES_UNIFORM_NODES});
    const animation::Animation& clip = c.animations[0];
    const std::vector<float> times = {-5.0f, clip.start, 0.3f, 0.77f, 1.5f, clip.end, 10.0f};
    expect_matches_reference(c, crowd(c, kInstances, 3), times, "RiggedSimple with many nodes");
}

// A matrix node whose bottom row is not (0, 0, 0, 1) (glTF wants matrices that decompose
// to TRS, §3.5.3; the importer does not check): the Vulkan kernel then stores every row
// instead of relying on the constant one it writes at load.
TEST_P(PoseBackends, NonAffineMatrixNodeMatchesTheReference) {
    const TempDir dir;
    animation::Character c = load(write_tiny(dir));
    ASSERT_TRUE(c.nodes[0].matrix.has_value());
    (*c.nodes[0].matrix)[0][3] = 0.01f;  // row 3, column 0
    (*c.nodes[0].matrix)[3][3] = 1.5f;
    const std::vector<float> times = {-1.0f, 0.3f, 1.0f, 2.2f, 4.5f};
    expect_matches_reference(c, crowd(c, kInstances, 4), times, "tiny with a non-affine matrix");
}

// Values worked out by hand, so that cpu-reference itself can fail (the other tests only
// compare the backends with it).
TEST_P(PoseBackends, TinyCharacterHasTheHandComputedPose) {
    const TempDir dir;
    const animation::Character c = load(write_tiny(dir));
    ASSERT_EQ(c.nodes.size(), 4u);
    PoseInstance placed;
    placed.placement.position = {10.0f, 0.0f, -1.0f};
    placed.placement.rotation = glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0));
    placed.clip = 0;
    PoseInstance once = placed;
    once.loop = false;
    PoseInstance rest = placed;
    rest.clip = -1;
    const std::vector<PoseInstance> instances = {placed, once, rest};
    ASSERT_TRUE(backend_->load(c, instances).ok());

    const glm::mat4 place = glm::translate(glm::mat4(1.0f), glm::vec3(10, 0, -1)) *
                            glm::mat4(glm::mat3(glm::vec3(0, 0, -1), glm::vec3(0, 1, 0), glm::vec3(1, 0, 0)));
    const glm::mat4 root(glm::vec4(0, 2, 0, 0), glm::vec4(-2, 0, 0, 0), glm::vec4(0, 0, 2, 0), glm::vec4(1, 2, 3, 1));
    const glm::quat identity(1.0f, 0.0f, 0.0f, 0.0f);
    const glm::quat x90(kS45, kS45, 0.0f, 0.0f);
    auto expect_pose = [&](const std::vector<glm::mat4>& world, std::size_t instance, const glm::mat4& arm,
                           const glm::mat4& hand, const glm::mat4& free, const char* what) {
        const glm::mat4 want[4] = {place * root, place * root * arm, place * root * arm * hand, place * free};
        for (std::size_t n = 0; n < 4; ++n) {
            EXPECT_LT(max_abs_difference(world[instance * 4 + n], want[n]), 2e-5) << what << ", node " << n;
        }
    };

    // Scene time 1.0: u = 0.5 in the first interval of clip 0. STEP: key 0. CUBICSPLINE
    // at u = 1/2 (t_d = 1): (p0 + p1) / 2 + (b0 - a1) / 8, so the arm turns by
    // normalize((0, s45, 0, 1 + c45) / 2) = 45 degrees about y, the hand moves to
    // (0, 1, 2) + ((2, 0, 0) - (0, 0, -2)) / 8 = (0.25, 1, 2.25) and scales to
    // (2, 1, 1) + ((1, 0, 0) - (-1, 0, 0)) / 8 = (2.25, 1, 1); LINEAR: (1, 0, 0).
    std::vector<glm::mat4> world = evaluate(*backend_, 1.0f);
    ASSERT_EQ(world.size(), 12u);
    const glm::quat y45(std::cos(glm::radians(22.5f)), 0.0f, std::sin(glm::radians(22.5f)), 0.0f);
    const glm::mat4 free_at_1 = trs({1, 0, 0}, identity, {1, 2, 1});
    expect_pose(world, 0, trs({0, 0, 1}, y45, {1, 1, 1}), trs({0.25f, 1, 2.25f}, x90, {2.25f, 1, 1}), free_at_1,
                "t 1.0, looping");
    expect_pose(world, 1, trs({0, 0, 1}, y45, {1, 1, 1}), trs({0.25f, 1, 2.25f}, x90, {2.25f, 1, 1}), free_at_1,
                "t 1.0, once");
    expect_pose(world, 2, trs({0, 1, 0}, identity, {1, 1, 1}), trs({0, 1, 0}, identity, {1, 1, 1}),
                trs({5, 0, 0}, identity, {1, 2, 1}), "rest");

    // Scene time 4.5 = start + 2 d: the looping instance wraps exactly onto key 0; the
    // other holds the last key.
    world = evaluate(*backend_, 4.5f);
    expect_pose(world, 0, trs({0, 0, 1}, identity, {1, 1, 1}), trs({0, 1, 0}, x90, {1, 1, 1}),
                trs({0, 0, 0}, identity, {1, 2, 1}), "t 4.5, looping");
    const glm::quat z90(kS45, 0.0f, 0.0f, kS45);
    const glm::quat y180(0.0f, 0.0f, 1.0f, 0.0f);
    expect_pose(world, 1, trs({1, 2, 1}, y180, {1, 1, 1}), trs({3, 0, 0}, z90, {1, 1, 2}),
                trs({4, 8, 0}, identity, {1, 2, 1}), "t 4.5, once");
}

// The same time twice gives the same bits (with another time in between).
TEST_P(PoseBackends, Deterministic) {
    const animation::Character c = load(kRiggedSimple);
    const std::vector<PoseInstance> instances = crowd(c, kInstances, 3);
    ASSERT_TRUE(backend_->load(c, instances).ok());
    const std::vector<glm::mat4> a = evaluate(*backend_, 0.9f);
    const std::vector<glm::mat4> other = evaluate(*backend_, 1.7f);
    const std::vector<glm::mat4> b = evaluate(*backend_, 0.9f);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::mat4)), 0);
    EXPECT_NE(std::memcmp(a.data(), other.data(), a.size() * sizeof(glm::mat4)), 0);
}

// evaluate_some(): every instance not allowed to keep its matrices has this time's (the
// reference's bits on the CPU backends); every one allowed has this time's or the last
// evaluation's, whole; the cpu backend keeps a batch of 16 whose instances all may, the
// reference and vulkan evaluate every instance. 203 instances of one clip, allowed to
// keep in runs of 16 and singly.
TEST_P(PoseBackends, EvaluateSomeKeepsWholeInstancesOrRenewsThem) {
    const TempDir dir;
    const animation::Character c = load(write_tiny(dir));
    // One clip, so that the cpu backend's batches are runs of 16 in instance order.
    std::vector<PoseInstance> instances = crowd(c, kInstances, 5);
    for (PoseInstance& p : instances) p.clip = 1;
    auto reference = make_pose_backend(BackendKind::CpuReference, {});
    ASSERT_TRUE(reference.ok());
    ASSERT_TRUE(reference.value()->load(c, instances).ok());
    ASSERT_TRUE(backend_->load(c, instances).ok());
    const std::size_t nodes = c.nodes.size();
    std::vector<std::uint8_t> may_keep(kInstances, 1);
    // The first evaluation after load() renews everything, whatever the allowance.
    ASSERT_TRUE(backend_->evaluate_some(0.4f, may_keep).ok());
    std::vector<glm::mat4> got;
    ASSERT_TRUE(backend_->read(got).ok());
    const double size = character_size(c);
    // Instance i of `got` is `want`'s: the same bits on the CPU backends, within
    // kVulkanBound of the size on vulkan.
    const auto same = [&](const std::vector<glm::mat4>& want, std::size_t i) {
        double worst = 0.0;
        for (std::size_t n = 0; n < nodes; ++n) worst = std::max(worst, max_abs_difference(want[i * nodes + n], got[i * nodes + n]) / size);
        return GetParam() == BackendKind::Vulkan ? worst <= kVulkanBound
                                                 : std::memcmp(&want[i * nodes], &got[i * nodes], nodes * sizeof(glm::mat4)) == 0;
    };
    const std::vector<glm::mat4> before = evaluate(*reference.value(), 0.4f);
    for (std::size_t i = 0; i < kInstances; ++i) EXPECT_TRUE(same(before, i)) << "instance " << i << " at the first evaluation";
    for (std::size_t i = 0; i < kInstances; ++i) may_keep[i] = (i / 16) % 2 == 1 || i % 7 == 3 ? 1 : 0;
    ASSERT_TRUE(backend_->evaluate_some(1.3f, may_keep).ok());
    ASSERT_TRUE(backend_->read(got).ok());
    const std::vector<glm::mat4> now = evaluate(*reference.value(), 1.3f);
    std::size_t kept = 0;
    for (std::size_t i = 0; i < kInstances; ++i) {
        if (may_keep[i] == 0) {
            EXPECT_TRUE(same(now, i)) << "instance " << i << " was to be evaluated at 1.3 s";
        } else if (same(before, i) && !same(now, i)) {
            ++kept;
        } else {
            EXPECT_TRUE(same(now, i)) << "instance " << i << ": neither the last nor this evaluation";
        }
    }
    std::printf("[ measured ] %s: %zu of %zu instances allowed to keep their matrices kept them\n",
                testing_support::case_name(GetParam()).c_str(), kept,
                static_cast<std::size_t>(std::count(may_keep.begin(), may_keep.end(), 1)));
    if (backend_->name() == "cpu") {
        EXPECT_GT(kept, 0u) << "the cpu backend skips batches whose instances all may keep";
    } else {
        EXPECT_EQ(kept, 0u) << "the others evaluate every instance";
    }
}

TEST_P(PoseBackends, RejectsAClipOutOfRangeNamingTheInstance) {
    const animation::Character c = load(kRiggedSimple);
    std::vector<PoseInstance> instances = crowd(c, 12, 4);
    instances[7].clip = 1;
    auto r = backend_->load(c, instances);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(r.error().message.find("instance 7: clip 1 does not exist"), std::string::npos) << r.error().message;
    instances[7].clip = -2;
    r = backend_->load(c, instances);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("instance 7: clip -2"), std::string::npos) << r.error().message;
    instances[7].clip = 0;
    instances[3].time_offset = std::nanf("");
    r = backend_->load(c, instances);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("instance 3: the time offset"), std::string::npos) << r.error().message;
    instances[3].time_offset = 0.0f;
    ASSERT_TRUE(backend_->load(c, instances).ok());
    EXPECT_FALSE(backend_->evaluate(std::numeric_limits<float>::infinity()).ok());
}

TEST_P(PoseBackends, NoInstancesIsFine) {
    const animation::Character c = load(kRiggedSimple);
    ASSERT_TRUE(backend_->load(c, {}).ok());
    std::vector<glm::mat4> world(3);
    ASSERT_TRUE(backend_->evaluate(1.0f).ok());
    ASSERT_TRUE(backend_->read(world).ok());
    EXPECT_TRUE(world.empty());
}

INSTANTIATE_TEST_SUITE_P(All, PoseBackends, testing_support::all_backend_kinds(), testing_support::backend_test_name);

// clip_time (pose_backend.hpp) on exact values: d = 2, so every step below is exact.
TEST(PoseClipTime, WrapsLoopsAndPassesOthersThrough) {
    animation::Animation clip;
    clip.start = 0.5f;
    clip.end = 2.5f;
    PoseInstance instance;
    instance.time_offset = 0.25f;
    // t = 5.25: 0.5 + 4.75 - 2 * floor(2.375) = 1.25.
    EXPECT_EQ(clip_time(clip, instance, 5.0f), 1.25f);
    // t = -1.25, before the start: 0.5 - 1.75 - 2 * floor(-0.875) = 0.75.
    EXPECT_EQ(clip_time(clip, instance, -1.5f), 0.75f);
    // Exactly on a wrap point (start + 2 d), and on the end: both the start.
    EXPECT_EQ(clip_time(clip, instance, 4.25f), 0.5f);
    EXPECT_EQ(clip_time(clip, instance, 2.25f), 0.5f);
    instance.loop = false;
    EXPECT_EQ(clip_time(clip, instance, 5.0f), 5.25f);
    EXPECT_EQ(clip_time(clip, instance, -1.5f), -1.25f);
    // A clip of one instant holds it.
    instance.loop = true;
    clip.end = clip.start;
    EXPECT_EQ(clip_time(clip, instance, 5.0f), 0.5f);
}
