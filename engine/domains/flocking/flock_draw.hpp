#pragma once
// How the flocking domain draws what its birds keep clear of, through render::Draw
// (kodawari/domains/flocking.hpp: kObstacleColor, kObstaclePlaneColor).

#include <span>

#include <glm/glm.hpp>
#include <kodawari/shared/flocking.h>

#include "domains/flocking/flock_world.hpp"
#include "kodawari/render/draw.hpp"

namespace kodawari::flocking {

/// Where the flocks fly (their first positions and every route's control points): the
/// part of a plane obstacle that is drawn lies over it. lo > hi where there is nothing.
struct DrawExtent {
    glm::vec3 lo{0.0f}, hi{0.0f};
};
[[nodiscard]] DrawExtent draw_extent(const FlockWorld& world);

/// The obstacles among `agents` (spheres, capsules, planes; the others are skipped), drawn
/// into `draw`.
void draw_obstacles(render::Draw& draw, std::span<const gpu::FlockAgentGpu> agents, const DrawExtent& extent);

}  // namespace kodawari::flocking
