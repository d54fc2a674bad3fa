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

#include <glm/glm.hpp>
#include <kodawari/shared/birds.h>
#include <kodawari/shared/flocking.h>

#include "kodawari/core/api.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/render/draw.hpp"
#include "kodawari/simulation/domain.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari {

/// The flocking domain's name in a Simulation, and its output the bird domain reads.
inline constexpr std::string_view kFlockingDomain = "flocking";
/// Its channel: per flocking bird per frame a gpu::BirdMotionGpu (a diagnostic: the bake's
/// glTF is the birds' poses). A bird on its perch or landing (docs/flocking.md, "Perches")
/// has position.w == KW_MOTION_ROUTE there: its route's time, speed and easing, not a
/// place (shared/birds.h).
inline constexpr std::string_view kFlockingMotionChannel = "flocking.motion";

/// A flocking domain for the driven birds of `world` (BirdWorld::driven; their flocks'
/// FlockSpec::flocking in `scene`), or none when no flock of the scene flocks.
[[nodiscard]] KODAWARI_API Result<std::unique_ptr<Domain>> make_flocking_domain(const Scene& scene, const birds::BirdWorld& world);

/// What an application places among the flocking birds, per frame or once (issue 32: a
/// flock that reacts to the application): a predator they flee (across its path, with
/// panic, as the scene's `predators`), an attractor they are drawn to, or a sphere they keep
/// out of (an obstacle: a balloon, a tower's top, the player).
struct FlockAgent {
    enum class Kind : std::uint32_t {
        Predator = 0,   ///< fled within `radius`, at `weight` m/s^2 at the agent falling to 0 at `radius`
        Attractor = 1,  ///< drawn to within `radius`, the same falloff
        Obstacle = 2,   ///< a sphere of `radius`: pushed out within `margin` of its surface, `weight` at the surface
        Capsule = 3,    ///< a capsule of `radius` from `position` to `end`: kept out of as the sphere, steered round its axis
        Plane = 4,      ///< the plane through `position` with `normal`: birds kept on the normal's side, within `margin`
    };
    Kind kind = Kind::Predator;
    glm::vec3 position{0.0f};  ///< m, world; |each| <= 1e6
    /// m/s, |each| <= 1000: a predator's own velocity (birds flee across its path); unused
    /// by the others.
    glm::vec3 velocity{0.0f};
    float radius = 15.0f;  ///< m, in (0, 10 000]
    float weight = 40.0f;  ///< m/s^2, in [0, 1000]
    float margin = 2.0f;   ///< m, an obstacle's (sphere, capsule, plane), in (0, 1000]
    glm::vec3 end{0.0f};   ///< m, world, |each| <= 1e6: a capsule's other end
    /// A plane's normal, any length above 1e-6 (normalized): the side birds keep to.
    glm::vec3 normal{0.0f, 1.0f, 0.0f};
};
/// How the renderer draws the obstacles birds keep clear of (the scene's and the
/// application's): spheres and capsules as lit solids in kObstacleColor, a plane as a grid
/// of lines in kObstaclePlaneColor over the part of it near the flock (its routes and first
/// positions). Predators and attractors are forces, not objects, and are not drawn (a
/// predator that is another flock's bird is drawn as that bird).
inline constexpr render::Rgba8 kObstacleColor{156, 142, 112};
inline constexpr render::Rgba8 kObstaclePlaneColor{70, 112, 168};

/// The most agents an application may place at once (each bird visits every agent every
/// substep).
inline constexpr std::uint32_t kMaxFlockAgents = 64;

/// Places `agents` among the flocking birds of `sim` from its next step on, beside the
/// scene's predators, until called again (an empty span removes them). InvalidInput naming
/// `agents[i]` and the member (nothing changes then); with no flocking flock in the scene,
/// nothing to do.
[[nodiscard]] KODAWARI_API Result<void> set_flock_agents(Simulation& sim, std::span<const FlockAgent> agents);

