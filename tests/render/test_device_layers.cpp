// The renderer's layers drawn from the vulkan backends' own buffers on the renderer's
// device (issue 5: one device, buffers shared, no copy back per frame): the images equal
// those drawn from the state read back, and nothing is read back.

#include <gtest/gtest.h>

#include "kodawari/domains/bird_draw.hpp"
#include "kodawari/domains/chain_draw.hpp"
#include "render_support.hpp"

namespace kodawari {
namespace {

using namespace render_test;

// The viewer's path (issue 5: one device, buffers shared, no copy back per frame): the
// vulkan rod backend runs on the renderer's device and the chains are drawn from its
// state buffers. The image must be the very one drawn from the snapshot read back from
// those buffers (the same positions, bit for bit, through the same shader), and drawing
// 20 frames that way must read nothing back.
TEST(Render, ChainsDrawnFromTheVulkanBackendsBuffersNeedNoReadBack) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto scene = load_scene(scene_path("ahoge.json"));
    ASSERT_TRUE(scene.ok());
    auto rods = build_rod_scene(scene.value());
    ASSERT_TRUE(rods.ok());
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    BackendOptions options;
    options.context = renderer->device_context();
    auto backend = make_rod_backend(BackendKind::Vulkan, options);
    ASSERT_TRUE(backend.ok()) << backend.error().message;
    RodBackend& vulkan = *backend.value();
    ASSERT_TRUE(kodawari::show_chains(*renderer, &rods.value().world).ok());
    constexpr std::uint32_t kFrames = 60;
    const std::uint64_t before = renderer->read_back_bytes();
    std::optional<render::DrawList> list;
    Image from_device;
    for (std::uint32_t f = 0; f <= kFrames; ++f) {
        const rods::RodFrame input = rods.value().frame(f);
        ASSERT_TRUE((f == 0 ? vulkan.load(rods.value().world, input) : vulkan.step(input)).ok());
        if (f + 20 <= kFrames) continue;
        ASSERT_TRUE(kodawari::draw_chains(*renderer, vulkan).ok());
        ASSERT_TRUE(kodawari::chains_drawn_on_device(*renderer));
        list.emplace(kodawari::scene_camera(scene.value(), f), kWidth, kHeight);
        auto image = renderer->render(*list);
        ASSERT_TRUE(image.ok()) << image.error().message;
        from_device = std::move(image).value();
    }
    const std::uint64_t read_back = renderer->read_back_bytes() - before;
    EXPECT_EQ(read_back, 0u) << "drawing from the backend's buffers read state back";

    ChainSnapshot snapshot;
    ASSERT_TRUE(vulkan.read(snapshot).ok());
    EXPECT_GT(renderer->read_back_bytes() - before, 0u) << "read() is counted: the check above can fail";
    ASSERT_TRUE(kodawari::draw_chains(*renderer, snapshot).ok());
    EXPECT_FALSE(kodawari::chains_drawn_on_device(*renderer));
    auto from_host = renderer->render(*list);
    ASSERT_TRUE(from_host.ok());
    int chain_pixels = 0;
    for (std::size_t i = 0; i < from_device.rgba.size(); i += 4) {
        chain_pixels += lit_distance(Rgba8{from_device.rgba[i], from_device.rgba[i + 1], from_device.rgba[i + 2], 255}, kodawari::kChainColor) <= 2;
    }
    std::printf("[ render ] device-drawn chains: %d chain pixels, %llu bytes read back over 20 frames\n", chain_pixels,
                static_cast<unsigned long long>(read_back));
    // The strand is about 60 pixels long and 2 wide here; anti-aliasing blends its edges
    // with the background, so about one pixel per row of it keeps a pure lit shade.
    EXPECT_GE(chain_pixels, 30) << "the strand is in view";
    EXPECT_TRUE(from_device.rgba == from_host.value().rgba) << "the device-drawn chains differ from the uploaded snapshot's";
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

// The same for birds: the vulkan bird backend's pose ring drawn where it is, against the
// same poses read back by a second backend on the same device.
TEST(Render, BirdsDrawnFromTheVulkanBackendsRingNeedNoReadBack) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto scene = load_scene(scene_path("flock.json"));
    ASSERT_TRUE(scene.ok());
    auto world = build_bird_world(scene.value());
    ASSERT_TRUE(world.ok());
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    BackendOptions options;
    options.context = renderer->device_context();
    auto shared = make_bird_backend(BackendKind::Vulkan, options);
    auto reading = make_bird_backend(BackendKind::Vulkan, options);
    ASSERT_TRUE(shared.ok() && reading.ok());
    ASSERT_TRUE(shared.value()->load(world.value()).ok());
    ASSERT_TRUE(reading.value()->load(world.value()).ok());
    ASSERT_TRUE(kodawari::show_birds(*renderer, &world.value()).ok());
    constexpr std::uint32_t kFrame = 120;
    const render::DrawList list(kodawari::scene_camera(scene.value(), kFrame), kWidth, kHeight);
    const std::uint64_t before = renderer->read_back_bytes();
    Image from_device;
    for (std::uint32_t f = 0; f <= kFrame; ++f) {
        ASSERT_TRUE(shared.value()->simulate(1, {}).ok());
        if (f + 10 <= kFrame) continue;
        ASSERT_TRUE(kodawari::draw_birds(*renderer, *shared.value()).ok());
        auto image = renderer->render(list);
        ASSERT_TRUE(image.ok());
        from_device = std::move(image).value();
    }
    const std::uint64_t read_back = renderer->read_back_bytes() - before;
    EXPECT_EQ(read_back, 0u);

