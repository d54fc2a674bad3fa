// The flocking domain draws what its birds keep clear of (kodawari/domains/flocking.hpp,
// docs/rendering.md): the scene's sphere and capsule obstacles as lit solids and its plane
// as a grid of lines, the application's obstacles (set_flock_agents) from the frame they
// are placed until they are removed; attractors are not drawn.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "kodawari/domains/flocking.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "render/render_support.hpp"

using namespace kodawari;
using namespace kodawari::render_test;

namespace {

constexpr std::uint32_t kW = 480, kH = 300;

// 101 birds on a loop round (0, 45, 0), 45 m each way; the obstacles beside it.
std::string obstacle_scene(bool obstacles) {
    const std::string flocking =
        obstacles ? R"({"obstacles": [
                         {"type": "sphere", "center": [80, 45, 0], "radius": 6},
                         {"type": "capsule", "a": [-80, 0, 0], "b": [-80, 40, 0], "radius": 4},
                         {"type": "plane", "point": [0, 20, 0], "normal": [0, 1, 0]}],
                       "attractors": [{"position": [0, 90, 0], "radius": 30, "weight": 5}]})"
                  : R"({"attractors": [{"position": [0, 90, 0], "radius": 30, "weight": 5}]})";
    return R"({"format": "kodawari-scene", "version": 1, "name": "obstacles", "fps": 30, "duration": 1,
               "camera": {"position": [0, 60, -200], "target": [0, 40, 0], "fov_deg": 60},
               "flocks": [{"name": "starlings", "wing_type": "pigeon", "count": 101, "speed": 15,
                 "generated_route": {"seed": 7, "segments": 8, "center": [0, 45, 0], "extent": [45, 8, 45], "loop": true},
                 "formation": {"spread": [6, 3, 6]}, "flocking": )" +
           flocking + "}]}";
}

struct Drawn {
    Image image;
    int plane_pixels = 0;  // exactly kObstaclePlaneColor
};

// The scene stepped a frame for each of `placed` (what the application places before
// that step), and the last frame drawn from the scene's camera.
Drawn draw(bool obstacles, const std::vector<std::vector<FlockAgent>>& placed) {
    auto scene = parse_scene(obstacle_scene(obstacles), "obstacles.json");
    EXPECT_TRUE(scene.ok()) << scene.error().message;
    if (!scene.ok()) return {};
    auto sim = Simulation::create(std::move(scene).value(), {.backend = BackendKind::Cpu});
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    auto renderer = make_renderer(kW, kH);
    if (!sim.ok() || renderer == nullptr) return {};
    EXPECT_TRUE(sim.value()->show_on(*renderer).ok());
    for (const std::vector<FlockAgent>& agents : placed) {
        EXPECT_TRUE(set_flock_agents(*sim.value(), agents).ok());
        EXPECT_TRUE(sim.value()->step(1).ok());
    }
    EXPECT_TRUE(sim.value()->draw_on(*renderer).ok());
    render::CameraView view;
    view.position = {0.0f, 60.0f, -200.0f};
    view.target = {0.0f, 40.0f, 0.0f};
    view.fov_deg = 60.0f;
    auto image = renderer->render(render::DrawList(view, kW, kH));
    EXPECT_TRUE(image.ok()) << image.error().message;
    EXPECT_EQ(renderer->validation_messages(), 0u);
    Drawn out;
    if (!image.ok()) return out;
    out.image = std::move(image).value();
    for (std::uint32_t y = 0; y < kH; ++y) {
        for (std::uint32_t x = 0; x < kW; ++x) out.plane_pixels += out.image.at(x, y) == kObstaclePlaneColor;
    }
    return out;
}

TEST(FlockDraw, ObstaclesAreDrawnAsTheObjectsTheyStandFor) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    const Pinhole camera({0.0f, 60.0f, -200.0f}, {0.0f, 40.0f, 0.0f}, 60.0f, kW, kH);
    const auto at = [&](const glm::vec3& p) {
        glm::vec2 q;
        EXPECT_TRUE(camera.project(p, q));
        return q;
    };
    // The sides facing the camera: the sphere's and the capsule's nearest points.
    const glm::vec2 sphere = at({80.0f, 45.0f, -6.0f}), capsule = at({-80.0f, 20.0f, -4.0f});
    const glm::vec2 attractor = at({0.0f, 90.0f, 0.0f}), placed = at({0.0f, 100.0f, -5.0f});
    FlockAgent balloon;
    balloon.kind = FlockAgent::Kind::Obstacle;
    balloon.position = {0.0f, 100.0f, 0.0f};
    balloon.radius = 5.0f;

    const Drawn bare = draw(false, {{}, {}});
    const Drawn with = draw(true, {{}, {balloon}});
    const Drawn removed = draw(true, {{balloon}, {}});
    // A lit shade of the colour (lit_distance 2 at most: rounding; measured 0) within a
    // pixel of where each solid's middle projects; the same pixels without obstacles are
    // the sky (the background's distance to the colour is tens).
    EXPECT_LE(nearest_lit_match(with.image, sphere, 1, kObstacleColor), 2) << "the scene's sphere";
    EXPECT_LE(nearest_lit_match(with.image, capsule, 1, kObstacleColor), 2) << "the scene's capsule";
    EXPECT_LE(nearest_lit_match(with.image, placed, 1, kObstacleColor), 2) << "the application's sphere";
    for (const glm::vec2 p : {sphere, capsule, placed, attractor}) {
        EXPECT_GT(nearest_lit_match(bare.image, p, 1, kObstacleColor), 10) << p.x << ", " << p.y << " without obstacles";
    }
    EXPECT_GT(nearest_lit_match(with.image, attractor, 1, kObstacleColor), 10) << "an attractor is a force, not drawn";
    // The application's sphere goes when the application removes it; the scene's stay.
    EXPECT_GT(nearest_lit_match(removed.image, placed, 1, kObstacleColor), 10) << "the application's sphere, removed";
    EXPECT_LE(nearest_lit_match(removed.image, sphere, 1, kObstacleColor), 2) << "the scene's sphere, a frame later";
    // The plane (20 m up) as lines, unlit: exactly their colour along them. 1-pixel lines
    // over the width of the picture, 10 to 25 each way: hundreds of pixels.
    std::printf("[ flock draw ] plane lines: %d pixels (none without obstacles: %d)\n", with.plane_pixels, bare.plane_pixels);
    EXPECT_GT(with.plane_pixels, 500);
    EXPECT_EQ(bare.plane_pixels, 0);
}

}  // namespace
