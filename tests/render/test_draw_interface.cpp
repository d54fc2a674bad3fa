// The neutral drawing interface (kodawari/render/draw.hpp, issue 31): each primitive a
// domain draws through render::Draw lands where an independent pinhole projection puts
// it, in its colour (lit shades of it for the lit ones), and clear_draws() removes it.
#include <gtest/gtest.h>

#include <vector>

#include "render/render_support.hpp"

using namespace kodawari;
using namespace kodawari::render_test;

namespace {

constexpr Rgba8 kColor{200, 120, 40};

struct Fixture {
    std::unique_ptr<render::Renderer> renderer;
    render::CameraView camera;
    Pinhole pinhole{{0.0f, 1.0f, 4.0f}, {0.0f, 1.0f, 0.0f}, 50.0f, kWidth, kHeight};

    Fixture() {
        renderer = make_renderer(kWidth, kHeight);
        camera.position = {0.0f, 1.0f, 4.0f};
        camera.target = {0.0f, 1.0f, 0.0f};
        camera.fov_deg = 50.0f;
    }
    Image render() {
        auto image = renderer->render(render::DrawList(camera, kWidth, kHeight));
        EXPECT_TRUE(image.ok()) << image.error().message;
        return image.ok() ? std::move(image).value() : Image{};
    }
    glm::vec2 at(const glm::vec3& p) const {
        glm::vec2 out;
        EXPECT_TRUE(pinhole.project(p, out));
        return out;
    }
};

TEST(DrawInterface, EveryPrimitiveLandsWhereItIsAndClears) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    Fixture f;
    ASSERT_NE(f.renderer, nullptr);
    render::Draw& draw = *f.renderer;
    const glm::vec3 left{-1.2f, 1.0f, 0.0f}, right{1.2f, 1.0f, 0.0f};

    // Unlit: exactly the colour at the middle (distance 0), within 1 pixel.
    {
        const glm::vec3 c[] = {left};
        draw.discs(c, 0.08f, kColor);
        const glm::vec3 pairs[] = {right - glm::vec3(0.0f, 0.3f, 0.0f), right + glm::vec3(0.0f, 0.3f, 0.0f)};
        draw.lines(pairs, kColor);
        const Image image = f.render();
        EXPECT_EQ(nearest_match(image, f.at(left), 1, kColor), 0) << "disc";
        EXPECT_EQ(nearest_match(image, f.at(right), 1, kColor), 0) << "line";
        // Nothing at the middle of the picture, between them.
        EXPECT_GT(channel_distance(image.at(kWidth / 2, kHeight / 2), kColor), 40);
    }
    f.renderer->clear_draws();
    {
        const Image image = f.render();
        EXPECT_GT(nearest_match(image, f.at(left), 1, kColor), 40) << "cleared";
    }
    // Lit: a shade of the colour (lit_distance small) at each one's middle.
    {
        const glm::vec3 points[] = {left - glm::vec3(0.0f, 0.5f, 0.0f), left, left + glm::vec3(0.0f, 0.5f, 0.0f)};
        const render::Polyline line[] = {{0, 3, 0.05f, kColor}};
        draw.tubes(points, line);
        const render::Capsule capsule[] = {{{0.0f, 0.7f, 0.0f}, {0.0f, 1.3f, 0.0f}, 0.12f}};
        draw.capsules(capsule, kColor);
        // A unit cube's 12 triangles, scaled to 0.3 m and placed on the right.
        const glm::vec3 corners[] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                     {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
        const std::uint32_t indices[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                         2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};
        glm::mat4 place(0.15f);
        place[3] = glm::vec4(right, 1.0f);
        const glm::mat4 transforms[] = {place};
        draw.meshes({corners, indices}, transforms, kColor);
        const Image image = f.render();
        EXPECT_LE(nearest_lit_match(image, f.at(left), 1, kColor), 2) << "tube";
        EXPECT_LE(nearest_lit_match(image, f.at({0.0f, 1.0f, 0.12f}), 1, kColor), 2) << "capsule";
        EXPECT_LE(nearest_lit_match(image, f.at(right + glm::vec3(0.0f, 0.0f, 0.15f)), 1, kColor), 2) << "mesh";
    }
    EXPECT_EQ(f.renderer->validation_messages(), 0u);
}

}  // namespace
