// The same test bodies against every bird backend: cpu-reference, cpu (at every SIMD
// instruction set of the machine: test_support.hpp) and vulkan (on
// lavapipe where there is no GPU, with validation and synchronization validation on:
// ctest sets KODAWARI_VALIDATION=1 and any message fails the test).
#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "test_support.hpp"
#include "backends/bird_backend_test.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/birds/wingbeat.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/backends/compare.hpp"
#include "kodawari/vulkan/gpu_info.hpp"
#include "kodawari/scene/scene.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

std::string scene_path(const char* name) { return std::string(KODAWARI_SOURCE_DIR) + "/scenes/" + name; }

birds::BirdWorld load_world(const char* name) {
    auto scene = load_scene(scene_path(name));
    EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error().message);
    if (!scene.ok()) return {};
    auto world = build_bird_world(scene.value());
    EXPECT_TRUE(world.ok()) << (world.ok() ? "" : world.error().message);
    return world.ok() ? std::move(world).value() : birds::BirdWorld{};
}

// A hand-made world of `count` birds on two routes (one looping, one parametric).
birds::BirdWorld small_world(std::uint32_t count) {
    birds::BirdWorld world;
    world.frames = 90;
    birds::RouteSpec loop;
    loop.points = {{0, 10, 0}, {40, 20, 0}, {40, 0, 40}, {0, 10, 40}, {-40, 20, 40}, {-40, 0, 0}, {0, 10, 0}};
    loop.loop = true;
    birds::RouteSpec dive;
    dive.points = {{0, 50, 0}, {0, 50, 30}, {0, 10, 30}, {0, 10, 60}};
    dive.timing = birds::RouteTiming::Parametric;
    dive.segment_duration = 1.0f;
    EXPECT_TRUE(world.add_route(loop, "loop").ok());
    EXPECT_TRUE(world.add_route(dive, "dive").ok());
    for (std::uint32_t i = 0; i < count; ++i) {
        gpu::BirdParams b{};
        b.offset = {static_cast<float>(i % 7), 0.0f, static_cast<float>(i % 5), 0.01f * static_cast<float>(i)};
        b.motion = {10.0f + 0.1f * static_cast<float>(i % 10), 3.0f + 0.05f * static_cast<float>(i % 20), 1.0f, 0.013f * static_cast<float>(i % 77)};
        b.ids = {i % 2, i % 3, 0, 0};
        world.birds.push_back(b);
    }
    return world;
}

struct Frames {
    std::vector<gpu::BirdPose> poses;
    std::vector<gpu::BirdDiag> diag;
};

// Runs all frames, in chunks of `chunk` frames.
Frames simulate_all(BirdBackend& backend, const birds::BirdWorld& world, std::uint32_t chunk) {
    Frames r;
    const std::size_t n = world.birds.size();
    r.poses.resize(std::size_t{world.frames} * n);
    r.diag.resize(r.poses.size());
    EXPECT_TRUE(backend.load(world).ok());
    for (std::uint32_t done = 0; done < world.frames;) {
        const std::uint32_t k = std::min(chunk, world.frames - done);
        const auto result = backend.simulate(k, {std::span(r.poses).subspan(done * n, k * n), std::span(r.diag).subspan(done * n, k * n)});
        EXPECT_TRUE(result.ok()) << (result.ok() ? "" : result.error().message);
        done += k;
    }
    return r;
}

class BirdBackends : public testing_support::BirdBackendTest {
protected:
    void expect_parity(const birds::BirdWorld& world, std::uint32_t chunk) {
        const Frames ref = simulate_all(*reference_, world, 600);
        const Frames got = simulate_all(*backend_, world, chunk);
        BirdComparison comparison(world);
        comparison.add(0, world.frames, ref.poses, got.poses, ref.diag, got.diag);
        for (const Deviation& d : comparison.results()) {
            EXPECT_TRUE(d.within()) << d.quantity << ": max " << d.max << " " << d.unit << " (bird " << d.worst_bird << ", frame "
                                    << d.worst_frame << ") over tolerance " << d.tolerance;
        }
        if (GetParam() == BackendKind::CpuReference) {
            EXPECT_EQ(std::memcmp(ref.poses.data(), got.poses.data(), ref.poses.size() * sizeof(gpu::BirdPose)), 0);
        } else if (GetParam() == BackendKind::Cpu) {
            expect_reference_bits_but_wings(ref, got);
        }
    }

