// Shards of a bake (kodawari/simulation/shards.hpp, SimulationOptions::shard): a shard simulates the
// whole scene's instances of its range bit for bit on every backend (its result does not
// depend on the shard count), and merging the part files gives the single bake's bytes.
// The MPI path is tested with real mpirun in tests/scaleout_test.sh.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "kodawari/simulation/bake.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/simulation/shards.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/domains/trace.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

using namespace kodawari;
using testing_support::TempDir;

namespace {

std::string scene_path(const char* name) { return std::string(KODAWARI_SOURCE_DIR) + "/scenes/" + name; }

template <class T>
bool same_bits(const T& a, const T& b) {
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}

std::unique_ptr<Simulation> open(const std::string& scene, std::uint32_t frames, Shard shard = {},
                                 const testing_support::BackendCase& backend = {BackendKind::Cpu, ""}) {
    SimulationOptions options{.backend = backend.kind, .options = testing_support::backend_options(backend), .frames = frames,
                              .shard = shard};
    auto made = Simulation::open(scene, options);
    EXPECT_TRUE(made.ok()) << made.error().message;
    return made.ok() ? std::move(made).value() : nullptr;
}

// Bakes `scene` into the .glb files a single `kodawari run` writes at `out`.
std::vector<std::unique_ptr<BakeSink>> glb_sinks(const BakeWorld& world, const std::string& out) {
    std::vector<std::unique_ptr<BakeSink>> sinks;
    if (!bird_world_of(world).birds.empty()) sinks.push_back(make_birds_glb_sink(out));
    if (rod_scene_of(world) != nullptr) sinks.push_back(make_chains_glb_sink(out));
    return sinks;
}

std::vector<BakeSink*> pointers(const std::vector<std::unique_ptr<BakeSink>>& sinks) {
    std::vector<BakeSink*> out;
    for (const auto& s : sinks) out.push_back(s.get());
    return out;
}

// Writes shard `shard` of `scene` to `part`.
void bake_part(const std::string& scene, std::uint32_t frames, Shard shard, const std::string& part) {
    auto sim = open(scene, frames, shard);
    ASSERT_NE(sim, nullptr);
    auto sink = make_part_sink(part, *sim);
    BakeSink* sinks[] = {sink.get()};
    auto written = bake(*sim, sinks);
    ASSERT_TRUE(written.ok()) << written.error().message;
}

// The single bake's bytes and the merged parts' bytes of `scene` over `count` shards.
void expect_merge_is_single_bake(const char* scene_name, std::uint32_t frames, std::uint32_t count) {
    TempDir dir;
    const std::string scene = scene_path(scene_name);
    auto single = open(scene, frames);
    ASSERT_NE(single, nullptr);
    const BakeWorld world = make_simulation_source(*single)->world();
    auto single_sinks = glb_sinks(world, dir.file("single.glb"));
    ASSERT_TRUE(bake(*single, pointers(single_sinks)).ok());

    std::vector<std::string> parts;
    // Written in reverse order and opened so: open_parts orders them by shard.
    for (std::uint32_t i = count; i-- > 0;) {
        parts.push_back(dir.file("part" + std::to_string(i)));
        bake_part(scene, frames, {i, count}, parts.back());
    }
    auto source = open_parts(parts);
    ASSERT_TRUE(source.ok()) << source.error().message;
    auto merged_sinks = glb_sinks(source.value()->world(), dir.file("merged.glb"));
    auto merged = bake(*source.value(), pointers(merged_sinks));
    ASSERT_TRUE(merged.ok()) << merged.error().message;
    const std::string a = testing_support::file_bytes(dir.file("single.glb"));
    EXPECT_FALSE(a.empty());
    EXPECT_TRUE(a == testing_support::file_bytes(dir.file("merged.glb"))) << scene_name << ": the merged file differs from the single bake's";
}

}  // namespace

TEST(ShardRange, CoversEveryInstanceOnceInOrder) {
    for (std::uint32_t n : {0u, 1u, 5u, 270u, 1001u}) {
        for (std::uint32_t count = 1; count <= 9; ++count) {
            std::uint32_t next = 0;
            for (std::uint32_t i = 0; i < count; ++i) {
                const InstanceRange r = shard_range(n, {i, count});
                EXPECT_EQ(r.begin, next) << n << " in " << count;
                EXPECT_LE(r.size(), n / count + 1);
                EXPECT_GE(r.size(), n / count);
                next = r.end;
            }
            EXPECT_EQ(next, n);
        }
    }
}

