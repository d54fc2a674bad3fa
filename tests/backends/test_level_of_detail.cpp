// Levels of detail (issue 35, kodawari/rods/lod.hpp) against every rod backend: the same
// levels and the same posed frames as the CPU reference, and no jump at a change of
// level. A camera dollies into a grid of 26 swaying characters and out again while it
// pans across them, so that characters turn full, posed and hidden, and back; each test
// runs again with the reduced level on (rods::LodSettings::reduced_pixels), so that they
// turn reduced too.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "test_support.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/rods/lod.hpp"
#include "kodawari/rods/synthetic.hpp"

using namespace kodawari;

namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr std::uint32_t kFrames = 150;

// 203 chains of 13 joints (a partial workgroup), 26 characters of 8 chains with a head
// collider, on a 6 x 5 grid 1.5 m apart (synthetic.cpp), swaying and turning.
rods::SyntheticOptions grid_options() {
    rods::SyntheticOptions o;
    o.chains = 203;
    o.joints = 13;
    o.chains_per_character = 8;
    o.views = 3;
    o.colliders = true;
    return o;
}

// A character is full within 11.6 m and stays full within 15.4 m (1 m at 100 px of 1080,
// 50 degrees): the grid spans 2 to 30 m from the camera over the run. `reduced`: reduced
// from there to 16.5 m (70 px), staying so within 22.1 m.
rods::LodSettings lod_settings(bool reduced) {
    rods::LodSettings lod;
    lod.enabled = true;
    lod.full_pixels = 100.0f;
    lod.reduced_pixels = reduced ? 70.0f : 0.0f;
    return lod;
}

// The synthetic scene's frame with the dolly camera: from 22 m in front of the grid to
// 2 m and back, looking at a point that pans 14 m either side of the grid's middle.
void dolly_frame(const rods::SyntheticScene& scene, std::uint32_t index, rods::RodFrame& out) {
    scene.frame(index, kDt, out);
    const float f = static_cast<float>(index) / static_cast<float>(kFrames);
    const float away = std::abs(1.0f - 2.0f * f);
    out.camera.projection = rods::Camera::Projection::Perspective;
    out.camera.position = glm::vec3(3.75f, 2.0f, 9.5f + 20.0f * away);
    const glm::vec3 target(3.75f + 14.0f * std::sin(6.2831853f * f), 1.6f, 3.75f);
    out.camera.forward = glm::normalize(target - out.camera.position);
    // Numbered, so that far posed and hidden chains step at their levels' rate
    // (rods::chain_rests); the world's character 0 the scene's 5th, so that a group of 16
    // that take turns together straddles the backends' batches.
    out.number = index;
    out.first_character = 5;
}

class LevelOfDetail : public ::testing::TestWithParam<testing_support::BackendCase> {
protected:
    void SetUp() override {
        if (GetParam() == BackendKind::Vulkan) {
            if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
        }
        auto made = rods::SyntheticScene::make(grid_options());
        ASSERT_TRUE(made.ok()) << made.error().message;
        scene_ = std::make_unique<rods::SyntheticScene>(std::move(made).value());
        for (const bool reduced : {false, true}) {
            rods::RodWorld& world = worlds_[reduced ? 1 : 0];
            world = scene_->world();
            world.lod = lod_settings(reduced);
            ASSERT_TRUE(world.finalize().ok());
        }
    }

    std::unique_ptr<RodBackend> make_backend() {
        auto made = make_rod_backend(GetParam(), testing_support::backend_options(GetParam()));
        EXPECT_TRUE(made.ok()) << made.error().message;
        return made.ok() ? std::move(made).value() : nullptr;
    }

    std::unique_ptr<rods::SyntheticScene> scene_;
    std::array<rods::RodWorld, 2> worlds_;  // the reduced level off, on
};

}  // namespace

