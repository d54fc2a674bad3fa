// The offscreen renderer (issue 5) on whatever Vulkan device exists (lavapipe without a
// GPU), with validation on under ctest. The image checks project the simulation's own
// world positions with camera math written here independently of the renderer's, so a
// wrong camera, projection or draw fails them.

#include <gtest/gtest.h>

#include "kodawari/domains/bird_draw.hpp"
#include "kodawari/domains/chain_draw.hpp"
#include "render_support.hpp"

namespace kodawari {
namespace {

using namespace render_test;

TEST(Render, ChainPixelsAreWhereTheSimulationPutsThem) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    const std::vector<std::uint32_t> frames = {0, 45, 200, 530};
    const AhogeRun run = simulate_ahoge(frames);
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const std::uint32_t f = frames[i];
        const ChainSnapshot& snapshot = run.snapshots[i];
        auto image = renderer->render(ahoge_frame(*renderer, run, f, snapshot));
        ASSERT_TRUE(image.ok()) << image.error().message;
        const Image& img = image.value();
        ASSERT_EQ(img.width, kWidth);
        ASSERT_EQ(img.height, kHeight);

        // The scene's camera as RodScene gives it (not the renderer's CameraView).
        const rods::CameraPose pose = run.rods.camera_pose(f);
        const Pinhole camera(pose.position, pose.target, run.rods.fov_deg, kWidth, kHeight);

        // Every chain joint inside the image has a lit shade of the chain colour at its
        // projection (within a pixel: the tube is at least 2 pixels wide here).
        std::vector<glm::vec2> chain_px;
        int joints = 0, worst = 0;
        for (const glm::vec3& p : snapshot.positions) {
            glm::vec2 q;
            ASSERT_TRUE(camera.project(p, q));
            chain_px.push_back(q);
            if (q.x < 2 || q.y < 2 || q.x > kWidth - 2 || q.y > kHeight - 2) continue;
            const int d = nearest_lit_match(img, q, 1, kodawari::kChainColor);
            worst = std::max(worst, d);
            EXPECT_LE(d, 2) << "frame " << f << ": no chain colour near the joint projected at (" << q.x << ", " << q.y << ")";
            ++joints;
        }
        EXPECT_GE(joints, 10) << "frame " << f << ": the strand should be in view";

        // Pixels far from the strand and the skeleton whose ray goes up (it cannot meet
        // the ground grid) show the background gradient.
        std::vector<std::pair<glm::vec2, glm::vec2>> segments;
        for (std::size_t j = 0; j + 1 < chain_px.size(); ++j) segments.push_back({chain_px[j], chain_px[j + 1]});
        const auto bones = run.rods.joint_poses(0, f);
        const auto& parents = run.rods.joint_parents(0);
        for (std::size_t j = 0; j < bones.size(); ++j) {
            glm::vec2 a, b;
            if (parents[j] < 0) continue;
            if (camera.project(bones[j].position, a) && camera.project(bones[std::size_t(parents[j])].position, b)) {
                segments.push_back({a, b});
            }
        }
        int background = 0, background_worst = 0;
        for (std::uint32_t y = 0; y < kHeight; y += 5) {
            for (std::uint32_t x = 0; x < kWidth; x += 5) {
                if (camera.ray(x, y).y <= 0.02f) continue;
                const glm::vec2 centre{float(x) + 0.5f, float(y) + 0.5f};
                bool near = false;
                for (const auto& [a, b] : segments) near = near || segment_distance(centre, a, b) < 12.0f;
                if (near) continue;
                const int d = channel_distance(img.at(x, y), background_at(y, kHeight));
                background_worst = std::max(background_worst, d);
                EXPECT_LE(d, 2) << "frame " << f << ": pixel (" << x << ", " << y << ") should be background";
                ++background;
            }
        }
        EXPECT_GE(background, 200) << "frame " << f;
        std::printf("[ render ] ahoge frame %u: %d joints in chain colour (worst channel distance %d), "
                    "%d background pixels (worst %d)\n",
                    f, joints, worst, background, background_worst);
    }
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

TEST(Render, SameFrameTwiceGivesTheSameBytesAndThePngReloads) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    const AhogeRun run = simulate_ahoge({30});
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    const render::DrawList list = ahoge_frame(*renderer, run, 30, run.snapshots[0]);
    auto first = renderer->render(list);
    auto second = renderer->render(list);
    ASSERT_TRUE(first.ok() && second.ok());
    EXPECT_TRUE(first.value().rgba == second.value().rgba) << "two renders of one draw list differ";