// A slice's kinematic input is the whole scene's entries of its instances, bit for bit,
// for procedural and rigged characters.
TEST(RodSceneSlice, FramesAreTheWholeScenesEntries) {
    for (const char* name : {"crowd.json", "crowd-gltf.json"}) {
        auto scene = load_scene(scene_path(name));
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        auto whole = build_rod_scene(scene.value());
        ASSERT_TRUE(whole.ok()) << whole.error().message;
        const RodScene& w = whole.value();
        constexpr std::uint32_t kBegin = 3, kEnd = 20;
        const RodScene part = w.slice(kBegin, kEnd);
        ASSERT_EQ(part.instances.size(), kEnd - kBegin);
        EXPECT_EQ(part.character_names.front(), w.character_names[kBegin]);
        const std::uint32_t chain0 = w.instances[kBegin].chain_begin;
        const std::uint32_t collider0 = w.instances[kBegin].collider_begin;
        ASSERT_EQ(part.chain_names.front(), w.chain_names[chain0]);
        for (std::uint32_t f : {0u, 7u}) {
            const rods::RodFrame a = w.frame(f);
            const rods::RodFrame b = part.frame(f);
            ASSERT_TRUE(check_frame(part.world, b).ok());
            for (std::size_t i = 0; i < b.reference.size(); ++i) {
                EXPECT_TRUE(same_bits(a.reference[kBegin + i], b.reference[i])) << name << " instance " << i;
            }
            for (std::size_t i = 0; i < b.roots.size(); ++i) {
                EXPECT_TRUE(same_bits(a.roots[chain0 + i], b.roots[i])) << name << " chain " << i;
            }
            ASSERT_FALSE(b.colliders.empty()) << name;
            for (std::size_t i = 0; i < b.colliders.size(); ++i) {
                EXPECT_TRUE(same_bits(a.colliders[collider0 + i], b.colliders[i])) << name << " collider " << i;
            }
        }
    }
}

class ShardedSimulation : public ::testing::TestWithParam<testing_support::BackendCase> {
protected:
    void SetUp() override {
        if (GetParam() == BackendKind::Vulkan) {
            if (auto reason = testing_support::no_vulkan_device_reason(); !reason.empty()) GTEST_SKIP() << reason;
        }
    }
};

// 270 birds in 7 shards (38 or 39 each, not multiples of any SIMD width or workgroup):
// every shard's poses are the whole run's of its birds, bit for bit.
TEST_P(ShardedSimulation, BirdShardsAreTheWholeRunsBirds) {
    constexpr std::uint32_t kFrames = 24, kShards = 7;
    auto whole = open(scene_path("flock.json"), kFrames, {}, GetParam());
    ASSERT_NE(whole, nullptr);
    const std::size_t n = bird_world(*whole).birds.size();
    std::vector<gpu::BirdPose> all(kFrames * n);
    ASSERT_TRUE(step_birds(*whole, kFrames, all).ok());
    for (std::uint32_t s = 0; s < kShards; ++s) {
        auto part = open(scene_path("flock.json"), kFrames, {s, kShards}, GetParam());
        ASSERT_NE(part, nullptr);
        const InstanceRange range = part->shard().part("birds").range;
        ASSERT_EQ(bird_world(*part).birds.size(), range.size());
        EXPECT_EQ(part->shard().part("birds").scene_count, n);
        std::vector<gpu::BirdPose> poses(kFrames * range.size());
        ASSERT_TRUE(step_birds(*part, kFrames, poses).ok());
        for (std::uint32_t f = 0; f < kFrames; ++f) {
            for (std::uint32_t b = 0; b < range.size(); ++b) {
                ASSERT_TRUE(same_bits(poses[f * range.size() + b], all[f * n + range.begin + b]))
                    << "shard " << s << ", frame " << f << ", bird " << range.begin + b;
            }
        }
    }
}

