// `render --show-lod` and `view --show-lod` (key L): a dot over each character in the colour
// of its level of detail (docs/level-of-detail.md), the same picture in both.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "kodawari/render/draw.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/result.hpp"
#include "kodawari/rods/lod.hpp"

namespace kodawari {
class Simulation;
}

namespace kodawari::cli {

/// The levels' colours and names (rods::Level: full, posed, hidden): green, amber, blue.
inline constexpr std::array<render::Rgba8, 3> kLevelColors = {render::Rgba8{70, 200, 90, 255}, render::Rgba8{240, 170, 40, 255},
                                                              render::Rgba8{90, 130, 230, 255}};
inline constexpr std::array<const char*, 3> kLevelNames = {"full", "posed", "hidden"};

/// A dot over each character's reference joint in its level's colour: the level of its
/// first chain (every chain of a character takes the same, shaders/lib/rod_lod.glsl), read
/// back from the rod backend into `levels` (scratch, kept by the caller). Returns how many
/// characters are at each level; nothing for a simulation without characters.
[[nodiscard]] Result<std::array<std::uint32_t, 3>> add_level_dots(render::DrawList& list, Simulation& sim,
                                                                  std::vector<rods::Level>& levels);

}  // namespace kodawari::cli
