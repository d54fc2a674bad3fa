// The shipped character scenes on every rod backend, against the CPU reference run.

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

#include <kodawari/vulkan/backend_factory.hpp>
#include <kodawari/vulkan/gpu_info.hpp>
#include <kodawari/backends/rod_backend.hpp>

#include "test_support.hpp"
#include <kodawari/scene/scene.hpp>
#include <kodawari/rods/kinematics.hpp>
#include <kodawari/rods/solver.hpp>
#include <kodawari/rods/world.hpp>

#include "character_support.hpp"

using namespace kodawari::testing_support::characters;  // the character suites' shared helpers

// ---------------------------------------------------------------------------------------
// The shipped character scenes on every rod backend (rod_backend.hpp): the RodScene's
// world and frames are what the backends take, and they agree with the loop above.

namespace {

class CharacterBackends : public ::testing::TestWithParam<kodawari::testing_support::BackendCase> {
protected:
    void SetUp() override {
        if (GetParam() == kodawari::BackendKind::Vulkan) {
            if (const std::string why = kodawari::testing_support::no_vulkan_device_reason(); !why.empty()) {
                GTEST_SKIP() << why;
            }
        }
        auto made = kodawari::make_rod_backend(GetParam(), kodawari::testing_support::backend_options(GetParam()));
        ASSERT_TRUE(made.ok()) << made.error().message;
        backend_ = std::move(made).value();
    }
    void TearDown() override {
        if (backend_) {
            EXPECT_EQ(backend_->validation_messages(), 0u) << "Vulkan validation reported problems (see stderr)";
        }
    }
    std::unique_ptr<kodawari::RodBackend> backend_;
};

// The largest distance of a joint of chain `c` in `snap` from the reference run `sim`, in
// the chain's lengths; worst_of_length(): over every chain.
float chain_off(const RodScene& rs, const Simulation& sim, const kodawari::ChainSnapshot& snap, std::uint32_t c) {
    const rods::ChainInstance& ch = rs.world.chains[c];
    const rods::Chain& chain = rs.world.templ(ch).chain;
    float length = 0.0f;
    for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) length += chain.segment_length[i];
    float worst = 0.0f;
    for (std::uint32_t i = 0; i < chain.joint_count; ++i) {
        worst = std::max(worst, glm::length(sim.x(c, i) - snap.positions[ch.joint_begin + i]) / length);
    }
    return worst;
}

float worst_of_length(const RodScene& rs, const Simulation& sim, const kodawari::ChainSnapshot& snap) {
    float worst = 0.0f;
    for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) worst = std::max(worst, chain_off(rs, sim, snap, c));
    return worst;
}

}  // namespace

// The first 2 s of each small scene (120 frames: lavapipe takes 2 to 40 ms a frame on a
// shared 2-core machine; the whole scenes ended within 9.3e-7 of the chain length of the
// reference). Bounds: the CPU backends run the reference's code, so the same bits;
// Vulkan within 1e-3 of the chain length (the rod backends' own 300-frame parity bound):
// GLSL's transcendental functions are a few ulp off, and those ~1e-7 m per frame
// compound through the dynamics and the collisions but stay bounded, as damping and the
// rest-pose attraction pull both runs towards the same rest shapes.
TEST_P(CharacterBackends, ShippedScenesMatchTheReference) {
    for (const char* file : {"scenes/bunny.json", "scenes/ahoge.json", "scenes/bangs.json"}) {
        const RodScene rs = build(load(file));
        rods::RodFrame frame;
        rs.frame(0, frame);
        ASSERT_TRUE(backend_->load(rs.world, frame).ok()) << file;
        Simulation sim(rs);
        const std::uint32_t frames = std::min(rs.frames, 121u);
        for (std::uint32_t f = 1; f < frames; ++f) {
            rs.frame(f, frame);
            const auto stepped = backend_->step(frame);
            ASSERT_TRUE(stepped.ok()) << file << ": " << stepped.error().message;
            sim.step(f);
        }
        kodawari::ChainSnapshot snap;
        ASSERT_TRUE(backend_->read(snap).ok());
        const float worst = worst_of_length(rs, sim, snap);
        std::printf("[ measured ] %s on %s, %u frames: max %.3g of the chain length from the reference\n", file,
                    kodawari::testing_support::case_name(GetParam()).c_str(), frames - 1, static_cast<double>(worst));
        if (GetParam() == kodawari::BackendKind::Vulkan) {
            EXPECT_LT(worst, 1e-3f) << file;
        } else {
            EXPECT_EQ(worst, 0.0f) << file << ": the CPU backends run the reference's code";
        }
    }
}

