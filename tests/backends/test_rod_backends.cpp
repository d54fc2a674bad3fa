// The same test bodies against every rod backend: cpu-reference, cpu (at every SIMD
// instruction set of the machine: test_support.hpp) and vulkan (on
// lavapipe where there is no GPU, with validation and synchronization validation on:
// ctest sets KODAWARI_VALIDATION=1 and any message fails the test).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include <kodawari/shared/rods.h>

#include "test_support.hpp"
#include "kodawari/backend_factory.hpp"
#include "kodawari/gpu_info.hpp"
#include "kodawari/rod_backend.hpp"
#include "kodawari/rods/synthetic.hpp"

using namespace kodawari;

namespace {

constexpr float kDt = 1.0f / 60.0f;

// 203 chains (3 full workgroups and a partial one) of 13 joints, 3 view examples, on 26
// characters of 8 chains (the last has 3). 13 joints: not a power of two either.
rods::SyntheticOptions small_options(bool colliders) {
    rods::SyntheticOptions o;
    o.chains = 203;
    o.joints = 13;
    o.chains_per_character = 8;
    o.views = 3;
    o.colliders = colliders;
    return o;
}

float max_distance(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
    float e = 0.0f;
    for (std::size_t i = 0; i < a.size(); ++i) e = std::max(e, glm::length(a[i] - b[i]));
    return e;
}

class RodBackends : public ::testing::TestWithParam<testing_support::BackendCase> {
protected:
    void SetUp() override {
        if (GetParam() == BackendKind::Vulkan) {
            if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
        }
        auto made = make_rod_backend(GetParam(), testing_support::backend_options(GetParam()));
        ASSERT_TRUE(made.ok()) << made.error().message;
        backend_ = std::move(made).value();
    }
    void TearDown() override {
        if (backend_) {
            EXPECT_EQ(backend_->validation_messages(), 0u) << "Vulkan validation reported problems (see stderr)";
        }
    }

    // Runs `frames` frames of `scene` on `backend`.
    static void run(RodBackend& backend, const rods::SyntheticScene& scene, std::uint32_t frames) {
        rods::RodFrame frame;
        scene.frame(0, kDt, frame);
        const auto loaded = backend.load(scene.world(), frame);
        ASSERT_TRUE(loaded.ok()) << loaded.error().message;
        for (std::uint32_t f = 1; f <= frames; ++f) {
            scene.frame(f, kDt, frame);
            const auto stepped = backend.step(frame);
            ASSERT_TRUE(stepped.ok()) << stepped.error().message;
        }
    }

    std::unique_ptr<RodBackend> backend_;
};

}  // namespace

TEST_P(RodBackends, KeepsSegmentLengthsAndReportsWeights) {
    auto scene = rods::SyntheticScene::make(small_options(true));
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const rods::RodWorld& world = scene.value().world();
    ASSERT_NE(world.chains.size() % KW_RODS_WORKGROUP_SIZE, 0u) << "must exercise a partial workgroup";
    run(*backend_, scene.value(), 120);
    ChainSnapshot snap;
    ASSERT_TRUE(backend_->read(snap).ok());
    ASSERT_EQ(snap.positions.size(), world.joint_count);
    float worst = 0.0f;
    for (std::size_t c = 0; c < world.chains.size(); ++c) {
        const rods::ChainInstance& ch = world.chains[c];
        const rods::Chain& chain = world.templ(ch).chain;
        for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) {
            const float l = glm::length(snap.positions[ch.joint_begin + i + 1] - snap.positions[ch.joint_begin + i]);
            ASSERT_TRUE(std::isfinite(l));
            worst = std::max(worst, std::abs(l - chain.segment_length[i]) / chain.segment_length[i]);
        }
        // SPEC A.3: the weights sum to 1 and are in [0, 1]; 1e-5 is float rounding of 4 terms.
        float sum = 0.0f;
        for (std::size_t k = 0; k <= rods::kMaxViewExamples; ++k) {
            const float w = snap.weights[c * (rods::kMaxViewExamples + 1) + k];
            EXPECT_GE(w, 0.0f);
            EXPECT_LE(w, 1.0f);
            sum += w;
        }
        EXPECT_NEAR(sum, 1.0f, 1e-5f);
        EXPECT_NEAR(glm::length(snap.view_directions[c]), 1.0f, 1e-5f);
    }
    // 0.5% of a segment: the inextensibility bound.
    EXPECT_LT(worst, 0.005f);
    std::printf("[ measured ] %s: max stretch %.3g of a segment\n", testing_support::case_name(GetParam()).c_str(),
                static_cast<double>(worst));
}

