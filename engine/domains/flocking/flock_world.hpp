#pragma once
// The flocking domain's world (docs/flocking.md): what its kernels read, built from the
// scene's flocking flocks and the bird world's driven birds, and what changes per frame
// (the flocks' route leaders, the predators).

#include <cstdint>
#include <span>
#include <vector>

#include <kodawari/shared/flocking.h>

#include "kodawari/birds/world.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari::flocking {

struct FlockWorld {
    std::vector<gpu::FlockParamsGpu> flocks;  ///< per flocking flock (target: frame_inputs())
    std::vector<gpu::FlockBirdGpu> birds;     ///< per driven bird, by its slot (BirdParams::ids.z)
    std::vector<gpu::FlockPerchGpu> perches_of;  ///< per driven bird: its landing (zero without one)
    std::vector<gpu::FlockStateGpu> initial;  ///< frame 0: where and how its route flies it
    std::vector<gpu::BirdMotionGpu> first;    ///< frame 0's motion (the route's acceleration)
    /// Per flock: the route its leader flies (arc-length timing) at `speed`.
    struct Leader {
        std::uint32_t route = 0;
        float speed = 0.0f;
    };
    std::vector<Leader> leaders;
    std::vector<PredatorSpec> predators;  ///< every flocking flock's, fleeing any of them
    /// Every flocking flock's obstacles and attractors, the same every frame (after the
    /// predators among a frame's agents).
    std::vector<gpu::FlockAgentGpu> fixed_agents;
    /// Per predator that is a flock's bird (PredatorSpec::flock): that bird's params (its
    /// route, speed, offsets); unused for the others.
    std::vector<gpu::BirdParams> predator_birds;
    birds::BirdWorld routes;              ///< the bird world's routes (sample_route())
    float dt = 1.0f / 60.0f;              ///< a substep (s)
    float frame_dt = 1.0f / 60.0f;        ///< a frame (s), as the bird domain rounds it (BirdWorld::uniforms())
    bool perches = false;                 ///< some flock takes off or lands (docs/flocking.md, "Perches")
    std::uint32_t substeps = 1;           ///< per frame: at most 1/60 s each
    float search_radius = 1.0f;           ///< the grid's cell: the largest flock's
    float gravity = 9.81f;
    std::uint32_t buckets = 0;            ///< bucket_count(birds)

    /// The scene's agents a frame has: the predators, then the obstacles and attractors.
    [[nodiscard]] std::size_t scene_agents() const { return predators.size() + fixed_agents.size(); }
    /// Frame `frame`'s flock parameters (their leaders there) and agents (the predators,
    /// weight 0 while not passing, then fixed_agents; scene_agents() of them).
    void frame_inputs(std::uint32_t frame, std::span<gpu::FlockParamsGpu> flocks_out, std::span<gpu::FlockAgentGpu> agents_out) const;
};

/// The flocking world of `scene`'s flocks with a `flocking` object, whose birds are
/// `world`'s driven birds. Errors name the scene file and the flock.
[[nodiscard]] Result<FlockWorld> build_flock_world(const Scene& scene, const birds::BirdWorld& world);

}  // namespace kodawari::flocking