    std::vector<gpu::BirdPose> poses(world.value().birds.size());
    for (std::uint32_t f = 0; f <= kFrame; ++f) ASSERT_TRUE(reading.value()->simulate(1, {.poses = poses, .diag = {}}).ok());
    EXPECT_GT(renderer->read_back_bytes() - before, 0u) << "pose read back is counted: the check above can fail";
    ASSERT_TRUE(kodawari::draw_birds(*renderer, poses).ok());
    auto from_host = renderer->render(list);
    ASSERT_TRUE(from_host.ok());
    int drawn = 0;
    for (std::uint32_t y = 0; y < kHeight; ++y) {
        for (std::uint32_t x = 0; x < kWidth; ++x) drawn += channel_distance(from_device.at(x, y), background_at(y, kHeight)) > 8;
    }
    std::printf("[ render ] device-drawn flock: %d bird pixels, %llu bytes read back over 10 frames\n", drawn,
                static_cast<unsigned long long>(read_back));
    EXPECT_GE(drawn, 100);
    EXPECT_TRUE(from_device.rgba == from_host.value().rgba) << "the device-drawn birds differ from the read-back poses'";
    // A CPU backend has no poses on the device: an error, not a silent empty frame.
    auto cpu = make_bird_backend(BackendKind::Cpu, {});
    ASSERT_TRUE(cpu.ok());
    EXPECT_FALSE(kodawari::draw_birds(*renderer, *cpu.value()).ok());
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

// Colliders are drawn from the rod input where it is: on one device the rigged
// characters' colliders are written there by the rod-input kernel
// (CrowdAnimator::write_inputs_on) and the collider layer reads them from the rod
// backend's input buffer, nothing read back. Checked against the same frame's colliders
// computed on the host (CrowdAnimator::host_frame) and uploaded: each collider's circle
// passes where the host's capsule projects, and the two images differ by at most 1% of
// the collider pixels (the inputs differ by float rounding, about 1e-7 m: a line pixel
// can flip). 5 chibis: not a multiple of any workgroup size.
TEST(Render, CollidersDrawnFromTheRodInputOnTheDevice) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto scene = load_scene(scene_path("crowd-gltf.json"));
    ASSERT_TRUE(scene.ok());
    scene.value().crowds[0].count = 5;
    auto built = build_rod_scene(scene.value());
    ASSERT_TRUE(built.ok());
    const RodScene& rods = built.value();
    ASSERT_GT(rods.world.collider_count, 0u);
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    BackendOptions options;
    options.context = renderer->device_context();
    auto backend = make_rod_backend(BackendKind::Vulkan, options);
    ASSERT_TRUE(backend.ok());
    auto animator = CrowdAnimator::create(rods, BackendKind::Vulkan, options);
    ASSERT_TRUE(animator.ok());
    constexpr std::uint32_t kFrame = 40;
    rods::RodFrame input;
    for (std::uint32_t f = 0; f <= kFrame; ++f) {
        ASSERT_TRUE(animator.value().frame(f, input).ok());
        ASSERT_TRUE((f == 0 ? backend.value()->load(rods.world, input) : backend.value()->step(input)).ok());
        if (f == 0) {
            auto took = animator.value().write_inputs_on(*backend.value());
            ASSERT_TRUE(took.ok() && took.value());
        }
    }
    ASSERT_TRUE(kodawari::show_chains(*renderer, &rods.world).ok());  // the colliders' world; no chain state given: none drawn
    const render::CameraView view = kodawari::scene_camera(scene.value(), kFrame);
    const render::DrawList list(view, kWidth, kHeight);
    const std::uint64_t before = renderer->read_back_bytes();
    ASSERT_TRUE(kodawari::draw_colliders(*renderer, *backend.value(), input).ok());
    auto from_device = renderer->render(list);
    ASSERT_TRUE(from_device.ok());
    EXPECT_EQ(renderer->read_back_bytes() - before, 0u);