    // The cpu backend repeats flight.cpp's arithmetic for everything but its sines and
    // cosines (simd/birds_simd.hpp): what the decisions rest on and the route's kinematics
    // (velocity, acceleration, blend, mode, attitude, phase, speed fraction, seconds
    // glided) are the reference's bits; the poses, which take sines of the wingbeat phase
    // (wings, bob, head and tail), are within the tolerances above.
    static void expect_reference_bits_but_wings(const Frames& ref, const Frames& got) {
        ASSERT_EQ(ref.poses.size(), got.poses.size());
        std::size_t differ = 0, first = 0;
        for (std::size_t i = 0; i < ref.poses.size(); ++i) {
            const gpu::BirdDiag &da = ref.diag[i], &db = got.diag[i];
            const bool same = std::memcmp(&da.velocity, &db.velocity, 2 * sizeof(gpu::vec4)) == 0 &&
                              std::memcmp(&da.attitude, &db.attitude, sizeof(gpu::vec4)) == 0 &&
                              std::memcmp(&da.flight.x, &db.flight.x, sizeof(float)) == 0 &&
                              std::memcmp(&da.flight.w, &db.flight.w, sizeof(float)) == 0;
            if (!same && differ++ == 0) first = i;
        }
        EXPECT_EQ(differ, 0u) << "bird-frames whose exact quantities differ from the reference; first: entry " << first;
    }

};

}  // namespace

TEST_P(BirdBackends, MatchesTheReferenceOnTheFlockScene) {
    const birds::BirdWorld world = load_world("flock.json");
    ASSERT_FALSE(world.birds.empty());
    ASSERT_NE(world.birds.size() % KW_BIRDS_WORKGROUP_SIZE, 0u) << "the scene must exercise a partial workgroup";
    ASSERT_GE(world.frames, 600u);
    expect_parity(world, 600);
}

TEST_P(BirdBackends, TakeOffGlideLandingAndHoverMatchTheReference) {
    // scenes/perch.json: pigeons take off from a line of perches one after another, circle,
    // glide and land; hummingbirds hover (docs/flight-modes.md). Every new mode must occur,
    // with transitions, so a backend that lacked one could not pass; 29 birds, chunks of
    // 97 frames that end inside transitions.
    const birds::BirdWorld world = load_world("perch.json");
    ASSERT_GE(world.frames, 1500u);
    const Frames r = simulate_all(*backend_, world, 97);
    std::array<std::size_t, KW_MODE_COUNT> modes{};
    for (const gpu::BirdDiag& d : r.diag) ++modes[static_cast<std::size_t>(d.acceleration.w)];
    for (std::uint32_t m : {KW_MODE_LEVEL, KW_MODE_GLIDE, KW_MODE_TAKEOFF, KW_MODE_LANDING, KW_MODE_HOVER}) {
        EXPECT_GT(modes[m], 0u) << birds::mode_name(static_cast<birds::FlightMode>(m)) << " never occurs";
    }
    expect_parity(world, 97);
}

TEST_P(BirdBackends, MatchesTheReferenceOnTheMurmuration) {
    birds::BirdWorld world = load_world("murmuration.json");
    ASSERT_GE(world.birds.size(), 10000u);
    world.frames = 600;
    expect_parity(world, 600);
}

TEST_P(BirdBackends, CountsAroundTheWorkgroupSize) {
    for (std::uint32_t count : {1u, 63u, 65u, 130u, 1001u}) {
        SCOPED_TRACE("birds: " + std::to_string(count));
        expect_parity(small_world(count), 17);
    }
}

TEST_P(BirdBackends, SeedRulesMatchTheReference) {
    // The seed's bank and mode rules (the Vulkan kernel's other specializations).
    birds::BirdWorld world = small_world(201);
    world.settings.bank_rule = birds::BankRule::Seed;
    world.settings.mode_rule = birds::ModeRule::Seed;
    expect_parity(world, 31);
}

