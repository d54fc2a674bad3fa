#pragma once
// The part meshes and colours of the birds, shared by the glTF export
// (engine/export/gltf_birds_meshes.cpp) and the renderer (engine/domains/bird_layer.cpp) so
// that both show the same birds.

#include <array>

#include "core/flat_mesh.hpp"
#include "core/internal_api.hpp"
#include "kodawari/birds/rig.hpp"

namespace kodawari::birds {

/// The seven meshes of a wing type in part order, each in its part's frame.
[[nodiscard]] KODAWARI_INTERNAL std::array<core::MeshData, kPartCount> bird_part_meshes(WingType type);

/// Base colours per wing type: pigeon grey-blue, gull white, hawk brown, hummingbird green,
/// starling glossy black (lifted a little, so that its shading still reads).
inline constexpr std::array<std::array<double, 4>, kWingTypeCount> kBirdColours = {{
    {0.42, 0.45, 0.55, 1.0},
    {0.92, 0.92, 0.90, 1.0},
    {0.48, 0.30, 0.16, 1.0},
    {0.10, 0.55, 0.30, 1.0},
    {0.10, 0.09, 0.12, 1.0},
}};

/// The base colour of a wing type (linear RGB in [0, 1]).
[[nodiscard]] KODAWARI_INTERNAL std::array<float, 3> bird_base_color(WingType type);

}  // namespace kodawari::birds
