// The birds' part geometry: a body, a head, a tail and four wing panels per wing type, sized by its rig.
#include "birds/bird_meshes.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace kodawari::birds {
namespace {

using namespace core;  // the flat-mesh builders, as the exporter used them

/// A flat panel lying in the XZ plane: the root edge at x = x0 spans z in
/// [root_back, root_front], the tip edge at x = x1 spans [tip_back, tip_front].
MeshData panel(float x0, float x1, float root_back, float root_front, float tip_back, float tip_front,
               float thickness) {
    const float h = 0.5f * thickness;
    std::array<Vec3, 8> c{};
    for (int i = 0; i < 8; ++i) {
        const bool tip = (i & 1) != 0;
        const bool front = (i & 4) != 0;
        const float x = tip ? x1 : x0;
        const float z = tip ? (front ? tip_front : tip_back) : (front ? root_front : root_back);
        c[i] = {x, (i & 2) ? h : -h, z};
    }
    return hexahedron(c);
}

/// The body: an octahedron stretched along Z (nose forward).
MeshData body_mesh(float length) {
    const float front = 0.38f * length;
    const float back = -0.35f * length;
    const float mid = 0.05f * length;
    const float half_width = 0.11f * length;
    const float half_height = 0.10f * length;
    const std::vector<Vec3> corners = {
        {0.0f, 0.0f, front},       {0.0f, 0.0f, back},         {half_width, 0.0f, mid},
        {0.0f, half_height, mid},  {-half_width, 0.0f, mid},   {0.0f, -half_height, mid},
    };
    const std::vector<std::array<int, 3>> triangles = {
        {0, 2, 3}, {0, 3, 4}, {0, 4, 5}, {0, 5, 2}, {1, 2, 3}, {1, 3, 4}, {1, 4, 5}, {1, 5, 2},
    };
    MeshData mesh;
    add_convex_triangles(mesh, corners, triangles);
    return mesh;
}

constexpr float kWingThickness = 0.01f;

/// The seven meshes of a wing type, in part order.
std::array<MeshData, birds::kPartCount> part_meshes(birds::WingType type) {
    const birds::WingTypeSpec& spec = birds::wing_type_spec(type);
    const auto offsets = birds::part_offsets(type);
    const float length = spec.body_length;
    const float chord = spec.mean_chord;
    // The wing lengths follow the rig, so the arm2 joint sits where arm1's panel ends.
    const float arm1 = std::abs(offsets[KW_PART_LEFT_ARM2][0]);
    const float half_span = 0.5f * spec.wingspan - std::abs(offsets[KW_PART_LEFT_ARM1][0]);
    const float arm2 = std::max(half_span - arm1, 0.1f * half_span);
    // The leading edge sits a little ahead of the joint, as on a real wing; arm2 tapers.
    const float front = 0.3f * chord;
    const float back = -0.7f * chord;

    std::array<MeshData, birds::kPartCount> meshes;
    meshes[KW_PART_BODY] = body_mesh(length);
    const float head = 0.06f * length;
    meshes[KW_PART_HEAD] = box({-head, -head, -head}, {head, head, head});
    meshes[KW_PART_TAIL] = panel(0.0f, -0.2f * length, -0.03f * length, 0.03f * length, -0.14f * length,
                                 0.14f * length, kWingThickness);
    // The tail panel above is built along X; turn it to point backward (-Z), fanning out.
    for (Vec3& p : meshes[KW_PART_TAIL].positions) p = {p[2], p[1], p[0]};
    for (Vec3& n : meshes[KW_PART_TAIL].normals) n = {n[2], n[1], n[0]};
    // Swapping two axes mirrors the mesh: restore outward winding.
    for (std::size_t i = 0; i + 2 < meshes[KW_PART_TAIL].indices.size(); i += 3) {
        std::swap(meshes[KW_PART_TAIL].indices[i + 1], meshes[KW_PART_TAIL].indices[i + 2]);
    }
    meshes[KW_PART_LEFT_ARM1] = panel(0.0f, arm1, back, front, back, front, kWingThickness);
    meshes[KW_PART_LEFT_ARM2] = panel(0.0f, arm2, back, front, 0.5f * back, 0.5f * front, kWingThickness);
    meshes[KW_PART_RIGHT_ARM1] = panel(0.0f, -arm1, back, front, back, front, kWingThickness);
    meshes[KW_PART_RIGHT_ARM2] = panel(0.0f, -arm2, back, front, 0.5f * back, 0.5f * front, kWingThickness);
    return meshes;
}

}  // namespace

std::array<core::MeshData, kPartCount> bird_part_meshes(WingType type) { return part_meshes(type); }

std::array<float, 3> bird_base_color(birds::WingType type) {
    const auto& c = kBirdColours[static_cast<std::size_t>(type)];
    return {static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])};
}

}  // namespace kodawari::birds