/// The flocking domain's device buffers (Simulation::buffer, on the vulkan backend).
namespace flock_buffers {
/// The application's agents on the device (set_flock_device_agents): kMaxFlockAgents
/// gpu::FlockAgentGpu (kodawari/shared/flocking.h, the kernels' own encoding:
/// encode_flock_agent()) after the scene's predators, the range handed out.
inline constexpr std::string_view agents = "flocking.agents";
}  // namespace flock_buffers

/// Agents the application writes on its device, in its own command buffers, for
/// record() (Simulation::record) to read: from the next recorded frame on, the first
/// `count` elements of the buffer flock_buffers::agents (at most kMaxFlockAgents) are the
/// application's agents, in place of set_flock_agents' (each call replaces the other's;
/// 0 removes them). Write them after the previous frame's record() has read them (a
/// barrier from compute-shader reads) and before this frame's: record() begins with a
/// barrier from transfer and compute-shader writes. Their values are not checked: write
/// what encode_flock_agent() gives. InvalidInput naming `count` above kMaxFlockAgents, or
/// on a CPU backend, or on a simulation that cannot record (Simulation::can_record(): it
/// opened its own device); while `count` > 0, step() is refused (it cannot see them).
[[nodiscard]] KODAWARI_API Result<void> set_flock_device_agents(Simulation& sim, std::uint32_t count);

/// `agent` as the kernels read it (what set_flock_agents() writes, and what an application
/// writes into flock_buffers::agents), or InvalidInput naming the member out of range.
[[nodiscard]] KODAWARI_API Result<gpu::FlockAgentGpu> encode_flock_agent(const FlockAgent& agent);

/// Where a flocking domain's time went since it opened, on the CPU backends: the grid's
/// counting sort (one thread), the neighbour search (each bird's k nearest in view) and
/// the rules and limits, the last two summed over the threads that ran them (so their sum
/// is thread-seconds). On vulkan, whose passes run in one submission, those three are 0
/// (profile_flocking() times them apart) and bird_steps and device_seconds are kept.
/// `kodawari bench flock` reports the search's share.
struct FlockingTiming {
    double grid_seconds = 0.0;
    double search_seconds = 0.0;
    double rules_seconds = 0.0;
    std::uint64_t bird_steps = 0;  ///< birds x substeps stepped
    /// vulkan: the device's time of the step's submissions by its timestamps (from the
    /// frames' first dispatch to their last); -1 on the CPU kinds and on a device without
    /// timestamps.
    double device_seconds = -1.0;
};
[[nodiscard]] KODAWARI_API FlockingTiming flocking_timing(const Domain& domain);

/// Times the parts of the flocking step apart on the vulkan backend, whose step is one
/// submission (the CPU kinds measure theirs as they run: flocking_timing()): `frames`
/// frames of the grid's six passes alone, then of the passes and the neighbour search (a
/// kernel that finds every bird's neighbours and keeps its state), then of the whole step,
/// each a submission of its own, with the current frame's flock parameters and host
/// agents, timed by the device's timestamps (by the wall clock around the submission where
/// it has none). grid_seconds is the first, search_seconds the second less the first,
/// rules_seconds the third less the second (an ablation: the rules are what the whole
/// step adds to the search; a difference below 0, noise, is given as 0), bird_steps
/// birds x substeps x `frames`, device_seconds the
/// third. The flock is left as it was (its state and the motion of record()'s last frame).
/// It waits for its own submissions only: call it with none of the application's work on
/// the device in flight (it writes the flock's input buffers from the host). InvalidInput
/// for another domain, a domain not open or `frames` 0; Unsupported on the CPU kinds.
[[nodiscard]] KODAWARI_API Result<FlockingTiming> profile_flocking(Domain& domain, std::uint32_t frames);

/// The motion the flocking domain `domain` gave for the frames of its last step():
/// frames x BirdWorld::driven, frame-major; empty for another domain.
[[nodiscard]] KODAWARI_API std::span<const gpu::BirdMotionGpu> flocking_motion(const Domain& domain);

}  // namespace kodawari