TEST_P(BirdBackends, ChunkingAndRepetitionGiveTheSameBits) {
    const birds::BirdWorld world = small_world(333);
    const Frames whole = simulate_all(*backend_, world, 1000);
    const Frames chunked = simulate_all(*backend_, world, 7);
    const Frames again = simulate_all(*backend_, world, 1000);
    ASSERT_EQ(whole.poses.size(), chunked.poses.size());
    EXPECT_EQ(std::memcmp(whole.poses.data(), chunked.poses.data(), whole.poses.size() * sizeof(gpu::BirdPose)), 0);
    EXPECT_EQ(std::memcmp(whole.poses.data(), again.poses.data(), whole.poses.size() * sizeof(gpu::BirdPose)), 0);
    EXPECT_EQ(std::memcmp(whole.diag.data(), again.diag.data(), whole.diag.size() * sizeof(gpu::BirdDiag)), 0);
}

TEST_P(BirdBackends, EveryModeAndTransitionOccursInTheFlockScene) {
    // The default scene must show what the engine does: every wing type in it climbs,
    // dives and levels off, with transitions between.
    const birds::BirdWorld world = load_world("flock.json");
    const Frames r = simulate_all(*backend_, world, 600);
    std::size_t modes[birds::kWingTypeCount][3] = {};
    std::size_t blending = 0;
    for (std::size_t i = 0; i < r.diag.size(); ++i) {
        const gpu::BirdDiag& d = r.diag[i];
        const std::uint32_t type = world.birds[i % world.birds.size()].ids.y;
        modes[type][static_cast<int>(d.acceleration.w)]++;
        if (d.velocity.w < 1.0f) ++blending;
        ASSERT_GE(d.attitude.w, 0.0f);
        ASSERT_LT(d.attitude.w, 6.2831855f);
    }
    std::array<bool, birds::kWingTypeCount> present{};
    for (const gpu::BirdParams& bird : world.birds) present[bird.ids.y] = true;
    EXPECT_EQ(std::count(present.begin(), present.end(), true), 3) << "flock.json flies pigeons, gulls and hawks";
    for (std::size_t type = 0; type < birds::kWingTypeCount; ++type) {
        if (!present[type]) continue;
        for (int mode = 0; mode < 3; ++mode) {
            EXPECT_GT(modes[type][mode], 0u) << birds::wing_type_spec(static_cast<birds::WingType>(type)).name << " never in mode "
                                             << mode;
        }
    }
    EXPECT_GT(blending, 0u);
}

TEST_P(BirdBackends, OutputWithoutReadbackStillAdvances) {
    // Benchmarks simulate without output; the state must advance exactly as with it.
    const birds::BirdWorld world = small_world(100);
    const Frames full = simulate_all(*backend_, world, 1000);
    ASSERT_TRUE(backend_->load(world).ok());
    ASSERT_TRUE(backend_->simulate(world.frames - 1, {}).ok());
    std::vector<gpu::BirdPose> last(world.birds.size());
    ASSERT_TRUE(backend_->simulate(1, {last, {}}).ok());
    EXPECT_EQ(std::memcmp(last.data(), full.poses.data() + (world.frames - 1) * world.birds.size(), last.size() * sizeof(gpu::BirdPose)),
              0);
}

INSTANTIATE_TEST_SUITE_P(All, BirdBackends, testing_support::all_backend_kinds(), testing_support::backend_test_name);

TEST(VulkanStaging, DiscreteGpuPathMatchesTheReference) {
    // lavapipe has unified memory; force the staging-copy path a discrete GPU takes.
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    BackendOptions staging = testing_support::gpu_options();
    staging.force_staging = true;
    auto made = make_bird_backend(BackendKind::Vulkan, staging);
    ASSERT_TRUE(made.ok()) << made.error().message;
    auto reference = std::move(make_bird_backend(BackendKind::CpuReference, {})).value();
    const birds::BirdWorld world = small_world(257);
    const Frames ref = simulate_all(*reference, world, 1000);
    const Frames got = simulate_all(*made.value(), world, 13);
    BirdComparison comparison(world);
    comparison.add(0, world.frames, ref.poses, got.poses, ref.diag, got.diag);
    for (const Deviation& d : comparison.results()) {
        EXPECT_TRUE(d.within()) << d.quantity << ": max " << d.max << " (bird " << d.worst_bird << ", frame " << d.worst_frame << ")";
    }
    EXPECT_EQ(made.value()->validation_messages(), 0u);
}