    testing_support::TempDir dir;
    const std::string a = dir.file("a.png"), b = dir.file("b.png");
    ASSERT_TRUE(render::write_png(a, first.value()).ok());
    ASSERT_TRUE(render::write_png(b, second.value()).ok());
    const auto bytes = [](const std::string& path) {
        std::ifstream in(path, std::ios::binary);
        return std::vector<char>(std::istreambuf_iterator<char>(in), {});
    };
    EXPECT_EQ(bytes(a), bytes(b));
    EXPECT_EQ(dir.entries().size(), 2u) << "no temporary file is left";

    int w = 0, h = 0, channels = 0;
    unsigned char* pixels = stbi_load(a.c_str(), &w, &h, &channels, 4);
    ASSERT_NE(pixels, nullptr) << stbi_failure_reason();
    EXPECT_EQ(w, int(kWidth));
    EXPECT_EQ(h, int(kHeight));
    EXPECT_TRUE(std::equal(pixels, pixels + std::size_t(w) * std::size_t(h) * 4, first.value().rgba.begin()));
    stbi_image_free(pixels);
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

TEST(Render, BirdsAreWhereTheyFly) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto scene = load_scene(scene_path("flock.json"));
    ASSERT_TRUE(scene.ok());
    auto world = build_bird_world(scene.value());
    ASSERT_TRUE(world.ok());
    auto backend = make_bird_backend(BackendKind::Cpu, {});
    ASSERT_TRUE(backend.ok());
    ASSERT_TRUE(backend.value()->load(world.value()).ok());
    constexpr std::uint32_t kFrame = 120;
    std::vector<gpu::BirdPose> poses(world.value().birds.size());
    for (std::uint32_t f = 0; f <= kFrame; ++f) ASSERT_TRUE(backend.value()->simulate(1, {.poses = poses, .diag = {}}).ok());

    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    // Birds only, no grid: any non-background pixel is a bird.
    const render::DrawList list(kodawari::scene_camera(scene.value(), kFrame), kWidth, kHeight);
    ASSERT_TRUE(kodawari::show_birds(*renderer, &world.value()).ok());
    ASSERT_TRUE(kodawari::draw_birds(*renderer, poses).ok());
    auto image = renderer->render(list);
    ASSERT_TRUE(image.ok());
    const Image& img = image.value();