    rods::RodFrame host;
    ASSERT_TRUE(animator.value().host_frame(kFrame, host).ok());
    auto cpu = make_rod_backend(BackendKind::Cpu, {});  // no device state: its frame's colliders are uploaded
    ASSERT_TRUE(cpu.ok());
    ASSERT_TRUE(kodawari::draw_colliders(*renderer, *cpu.value(), host).ok());
    auto from_host = renderer->render(list);
    ASSERT_TRUE(from_host.ok());

    const Pinhole camera(view.position, view.target, view.fov_deg, kWidth, kHeight);
    int shapes = 0, found = 0;
    for (const rods::Collider& c : host.colliders) {
        glm::vec2 q;
        if (!camera.project(0.5f * (c.a + c.b), q)) continue;
        if (q.x < 2 || q.y < 2 || q.x > kWidth - 2 || q.y > kHeight - 2) continue;
        ++shapes;
        found += nearest_lit_match(from_device.value(), q, 1, kodawari::kColliderColor) <= 2 ? 1 : 0;
    }
    const auto body = [](const Image& image, std::uint32_t x, std::uint32_t y) {
        return lit_distance(image.at(x, y), kodawari::kColliderColor) <= 2;
    };
    int collider_pixels = 0, differ = 0;
    for (std::uint32_t y = 0; y < kHeight; ++y) {
        for (std::uint32_t x = 0; x < kWidth; ++x) {
            collider_pixels += body(from_device.value(), x, y) ? 1 : 0;
            differ += channel_distance(from_device.value().at(x, y), from_host.value().at(x, y)) > 2 ? 1 : 0;
        }
    }
    std::printf("[ render ] colliders from the device: %d of %d capsule middles in a lit collider colour, %d collider pixels, %d "
                "differ from the host's\n",
                found, shapes, collider_pixels, differ);
    EXPECT_GE(shapes, 3);
    EXPECT_EQ(found, shapes);
    EXPECT_GE(collider_pixels, 50);
    EXPECT_LE(differ, collider_pixels / 100);

    // With the meshes drawn by the skinned layer, no capsule shows (none posed: no mesh either).
    ASSERT_TRUE(kodawari::show_skinned(*renderer, &rods).ok());
    auto hidden = renderer->render(list);
    ASSERT_TRUE(hidden.ok());
    int hidden_pixels = 0;
    for (std::uint32_t y = 0; y < kHeight; ++y) {
        for (std::uint32_t x = 0; x < kWidth; ++x) hidden_pixels += body(hidden.value(), x, y) ? 1 : 0;
    }
    EXPECT_EQ(hidden_pixels, 0) << "the colliders of characters drawn as meshes are drawn";
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

// VRM avatars whose chains all list their own colliders (scenes/avatars.json): drawn as
// meshes by the skinned layer, none of their colliders is drawn as a capsule (the arm
// capsules stuck out of the skin). Control: without show_skinned the capsules show.
TEST(Render, SkinnedAvatarsShowNoColliderCapsules) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    auto scene = load_scene(scene_path("avatars.json"));
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    scene.value().crowds[0].count = 3;
    scene.value().crowds[1].count = 2;
    auto built = build_rod_scene(scene.value());
    ASSERT_TRUE(built.ok());
    const RodScene& rods = built.value();
    auto renderer = make_renderer(kWidth, kHeight);
    ASSERT_TRUE(renderer);
    auto cpu = make_rod_backend(BackendKind::Cpu, {});
    ASSERT_TRUE(cpu.ok());
    const rods::RodFrame frame = rods.frame(0);
    ASSERT_TRUE(kodawari::show_chains(*renderer, &rods.world).ok());
    ASSERT_TRUE(kodawari::draw_colliders(*renderer, *cpu.value(), frame).ok());
    const render::DrawList list(kodawari::scene_camera(scene.value(), 0), kWidth, kHeight);
    const auto collider_pixels = [&](const Image& image) {
        int n = 0;
        for (std::uint32_t y = 0; y < kHeight; ++y) {
            for (std::uint32_t x = 0; x < kWidth; ++x) n += lit_distance(image.at(x, y), kodawari::kColliderColor) <= 2 ? 1 : 0;
        }
        return n;
    };
    auto shown = renderer->render(list);
    ASSERT_TRUE(shown.ok());
    ASSERT_TRUE(kodawari::show_skinned(*renderer, &rods).ok());
    auto hidden = renderer->render(list);
    ASSERT_TRUE(hidden.ok());
    std::printf("[ render ] avatars' collider pixels: %d without the skinned layer, %d with it\n", collider_pixels(shown.value()),
                collider_pixels(hidden.value()));
    EXPECT_GE(collider_pixels(shown.value()), 50);
    EXPECT_EQ(collider_pixels(hidden.value()), 0);
    EXPECT_EQ(renderer->validation_messages(), 0u);
}

// present() needs a window: an offscreen renderer says so instead of crashing.
}  // namespace
}  // namespace kodawari
