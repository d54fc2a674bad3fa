// `render --show-lod` and `view --show-lod` (key L): level_dots.hpp.
#include "level_dots.hpp"

#include <algorithm>

#include "kodawari/domains/chains.hpp"
#include "kodawari/rods/rod_scene.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari::cli {

std::string levels_text(const LevelCounts& counts, bool reduced, const char* separator) {
    std::string text;
    for (const rods::Level level : {rods::Level::Full, rods::Level::Reduced, rods::Level::Posed, rods::Level::Hidden}) {
        if (level == rods::Level::Reduced && !reduced) continue;
        const auto l = static_cast<std::size_t>(level);
        if (!text.empty()) text += separator;
        text += std::string(kLevelNames[l]) + " " + std::to_string(counts[l]);
    }
    return text;
}

Result<LevelCounts> add_level_dots(render::DrawList& list, Simulation& sim, std::vector<rods::Level>& levels) {
    LevelCounts counts{};
    const RodScene* scene = rod_scene(sim);
    if (scene == nullptr) return counts;
    KW_TRY(read_chain_levels(sim, levels));
    auto input = host_chain_input(sim);
    if (!input) return input.error();
    const rods::RodFrame& frame = *input.value();
    std::vector<std::uint8_t> seen(scene->world.character_count, 0);
    for (std::size_t c = 0; c < levels.size() && c < scene->world.chains.size(); ++c) {
        const std::uint32_t character = scene->world.chains[c].character;
        if (seen[character] != 0 || character >= frame.reference.size()) continue;
        seen[character] = 1;
        const auto level = std::min<std::size_t>(static_cast<std::size_t>(levels[c]), kLevelCount - 1);
        ++counts[level];
        // Over the reference joint (a head, 1 m characters by default: LodSettings::size)
        // clear of the hair, 0.16 m across and never under 4 px, so that the far crowd shows too.
        const float lift = 0.5f * sim.scene().lod.size;
        list.add_dot(frame.reference[character].position + glm::vec3(0.0f, lift, 0.0f), 0.08f, 4.0f, kLevelColors[level]);
    }
    return counts;
}

}  // namespace kodawari::cli