// The one-step consistency: the backend's state after k frames, advanced one
// frame by the CPU reference and by the backend, agrees within 1e-5 of the chain length
// at every joint. Both sides start from the very same state, so only the arithmetic of
// one frame (2 substeps x 4 iterations) differs: GLSL's sin, cos, acos, atan, pow and
// division are not correctly rounded (up to a few ulp), which moves positions by ~1e-7 m.
TEST_P(RodBackends, OneStepMatchesTheReferenceFromTheSameState) {
    auto scene = rods::SyntheticScene::make(small_options(true));
    ASSERT_TRUE(scene.ok());
    const rods::RodWorld& world = scene.value().world();
    const float length = scene.value().chain_length();
    for (std::uint32_t k : {1u, 45u}) {
        run(*backend_, scene.value(), k);
        std::vector<rods::ChainState> states;
        ASSERT_TRUE(backend_->read_states(states).ok());
        rods::RodFrame frame;
        scene.value().frame(k + 1, kDt, frame);
        // Synthetic chains have no keyed examples: a fresh key state is theirs.
        std::vector<rods::KeyState> keys(world.chains.size());
        for (std::uint32_t c = 0; c < world.chains.size(); ++c) step_chain_reference(world, c, frame, states[c], keys[c]);
        ASSERT_TRUE(backend_->step(frame).ok());
        ChainSnapshot snap;
        ASSERT_TRUE(backend_->read(snap).ok());
        float worst = 0.0f;
        for (std::uint32_t c = 0; c < world.chains.size(); ++c) {
            const rods::ChainInstance& ch = world.chains[c];
            for (std::uint32_t i = 0; i < world.templ(ch).chain.joint_count; ++i) {
                worst = std::max(worst, glm::length(rods::position(states[c], i) - snap.positions[ch.joint_begin + i]));
            }
        }
        EXPECT_LT(worst, 1e-5f * length) << "after " << k << " frames";
        if (GetParam() != BackendKind::Vulkan) {
            // The cpu backend repeats the reference's arithmetic operation for operation
            // (simd/rods_simd.hpp), at every instruction set.
            EXPECT_EQ(worst, 0.0f) << "the CPU backends compute the reference's bits";
        }
        std::printf("[ measured ] %s, one frame from frame %u: max %.3g of the chain length\n",
                    testing_support::case_name(GetParam()).c_str(), k, static_cast<double>(worst / length));
    }
}

// The trajectory parity: 300 frames without collisions, every joint within 1e-3
// of the chain length of the reference. Per-frame differences of ~1e-7 m compound
// through the dynamics; damping (2/s) and the shape matching pull both towards the same
// rest shape, so they stay bounded.
TEST_P(RodBackends, ThreeHundredFramesMatchTheReference) {
    auto scene = rods::SyntheticScene::make(small_options(false));
    ASSERT_TRUE(scene.ok());
    const float length = scene.value().chain_length();
    auto reference = make_rod_backend(BackendKind::CpuReference, {});
    ASSERT_TRUE(reference.ok());
    run(*reference.value(), scene.value(), 300);
    run(*backend_, scene.value(), 300);
    ChainSnapshot want, got;
    ASSERT_TRUE(reference.value()->read(want).ok());
    ASSERT_TRUE(backend_->read(got).ok());
    const float worst = max_distance(want.positions, got.positions);
    EXPECT_LT(worst, 1e-3f * length);
    EXPECT_LT(max_distance(want.rest, got.rest), 1e-3f * length);
    if (GetParam() != BackendKind::Vulkan) {
        EXPECT_EQ(std::memcmp(want.positions.data(), got.positions.data(), want.positions.size() * sizeof(glm::vec3)), 0);
    }
    std::printf("[ measured ] %s, 300 frames: max %.3g of the chain length\n", testing_support::case_name(GetParam()).c_str(),
                static_cast<double>(worst / length));
}

// Same input, same backend, same output bits.
TEST_P(RodBackends, Deterministic) {
    auto scene = rods::SyntheticScene::make(small_options(true));
    ASSERT_TRUE(scene.ok());
    ChainSnapshot a, b;
    run(*backend_, scene.value(), 30);
    ASSERT_TRUE(backend_->read(a).ok());
    run(*backend_, scene.value(), 30);
    ASSERT_TRUE(backend_->read(b).ok());
    EXPECT_EQ(std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(glm::vec3)), 0);
    EXPECT_EQ(std::memcmp(a.orientations.data(), b.orientations.data(), a.orientations.size() * sizeof(glm::quat)), 0);
}

TEST_P(RodBackends, RejectsAFrameThatDoesNotFitTheWorld) {
    auto scene = rods::SyntheticScene::make(small_options(true));
    ASSERT_TRUE(scene.ok());
    rods::RodFrame frame;
    scene.value().frame(0, kDt, frame);
    ASSERT_TRUE(backend_->load(scene.value().world(), frame).ok());
    frame.roots.pop_back();
    const auto r = backend_->step(frame);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("roots"), std::string::npos) << r.error().message;
    scene.value().frame(1, kDt, frame);
    frame.dt = 0.0f;
    EXPECT_FALSE(backend_->step(frame).ok());
}

INSTANTIATE_TEST_SUITE_P(All, RodBackends, testing_support::all_backend_kinds(), testing_support::backend_test_name);
