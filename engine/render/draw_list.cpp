// DrawList: what a frame draws besides the device layers, built on the CPU and uploaded
// by the renderer (renderer.cpp) every frame.

#include <algorithm>
#include <cassert>
#include <cmath>

#include "kodawari/render/renderer.hpp"
#include "render/grid_spacing.hpp"

namespace kodawari::render {

namespace {

gpu::vec4 v4(const glm::vec3& v, float w) { return {v.x, v.y, v.z, w}; }
gpu::vec4 v4(Rgba8 c, float lit) {
    return {static_cast<float>(c.r) / 255.0f, static_cast<float>(c.g) / 255.0f, static_cast<float>(c.b) / 255.0f, lit};
}

}  // namespace

DrawList::DrawList(const CameraView& camera, std::uint32_t width, std::uint32_t height)
    : camera_(camera), basis_(camera_basis(camera)), width_(width), height_(height) {
    assert(width > 0 && height > 0 && camera.near > 0.0f && camera.far > camera.near);
    assert(!camera.orthographic || camera.ortho_height > 0.0f);
    pixel_per_depth_ = camera.orthographic ? camera.ortho_height / static_cast<float>(height)
                                           : 2.0f * std::tan(0.5f * glm::radians(camera.fov_deg)) / static_cast<float>(height);
}

float DrawList::pixel_size_at(const glm::vec3& p) const {
    if (camera_.orthographic) return pixel_per_depth_;
    const float depth = glm::dot(p - camera_.position, basis_.forward);
    return depth > camera_.near ? depth * pixel_per_depth_ : 0.0f;
}

glm::vec3 DrawList::towards_viewer(const glm::vec3& p) const {
    return camera_.orthographic ? -basis_.forward : camera_.position - p;
}

void DrawList::add_line(const glm::vec3& a, const glm::vec3& b, Rgba8 color) {
    const gpu::vec4 c = v4(color, 0.0f);
    lines_.push_back({v4(a, 1.0f), c, {0.0f, 0.0f, 0.0f, KW_RENDER_WORLD}});
    lines_.push_back({v4(b, 1.0f), c, {0.0f, 0.0f, 0.0f, KW_RENDER_WORLD}});
}

void DrawList::add_lit_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& normal,
                                glm::vec3 color) {
    const gpu::vec4 col{color.x, color.y, color.z, 1.0f};
    const gpu::vec4 n = v4(normal, KW_RENDER_WORLD);
    triangles_.push_back({v4(a, 1.0f), col, n});
    triangles_.push_back({v4(b, 1.0f), col, n});
    triangles_.push_back({v4(c, 1.0f), col, n});
}

void DrawList::add_unlit_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, Rgba8 color) {
    const gpu::vec4 col = v4(color, 0.0f);
    const gpu::vec4 n{0.0f, 0.0f, 0.0f, KW_RENDER_WORLD};
    triangles_.push_back({v4(a, 1.0f), col, n});
    triangles_.push_back({v4(b, 1.0f), col, n});
    triangles_.push_back({v4(c, 1.0f), col, n});
}

void DrawList::add_segment(const glm::vec3& a, const glm::vec3& b, float width, float min_px, Rgba8 color) {
    const glm::vec3 along = b - a;
    // The quad lies in the plane of the segment and the line of sight to its middle.
    const glm::vec3 side = glm::cross(along, towards_viewer(0.5f * (a + b)));
    const float side_length = glm::length(side);
    if (!(side_length > 0.0f)) return;  // seen end-on (its dots still show it) or degenerate
    const glm::vec3 unit = side / side_length;
    const glm::vec3 ha = 0.5f * std::max(width, min_px * pixel_size_at(a)) * unit;
    const glm::vec3 hb = 0.5f * std::max(width, min_px * pixel_size_at(b)) * unit;
    add_unlit_triangle(a - ha, a + ha, b + hb, color);
    add_unlit_triangle(a - ha, b + hb, b - hb, color);
}

void DrawList::add_dot(const glm::vec3& p, float radius, float min_px, Rgba8 color) {
    const float r = std::max(radius, min_px * pixel_size_at(p));
    constexpr int kSides = 8;
    constexpr float kStep = 6.28318530718f / kSides;
    for (int i = 0; i < kSides; ++i) {
        const float a0 = kStep * static_cast<float>(i), a1 = kStep * static_cast<float>(i + 1);
        add_unlit_triangle(p, p + r * (std::cos(a0) * basis_.right + std::sin(a0) * basis_.up),
                           p + r * (std::cos(a1) * basis_.right + std::sin(a1) * basis_.up), color);
    }
}

