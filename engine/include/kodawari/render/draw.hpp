#pragma once
/// @file
/// The neutral drawing interface (issue 31, as Box2D v3's b2DebugDraw): what a domain
/// draws of itself, in world space, from host arrays, for the frame being drawn. It names
/// no domain; the renderer implements it (render::Renderer), and a domain calls it from
/// Domain::draw_on(). Colours are sRGB values; lit primitives are shaded by the renderer's
/// one light (kAmbientLight .. 1 of the colour), unlit ones are exactly their colour.

#include <cstdint>
#include <span>

#include <glm/glm.hpp>

namespace kodawari::render {

/// An 8-bit colour (sRGB values, written to the image as they are).
struct Rgba8 {
    std::uint8_t r = 0, g = 0, b = 0, a = 255;
    friend bool operator==(const Rgba8&, const Rgba8&) = default;
};

/// A polyline of Draw::tubes(): points [first, first + count) of the points given.
struct Polyline {
    std::uint32_t first = 0;
    std::uint32_t count = 0;  ///< >= 2 to draw anything
    float radius = 0.01f;     ///< m
    Rgba8 color{};
};

/// A capsule (a sphere when a == b).
struct Capsule {
    glm::vec3 a{0.0f}, b{0.0f};
    float radius = 0.05f;  ///< m
};

/// Triangles of Draw::meshes(), in the mesh's own frame: indices into positions, three
/// per triangle, each turned counter-clockwise seen from outside.
struct MeshView {
    std::span<const glm::vec3> positions;
    std::span<const std::uint32_t> indices;
};

/// What a domain draws through. Calls add to the frame being drawn; the renderer clears
/// them when a Simulation draws the next frame (Simulation::draw_on()).
class Draw {
public:
    virtual ~Draw() = default;
    /// 1-pixel lines, one from each even point to the next: pairs.size() / 2 lines.
    virtual void lines(std::span<const glm::vec3> pairs, Rgba8 color) = 0;
    /// Lit tubes along polylines of `points` (camera-facing ribbons shaded as cylinders),
    /// at least `min_px` pixels wide at 720 rows.
    virtual void tubes(std::span<const glm::vec3> points, std::span<const Polyline> polylines, float min_px = 2.0f) = 0;
    /// Lit solid capsules.
    virtual void capsules(std::span<const Capsule> capsules, Rgba8 color) = 0;
    /// Unlit discs facing the viewer, `radius` m but at least `min_px` pixels at 720 rows.
    virtual void discs(std::span<const glm::vec3> centers, float radius, Rgba8 color, float min_px = 2.0f) = 0;
    /// `mesh` drawn lit at every transform (model to world; flat shaded).
    virtual void meshes(const MeshView& mesh, std::span<const glm::mat4> transforms, Rgba8 color) = 0;
};

}  // namespace kodawari::render
