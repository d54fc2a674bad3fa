#pragma once
// What the files of the scalar rods solver share (not public): solver.cpp (the step),
// solver_collide.cpp (the colliders), solver_root_motion.cpp (teleports, centers, starts)
// and solver_posed.cpp (the posed level of detail).

#include <array>
#include <cstddef>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/rods/solver.hpp"

namespace kodawari::rods::detail {

// The same rotation with w >= 0, the identity's hemisphere.
inline glm::quat positive_w(glm::quat q) { return q.w < 0.0f ? -q : q; }

// World position of the point of segment [a, b] nearest to p.
glm::vec3 closest_on_segment(glm::vec3 p, glm::vec3 a, glm::vec3 b);

// The colliders of one substep, relative to the frame's origin (a plane's b: its unit
// normal), with the distance each keeps (collider_reach()).
struct SubstepColliders {
    std::array<glm::vec3, kMaxChainColliders> a{}, b{};
    std::array<float, kMaxChainColliders> reach{};
    std::array<ColliderKind, kMaxChainColliders> kind{};
    std::size_t count = 0;
};

// One particle against every collider, the whole set kColliderPasses times (solver.hpp):
// Gauss-Seidel over the set, so a particle pushed out of one collider into another is
// pushed out again by the next pass instead of ending inside whichever came first.
void collide_all(glm::vec3& p, const SubstepColliders& c);

}  // namespace kodawari::rods::detail