namespace {

// Steps `part`, a shard of `whole` (stepped already, its chains per frame in `all`), and
// expects each frame's chains to be the whole run's of the shard's characters, bit for bit.
void expect_shard_is_whole(Simulation& part, const Simulation& whole, const std::vector<ChainSnapshot>& all,
                           const std::string& what) {
    const InstanceRange range = part.shard().part("characters").range;
    const RodScene& scene = *rod_scene(whole);
    const std::uint32_t joint0 = scene.world.chains[scene.instances[range.begin].chain_begin].joint_begin;
    ChainSnapshot snapshot;
    for (std::uint32_t f = 0; f < all.size(); ++f) {
        ASSERT_TRUE(part.step(1).ok());
        ASSERT_TRUE(read_chains(part, snapshot).ok());
        ASSERT_EQ(snapshot.positions.size(), rod_scene(part)->world.joint_count);
        for (std::size_t j = 0; j < snapshot.positions.size(); ++j) {
            ASSERT_TRUE(same_bits(snapshot.positions[j], all[f].positions[joint0 + j]) &&
                        same_bits(snapshot.orientations[j], all[f].orientations[joint0 + j]))
                << what << ", frame " << f << ", joint " << joint0 + j;
        }
    }
}

}  // namespace

// Chains of procedural (crowd.json) and rigged (crowd-gltf.json) characters in 3 shards.
TEST_P(ShardedSimulation, CharacterShardsAreTheWholeRunsChains) {
    constexpr std::uint32_t kFrames = 4, kShards = 3;
    for (const char* name : {"crowd.json", "crowd-gltf.json"}) {
        auto whole = open(scene_path(name), kFrames, {}, GetParam());
        ASSERT_NE(whole, nullptr);
        std::vector<ChainSnapshot> all(kFrames);
        for (auto& snapshot : all) {
            ASSERT_TRUE(whole->step(1).ok());
            ASSERT_TRUE(read_chains(*whole, snapshot).ok());
        }
        for (std::uint32_t s = 0; s < kShards; ++s) {
            auto part = open(scene_path(name), kFrames, {s, kShards}, GetParam());
            ASSERT_NE(part, nullptr);
            expect_shard_is_whole(*part, *whole, all, std::string(name) + ": shard " + std::to_string(s));
        }
    }
}

// With levels of detail on (crowd-10k.json: 100 chibis 90 m from the camera, posed, their
// clips every second frame in turns by groups of 16 instances of the whole scene), 3
// shards of 33, 33 and 34 characters: their groups are not the shards' own, and every
// shard's chains are still the whole run's, bit for bit (RodScene::first_instance).
TEST_P(ShardedSimulation, LevelOfDetailShardsAreTheWholeRunsChains) {
    constexpr std::uint32_t kFrames = 8, kShards = 3, kCount = 100;
    auto make = [&](Shard shard) -> std::unique_ptr<Simulation> {
        auto loaded = load_scene(scene_path("crowd-10k.json"));
        EXPECT_TRUE(loaded.ok()) << loaded.error().message;
        if (!loaded.ok()) return nullptr;
        Scene scene = std::move(loaded).value();
        scene.crowds[0].count = kCount;
        scene.lod.enabled = true;
        auto made = Simulation::create(std::move(scene), {.backend = GetParam().kind,
                                                          .options = testing_support::backend_options(GetParam()),
                                                          .frames = kFrames, .shard = shard});
        EXPECT_TRUE(made.ok()) << made.error().message;
        return made.ok() ? std::move(made).value() : nullptr;
    };
    auto whole = make({});
    ASSERT_NE(whole, nullptr);
    std::vector<ChainSnapshot> all(kFrames);
    std::vector<rods::Level> levels;
    for (auto& snapshot : all) {
        ASSERT_TRUE(whole->step(1).ok());
        ASSERT_TRUE(read_chains(*whole, snapshot).ok());
    }
    ASSERT_TRUE(read_chain_levels(*whole, levels).ok());
    EXPECT_EQ(std::count(levels.begin(), levels.end(), rods::Level::Posed), static_cast<std::ptrdiff_t>(levels.size()))
        << "every chain posed";
    for (std::uint32_t s = 0; s < kShards; ++s) {
        auto part = make({s, kShards});
        ASSERT_NE(part, nullptr);
        if (s > 0) {
            EXPECT_NE(part->shard().part("characters").range.begin % 16, 0u) << "the shard must not start a group of 16";
        }
        expect_shard_is_whole(*part, *whole, all, "shard " + std::to_string(s));
    }
}

INSTANTIATE_TEST_SUITE_P(All, ShardedSimulation, testing_support::all_backend_kinds(), testing_support::backend_test_name);

// Over two chunks of frames (120 birds' frames per chunk at 270 birds).
TEST(Shards, MergedBirdPartsAreTheSingleBakesBytes) { expect_merge_is_single_bake("flock.json", 130, 4); }

