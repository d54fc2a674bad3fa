// `render --show-lod` and `view --show-lod` (key L): a dot over each character in the colour
// of its level of detail (docs/level-of-detail.md), the same picture in both.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "kodawari/render/draw.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/lod.hpp"

namespace kodawari {
class Simulation;
}

namespace kodawari::cli {

/// The levels' colours and names, indexed by rods::Level (full, posed, hidden, reduced):
/// green, amber, blue, and yellow-green between full's and posed's.
inline constexpr std::size_t kLevelCount = 4;
inline constexpr std::array<render::Rgba8, kLevelCount> kLevelColors = {
    render::Rgba8{70, 200, 90, 255}, render::Rgba8{240, 170, 40, 255}, render::Rgba8{90, 130, 230, 255},
    render::Rgba8{185, 215, 50, 255}};
inline constexpr std::array<const char*, kLevelCount> kLevelNames = {"full", "posed", "hidden", "reduced"};
/// Characters (or chains) at each level, indexed by rods::Level.
using LevelCounts = std::array<std::uint32_t, kLevelCount>;

/// "full N<sep>reduced N<sep>posed N<sep>hidden N", from the most simulated level down;
/// the reduced level only where the scene has it on (`reduced`: LodSettings::reduced_pixels > 0).
[[nodiscard]] std::string levels_text(const LevelCounts& counts, bool reduced, const char* separator);

/// A dot over each character's reference joint in its level's colour: the level of its
/// first chain (every chain of a character takes the same, shaders/lib/rod_lod.glsl), read
/// back from the rod backend into `levels` (scratch, kept by the caller). Returns how many
/// characters are at each level; nothing for a simulation without characters.
[[nodiscard]] Result<LevelCounts> add_level_dots(render::DrawList& list, Simulation& sim, std::vector<rods::Level>& levels);

}  // namespace kodawari::cli
