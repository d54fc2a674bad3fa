// A chain carried by its root's motion outside the step: a center frame's motion, a
// teleport, and a first step's start (solver.hpp).
#include <cmath>
#include <cstdint>

#include "rods/solver_internal.hpp"

namespace kodawari::rods {

using detail::positive_w;

void follow_center(const Transform& from, const Transform& to, ChainState& s) {
    const glm::quat r = glm::normalize(to.rotation * glm::conjugate(from.rotation));
    for (std::uint32_t i = 0; i < kMaxChainJoints; ++i) {
        s.x[i] = r * s.x[i];
        s.v[i] = r * s.v[i];
        s.q[i] = glm::normalize(r * s.q[i]);
        s.omega[i] = r * s.omega[i];
    }
    s.root.position = to.position + r * (s.root.position - from.position);
    s.root.rotation = glm::normalize(r * s.root.rotation);
}

Transform frame_before(const Transform& root, const ChainState& s, float dt) {
    const glm::vec3 turn = s.omega[0] * dt;
    const float angle = glm::length(turn);
    const glm::vec3 axis = angle > 0.0f ? turn / angle : glm::vec3(0.0f);
    const glm::quat back(std::cos(0.5f * angle), -std::sin(0.5f * angle) * axis);
    return {root.position - s.v[0] * dt, glm::normalize(back * root.rotation)};
}

void start_moving(const Transform& root, float dt, ChainState& s) {
    const glm::quat turn = positive_w(glm::normalize(root.rotation * glm::conjugate(s.root.rotation)));
    const glm::vec3 travel = root.position - s.root.position;
    const glm::vec3 omega = (2.0f / dt) * glm::vec3(turn.x, turn.y, turn.z);
    for (std::uint32_t i = 0; i < kMaxChainJoints; ++i) {
        s.v[i] += (travel + (turn * s.x[i] - s.x[i])) / dt;
        s.omega[i] += omega;
    }
}

bool follow_teleport(const SolverParams& params, const Transform& root, float dt, ChainState& s) {
    if (!teleported(s.root.position, root.position, params.teleport_distance)) return false;
    // Carried to the new root, then back by one frame of the root's own motion (joint 0
    // follows the root: its velocities, carried too, are the root's), so that step() sees
    // the root move on as it moved and the chain's velocities, which carry that motion,
    // do not take it a second time.
    follow_center(s.root, root, s);
    follow_center(root, frame_before(root, s, dt), s);
    return true;
}

}  // namespace kodawari::rods