    const auto& spec = scene.value().camera;
    const Pinhole camera(glm::vec3(spec.position[0], spec.position[1], spec.position[2]),
                         glm::vec3(spec.target[0], spec.target[1], spec.target[2]), spec.fov_deg, kWidth, kHeight);
    // Per bird in front of the camera: its projection and how far from it the bird may
    // reach on screen (its wingspan, or the renderer's minimum size, plus a margin).
    std::vector<std::pair<glm::vec2, float>> birds_px;
    int visible = 0, found = 0;
    for (std::size_t b = 0; b < poses.size(); ++b) {
        const gpu::BirdPose& pose = poses[b];
        const glm::vec3 p{pose.position.x, pose.position.y, pose.position.z};
        glm::vec2 q;
        if (!camera.project(p, q)) continue;
        const float depth = glm::dot(p - camera.eye, camera.forward);
        const float span = birds::wing_type_spec(static_cast<birds::WingType>(world.value().birds[b].ids.y)).wingspan;
        const float span_px = span / (2.0f * depth * camera.tan_half) * float(kHeight);
        birds_px.push_back({q, 4.0f + std::max(span_px, kodawari::kBirdMinPixels)});
        if (q.x < 3 || q.y < 3 || q.x > kWidth - 3 || q.y > kHeight - 3) continue;
        ++visible;
        bool hit = false;
        for (int dy = -2; dy <= 2 && !hit; ++dy) {
            for (int dx = -2; dx <= 2 && !hit; ++dx) {
                const auto x = std::uint32_t(int(q.x) + dx), y = std::uint32_t(int(q.y) + dy);
                hit = channel_distance(img.at(x, y), background_at(y, kHeight)) > 8;
            }
        }
        found += hit ? 1 : 0;
    }
    // And nothing is drawn far from every bird (the largest bird is a few pixels here).
    int stray = 0;
    for (std::uint32_t y = 0; y < kHeight; ++y) {
        for (std::uint32_t x = 0; x < kWidth; ++x) {
            if (channel_distance(img.at(x, y), background_at(y, kHeight)) <= 2) continue;
            const glm::vec2 c{float(x) + 0.5f, float(y) + 0.5f};
            const bool near = std::any_of(birds_px.begin(), birds_px.end(),
                                          [&](const std::pair<glm::vec2, float>& b) { return glm::length(c - b.first) < b.second; });
            stray += near ? 0 : 1;
        }
    }
    std::printf("[ render ] flock frame %u: %d of %d birds in view drawn at their projection, %d stray pixels\n", kFrame, found,
                visible, stray);
    EXPECT_GE(visible, 50);
    EXPECT_EQ(found, visible);
    EXPECT_EQ(stray, 0);
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

// The viewer's overlays (stroke, status line): pixel coordinates with the origin at the
// top-left corner and y down, drawn over the scene whatever the depth there.
TEST(Render, ScreenOverlaysAreInPixelsAndOnTop) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    const AhogeRun run = simulate_ahoge({0});
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    render::DrawList list = ahoge_frame(*renderer, run, 0, run.snapshots[0]);
    // Where the strand is: its first joint, projected independently.
    const render::CameraView camera = kodawari::scene_camera(run.scene, 0);
    const Pinhole pinhole(camera.position, camera.target, camera.fov_deg, kWidth, kHeight);
    glm::vec2 root;
    ASSERT_TRUE(pinhole.project(run.snapshots[0].positions[0], root));
    const Rgba8 overlay{10, 200, 30};
    // A 20 x 12 px rectangle over the root, and a horizontal line near the top-left corner.
    const glm::vec2 a = root - glm::vec2(10.0f, 6.0f), b = root + glm::vec2(10.0f, 6.0f);
    list.add_screen_triangle(a, {b.x, a.y}, b, overlay);
    list.add_screen_triangle(a, b, {a.x, b.y}, overlay);
    list.add_screen_line({5.0f, 7.5f}, {60.0f, 7.5f}, overlay);
    auto image = renderer->render(list);
    ASSERT_TRUE(image.ok()) << image.error().message;
    const Image& img = image.value();
    const auto px = [&](float x, float y) { return img.at(std::uint32_t(x), std::uint32_t(y)); };
    EXPECT_EQ(px(root.x, root.y), overlay) << "the overlay covers the strand";
    EXPECT_EQ(px(a.x + 1.0f, a.y + 1.0f), overlay);
    EXPECT_EQ(px(b.x - 1.0f, b.y - 1.0f), overlay);
    EXPECT_NE(px(a.x - 2.0f, root.y), overlay) << "nothing left of the rectangle";
    EXPECT_NE(px(root.x, b.y + 2.0f), overlay) << "nothing below it";
    EXPECT_EQ(px(30.0f, 7.0f), overlay) << "the line is on row 7";
    EXPECT_EQ(px(30.0f, 12.0f), background_at(12, kHeight));
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

// An orthographic scene camera is drawn orthographic: the strand's joints are where an
// orthographic projection (written here: the view as tall as the perspective frustum at
// the target) puts them. The target is 5 m away, behind and to the side of the character,
// so a perspective drawing would put them far off (checked: the test can tell the two
// apart).
TEST(Render, OrthographicSceneCameraIsDrawnOrthographic) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto scene = load_scene(scene_path("ahoge.json"));
    ASSERT_TRUE(scene.ok());
    rods::CameraMotion& motion = scene.value().camera.motion;
    motion = rods::CameraMotion{};
    motion.projection = rods::Camera::Projection::Orthographic;
    motion.position = {0.0f, 1.7f, 1.5f};
    motion.target = {1.2f, 1.55f, -3.5f};
    auto rods = build_rod_scene(scene.value());
    ASSERT_TRUE(rods.ok());
    auto backend = make_rod_backend(BackendKind::Cpu, {});
    ASSERT_TRUE(backend.ok());
    constexpr std::uint32_t kFrame = 30;
    for (std::uint32_t f = 0; f <= kFrame; ++f) {
        const rods::RodFrame input = rods.value().frame(f);
        ASSERT_TRUE((f == 0 ? backend.value()->load(rods.value().world, input) : backend.value()->step(input)).ok());
    }
    ChainSnapshot snapshot;
    ASSERT_TRUE(backend.value()->read(snapshot).ok());
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    const render::CameraView view = kodawari::scene_camera(scene.value(), kFrame);
    EXPECT_TRUE(view.orthographic);
    render::DrawList list(view, kWidth, kHeight);
    kodawari::add_characters(list, rods.value(), kFrame);
    ASSERT_TRUE(kodawari::show_chains(*renderer, &rods.value().world).ok());
    ASSERT_TRUE(kodawari::draw_chains(*renderer, snapshot).ok());
    auto image = renderer->render(list);
    ASSERT_TRUE(image.ok()) << image.error().message;