// VRM's collider model on every backend (issue 18): a walking, turning crowd of 37
// characters (148 chains: not a multiple of the batch or workgroup size) whose chains
// each have their own collider set (outside spheres and capsules, an inside sphere, an
// inside capsule, a plane; one chain all of them, the insides wide enough for it to keep
// to both at once: conflicting constraints make a chain chaotic, and any rounding then
// grows to centimetres) and half of which measure their inertia in the body's space
// (`center`), all with the shipped scenes' damping (3/s). Bounds: the CPU backends the
// reference's bits; Vulkan within 1e-3 of the chain length at the end (as
// ShippedScenesMatchTheReference), and in every frame within 1e-3 for chains c and d
// and 5e-3 for chains a and b. Those two hang longer than their inside collider is wide,
// so they are pressed into it, and a pressed chain amplifies rounding for a while: with
// the dynamic follow-the-leader correction (issue 39: the sweep no longer drains energy)
// Vulkan's few-ulp differences grew to 2.7e-3 of b's length around frame 40 and damping
// drew the runs back to 1.7e-4 by frame 120. At damping 1/s the same chains are chaotic
// (the reference with its inside radii 1e-7 m wider ends a third of b's length away;
// docs/models.md), so no backend can be held to another's bits there. Also checks, on
// the reference run, that each chain kept to its own colliders (gap >= -1e-5 m: the
// projection leaves a particle on the bound, to rounding) and that chains a, b and c
// touched theirs, so the collider sets are really in play.
TEST_P(CharacterBackends, ColliderKindsGroupsAndCentersMatchTheReference) {
    const std::string text = R"({
      "format": "kodawari-scene", "version": 2, "name": "colliders", "fps": 60, "duration": 2,
      "camera": {"orbit": {"target": [0, 1.5, 0], "radius": 3, "period": 8}},
      "characters": [{
        "name": "probe",
        "physics": {"stiffness": 0.6, "damping": 3},
        "skeleton": [
          {"name": "body", "position": [0, 0.9, 0]},
          {"name": "head", "parent": "body", "position": [0, 0.6, 0]}
        ],
        "motions": [
          {"type": "walk", "speed": 1.5, "turn_rate_deg": 60, "bob": 0.04, "step_frequency": 2, "ramp_in": 0.2},
          {"type": "head_turn", "amplitude_deg": 40, "frequency": 0.7}
        ],
        "colliders": [
          {"name": "skull", "type": "sphere", "joint": "head", "center": [0, 0.05, 0], "radius": 0.1},
          {"name": "torso", "type": "capsule", "joint": "body", "a": [0, 0.1, 0], "b": [0, 0.45, 0], "radius": 0.14},
          {"name": "cage", "type": "sphere", "joint": "head", "center": [0, 0.1, 0.1], "radius": 0.35, "inside": true},
          {"name": "tube", "type": "capsule", "joint": "head", "a": [-0.1, 0, -0.05], "b": [0.1, 0, -0.05], "radius": 0.35, "inside": true},
          {"name": "floor", "type": "plane", "joint": "body", "point": [0, 0.2, 0], "normal": [0, 1, 0.3]}
        ],
        "chains": [
          {"name": "a", "joint": "head", "offset": {"position": [0.05, 0.1, 0.1]}, "colliders": ["skull", "cage"],
           "shape": {"arc": {"joints": 7, "length": 0.45, "direction": [0, -1, 0.2], "bend_axis": [1, 0, 0], "curl_deg": 20}}},
          {"name": "b", "joint": "head", "offset": {"position": [-0.05, 0.1, -0.1]}, "colliders": ["tube", "skull"], "center": "body",
           "shape": {"arc": {"joints": 9, "length": 0.5, "direction": [0, -1, -0.3], "bend_axis": [1, 0, 0], "curl_deg": 10}}},
          {"name": "c", "joint": "body", "offset": {"position": [0.1, 0.3, 0.15]}, "colliders": ["floor", "torso"], "center": "body",
           "shape": {"arc": {"joints": 6, "length": 0.5, "direction": [0.3, -1, 0.2], "bend_axis": [0, 0, 1], "curl_deg": 5}}},
          {"name": "d", "joint": "head", "offset": {"position": [0, 0.16, 0]},
           "shape": {"arc": {"joints": 5, "length": 0.2, "direction": [0, 1, 0], "bend_axis": [1, 0, 0], "curl_deg": 30}}}
        ]
      }],
      "crowds": [{"character": "probe", "count": 37, "spacing": 2, "time_offset": 1}]
    })";
    auto parsed = kodawari::parse_scene(text, "colliders.json");
    ASSERT_TRUE(parsed.ok()) << parsed.error().message;
    const RodScene rs = build(parsed.value());
    ASSERT_EQ(rs.world.chains.size(), 148u);
    ASSERT_EQ(rs.world.center_count, 74u);
    // Chain d has all five colliders; a, b and c their own runs after them.
    EXPECT_EQ(rs.world.chains[3].collider_count, 5u);
    EXPECT_EQ(rs.world.chains[0].collider_count, 2u);
    rods::RodFrame frame;
    rs.frame(0, frame);
    ASSERT_TRUE(backend_->load(rs.world, frame).ok());
    Simulation sim(rs);
    const bool vulkan = GetParam() == kodawari::BackendKind::Vulkan;
    // Vulkan's worst distance from the reference over the run per chain (a, b, c, d), as
    // a share of its length.
    float over_run[4] = {0, 0, 0, 0};
    std::vector<float> nearest(rs.world.chains.size(), 1e9f);
    float violated = 0.0f;
    for (std::uint32_t f = 1; f <= 120; ++f) {
        rs.frame(f, frame);
        const auto stepped = backend_->step(frame);
        ASSERT_TRUE(stepped.ok()) << stepped.error().message;
        sim.step(f);
        if (vulkan) {
            kodawari::ChainSnapshot now;
            ASSERT_TRUE(backend_->read(now).ok());
            for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
                over_run[c % 4] = std::max(over_run[c % 4], chain_off(rs, sim, now, c));
            }
        }
        for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
            const rods::ChainInstance& ch = rs.world.chains[c];
            const rods::Chain& chain = rs.world.templ(ch).chain;
            for (std::uint32_t k = 0; k < ch.collider_count; ++k) {
                for (std::uint32_t i = 1; i < chain.joint_count; ++i) {
                    const float gap = rods::collider_gap(frame.colliders[ch.collider_begin + k], sim.x(c, i), chain.thickness);
                    violated = std::max(violated, -gap);
                    nearest[c] = std::min(nearest[c], gap);
                }
            }
        }
    }
    EXPECT_LT(violated, 1e-5f) << "a particle ended a frame inside what its colliders forbid";
    for (std::uint32_t c = 0; c < 3; ++c) EXPECT_LT(nearest[c], 1e-4f) << "chain " << c << " never touched its colliders";
    kodawari::ChainSnapshot snap;
    ASSERT_TRUE(backend_->read(snap).ok());
    const float worst = worst_of_length(rs, sim, snap);
    std::printf("[ measured ] collider kinds, groups and centers on %s: max %.3g of the chain length from the reference\n",
                kodawari::testing_support::case_name(GetParam()).c_str(), static_cast<double>(worst));
    if (vulkan) {
        EXPECT_LT(worst, 1e-3f);
        const char* names = "abcd";
        for (int k = 0; k < 4; ++k) {
            std::printf("[ measured ] chain %c: at most %.3g of its length from the reference in any frame\n", names[k],
                        static_cast<double>(over_run[k]));
            EXPECT_LT(over_run[k], k < 2 ? 5e-3f : 1e-3f) << "chain " << names[k];
        }
    } else {
        EXPECT_EQ(worst, 0.0f) << "the CPU backends run the reference's code";
    }
}

