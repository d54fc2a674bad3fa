// The shipped rod scenes: they load, build and give deterministic, valid frames that simulate.

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

#include <kodawari/vulkan/gpu_info.hpp>
#include <kodawari/backends/rod_backend.hpp>
#include <kodawari/scene/scene.hpp>
#include <kodawari/rods/kinematics.hpp>
#include <kodawari/rods/solver.hpp>
#include <kodawari/rods/world.hpp>

#include "character_support.hpp"

using namespace kodawari::testing_support::characters;  // the character suites' shared helpers

// ---------------------------------------------------------------------------------------
// The shipped rod scenes

namespace {

// Every `every`-th frame (and the last) fits the world: sizes, dt, finite values.
void expect_frames_valid(const RodScene& rs, std::uint32_t every) {
    rods::RodFrame frame;
    for (std::uint32_t f = 0; f < rs.frames; f += (f + every < rs.frames || f + 1 == rs.frames) ? every : rs.frames - 1 - f) {
        rs.frame(f, frame);
        const auto ok = rods::check_frame(rs.world, frame);
        ASSERT_TRUE(ok.ok()) << "frame " << f << ": " << ok.error().message;
        if (f + 1 == rs.frames) break;
    }
}

}  // namespace

TEST(CharacterScenes, ShippedRodScenesLoadAndBuild) {
    struct Expect {
        const char* file;
        std::uint32_t characters, chains, views_of_first;
    };
    for (const Expect& e : {Expect{"scenes/bunny.json", 1, 2, 3}, Expect{"scenes/ahoge.json", 1, 1, 5},
                            Expect{"scenes/bangs.json", 1, 6, 1}, Expect{"scenes/crowd.json", 1024, 8192, 3}}) {
        SCOPED_TRACE(e.file);
        const Scene scene = load(e.file);
        EXPECT_EQ(scene.version, 2u);
        EXPECT_EQ(scene.camera.motion.kind, rods::CameraMotion::Kind::Orbit) << "every rod scene shows its effect round the character";
        const RodScene rs = build(scene);
        EXPECT_EQ(rs.world.character_count, e.characters);
        EXPECT_EQ(rs.world.chains.size(), e.chains);
        ASSERT_FALSE(rs.world.templates.empty());
        EXPECT_EQ(rs.world.templates[0].views.size(), e.views_of_first);
        EXPECT_EQ(rs.character_names.size(), e.characters);
        EXPECT_EQ(rs.chain_names.size(), e.chains);
        EXPECT_EQ(rs.frames, scene.frame_count());
        expect_frames_valid(rs, std::string(e.file) == "scenes/crowd.json" ? 10 : 1);
    }
    // The bunny's ears: 10-12 joints, front, left and right examples.
    const RodScene bunny = build(load("scenes/bunny.json"));
    EXPECT_EQ(bunny.chain_names, (std::vector<std::string>{"bunny#0/ear_l", "bunny#0/ear_r"}));
    for (const rods::ChainTemplate& t : bunny.world.templates) {
        EXPECT_GE(t.chain.joint_count, 10u);
        EXPECT_LE(t.chain.joint_count, 12u);
    }
    // The crowd: 1000+ characters, 8+ chains each of 8-16 joints, each instance on its own clock.
    const RodScene crowd = build(load("scenes/crowd.json"));
    EXPECT_GE(crowd.world.character_count, 1000u);
    EXPECT_GE(crowd.chain_count(0), 8u);
    EXPECT_EQ(crowd.world.joint_count, 75776u);  // scenes/README.md
    for (const rods::ChainTemplate& t : crowd.world.templates) {
        EXPECT_GE(t.chain.joint_count, 8u) << t.name;
        EXPECT_LE(t.chain.joint_count, 16u) << t.name;
    }
    EXPECT_EQ(crowd.character_names[12], "critter#12");
    EXPECT_EQ(crowd.chain_names[12 * crowd.chain_count(0)], "critter#12/ear_l");
    EXPECT_EQ(crowd.joint_names(12), (std::vector<std::string>{"body", "neck", "head"}));
    EXPECT_EQ(crowd.joint_parents(12), (std::vector<std::int32_t>{-1, 0, 1}));
}

