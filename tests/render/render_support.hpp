#pragma once
// What the renderer suites share: a pinhole camera written independently of the
// renderer's, pixel matching, a renderer on whatever device exists, and the ahoge
// simulated to draw.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include <stb/stb_image.h>

#include "kodawari/domains/bird_draw.hpp"
#include "kodawari/domains/chain_draw.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/birds/rig.hpp"
#include "kodawari/vulkan/crowd_animator.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/domains/scene_draw.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/scene/scene.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

namespace kodawari::render_test {

using render::Image;
using render::Rgba8;

using render::Image;
using render::Rgba8;

// Odd sizes: row pitch and aspect mistakes show.
inline constexpr std::uint32_t kWidth = 317, kHeight = 199;

/// A pinhole camera from first principles: eye, target, vertical fov, +Y up.
struct Pinhole {
    glm::vec3 eye, right, up, forward;
    float tan_half, aspect;
    float width, height;

    Pinhole(const glm::vec3& e, const glm::vec3& target, float fov_deg, std::uint32_t w, std::uint32_t h)
        : eye(e), tan_half(std::tan(0.5f * fov_deg * 3.14159265f / 180.0f)), aspect(float(w) / float(h)), width(float(w)),
          height(float(h)) {
        forward = glm::normalize(target - e);
        right = glm::normalize(glm::cross(forward, glm::vec3(0.0f, 1.0f, 0.0f)));
        up = glm::cross(right, forward);
    }
    /// Pixel coordinates (x right, y down; pixel (i, j) covers [i, i+1) x [j, j+1)); false behind the eye.
    bool project(const glm::vec3& p, glm::vec2& out) const {
        const glm::vec3 d = p - eye;
        const float z = glm::dot(d, forward);
        if (z <= 1e-3f) return false;
        const float nx = glm::dot(d, right) / (z * tan_half * aspect);
        const float ny = glm::dot(d, up) / (z * tan_half);
        out = {(nx + 1.0f) * 0.5f * width, (1.0f - ny) * 0.5f * height};
        return true;
    }
    /// The direction of the ray through the centre of pixel (x, y).
    glm::vec3 ray(std::uint32_t x, std::uint32_t y) const {
        const float nx = (float(x) + 0.5f) / width * 2.0f - 1.0f;
        const float ny = 1.0f - (float(y) + 0.5f) / height * 2.0f;
        return forward + right * (nx * tan_half * aspect) + up * (ny * tan_half);
    }
};

inline int channel_distance(Rgba8 a, Rgba8 b) {
    return std::max({std::abs(int(a.r) - int(b.r)), std::abs(int(a.g) - int(b.g)), std::abs(int(a.b) - int(b.b))});
}

inline Rgba8 background_at(std::uint32_t y, std::uint32_t height) {
    const glm::vec3 c = render::background_color((float(y) + 0.5f) / float(height)) * 255.0f;
    return {std::uint8_t(std::lround(c.x)), std::uint8_t(std::lround(c.y)), std::uint8_t(std::lround(c.z)), 255};
}

// Smallest colour distance to `color` among the pixels within `radius` of (x, y).
inline int nearest_match(const Image& image, glm::vec2 p, int radius, Rgba8 color) {
    int best = 999;
    const int cx = int(std::floor(p.x)), cy = int(std::floor(p.y));
    for (int y = cy - radius; y <= cy + radius; ++y) {
        for (int x = cx - radius; x <= cx + radius; ++x) {
            if (x < 0 || y < 0 || x >= int(image.width) || y >= int(image.height)) continue;
            best = std::min(best, channel_distance(image.at(std::uint32_t(x), std::uint32_t(y)), color));
        }
    }
    return best;
}

// How far `c` is from every lit shade of `base`: the chain and collider layers draw
// f x base with the light factor f in [kAmbientLight, 1] (lit.frag), rounded to 8 bits.
// f by least squares, clamped to that range; the distance is the largest channel error
// (0 or 1 for a shade, rounding; a few units where an anti-aliased edge pixel blends).
inline int lit_distance(Rgba8 c, Rgba8 base) {
    const glm::vec3 x(c.r, c.g, c.b), b(base.r, base.g, base.b);
    const float f = std::clamp(glm::dot(x, b) / glm::dot(b, b), render::kAmbientLight, 1.0f);
    const glm::vec3 e = glm::abs(x - f * b);
    return int(std::lround(std::max({e.x, e.y, e.z})));
}

// Smallest lit_distance() to `base` among the pixels within `radius` of (x, y).
inline int nearest_lit_match(const Image& image, glm::vec2 p, int radius, Rgba8 base) {
    int best = 999;
    const int cx = int(std::floor(p.x)), cy = int(std::floor(p.y));
    for (int y = cy - radius; y <= cy + radius; ++y) {
        for (int x = cx - radius; x <= cx + radius; ++x) {
            if (x < 0 || y < 0 || x >= int(image.width) || y >= int(image.height)) continue;
            best = std::min(best, lit_distance(image.at(std::uint32_t(x), std::uint32_t(y)), base));
        }
    }
    return best;
}

inline float segment_distance(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
    const glm::vec2 ab = b - a;
    const float t = glm::dot(ab, ab) > 0.0f ? std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0f, 1.0f) : 0.0f;
    return glm::length(p - (a + t * ab));
}

