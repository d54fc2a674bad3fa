// Birds that roll and turn smoothly (issue 39 item 4): the bank's first-order filter
// (docs/flight-modes.md F.6) and the shipped scenes' largest Body turn between two frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "kodawari/birds/flight.hpp"
#include "kodawari/scene/scene.hpp"
#include "test_paths.hpp"

using namespace kodawari;
using namespace kodawari::birds;

namespace {

constexpr double kRadToDeg = 57.29577951308232;

// The angle of the rotation between unit quaternions p and q: 2 acos |p.q|, in degrees,
// in double so that the small angles of a smooth flight are not lost to acos's rounding.
double turn_deg(const gpu::vec4& p, const gpu::vec4& q) {
    const double d = std::fabs(double{p.x} * double{q.x} + double{p.y} * double{q.y} + double{p.z} * double{q.z} + double{p.w} * double{q.w});
    return 2.0 * std::acos(std::min(d, 1.0)) * kRadToDeg;
}

struct Worst {
    double deg = 0.0;
    std::size_t bird = 0;
    std::uint32_t frame = 0;
};

// The largest Body turn between consecutive frames of the birds [0, count) step `stride`
// over every frame of the world, on cpu-reference (the backend parity tests hold cpu and
// Vulkan to it).
Worst worst_body_turn(const BirdWorld& world, std::size_t stride) {
    const gpu::FlightUniforms u = world.uniforms();
    Worst worst;
    for (std::size_t b = 0; b < world.birds.size(); b += stride) {
        // Flocking birds fly their flocking domain's motion, not a route: their turns are
        // held to the same bound by tests/flocking/test_flocking.cpp.
        if (world.birds[b].ids.w == KW_BIRD_DRIVEN) continue;
        gpu::BirdState state = initial_state();
        gpu::vec4 last{};
        for (std::uint32_t k = 0; k < world.frames; ++k) {
            const BirdFrame f = step_bird(world, u, world.birds[b], state, k);
            const gpu::vec4 body = f.pose.rotation[KW_PART_BODY];
            if (k > 0) {
                const double deg = turn_deg(last, body);
                if (deg > worst.deg) worst = {deg, b, k};
            }
            last = body;
        }
    }
    return worst;
}

}  // namespace

TEST(BankFilter, NoShippedBirdTurnsMoreThanSixDegreesBetweenFrames) {
    // Every scene in scenes/ with flocks, whole duration, wingbeats included (step_bird
    // is the whole pose). 6 degrees a frame (360 deg/s at 60 fps) is the bound: the
    // wingbeat's own pitch oscillation moves the Body up to ~2 degrees a frame, a
    // sustained turn ~1-2, and the filtered roll the rest. Scenes of more than 1024 birds
    // are sampled with an odd stride, which meets every route variant (a power of two
    // or fewer of them) and every place in the formation's trail.
    const std::filesystem::path dir = std::filesystem::path(KODAWARI_SOURCE_DIR) / "scenes";
    std::vector<std::filesystem::path> scenes;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        if (entry.path().extension() != ".json") continue;
        std::ifstream in(entry.path());
        std::stringstream text;
        text << in.rdbuf();
        if (text.str().find("\"flocks\"") != std::string::npos) scenes.push_back(entry.path());
    }
    std::sort(scenes.begin(), scenes.end());
    ASSERT_GE(scenes.size(), 4u);
    for (const auto& path : scenes) {
        auto scene = load_scene(path.string());
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        auto world = build_bird_world(scene.value());
        ASSERT_TRUE(world.ok()) << world.error().message;
        const std::size_t n = world.value().birds.size();
        const std::size_t stride = n > 1024 ? (n / 1024) | 1u : 1u;
        const Worst w = worst_body_turn(world.value(), stride);
        std::printf("%s: worst Body turn %.2f deg (bird %zu, frame %u)\n", path.filename().string().c_str(), w.deg, w.bird,
                    w.frame);
        EXPECT_LE(w.deg, 6.0) << path.filename() << " bird " << w.bird << " frame " << w.frame;
    }
}
