// The cpu backends' SIMD instruction sets (kodawari/backends/simd.hpp, BackendOptions::isa): the
// choice, its errors, and backends on different instruction sets side by side in one
// process giving one result (the shared backend bodies compare each with cpu-reference).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/gltf/import.hpp"
#include "kodawari/rods/synthetic.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/backends/simd.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

BackendOptions with_isa(const std::string& isa) {
    BackendOptions options;
    options.isa = isa;
    options.threads = 2;
    return options;
}

}  // namespace

TEST(SimdIsa, TheWidestIsTheDefaultAndEveryAvailableOneCanBeAskedFor) {
    const std::vector<std::string> available = available_simd_isas();
    ASSERT_FALSE(available.empty());
    EXPECT_EQ(available.back(), "scalar") << "Highway's fallback runs everywhere";
    ASSERT_TRUE(simd_isa().ok());
    EXPECT_EQ(simd_isa().value(), available.front());
    unsigned previous = 1000;
    for (const std::string& isa : available) {
        ASSERT_TRUE(simd_isa(isa).ok()) << isa;
        EXPECT_EQ(simd_isa(isa).value(), isa);
        EXPECT_LT(simd_lanes(isa), previous) << isa << ": widest first";
        previous = simd_lanes(isa);
    }
    EXPECT_EQ(simd_lanes("avx512"), 16u);
    EXPECT_EQ(simd_lanes("avx2"), 8u);
    EXPECT_EQ(simd_lanes("sse4"), 4u);
    EXPECT_EQ(simd_lanes("scalar"), 1u);
    EXPECT_EQ(simd_lanes("mmx"), 0u);
}

