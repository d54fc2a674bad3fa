#pragma once
// What a scene simulates, built from it with every random draw made but no backend: the
// whole scene's domains, as a Simulation builds them before cutting out a shard. What a
// merge of shards and the rank that writes a distributed bake's output hand to the sinks.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kodawari/simulation/bake.hpp"
#include "kodawari/simulation/domain.hpp"

namespace kodawari::detail {

struct SceneWorlds {
    std::vector<std::unique_ptr<Domain>> domains;  ///< build_scene_domains(), not opened
    std::uint32_t frames = 1;

    [[nodiscard]] std::vector<const Domain*> views() const {
        std::vector<const Domain*> out;
        for (const auto& d : domains) out.push_back(d.get());
        return out;
    }
    [[nodiscard]] BakeWorld bake_world(const Scene& scene, std::string backend) const {
        return {&scene, views(), frames, std::move(backend)};
    }
};

[[nodiscard]] inline Result<SceneWorlds> build_scene_worlds(const Scene& scene, std::uint32_t frames) {
    auto domains = build_scene_domains(scene, frames);
    if (!domains) return domains.error();
    return SceneWorlds{std::move(domains).value(), frames};
}

}  // namespace kodawari::detail