// The same scene gives the same bits, whatever order the frames are asked for in.
TEST(CharacterScenes, FramesAreDeterministic) {
    const Scene scene = load("scenes/crowd.json");
    const RodScene a = build(scene);
    const RodScene b = build(scene);
    ASSERT_EQ(a.instances.size(), b.instances.size());
    EXPECT_EQ(std::memcmp(a.instances.data(), b.instances.data(), a.instances.size() * sizeof(kodawari::CharacterInstance)), 0);
    rods::RodFrame reused;
    for (const std::uint32_t f : {149u, 0u, 37u, 100u, 37u}) {
        a.frame(f, reused);  // the out-parameter path, storage reused from another frame
        EXPECT_TRUE(same_frame(reused, b.frame(f))) << "frame " << f;
    }
}

// The crowd's per-frame input is cheap, and a few instances' chains simulate through the
// whole scene (stopping, turning, walking) without blowing up or stretching.
TEST(CharacterScenes, CrowdFrameCostAndInstancesSimulate) {
    const RodScene rs = build(load("scenes/crowd.json"));
    rods::RodFrame frame;
    rs.frame(0, frame);
    const auto start = std::chrono::steady_clock::now();
    for (std::uint32_t f = 0; f < rs.frames; ++f) rs.frame(f, frame);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("[ measured ] crowd: RodScene::frame for %u characters, %zu chains: %.3f ms per frame\n",
                rs.world.character_count, rs.world.chains.size(), 1e3 * seconds / static_cast<double>(rs.frames));
    constexpr std::uint32_t kInstances = 4;  // each on its own clock (time offsets)
    const std::uint32_t chains = kInstances * rs.chain_count(0);
    Simulation sim(rs, chains);
    float worst_stretch = 0.0f;
    for (std::uint32_t f = 1; f < rs.frames; ++f) {
        sim.step(f);
        for (std::uint32_t c = 0; c < chains; ++c) {
            const rods::Chain& chain = rs.world.templ(rs.world.chains[c]).chain;
            for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) {
                const float l = glm::length(sim.x(c, i + 1) - sim.x(c, i));
                ASSERT_TRUE(std::isfinite(l)) << rs.chain_names[c] << " frame " << f;
                worst_stretch = std::max(worst_stretch, std::abs(l - chain.segment_length[i]) / chain.segment_length[i]);
            }
        }
    }
    std::printf("[ measured ] crowd instances 0-%u: worst segment stretch %.3g over %u frames\n", kInstances - 1,
                static_cast<double>(worst_stretch), rs.frames);
    // Bound 2% of a segment. The solver projects collisions after the distance constraints
    // (SPEC A.4's order), so a segment pressed hard against the head sphere does stretch:
    // with the bangs 6 mm off the collider a run-and-stop stretched one by 4.9%; they now
    // ride 16 mm off it, and nothing else touches.
    EXPECT_LT(worst_stretch, 0.02f);
}

// The small scenes simulate through their whole length: every value finite, every segment
// within 2% of its length (the bound of the crowd test above, for the same reason).
TEST(CharacterScenes, SmallScenesSimulateWithoutStretch) {
    for (const char* file : {"scenes/bunny.json", "scenes/ahoge.json", "scenes/bangs.json"}) {
        const RodScene rs = build(load(file));
        Simulation sim(rs);
        float worst = 0.0f;
        for (std::uint32_t f = 1; f < rs.frames; ++f) {
            sim.step(f);
            for (std::uint32_t c = 0; c < rs.world.chains.size(); ++c) {
                const rods::Chain& chain = rs.world.templ(rs.world.chains[c]).chain;
                for (std::uint32_t i = 0; i + 1 < chain.joint_count; ++i) {
                    const float l = glm::length(sim.x(c, i + 1) - sim.x(c, i));
                    ASSERT_TRUE(std::isfinite(l)) << file << " " << rs.chain_names[c] << " frame " << f;
                    worst = std::max(worst, std::abs(l - chain.segment_length[i]) / chain.segment_length[i]);
                }
            }
        }
        std::printf("[ measured ] %s: worst segment stretch %.3g over %u frames\n", file, static_cast<double>(worst), rs.frames);
        EXPECT_LT(worst, 0.02f) << file;
    }
}