TEST(Shards, MergedRiggedCrowdPartsAreTheSingleBakesBytes) { expect_merge_is_single_bake("crowd-gltf.json", 6, 3); }

TEST(Shards, MergedProceduralCrowdPartsAreTheSingleBakesBytes) { expect_merge_is_single_bake("crowd.json", 5, 2); }

// More shards than characters: the empty shards hold no chains and merge all the same.
TEST(Shards, EmptyShardsMergeToo) { expect_merge_is_single_bake("bunny.json", 5, 3); }

// Parts that do not make one bake are refused, naming the file and what is wrong, before
// anything is written.
TEST(Shards, MergeRefusesPartsOfOtherBakes) {
    TempDir dir;
    const std::string scene = dir.file("flock.json");
    std::filesystem::copy_file(scene_path("flock.json"), scene);
    for (std::uint32_t i = 0; i < 3; ++i) bake_part(scene, 10, {i, 3}, dir.file("p" + std::to_string(i)));
    bake_part(scene, 11, {1, 3}, dir.file("other-frames"));
    bake_part(scene, 10, {1, 2}, dir.file("other-count"));
    const auto refused = [&](std::vector<std::string> parts, const std::string& expected) {
        for (auto& p : parts) p = dir.file(p);
        auto source = open_parts(parts);
        ASSERT_FALSE(source.ok()) << expected;
        EXPECT_NE(source.error().message.find(expected), std::string::npos) << source.error().message;
    };
    refused({"p0", "p2"}, "shard 1 of 3 is missing");
    refused({"p0", "p1", "p1", "p2"}, "is given twice");
    refused({"p0", "other-frames", "p2"}, "header field \"frames\"");
    refused({"p0", "other-count", "p2"}, "does not belong with");
    {
        std::ofstream(dir.file("not-a-part")) << "{\"scene\": 1}\n";
        refused({"p0", "not-a-part", "p2"}, "not a kodawari part file");
    }
    {
        const std::string data = testing_support::file_bytes(dir.file("p1"));
        std::ofstream(dir.file("cut"), std::ios::binary) << data.substr(0, data.size() - 100);
        auto source = open_parts(std::vector<std::string>{dir.file("p0"), dir.file("cut"), dir.file("p2")});
        ASSERT_TRUE(source.ok()) << source.error().message;  // the header is whole: found while reading
        auto sink = make_birds_glb_sink(dir.file("out.glb"));
        BakeSink* sinks[] = {sink.get()};
        auto merged = bake(*source.value(), sinks);
        ASSERT_FALSE(merged.ok());
        EXPECT_NE(merged.error().message.find("cut"), std::string::npos) << merged.error().message;
        EXPECT_FALSE(std::filesystem::exists(dir.file("out.glb")));
    }
    // A trace needs what part files do not hold.
    {
        auto source = open_parts(std::vector<std::string>{dir.file("p0"), dir.file("p1"), dir.file("p2")});
        ASSERT_TRUE(source.ok()) << source.error().message;
        auto sink = make_trace_sink(dir.file("out.jsonl"));
        BakeSink* sinks[] = {sink.get()};
        auto merged = bake(*source.value(), sinks);
        ASSERT_FALSE(merged.ok());
        EXPECT_NE(merged.error().message.find("trace"), std::string::npos) << merged.error().message;
        EXPECT_FALSE(std::filesystem::exists(dir.file("out.jsonl")));
    }
    // The scene changed since: its instances could be others.
    std::ofstream(scene, std::ios::app) << " ";
    refused({"p0", "p1", "p2"}, "changed since the parts were baked");
    // Moved: --scene names it, and the bytes are checked all the same.
    std::filesystem::remove(scene);
    refused({"p0", "p1", "p2"}, "cannot read the scene file");
    auto moved = open_parts(std::vector<std::string>{dir.file("p0"), dir.file("p1"), dir.file("p2")},
                            {.scene = scene_path("flock.json")});
    EXPECT_TRUE(moved.ok()) << moved.error().message;
}

TEST(Shards, ABadShardIsRefused) {
    for (Shard bad : {Shard{0, 0}, Shard{3, 3}}) {
        auto made = Simulation::open(scene_path("flock.json"), {.backend = BackendKind::Cpu, .shard = bad});
        ASSERT_FALSE(made.ok());
        EXPECT_NE(made.error().message.find("SimulationOptions::shard"), std::string::npos) << made.error().message;
    }
}
