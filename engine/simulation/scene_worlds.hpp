#pragma once
// What a scene simulates, built from it with every random draw made but no backend: the
// whole scene, as a Simulation builds it before cutting out a shard. What a merge of
// shards and the rank that writes a distributed bake's output hand to the sinks.

#include <cstdint>
#include <memory>
#include <vector>

#include "kodawari/bake.hpp"
#include "kodawari/domain.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"

namespace kodawari::detail {

struct SceneWorlds {
    std::vector<std::unique_ptr<Domain>> domains;  ///< build_scene_domains(), not opened
    const birds::BirdWorld* birds = nullptr;       ///< the flock (maybe without birds)
    const RodScene* rods = nullptr;                ///< none without characters
    std::uint32_t frames = 1;

    [[nodiscard]] BakeWorld bake_world(const Scene& scene, std::string backend) const {
        return {&scene, birds, rods, frames, std::move(backend)};
    }
};

[[nodiscard]] inline Result<SceneWorlds> build_scene_worlds(const Scene& scene, std::uint32_t frames) {
    auto domains = build_scene_domains(scene, frames);
    if (!domains) return domains.error();
    SceneWorlds worlds;
    worlds.domains = std::move(domains).value();
    worlds.frames = frames;
    for (const auto& domain : worlds.domains) {
        if (const birds::BirdWorld* birds = bird_world_of(*domain)) worlds.birds = birds;
        if (const RodScene* rods = rod_scene_of(*domain)) worlds.rods = rods;
    }
    return worlds;
}

}  // namespace kodawari::detail