// Issue 18's crowd of 200 VRoid-class avatars (scenes/avatars.json: the VRM 1.0 avatar
// and its VRM 0.x twin, 100 each, walking a circle or standing idle with the retargeted
// VRM Animation clips, their springs keeping to their own collider groups and one to its
// center): 6 400 chains, 60 frames on every backend against the CPU reference. Bounds as
// above: the CPU backends the reference's bits; Vulkan within 1e-3 of a chain's length.
TEST_P(CharacterBackends, AvatarCrowdOf200MatchesTheReference) {
    Scene scene = load("scenes/avatars.json");
    ASSERT_EQ(scene.crowds.size(), 2u);
    for (kodawari::CrowdSpec& crowd : scene.crowds) {
        crowd.count = 100;
        crowd.instances.clear();
    }
    const RodScene rs = build(scene);
    ASSERT_EQ(rs.instances.size(), 200u);
    rods::RodFrame frame;
    rs.frame(0, frame);
    ASSERT_TRUE(backend_->load(rs.world, frame).ok());
    Simulation sim(rs);
    for (std::uint32_t f = 1; f <= 60; ++f) {
        rs.frame(f, frame);
        const auto stepped = backend_->step(frame);
        ASSERT_TRUE(stepped.ok()) << stepped.error().message;
        sim.step(f);
    }
    kodawari::ChainSnapshot snap;
    ASSERT_TRUE(backend_->read(snap).ok());
    const float worst = worst_of_length(rs, sim, snap);
    std::printf("[ measured ] avatar crowd, %zu chains x 60 frames on %s: max %.3g of the chain length from the reference\n",
                rs.world.chains.size(), kodawari::testing_support::case_name(GetParam()).c_str(), static_cast<double>(worst));
    if (GetParam() == kodawari::BackendKind::Vulkan) {
        EXPECT_LT(worst, 1e-3f);
    } else {
        EXPECT_EQ(worst, 0.0f) << "the CPU backends run the reference's code";
    }
}

