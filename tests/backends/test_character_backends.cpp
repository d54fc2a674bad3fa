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

#include <kodawari/backend_factory.hpp>
#include <kodawari/gpu_info.hpp>
#include <kodawari/rod_backend.hpp>

#include "test_support.hpp"
#include <kodawari/rod_scene.hpp>
#include <kodawari/rods/kinematics.hpp>
#include <kodawari/rods/solver.hpp>
#include <kodawari/rods/world.hpp>
#include <kodawari/scene.hpp>

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
        float worst = 0.0f;
        float length = 1e9f;
        for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
            const rods::ChainInstance& ch = rs.world.chains[c];
            const rods::Chain& chain = rs.world.templ(ch).chain;
            float l = 0.0f;
            for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) l += chain.segment_length[i];
            length = std::min(length, l);
            for (std::uint32_t i = 0; i < chain.joint_count; ++i) {
                worst = std::max(worst, glm::length(sim.x(c, i) - snap.positions[ch.joint_begin + i]));
            }
        }
        std::printf("[ measured ] %s on %s, %u frames: max %.3g of the chain length from the reference\n", file,
                    kodawari::testing_support::case_name(GetParam()).c_str(), frames - 1, static_cast<double>(worst / length));
        if (GetParam() == kodawari::BackendKind::Vulkan) {
            EXPECT_LT(worst, 1e-3f * length) << file;
        } else {
            EXPECT_EQ(worst, 0.0f) << file << ": the CPU backends run the reference's code";
        }
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