void DrawList::add_ground_shadow(const glm::vec3& center, float radius, float opacity) {
    // Just above the ground: the grid lines (y = 0) lie under it, not through it.
    constexpr float kLift = 1e-3f;
    constexpr int kSides = 24;
    constexpr float kStep = 6.28318530718f / kSides;
    const gpu::vec4 n{0.0f, 1.0f, 0.0f, KW_RENDER_WORLD};
    const gpu::vec4 middle{center.x, kLift, center.z, 1.0f};
    // shadow.frag: r the opacity, a the way in from the rim.
    const float o = std::clamp(opacity, 0.0f, 1.0f);
    const gpu::vec4 dark{o, 0.0f, 0.0f, 1.0f}, clear{o, 0.0f, 0.0f, 0.0f};
    const auto rim = [&](int i) {
        const float a = kStep * static_cast<float>(i);
        return gpu::vec4{center.x + radius * std::cos(a), kLift, center.z + radius * std::sin(a), 1.0f};
    };
    for (int i = 0; i < kSides; ++i) {
        shadows_.push_back({middle, dark, n});
        shadows_.push_back({rim(i), clear, n});
        shadows_.push_back({rim(i + 1), clear, n});
    }
}

void DrawList::add_screen_line(glm::vec2 a, glm::vec2 b, Rgba8 color) {
    const gpu::vec4 c = v4(color, 0.0f);
    const auto clip = [&](glm::vec2 p) {
        return gpu::vec4{2.0f * p.x / static_cast<float>(width_) - 1.0f, 2.0f * p.y / static_cast<float>(height_) - 1.0f, 0.0f, 1.0f};
    };
    lines_.push_back({clip(a), c, {0.0f, 0.0f, 0.0f, KW_RENDER_CLIP}});
    lines_.push_back({clip(b), c, {0.0f, 0.0f, 0.0f, KW_RENDER_CLIP}});
}

void DrawList::add_screen_triangle(glm::vec2 a, glm::vec2 b, glm::vec2 c, Rgba8 color) {
    const gpu::vec4 col = v4(color, 0.0f);
    const auto clip = [&](glm::vec2 p) {
        return gpu::vec4{2.0f * p.x / static_cast<float>(width_) - 1.0f, 2.0f * p.y / static_cast<float>(height_) - 1.0f, 0.0f, 1.0f};
    };
    for (const glm::vec2 p : {a, b, c}) triangles_.push_back({clip(p), col, {0.0f, 0.0f, 0.0f, KW_RENDER_CLIP}});
}

void add_ground_grid(DrawList& list, std::span<const glm::vec3> points) {
    glm::vec2 lo{0.0f}, hi{0.0f};
    for (const glm::vec3& p : points) {
        if (!std::isfinite(p.x) || !std::isfinite(p.z)) continue;
        lo = glm::min(lo, glm::vec2(p.x, p.z));
        hi = glm::max(hi, glm::vec2(p.x, p.z));
    }
    const glm::vec2 center = 0.5f * (lo + hi);
    const float half = std::max(3.0f, 0.5f * std::max(hi.x - lo.x, hi.y - lo.y) * 1.3f + 2.0f);
    // A round spacing giving 10 to 25 lines each way.
    const float spacing = grid_spacing(2.0f * half);
    const float x0 = std::floor((center.x - half) / spacing) * spacing, x1 = std::ceil((center.x + half) / spacing) * spacing;
    const float z0 = std::floor((center.y - half) / spacing) * spacing, z1 = std::ceil((center.y + half) / spacing) * spacing;
    const int nx = static_cast<int>(std::lround((x1 - x0) / spacing)), nz = static_cast<int>(std::lround((z1 - z0) / spacing));
    for (int i = 0; i <= nx; ++i) {
        const float x = x0 + spacing * static_cast<float>(i);
        list.add_line({x, 0.0f, z0}, {x, 0.0f, z1}, kGridColor);
    }
    for (int i = 0; i <= nz; ++i) {
        const float z = z0 + spacing * static_cast<float>(i);
        list.add_line({x0, 0.0f, z}, {x1, 0.0f, z}, kGridColor);
    }
}

}  // namespace kodawari::render