// The vulkan kernel is specialized to the collider kinds and centers of the world it
// loaded (KW_RODS_SPEC_FEATURES: lavapipe would run the others' code masked): a frame
// bringing a kind the first frame did not have is refused with what to do, not run
// wrongly; the CPU backends take any kind at any frame.
TEST_P(CharacterBackends, AColliderKindTheWorldDidNotLoadWithIsRefusedOnVulkan) {
    const RodScene rs = build(load("scenes/bunny.json"));
    rods::RodFrame frame;
    rs.frame(0, frame);
    ASSERT_TRUE(backend_->load(rs.world, frame).ok());
    rs.frame(1, frame);
    ASSERT_FALSE(frame.colliders.empty());
    frame.colliders[0].kind = rods::ColliderKind::Plane;
    frame.colliders[0].b = glm::vec3(0.0f, 1.0f, 0.0f);
    const auto stepped = backend_->step(frame);
    if (GetParam() == kodawari::BackendKind::Vulkan) {
        ASSERT_FALSE(stepped.ok());
        EXPECT_NE(stepped.error().message.find("load() the world again"), std::string::npos) << stepped.error().message;
    } else {
        EXPECT_TRUE(stepped.ok()) << stepped.error().message;
    }
}

// The crowd's 8 192 chains load and step (one frame: the CPU reference takes seconds).
TEST_P(CharacterBackends, CrowdLoadsAndSteps) {
    const RodScene rs = build(load("scenes/crowd.json"));
    rods::RodFrame frame;
    rs.frame(0, frame);
    ASSERT_TRUE(backend_->load(rs.world, frame).ok());
    rs.frame(1, frame);
    const auto start = std::chrono::steady_clock::now();
    const auto stepped = backend_->step(frame);
    kodawari::ChainSnapshot snap;
    ASSERT_TRUE(stepped.ok()) << stepped.error().message;
    ASSERT_TRUE(backend_->read(snap).ok());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_EQ(snap.positions.size(), rs.world.joint_count);
    for (const glm::vec3& p : snap.positions) ASSERT_TRUE(std::isfinite(glm::dot(p, p)));
    std::printf("[ measured ] crowd on %s (%s): one frame of %zu chains in %.1f ms\n", kodawari::testing_support::case_name(GetParam()).c_str(),
                backend_->device().c_str(), rs.world.chains.size(), 1e3 * seconds);
}