    const Pinhole pinhole(motion.position, motion.target, scene.value().camera.fov_deg, kWidth, kHeight);
    const float height_m = 2.0f * glm::length(motion.target - motion.position) * pinhole.tan_half;
    const auto ortho = [&](const glm::vec3& p) {
        const glm::vec3 d = p - motion.position;
        return glm::vec2(0.5f * float(kWidth) + glm::dot(d, pinhole.right) / height_m * float(kHeight),
                         0.5f * float(kHeight) - glm::dot(d, pinhole.up) / height_m * float(kHeight));
    };
    int joints = 0, worst = 0;
    float apart = 0.0f;
    for (const glm::vec3& p : snapshot.positions) {
        const glm::vec2 q = ortho(p);
        glm::vec2 perspective;
        ASSERT_TRUE(pinhole.project(p, perspective));
        apart = std::max(apart, glm::length(perspective - q));
        if (q.x < 2 || q.y < 2 || q.x > kWidth - 2 || q.y > kHeight - 2) continue;
        const int d = nearest_lit_match(image.value(), q, 1, kodawari::kChainColor);
        worst = std::max(worst, d);
        EXPECT_LE(d, 2) << "no chain colour near the joint projected at (" << q.x << ", " << q.y << ")";
        ++joints;
    }
    std::printf("[ render ] orthographic: %d joints in chain colour (worst channel distance %d); perspective would put "
                "them up to %.0f px away\n",
                joints, worst, double(apart));
    EXPECT_GE(joints, 10);
    EXPECT_GT(apart, 20.0f) << "the scene does not tell orthographic from perspective";
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

// Joint dots only on request (RendererOptions::joints): unlit, the chain's exact colour at
// every joint in view; without them the lit tube alone, whose pixels reach the exact
// colour only where the light factor rounds to 1.
TEST(Render, JointDotsOnlyWhenAskedFor) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    constexpr std::uint32_t kFrame = 45;
    const AhogeRun run = simulate_ahoge({kFrame});
    const ChainSnapshot& snapshot = run.snapshots[0];
    // 720 rows: the strand is long enough on screen for its dots to stay apart (at the
    // suite's 199 rows the dot rule leaves them out).
    constexpr std::uint32_t kW = 1280, kH = 720;
    int exact[2] = {0, 0}, joints = 0, dotted = 0;
    for (const bool with_joints : {false, true}) {
        render::RendererOptions options;
        options.width = kW;
        options.height = kH;
        options.validation = testing_support::validation_requested();
        options.joints = with_joints;
        auto renderer = render::Renderer::create(options);
        ASSERT_TRUE(renderer.ok()) << renderer.error().message;
        auto image = renderer.value()->render(ahoge_frame(*renderer.value(), run, kFrame, snapshot));
        ASSERT_TRUE(image.ok()) << image.error().message;
        const Image& img = image.value();
        for (std::uint32_t y = 0; y < kH; ++y) {
            for (std::uint32_t x = 0; x < kW; ++x) exact[with_joints] += img.at(x, y) == kodawari::kChainColor;
        }
        if (with_joints) {
            const rods::CameraPose pose = run.rods.camera_pose(kFrame);
            const Pinhole camera(pose.position, pose.target, run.rods.fov_deg, kW, kH);
            for (const glm::vec3& p : snapshot.positions) {
                glm::vec2 q;
                if (!camera.project(p, q) || q.x < 2 || q.y < 2 || q.x > kW - 2 || q.y > kH - 2) continue;
                ++joints;
                dotted += nearest_match(img, q, 1, kodawari::kChainColor) == 0;
            }
        }
        EXPECT_EQ(renderer.value()->validation_messages(), 0u);
    }
    std::printf("[ render ] joint dots: %d of %d joints dotted; exact chain-colour pixels %d without dots, %d with\n", dotted, joints,
                exact[0], exact[1]);
    EXPECT_GE(joints, 10);
    EXPECT_EQ(dotted, joints);
    EXPECT_GE(exact[1], 3 * joints) << "each dot is several pixels";
    EXPECT_LE(exact[0], exact[1] / 4) << "dots drawn without RendererOptions::joints";
}

