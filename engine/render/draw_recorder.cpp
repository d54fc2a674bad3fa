// render::Draw's primitives as draw-list geometry (draw_recorder.hpp): each call copies
// its arrays, and is tessellated for the frame's camera when replayed.
#include "render/draw_recorder.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace kodawari::render {

namespace {

constexpr float kTau = 6.28318530718f;

glm::vec3 rgb(Rgba8 c) {
    return {static_cast<float>(c.r) / 255.0f, static_cast<float>(c.g) / 255.0f, static_cast<float>(c.b) / 255.0f};
}

// Two unit vectors perpendicular to `axis` (unit) and to each other.
void perpendiculars(const glm::vec3& axis, glm::vec3& u, glm::vec3& v) {
    const glm::vec3 other = std::abs(axis.y) < 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
    u = glm::normalize(glm::cross(axis, other));
    v = glm::cross(axis, u);
}

// A lit sphere, 16 x 12 facets, each facet's normal its centre's direction (8 x 6 showed
// its facets on an obstacle a fifth of the picture across: a flock's balloon).
void add_sphere(DrawList& list, const glm::vec3& c, float r, const glm::vec3& color) {
    constexpr int kAround = 16, kRings = 12;
    const auto at = [&](int i, int j) {
        const float theta = kTau * static_cast<float>(i) / kAround;
        const float phi = 0.5f * kTau * static_cast<float>(j) / kRings;
        return glm::vec3(std::sin(phi) * std::cos(theta), std::cos(phi), std::sin(phi) * std::sin(theta));
    };
    for (int j = 0; j < kRings; ++j) {
        for (int i = 0; i < kAround; ++i) {
            const glm::vec3 a = at(i, j), b = at(i + 1, j), d = at(i, j + 1), e = at(i + 1, j + 1);
            list.add_lit_triangle(c + r * a, c + r * e, c + r * d, a + d + e, color);
            list.add_lit_triangle(c + r * a, c + r * b, c + r * e, a + b + e, color);
        }
    }
}

}  // namespace

void DrawRecorder::lines(std::span<const glm::vec3> pairs, Rgba8 color) {
    ops_.push_back([points = std::vector<glm::vec3>(pairs.begin(), pairs.end()), color](DrawList& list, float) {
        for (std::size_t i = 0; i + 1 < points.size(); i += 2) list.add_line(points[i], points[i + 1], color);
    });
}

void DrawRecorder::tubes(std::span<const glm::vec3> points, std::span<const Polyline> polylines, float min_px) {
    ops_.push_back([p = std::vector<glm::vec3>(points.begin(), points.end()),
                    lines = std::vector<Polyline>(polylines.begin(), polylines.end()), min_px](DrawList& list, float scale) {
        for (const Polyline& line : lines) {
            if (line.count < 2 || std::size_t{line.first} + line.count > p.size()) continue;
            const glm::vec3 color = rgb(line.color);
            for (std::uint32_t k = line.first; k + 1 < line.first + line.count; ++k) {
                const glm::vec3 a = p[k], b = p[k + 1];
                // A ribbon in the plane of the segment and the line of sight, its normal
                // towards the viewer tilted along the side: shaded as a cylinder's
                // front, in two halves.
                const glm::vec3 towards = list.towards_viewer(0.5f * (a + b));
                const glm::vec3 side = glm::cross(b - a, towards);
                const float length = glm::length(side);
                if (!(length > 0.0f)) continue;
                const glm::vec3 unit = side / length;
                const glm::vec3 front = glm::normalize(glm::cross(unit, b - a));
                const float wa = std::max(line.radius, 0.5f * min_px * scale * list.pixel_size_at(a));
                const float wb = std::max(line.radius, 0.5f * min_px * scale * list.pixel_size_at(b));
                for (const float s : {-1.0f, 1.0f}) {
                    const glm::vec3 normal = front + 0.7f * s * unit;
                    list.add_lit_triangle(a, a + s * wa * unit, b + s * wb * unit, normal, color);
                    list.add_lit_triangle(a, b + s * wb * unit, b, normal, color);
                }
            }
        }
    });
}

void DrawRecorder::capsules(std::span<const Capsule> capsules, Rgba8 color) {
    ops_.push_back([all = std::vector<Capsule>(capsules.begin(), capsules.end()), color](DrawList& list, float) {
        const glm::vec3 c = rgb(color);
        for (const Capsule& k : all) {
            add_sphere(list, k.a, k.radius, c);
            const glm::vec3 along = k.b - k.a;
            const float length = glm::length(along);
            if (!(length > 0.0f)) continue;
            add_sphere(list, k.b, k.radius, c);
            glm::vec3 u, v;
            perpendiculars(along / length, u, v);
            constexpr int kSides = 24;  // as smooth as the end spheres round
            for (int i = 0; i < kSides; ++i) {
                const float t0 = kTau * static_cast<float>(i) / kSides, t1 = kTau * static_cast<float>(i + 1) / kSides;
                const glm::vec3 n0 = std::cos(t0) * u + std::sin(t0) * v, n1 = std::cos(t1) * u + std::sin(t1) * v;
                const glm::vec3 r0 = k.radius * n0, r1 = k.radius * n1;
                list.add_lit_triangle(k.a + r0, k.a + r1, k.b + r1, n0 + n1, c);
                list.add_lit_triangle(k.a + r0, k.b + r1, k.b + r0, n0 + n1, c);
            }
        }
    });
}

void DrawRecorder::discs(std::span<const glm::vec3> centers, float radius, Rgba8 color, float min_px) {
    ops_.push_back([p = std::vector<glm::vec3>(centers.begin(), centers.end()), radius, color, min_px](DrawList& list,
                                                                                                        float scale) {
        for (const glm::vec3& c : p) list.add_dot(c, radius, min_px * scale, color);
    });
}

void DrawRecorder::meshes(const MeshView& mesh, std::span<const glm::mat4> transforms, Rgba8 color) {
    ops_.push_back([positions = std::vector<glm::vec3>(mesh.positions.begin(), mesh.positions.end()),
                    indices = std::vector<std::uint32_t>(mesh.indices.begin(), mesh.indices.end()),
                    all = std::vector<glm::mat4>(transforms.begin(), transforms.end()), color](DrawList& list, float) {
        const glm::vec3 c = rgb(color);
        for (const glm::mat4& m : all) {
            for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
                if (indices[t] >= positions.size() || indices[t + 1] >= positions.size() || indices[t + 2] >= positions.size()) {
                    continue;
                }
                const glm::vec3 a = m * glm::vec4(positions[indices[t]], 1.0f);
                const glm::vec3 b = m * glm::vec4(positions[indices[t + 1]], 1.0f);
                const glm::vec3 d = m * glm::vec4(positions[indices[t + 2]], 1.0f);
                list.add_lit_triangle(a, b, d, glm::cross(b - a, d - a), c);
            }
        }
    });
}

void DrawRecorder::replay(DrawList& list, float rows_scale) const {
    for (const auto& op : ops_) op(list, rows_scale);
}

}  // namespace kodawari::render