inline std::string scene_path(const char* name) { return std::string(KODAWARI_SOURCE_DIR) + "/scenes/" + name; }

inline std::unique_ptr<render::Renderer> make_renderer(std::uint32_t width, std::uint32_t height) {
    render::RendererOptions options;
    options.width = width;
    options.height = height;
    options.validation = testing_support::validation_requested();
    auto renderer = render::Renderer::create(options);
    EXPECT_TRUE(renderer.ok()) << (renderer.ok() ? "" : renderer.error().message);
    return renderer.ok() ? std::move(renderer).value() : nullptr;
}

/// The ahoge scene simulated on the CPU up to each requested frame (ascending): per
/// frame its snapshot.
struct AhogeRun {
    Scene scene;
    RodScene rods;
    std::vector<ChainSnapshot> snapshots;
};

inline AhogeRun simulate_ahoge(const std::vector<std::uint32_t>& frames) {
    auto scene = load_scene(scene_path("ahoge.json"));
    EXPECT_TRUE(scene.ok());
    auto rods = build_rod_scene(scene.value());
    EXPECT_TRUE(rods.ok());
    AhogeRun run{std::move(scene).value(), std::move(rods).value(), {}};
    auto backend = make_rod_backend(BackendKind::Cpu, {});
    EXPECT_TRUE(backend.ok());
    std::size_t next = 0;
    for (std::uint32_t f = 0; next < frames.size(); ++f) {
        const rods::RodFrame input = run.rods.frame(f);
        EXPECT_TRUE((f == 0 ? backend.value()->load(run.rods.world, input) : backend.value()->step(input)).ok());
        if (f == frames[next]) {
            ChainSnapshot snapshot;
            EXPECT_TRUE(backend.value()->read(snapshot).ok());
            run.snapshots.push_back(std::move(snapshot));
            ++next;
        }
    }
    return run;
}

// The frame's draw list (grid, skeleton) and, on the renderer, its chains from `snapshot`.
inline render::DrawList ahoge_frame(render::Renderer& renderer, const AhogeRun& run, std::uint32_t frame, const ChainSnapshot& snapshot) {
    render::DrawList list(kodawari::scene_camera(run.scene, frame), renderer.width(), renderer.height());
    const rods::RodFrame input = run.rods.frame(frame);
    render::add_ground_grid(list, kodawari::content_points(&run.rods, &input, nullptr));
    kodawari::add_characters(list, run.rods, frame);
    EXPECT_TRUE(kodawari::show_chains(renderer, &run.rods.world).ok());
    EXPECT_TRUE(kodawari::draw_chains(renderer, snapshot).ok());
    return list;
}


}  // namespace kodawari::render_test