// Every frame, the CPU reference steps each chain from the backend's own state (its
// level included) and both must agree: the CPU backends to the bit, levels and all;
// vulkan within 1e-5 of the chain length (one frame's rounding, as
// RodBackends.OneStepMatchesTheReferenceFromTheSameState) and on every level. The run
// must also take every level and change levels, or it tests nothing.
TEST_P(LevelOfDetail, LevelsAndPosedFramesMatchTheReference) {
    for (const bool reduced : {false, true}) {
        SCOPED_TRACE(reduced ? "reduced level on" : "reduced level off");
        const rods::RodWorld& world = worlds_[reduced ? 1 : 0];
        std::unique_ptr<RodBackend> backend = make_backend();
        ASSERT_NE(backend, nullptr);
        rods::RodFrame frame;
        dolly_frame(*scene_, 0, frame);
        ASSERT_TRUE(backend->load(world, frame).ok());
        const float length = scene_->chain_length();
        std::vector<rods::KeyState> keys(world.chains.size());
        std::array<std::uint32_t, 4> seen{};
        std::uint32_t changes = 0, disagreements = 0, resting = 0;
        float worst = 0.0f;
        for (std::uint32_t f = 1; f <= kFrames; ++f) {
            std::vector<rods::ChainState> states;
            ASSERT_TRUE(backend->read_states(states).ok());
            const std::vector<rods::ChainState> before = states;
            dolly_frame(*scene_, f, frame);
            for (std::uint32_t c = 0; c < world.chains.size(); ++c) step_chain_reference(world, c, frame, states[c], keys[c]);
            ASSERT_TRUE(backend->step(frame).ok());
            ChainSnapshot snap;
            std::vector<rods::ChainState> got;
            ASSERT_TRUE(backend->read(snap).ok());
            ASSERT_TRUE(backend->read_states(got).ok());
            for (std::uint32_t c = 0; c < world.chains.size(); ++c) {
                const rods::ChainInstance& ch = world.chains[c];
                ASSERT_LT(got[c].level, reduced ? 4u : 3u);
                ++seen[got[c].level];
                if (got[c].level != before[c].level) ++changes;
                if (got[c].level != states[c].level || got[c].idle != states[c].idle) ++disagreements;
                if (got[c].idle > 0) ++resting;
                for (std::uint32_t i = 0; i < world.templ(ch).chain.joint_count; ++i) {
                    const glm::vec3 p = snap.positions[ch.joint_begin + i];
                    ASSERT_TRUE(std::isfinite(p.x + p.y + p.z));
                    worst = std::max(worst, glm::length(rods::position(states[c], i) - p));
                }
            }
        }
        std::printf("[ measured ] %s%s: chain-frames full %u, reduced %u, posed %u, hidden %u (%u of them kept between turns); "
                    "%u changes of level; worst %.3g of the chain length against the reference\n",
                    testing_support::case_name(GetParam()).c_str(), reduced ? " (reduced level on)" : "", seen[0], seen[3], seen[1],
                    seen[2], resting, changes, static_cast<double>(worst / length));
        EXPECT_GT(seen[0], 0u);
        EXPECT_GT(seen[1], 0u);
        EXPECT_GT(seen[2], 0u);
        if (reduced) {
            EXPECT_GT(seen[3], 1000u) << "the run must take the reduced level";
        }
        EXPECT_GT(changes, 100u) << "the run must change levels";
        EXPECT_GT(resting, reduced ? 100u : 1000u) << "far chains must keep their state between their turns";
        EXPECT_EQ(disagreements, 0u) << "levels or idle frames that differ from the reference's";
        EXPECT_LT(worst, 1e-5f * length);
        if (GetParam() != BackendKind::Vulkan) {
            EXPECT_EQ(worst, 0.0f) << "the CPU backends compute the reference's bits";
        }
    }
}

// The pop test of issue 35: no joint moves farther between two frames at a change of its
// chain's level than the farthest any joint moves between two frames of full simulation
// of the same run (the same backend, LOD off).
TEST_P(LevelOfDetail, NoJointJumpsAtAChangeOfLevel) {
    for (const bool reduced : {false, true}) {
        SCOPED_TRACE(reduced ? "reduced level on" : "reduced level off");
        const rods::RodWorld& world = worlds_[reduced ? 1 : 0];
        rods::RodWorld full_world = scene_->world();
        std::unique_ptr<RodBackend> full = make_backend();
        std::unique_ptr<RodBackend> lod = make_backend();
        ASSERT_NE(full, nullptr);
        ASSERT_NE(lod, nullptr);
        rods::RodFrame frame;
        dolly_frame(*scene_, 0, frame);
        ASSERT_TRUE(full->load(full_world, frame).ok());
        ASSERT_TRUE(lod->load(world, frame).ok());
        ChainSnapshot last_full, last_lod, snap;
        ASSERT_TRUE(full->read(last_full).ok());
        ASSERT_TRUE(lod->read(last_lod).ok());
        std::vector<rods::ChainState> levels_before, levels;
        ASSERT_TRUE(lod->read_states(levels_before).ok());
        float full_move = 0.0f, change_move = 0.0f, posed_move = 0.0f;
        std::uint32_t changes = 0;
        for (std::uint32_t f = 1; f <= kFrames; ++f) {
            dolly_frame(*scene_, f, frame);
            ASSERT_TRUE(full->step(frame).ok());
            ASSERT_TRUE(full->read(snap).ok());
            for (std::size_t j = 0; j < snap.positions.size(); ++j) {
                full_move = std::max(full_move, glm::length(snap.positions[j] - last_full.positions[j]));
            }
            last_full = snap;
            ASSERT_TRUE(lod->step(frame).ok());
            ASSERT_TRUE(lod->read(snap).ok());
            ASSERT_TRUE(lod->read_states(levels).ok());
            for (std::uint32_t c = 0; c < world.chains.size(); ++c) {
                const rods::ChainInstance& ch = world.chains[c];
                const bool changed = levels[c].level != levels_before[c].level;
                changes += changed ? 1u : 0u;
                for (std::uint32_t i = 0; i < world.templ(ch).chain.joint_count; ++i) {
                    const float move = glm::length(snap.positions[ch.joint_begin + i] - last_lod.positions[ch.joint_begin + i]);
                    if (changed) change_move = std::max(change_move, move);
                    if (!rods::dynamic(static_cast<rods::Level>(levels[c].level))) posed_move = std::max(posed_move, move);
                }
            }
            last_lod = snap;
            levels_before = levels;
        }
        std::printf("[ measured ] %s%s: largest move of a joint between two frames: %.4f m in full simulation, %.4f m at a "
                    "change of level (%u changes), %.4f m posed or hidden\n",
                    testing_support::case_name(GetParam()).c_str(), reduced ? " (reduced level on)" : "",
                    static_cast<double>(full_move), static_cast<double>(change_move), changes, static_cast<double>(posed_move));
        EXPECT_GT(changes, 100u);
        EXPECT_LE(change_move, full_move);
    }
}

INSTANTIATE_TEST_SUITE_P(All, LevelOfDetail, testing_support::all_backend_kinds(), testing_support::backend_test_name);
