#pragma once
// Flat-shaded triangle meshes of convex solids: the birds' part geometry and the
// exporter's joint boxes, in the layout that both the glTF writers and the renderer take.

#include <array>
#include <cstdint>
#include <vector>

#include "core/internal_api.hpp"

namespace kodawari::core {

using Vec3 = std::array<float, 3>;

/// A triangle mesh with one normal per triangle (flat shading: each triangle has its
/// own three vertices).
struct MeshData {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;
    std::vector<std::uint16_t> indices;
};

/// Adds the triangles of a convex solid, each turned so that its normal points away
/// from the solid's centre.
KODAWARI_INTERNAL void add_convex_triangles(MeshData& mesh, const std::vector<Vec3>& corners,
                                            const std::vector<std::array<int, 3>>& triangles);

/// A hexahedron from its 8 corners, indexed x + 2y + 4z (bit set = the "high" side).
[[nodiscard]] KODAWARI_INTERNAL MeshData hexahedron(const std::array<Vec3, 8>& c);

/// An axis-aligned box from its lower and upper corner.
[[nodiscard]] KODAWARI_INTERNAL MeshData box(const Vec3& lo, const Vec3& hi);

}  // namespace kodawari::core