// Anti-aliasing (a multisampled target, resolved): the strand's edges blend into the
// background, so pixels next to it are neither the background nor a lit shade of the
// chain. Without it every pixel is one or the other (only the chain is drawn here).
TEST(Render, StrandEdgesAreAntiAliased) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    constexpr std::uint32_t kFrame = 45;
    const AhogeRun run = simulate_ahoge({kFrame});
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    ASSERT_TRUE(kodawari::show_chains(*renderer, &run.rods.world).ok());
    ASSERT_TRUE(kodawari::draw_chains(*renderer, run.snapshots[0]).ok());
    auto image = renderer->render(render::DrawList(kodawari::scene_camera(run.scene, kFrame), kWidth, kHeight));
    ASSERT_TRUE(image.ok()) << image.error().message;
    int shade = 0, blend = 0;
    for (std::uint32_t y = 0; y < kHeight; ++y) {
        for (std::uint32_t x = 0; x < kWidth; ++x) {
            const Rgba8 c = image.value().at(x, y);
            if (channel_distance(c, background_at(y, kHeight)) <= 2) continue;
            (lit_distance(c, kodawari::kChainColor) <= 2 ? shade : blend) += 1;
        }
    }
    std::printf("[ render ] anti-aliasing: %d strand pixels of a pure shade, %d blended with the background\n", shade, blend);
    EXPECT_GE(shade, 30);
    EXPECT_GE(blend, shade / 2) << "no blended edge pixels: the target is not multisampled";
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

