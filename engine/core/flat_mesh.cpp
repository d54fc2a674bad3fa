// Flat-shaded meshes of convex solids (hexahedra, boxes), with outward normals.
#include "core/flat_mesh.hpp"

#include <cassert>
#include <cmath>
#include <utility>

namespace kodawari::core {

/// Adds the triangles of a convex solid, each turned so that its normal points away
/// from the solid's centre. Deciding the winding geometrically instead of by hand keeps
/// the mirrored right wing correct without a separate winding rule.
void add_convex_triangles(MeshData& mesh, const std::vector<Vec3>& corners,
                          const std::vector<std::array<int, 3>>& triangles) {
    double centre[3] = {0, 0, 0};
    for (const Vec3& c : corners) {
        for (int i = 0; i < 3; ++i) centre[i] += static_cast<double>(c[i]);
    }
    for (double& c : centre) c /= static_cast<double>(corners.size());

    for (const auto& tri : triangles) {
        Vec3 a = corners[tri[0]];
        Vec3 b = corners[tri[1]];
        Vec3 c = corners[tri[2]];
        double e1[3];
        double e2[3];
        double mid[3];
        for (int i = 0; i < 3; ++i) {
            e1[i] = static_cast<double>(b[i]) - static_cast<double>(a[i]);
            e2[i] = static_cast<double>(c[i]) - static_cast<double>(a[i]);
            mid[i] = (static_cast<double>(a[i]) + static_cast<double>(b[i]) + static_cast<double>(c[i])) / 3.0 -
                     centre[i];
        }
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        assert(length > 0.0 && "degenerate triangle in a part mesh");
        for (double& v : n) v /= length;
        if (n[0] * mid[0] + n[1] * mid[1] + n[2] * mid[2] < 0.0) {
            std::swap(b, c);
            for (double& v : n) v = -v;
        }
        const Vec3 normal = {static_cast<float>(n[0]), static_cast<float>(n[1]), static_cast<float>(n[2])};
        for (const Vec3& p : {a, b, c}) {
            mesh.indices.push_back(static_cast<std::uint16_t>(mesh.positions.size()));
            mesh.positions.push_back(p);
            mesh.normals.push_back(normal);
        }
    }
}

/// A hexahedron from its 8 corners, indexed x + 2y + 4z (bit set = the "high" side).
/// Tapered panels are allowed: every quad is split into two triangles.
MeshData hexahedron(const std::array<Vec3, 8>& c) {
    static const std::vector<std::array<int, 3>> kTriangles = {
        {0, 2, 6}, {0, 6, 4},  // -x
        {1, 5, 7}, {1, 7, 3},  // +x
        {0, 4, 5}, {0, 5, 1},  // -y
        {2, 3, 7}, {2, 7, 6},  // +y
        {0, 1, 3}, {0, 3, 2},  // -z
        {4, 6, 7}, {4, 7, 5},  // +z
    };
    MeshData mesh;
    add_convex_triangles(mesh, std::vector<Vec3>(c.begin(), c.end()), kTriangles);
    return mesh;
}

/// An axis-aligned box from its lower and upper corner.
MeshData box(const Vec3& lo, const Vec3& hi) {
    std::array<Vec3, 8> c{};
    for (int i = 0; i < 8; ++i) {
        c[i] = {(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]};
    }
    return hexahedron(c);
}

}  // namespace kodawari::core