TEST(SimdIsa, AnUnknownNameIsAnErrorNamingItAndTheAvailableOnes) {
    const auto bad = simd_isa("avx1024");
    ASSERT_FALSE(bad.ok());
    EXPECT_EQ(bad.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(bad.error().message.find("\"avx1024\""), std::string::npos) << bad.error().message;
    for (const std::string& isa : available_simd_isas()) {
        EXPECT_NE(bad.error().message.find(isa), std::string::npos) << bad.error().message;
    }
    // Every cpu factory says so; cpu-reference has no instruction set to choose.
    const BackendOptions options = with_isa("neon");
    const auto birds = make_bird_backend(BackendKind::Cpu, options);
    const auto rods = make_rod_backend(BackendKind::Cpu, options);
    const auto poses = make_pose_backend(BackendKind::Cpu, options);
    ASSERT_FALSE(birds.ok());
    ASSERT_FALSE(rods.ok());
    ASSERT_FALSE(poses.ok());
    EXPECT_NE(rods.error().message.find("\"neon\""), std::string::npos) << rods.error().message;
    EXPECT_EQ(poses.error().kind, Error::Kind::InvalidInput);
    EXPECT_TRUE(make_rod_backend(BackendKind::CpuReference, options).ok());
}

TEST(SimdIsa, TheBackendSaysItsInstructionSetAndThreads) {
    for (const std::string& isa : available_simd_isas()) {
        auto rods = make_rod_backend(BackendKind::Cpu, with_isa(isa));
        ASSERT_TRUE(rods.ok());
        EXPECT_EQ(rods.value()->device(), "2 threads, " + isa);
        auto birds = make_bird_backend(BackendKind::Cpu, with_isa(isa));
        ASSERT_TRUE(birds.ok());
        EXPECT_EQ(birds.value()->device(), "2 threads, " + isa);
    }
    EXPECT_EQ(cpu_backend_threads(with_isa("")), 2u);
}

// Chain counts that fill no vector (203 chains of 8 templates: batches of 16 and the rest),
// stepped on every instruction set at once, frame after frame: the same bits on each.
TEST(SimdIsa, ChainBackendsOnEveryInstructionSetSideBySideAgreeBitForBit) {
    rods::SyntheticOptions o;
    o.chains = 203;
    o.joints = 13;
    o.views = 3;
    auto scene = rods::SyntheticScene::make(o);
    ASSERT_TRUE(scene.ok());
    std::vector<std::unique_ptr<RodBackend>> backends;
    rods::RodFrame frame;
    scene.value().frame(0, 1.0f / 60.0f, frame);
    for (const std::string& isa : available_simd_isas()) {
        auto made = make_rod_backend(BackendKind::Cpu, with_isa(isa));
        ASSERT_TRUE(made.ok());
        ASSERT_TRUE(made.value()->load(scene.value().world(), frame).ok());
        backends.push_back(std::move(made).value());
    }
    ASSERT_GE(backends.size(), 2u) << "the tests must see two instruction sets";
    for (std::uint32_t f = 1; f <= 40; ++f) {
        scene.value().frame(f, 1.0f / 60.0f, frame);
        for (auto& b : backends) ASSERT_TRUE(b->step(frame).ok());
    }
    ChainSnapshot first, other;
    ASSERT_TRUE(backends[0]->read(first).ok());
    for (std::size_t i = 1; i < backends.size(); ++i) {
        ASSERT_TRUE(backends[i]->read(other).ok());
        EXPECT_EQ(std::memcmp(first.positions.data(), other.positions.data(), first.positions.size() * sizeof(glm::vec3)), 0)
            << backends[i]->device();
        EXPECT_EQ(std::memcmp(first.orientations.data(), other.orientations.data(), first.orientations.size() * sizeof(glm::quat)), 0)
            << backends[i]->device();
    }
}

// A batch with few chains in use runs on a narrower width (simd_rods.cpp cheapest_width:
// one chain on the scalar target, 2-4 on sse4, 5-8 on avx2): worlds whose templates hold
// 1 to 17 chains, on every instruction set, are cpu-reference's bits.
TEST(SimdIsa, PartlyFilledBatchesAreTheReferencesBitsOnEveryInstructionSet) {
    // The synthetic world's 8 templates take chain c in turn: 1, 5, 19, 37, 70 and 139
    // chains give templates of 0 to 18 chains, so batches of 1 to 16 lanes in use.
    for (const std::uint32_t chains : {1u, 5u, 19u, 37u, 70u, 139u}) {
        rods::SyntheticOptions o;
        o.chains = chains;
        o.joints = 9;
        o.views = 3;
        auto scene = rods::SyntheticScene::make(o);
        ASSERT_TRUE(scene.ok());
        rods::RodFrame frame;
        scene.value().frame(0, 1.0f / 60.0f, frame);
        auto reference = make_rod_backend(BackendKind::CpuReference, {});
        ASSERT_TRUE(reference.ok());
        ASSERT_TRUE(reference.value()->load(scene.value().world(), frame).ok());
        std::vector<std::unique_ptr<RodBackend>> backends;
        for (const std::string& isa : available_simd_isas()) {
            auto made = make_rod_backend(BackendKind::Cpu, with_isa(isa));
            ASSERT_TRUE(made.ok());
            ASSERT_TRUE(made.value()->load(scene.value().world(), frame).ok());
            backends.push_back(std::move(made).value());
        }
        for (std::uint32_t f = 1; f <= 20; ++f) {
            scene.value().frame(f, 1.0f / 60.0f, frame);
            ASSERT_TRUE(reference.value()->step(frame).ok());
            for (auto& b : backends) ASSERT_TRUE(b->step(frame).ok());
        }
        ChainSnapshot want, got;
        ASSERT_TRUE(reference.value()->read(want).ok());
        for (auto& b : backends) {
            ASSERT_TRUE(b->read(got).ok());
            std::size_t differ = 0;
            for (std::size_t j = 0; j < want.positions.size(); ++j) {
                differ += std::memcmp(&want.positions[j], &got.positions[j], sizeof(glm::vec3)) != 0 ||
                          std::memcmp(&want.orientations[j], &got.orientations[j], sizeof(glm::quat)) != 0;
            }
            EXPECT_EQ(differ, 0u) << chains << " chains, " << b->device() << ": " << differ << " of " << want.positions.size()
                                  << " joints differ";
        }
    }
}

// Birds: the wings' sine and cosine are the kernel's own, without fused multiply-add, so
// even they are the same bits on every instruction set (the exports stay one list).
TEST(SimdIsa, BirdBackendsOnEveryInstructionSetSideBySideAgreeBitForBit) {
    auto scene = load_scene(std::string(KODAWARI_SOURCE_DIR) + "/scenes/flock.json");
    ASSERT_TRUE(scene.ok());
    auto world = build_bird_world(scene.value());
    ASSERT_TRUE(world.ok());
    const std::size_t n = world.value().birds.size();
    ASSERT_NE(n % 16, 0u);
    constexpr std::uint32_t kFrames = 240;
    std::vector<std::vector<gpu::BirdPose>> poses;
    std::vector<std::vector<gpu::BirdDiag>> diag;
    std::vector<std::unique_ptr<BirdBackend>> backends;
    for (const std::string& isa : available_simd_isas()) {
        auto made = make_bird_backend(BackendKind::Cpu, with_isa(isa));
        ASSERT_TRUE(made.ok());
        ASSERT_TRUE(made.value()->load(world.value()).ok());
        backends.push_back(std::move(made).value());
        poses.emplace_back(kFrames * n);
        diag.emplace_back(kFrames * n);
    }
    for (std::uint32_t f = 0; f < kFrames; f += 40) {  // interleaved, 40 frames per call
        for (std::size_t i = 0; i < backends.size(); ++i) {
            const FrameOutput out{std::span(poses[i]).subspan(f * n, 40 * n), std::span(diag[i]).subspan(f * n, 40 * n)};
            ASSERT_TRUE(backends[i]->simulate(40, out).ok());
        }
    }
    for (std::size_t i = 1; i < backends.size(); ++i) {
        EXPECT_EQ(std::memcmp(poses[0].data(), poses[i].data(), poses[0].size() * sizeof(gpu::BirdPose)), 0) << backends[i]->device();
        EXPECT_EQ(std::memcmp(diag[0].data(), diag[i].data(), diag[0].size() * sizeof(gpu::BirdDiag)), 0) << backends[i]->device();
    }
}

// Poses: the shipped character's crowd (its three clips and the rest pose, 37 instances).
// 1, 5, 9, 17 and 37 instances over the rest pose and three clips (i % 4): batches of 1 to
// 10 instances, which run on the scalar target (1), sse4 (2-4), avx2 (5-8) or avx512
// (more) where the machine has them (simd_poses.cpp kPoseVectorCosts).
TEST(SimdIsa, PoseBackendsOnEveryInstructionSetAgreeWithTheReferenceBitForBit) {
    auto character = gltf::load_character(std::string(KODAWARI_SOURCE_DIR) + "/scenes/characters/chibi.glb");
    ASSERT_TRUE(character.ok()) << character.error().message;
    for (const std::size_t count : {1u, 5u, 9u, 17u, 37u}) {
        SCOPED_TRACE(std::to_string(count) + " instances");
        std::vector<PoseInstance> instances(count);
        for (std::size_t i = 0; i < instances.size(); ++i) {
            instances[i].placement.position = {static_cast<float>(i % 7), 0.0f, static_cast<float>(i / 7)};
            instances[i].placement.rotation = glm::angleAxis(0.3f * static_cast<float>(i), glm::vec3(0, 1, 0));
            instances[i].clip = static_cast<std::int32_t>(i % 4) - 1;
            instances[i].time_offset = 0.137f * static_cast<float>(i);
        }
        auto reference = make_pose_backend(BackendKind::CpuReference, {});
        ASSERT_TRUE(reference.ok());
        ASSERT_TRUE(reference.value()->load(character.value(), instances).ok());
        std::vector<glm::mat4> want, got;
        for (const std::string& isa : available_simd_isas()) {
            auto made = make_pose_backend(BackendKind::Cpu, with_isa(isa));
            ASSERT_TRUE(made.ok());
            ASSERT_TRUE(made.value()->load(character.value(), instances).ok());
            for (const float t : {0.0f, 0.51f, 1.7f, 3.33f}) {
                ASSERT_TRUE(reference.value()->evaluate(t).ok());
                ASSERT_TRUE(reference.value()->read(want).ok());
                ASSERT_TRUE(made.value()->evaluate(t).ok());
                ASSERT_TRUE(made.value()->read(got).ok());
                ASSERT_EQ(want.size(), got.size());
                EXPECT_EQ(std::memcmp(want.data(), got.data(), want.size() * sizeof(glm::mat4)), 0) << isa << " at t " << t;
            }
        }
    }
}

// The machine's ceilings (measure_ceilings(), `kodawari bench ceilings`) on every instruction
// set this machine runs: each a rate a core can have. Not a speed test: the bounds only
// say that the loops ran. Below: 0.1 GFLOP/s and 0.1 GB/s, far under anything since the
// Pentium (ASan does not touch the register-only loop). Above: 1 TFLOP/s and 1 TB/s on
// one thread, past any core (64 flops a cycle at 6 GHz is 0.38 TFLOP/s): a loop the
// compiler folded into its result (GCC did, for the non-FMA targets, while its operands
// were constants) measured 3e14.
TEST(SimdIsa, CeilingsAreMeasuredOnEveryInstructionSetAndBadArgumentsRefused) {
    for (const std::string& isa : available_simd_isas()) {
        SCOPED_TRACE(isa);
        auto measured = measure_ceilings(isa, 1, std::size_t{3} << 20);
        ASSERT_TRUE(measured.ok()) << measured.error().message;
        const MachineCeilings& c = measured.value();
        EXPECT_EQ(c.isa, isa);
        EXPECT_EQ(c.threads, 1u);
        EXPECT_EQ(c.triad_bytes, std::size_t{3} << 20);
        EXPECT_GT(c.fp32_flops, 1e8);
        EXPECT_LT(c.fp32_flops, 1e12);
        EXPECT_GT(c.triad_bytes_per_second, 1e8);
        EXPECT_LT(c.triad_bytes_per_second, 1e12);
    }
    const auto threads = measure_ceilings("", 0);
    ASSERT_FALSE(threads.ok());
    EXPECT_EQ(threads.error().kind, Error::Kind::InvalidInput);
    EXPECT_EQ(threads.error().message, "measure_ceilings: threads: expected 1 to 1024, got 0");
    const auto tiny = measure_ceilings("", 1, 1000);
    ASSERT_FALSE(tiny.ok());
    EXPECT_EQ(tiny.error().message, "measure_ceilings: triad_bytes: expected 3 MiB to 64 GiB, got 1000 bytes");
    const auto isa = measure_ceilings("avx1024", 1);
    ASSERT_FALSE(isa.ok());
    EXPECT_EQ(isa.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(isa.error().message.find("measure_ceilings: isa: SIMD instruction set \"avx1024\" is unknown"), std::string::npos)
        << isa.error().message;
}