// A ground contact shadow darkens the ground where it is put, most in its middle (by
// its opacity: black blended at that alpha) and not at all past its rim.
TEST(Render, GroundShadowIsUnderItsCentre) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    render::CameraView view;
    view.position = {0.0f, 2.0f, 2.5f};
    view.target = {0.0f, 0.0f, 0.0f};
    render::DrawList list(view, kWidth, kHeight);
    const glm::vec3 centre{0.6f, 0.0f, 0.2f};
    constexpr float kRadius = 0.3f, kOpacity = 0.35f;
    list.add_ground_shadow(centre, kRadius, kOpacity);
    auto image = renderer->render(list);
    ASSERT_TRUE(image.ok()) << image.error().message;
    const Pinhole camera(view.position, view.target, view.fov_deg, kWidth, kHeight);
    const auto pixel = [&](const glm::vec3& p) {
        glm::vec2 q{0.0f, 0.0f};
        EXPECT_TRUE(camera.project(p, q));
        const auto x = std::uint32_t(q.x), y = std::uint32_t(q.y);
        return std::pair{image.value().at(x, y), background_at(y, kHeight)};
    };
    // The middle: the background times 1 - opacity (within 3 per channel: 8-bit
    // rounding, and the pixel centre is a little off the disc's middle, where the fade
    // has begun).
    const auto [middle, behind] = pixel(centre);
    const Rgba8 expected{std::uint8_t(std::lround(behind.r * (1.0f - kOpacity))), std::uint8_t(std::lround(behind.g * (1.0f - kOpacity))),
                         std::uint8_t(std::lround(behind.b * (1.0f - kOpacity))), 255};
    EXPECT_LE(channel_distance(middle, expected), 3) << "middle (" << int(middle.r) << ", " << int(middle.g) << ", " << int(middle.b) << ")";
    // Past the rim, and mirrored across the origin: the background.
    for (const glm::vec3& p : {centre + glm::vec3(1.5f * kRadius, 0.0f, 0.0f), centre - glm::vec3(0.0f, 0.0f, 1.5f * kRadius),
                               glm::vec3(-centre.x, 0.0f, centre.z)}) {
        const auto [c, bg] = pixel(p);
        EXPECT_EQ(channel_distance(c, bg), 0) << "shadow at (" << p.x << ", " << p.z << ")";
    }
    std::printf("[ render ] ground shadow: middle (%d, %d, %d) over background (%d, %d, %d)\n", middle.r, middle.g, middle.b, behind.r,
                behind.g, behind.b);
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

TEST(Render, PresentWithoutAWindowIsAnError) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto renderer = make_renderer(64, 48);
    ASSERT_TRUE(renderer);
    const render::DrawList list(render::CameraView{}, 64, 48);
    auto presented = renderer->present(list, 64, 48);
    ASSERT_FALSE(presented.ok());
    EXPECT_NE(presented.error().message.find("window"), std::string::npos) << presented.error().message;
}

TEST(Render, ContactSheetAndDownscale) {
    Image image;
    image.width = 31;
    image.height = 17;
    image.rgba.assign(std::size_t(31) * 17 * 4, 0);
    for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
        image.rgba[i] = 200;
        image.rgba[i + 1] = 100;
        image.rgba[i + 2] = 50;
        image.rgba[i + 3] = 255;
    }
    const Image small = render::downscale(image, 7, 5);
    ASSERT_EQ(small.rgba.size(), std::size_t(7) * 5 * 4);
    EXPECT_EQ(small.at(3, 2), (Rgba8{200, 100, 50, 255}));
    const std::vector<Image> images(5, image);
    const Image sheet = render::contact_sheet(images, 3, 10, 6);
    EXPECT_EQ(sheet.width, 3u * 10 + 4 * 2);
    EXPECT_EQ(sheet.height, 2u * 6 + 3 * 2);
    EXPECT_EQ(sheet.at(0, 0), (Rgba8{255, 255, 255, 255}));
    EXPECT_EQ(sheet.at(2, 2), (Rgba8{200, 100, 50, 255}));
    EXPECT_EQ(sheet.at(sheet.width - 3, sheet.height - 3), (Rgba8{255, 255, 255, 255})) << "the sixth cell is empty";
}

}  // namespace
}  // namespace kodawari
