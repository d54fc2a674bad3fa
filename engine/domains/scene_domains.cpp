// The scene's own domains (kodawari/simulation/domain.hpp's build_scene_domains): the one place that
// lists the domains a scene file describes, so that the Simulation facade names none.
#include <optional>

#include "kodawari/simulation/domain.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/domains/flocking.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari {

Result<std::vector<std::unique_ptr<Domain>>> build_scene_domains(const Scene& scene, std::uint32_t frames) {
    auto birds = build_bird_world(scene);
    if (!birds) return birds.error();
    birds.value().frames = frames;
    std::optional<RodScene> rods;
    if (!scene.characters.empty()) {
        auto built = build_rod_scene(scene);
        if (!built) return built.error();
        rods.emplace(std::move(built).value());
    }
    // Flocking flocks' birds are flown by a flocking domain (none without them).
    auto flocking = make_flocking_domain(scene, birds.value());
    if (!flocking) return flocking.error();
    // Both always, also empty: a shard's part files name both instance kinds.
    std::vector<std::unique_ptr<Domain>> domains;
    domains.push_back(make_bird_domain(std::move(birds).value()));
    if (flocking.value()) domains.push_back(std::move(flocking).value());
    domains.push_back(make_chain_domain(std::move(rods)));
    return domains;
}

}  // namespace kodawari