INSTANTIATE_TEST_SUITE_P(All, CharacterBackends, kodawari::testing_support::all_backend_kinds(),
                         kodawari::testing_support::backend_test_name);

// Issue 39: the VRoid-class avatars of scenes/avatars.json (one VRM 1.0 and one VRM 0.x,
// walking the circle and standing idle: 64 springs, hair, skirt and bust against 46
// colliders) keep their springs' lengths and stay out of their colliders at every frame
// rate from 5 to 120 fps: at most 1% stretch or compression of any segment and 0.5 mm
// of penetration, at the end of every frame of 2 s (the issue's bounds; before it, a
// skirt particle ended 3.0 mm inside a leg collider with 9.7% stretch at 5 fps). The
// reference only: every backend runs its code (the parity tests above).
TEST(AvatarSprings, KeepLengthsAndCollidersAtEveryFrameRate) {
    for (const float fps : {5.0f, 24.0f, 60.0f, 120.0f}) {
        Scene scene = load("scenes/avatars.json");
        for (kodawari::CrowdSpec& crowd : scene.crowds) {
            crowd.count = 1;
            crowd.instances.clear();
        }
        scene.fps = fps;
        scene.duration = 2.0f;
        const RodScene rs = build(scene);
        Simulation sim(rs);
        float stretch = 0.0f, penetration = 0.0f;
        const std::uint32_t frames = static_cast<std::uint32_t>(std::lround(2.0f * fps));
        for (std::uint32_t f = 1; f <= frames; ++f) {
            sim.step(f);
            for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
                const rods::ChainInstance& ch = rs.world.chains[c];
                const rods::Chain& chain = rs.world.templ(ch).chain;
                for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) {
                    const float length = glm::length(sim.x(c, i + 1) - sim.x(c, i));
                    stretch = std::max(stretch, std::abs(length / chain.segment_length[i] - 1.0f));
                }
                for (std::uint32_t k = 0; k < ch.collider_count; ++k) {
                    for (std::uint32_t i = 1; i < chain.joint_count; ++i) {
                        const float gap = rods::collider_gap(sim.frame().colliders[ch.collider_begin + k], sim.x(c, i), chain.thickness);
                        penetration = std::max(penetration, -gap);
                    }
                }
            }
        }
        std::printf("[ measured ] avatars.json, %zu springs at %.0f fps for 2 s: stretch at most %.3g%%, penetration %.3g mm\n",
                    rs.world.chains.size(), static_cast<double>(fps), static_cast<double>(100.0f * stretch),
                    static_cast<double>(1000.0f * penetration));
        EXPECT_LE(stretch, 0.01f) << fps << " fps";
        EXPECT_LE(penetration, 5e-4f) << fps << " fps";
    }
}
