#pragma once
// The part meshes and colours of the birds' glTF export (gltf_birds.cpp), shared with the
// renderer (engine/render/scene_draw.cpp) so that both show the same birds.

#include <array>

#include "export/gltf_common.hpp"
#include "kodawari/birds/rig.hpp"

namespace kodawari {

/// The seven meshes of a wing type in part order, each in its part's frame.
[[nodiscard]] std::array<gltf::MeshData, birds::kPartCount> bird_part_meshes(birds::WingType type);

/// The base colour of a wing type (linear RGB in [0, 1]).
[[nodiscard]] std::array<float, 3> bird_base_color(birds::WingType type);

}  // namespace kodawari
