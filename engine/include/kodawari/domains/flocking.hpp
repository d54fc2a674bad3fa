#pragma once
/// @file
/// The flocking domain (issue 32, docs/flocking.md): the birds of flocks with a
/// `flocking` object fly by their neighbours (Reynolds' separation, alignment and cohesion
/// over the k nearest, Hildenbrandt et al. 2010's field of view and separation), drawn to
/// their flock's route, clear of the ground and fleeing predators, within what their wings
/// allow. Each frame it gives the bird domain the motion those birds fly (their wingbeats
/// and flight modes are then the thesis's, as a route bird's):
///
///   per frame f:  the flocks' route leaders and the predators at f
///                 -> a uniform grid of the birds (counting sort)
///                 -> per bird: its k nearest flockmates in view, the rules, the limits
///                 -> BirdMotionGpu per bird -> the bird domain (its input "flocking")
///
/// Every shard and rank simulates the whole flocking flock (a bird's neighbours may be in
/// another shard's range) and the bird domain keeps its own range: sharded and MPI bakes
/// are the bytes of one process.

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>

#include <kodawari/shared/birds.h>

#include "kodawari/api.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/domain.hpp"
#include "kodawari/scene.hpp"

namespace kodawari {

/// The flocking domain's name in a Simulation, and its output the bird domain reads.
inline constexpr std::string_view kFlockingDomain = "flocking";
/// Its channel: per flocking bird per frame a gpu::BirdMotionGpu (a diagnostic: the bake's
/// glTF is the birds' poses).
inline constexpr std::string_view kFlockingMotionChannel = "flocking.motion";

/// A flocking domain for the driven birds of `world` (BirdWorld::driven; their flocks'
/// FlockSpec::flocking in `scene`), or none when no flock of the scene flocks.
[[nodiscard]] KODAWARI_API Result<std::unique_ptr<Domain>> make_flocking_domain(const Scene& scene, const birds::BirdWorld& world);

/// The motion the flocking domain `domain` gave for the frames of its last step():
/// frames x BirdWorld::driven, frame-major; empty for another domain.
[[nodiscard]] KODAWARI_API std::span<const gpu::BirdMotionGpu> flocking_motion(const Domain& domain);

}  // namespace kodawari
