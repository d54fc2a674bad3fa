// scenes/tower.json, the shipped example of a flock's obstacles (docs/scene-format.md,
// "flocking"): 3 000 flocking starlings on a loop past a tower (a capsule), a balloon (a
// sphere) and a cliff (a plane). Over the whole run no bird enters an obstacle, which the
// same flock without them does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include <glm/glm.hpp>

#include "kodawari/domains/birds.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

// The obstacles as scenes/tower.json writes them.
constexpr glm::vec3 kTowerA{0.0f, 0.0f, 58.0f}, kTowerB{0.0f, 80.0f, 58.0f};
constexpr float kTowerRadius = 4.0f;
constexpr glm::vec3 kBalloon{38.0f, 35.0f, -32.0f};
constexpr float kBalloonRadius = 6.0f;
constexpr float kCliffX = -55.0f;  // the plane x = -50, birds on +x

float segment_distance(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b) {
    const float t = std::clamp(glm::dot(p - a, b - a) / glm::dot(b - a, b - a), 0.0f, 1.0f);
    return glm::length(p - (a + t * (b - a)));
}

struct Clearances {
    float tower = 1e9f, balloon = 1e9f, cliff = 1e9f;  // m from each surface, the nearest bird's
};

// Each obstacle's clearance at the nearest bird over the whole of `scene` on the cpu
// backend.
Clearances fly(Scene scene) {
    const std::uint32_t frames = scene.frame_count();
    const std::size_t birds = scene.flocks.at(0).count;
    auto sim = Simulation::create(std::move(scene), {.backend = BackendKind::Cpu});
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    Clearances c;
    if (!sim.ok()) return c;
    constexpr std::uint32_t kChunk = 60;
    std::vector<gpu::BirdPose> poses(std::size_t{kChunk} * birds);
    for (std::uint32_t done = 0; done < frames; done += kChunk) {
        const std::uint32_t n = std::min(kChunk, frames - done);
        EXPECT_TRUE(step_birds(*sim.value(), n, std::span(poses).first(std::size_t{n} * birds)).ok());
        for (std::size_t i = 0; i < std::size_t{n} * birds; ++i) {
            const glm::vec3 p(poses[i].position.x, poses[i].position.y, poses[i].position.z);
            c.tower = std::min(c.tower, segment_distance(p, kTowerA, kTowerB) - kTowerRadius);
            c.balloon = std::min(c.balloon, glm::length(p - kBalloon) - kBalloonRadius);
            c.cliff = std::min(c.cliff, p.x - kCliffX);
        }
    }
    return c;
}

TEST(TowerScene, TheFlockFliesRoundItsObstaclesAndNeverIntoThem) {
    auto scene = load_scene(std::string(KODAWARI_SOURCE_DIR) + "/scenes/tower.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_EQ(scene.value().flocks.size(), 1u);
    ASSERT_TRUE(scene.value().flocks[0].flocking.has_value());
    ASSERT_EQ(scene.value().flocks[0].flocking->obstacles.size(), 3u);
    Scene bare = scene.value();
    bare.flocks[0].flocking->obstacles.clear();
    const Clearances with = fly(std::move(scene).value());
    const Clearances without = fly(std::move(bare));
    std::printf("[ tower ] nearest bird to the tower's surface %.2f m (without the obstacles %.2f m), the balloon's %.2f m "
                "(%.2f m), the cliff %.2f m (%.2f m)\n",
                double(with.tower), double(without.tower), double(with.balloon), double(without.balloon), double(with.cliff),
                double(without.cliff));
    // Outside each, by more than a bird's half length (a pigeon's body reaches about
    // 0.2 m from its centre) ...
    EXPECT_GT(with.tower, 0.2f);
    EXPECT_GT(with.balloon, 0.2f);
    EXPECT_GT(with.cliff, 0.2f);
    // ... where the same flock without them flies into each: the route takes it there,
    // the avoidance keeps it out.
    EXPECT_LT(without.tower, 0.0f);
    EXPECT_LT(without.balloon, 0.0f);
    EXPECT_LT(without.cliff, 0.0f);
}

}  // namespace
