// The posed level of detail's frame and the hand-over to a full chain (solver.hpp,
// kodawari/rods/lod.hpp, docs/level-of-detail.md): no dynamics.
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rods/solver_internal.hpp"

namespace kodawari::rods {

using detail::collide_all;
using detail::positive_w;
using detail::SubstepColliders;

void step_posed(const Chain& chain, const SolverParams& params, const Transform& root, const ChainShape& rest,
                std::span<const Collider> colliders, float dt, float blend, ChainState& s) {
    assert(dt > 0.0f && std::isfinite(dt));
    assert(blend >= 0.0f && blend <= 1.0f);
    const std::uint32_t n = chain.joint_count;
    assert(n >= 2 && n <= kMaxChainJoints);
    assert(rest.positions.size() == n && rest.orientations.size() == n);
    assert(colliders.size() <= kMaxChainColliders);
    follow_teleport(params, root, dt, s);
    if (!s.started && params.settle_start) start_moving(root, dt, s);
    s.started = true;
    // Relative to the previous root position, as step() solves; the colliders too, at
    // their end-of-frame poses.
    const glm::vec3 travel = root.position - s.root.position;
    const glm::quat turn = glm::normalize(root.rotation * glm::conjugate(s.root.rotation));
    SubstepColliders placed;
    placed.count = colliders.size();
    for (std::size_t k = 0; k < colliders.size(); ++k) {
        placed.a[k] = colliders[k].a - s.root.position;
        placed.b[k] = colliders[k].kind == ColliderKind::Plane ? colliders[k].b : colliders[k].b - s.root.position;
        placed.reach[k] = collider_reach(colliders[k], chain.thickness);
        placed.kind[k] = colliders[k].kind;
    }
    glm::vec3 parent(0.0f);
    for (std::uint32_t i = 0; i < n; ++i) {
        glm::quat goal = glm::normalize(root.rotation * rest.orientations[i]);
        glm::vec3 x = travel + root.rotation * rest.positions[i];
        glm::quat q = goal;
        if (i > 0) {
            const glm::vec3 target = travel + root.rotation * (rest.positions[i] + s.sag[i]);
            const glm::vec3 carried = travel + turn * s.x[i];
            x = carried + blend * (target - carried);
            // On its parent's segment length, then out of the colliders (one round of
            // step()'s last sweep: a posed chain is far from the camera, and a chain that
            // turns full starts from a shape its constraints nearly keep).
            const glm::vec3 d = x - parent;
            const float len = glm::length(d);
            if (len > 1e-9f) x = parent + (chain.segment_length[i - 1] / len) * d;
            if (placed.count > 0) collide_all(x, placed);
            const glm::quat held = glm::normalize(turn * s.q[i]);
            if (glm::dot(held, goal) < 0.0f) goal = -goal;
            q = glm::normalize(held + blend * (goal - held));
        }
        parent = x;
        s.v[i] = (x - s.x[i]) / dt;
        const glm::quat dq = positive_w(q * glm::conjugate(s.q[i]));
        s.omega[i] = (2.0f / dt) * glm::vec3(dq.x, dq.y, dq.z);
        s.x[i] = x - travel;
        s.q[i] = q;
        s.rest_position[i] = rest.positions[i];
        s.rest_orientation[i] = rest.orientations[i];
    }
    s.root = root;
}

void hand_over(const Chain& chain, const ChainState& before, const ChainState& posed, float share, float dt, ChainState& s) {
    assert(share >= 0.0f && share <= 1.0f);
    // Positions relative to the new root position (the state's), the frame's start too.
    const glm::vec3 travel = s.root.position - before.root.position;
    for (std::uint32_t i = 0; i < chain.joint_count; ++i) {
        const glm::vec3 x = posed.x[i] + share * (s.x[i] - posed.x[i]);
        glm::quat full = s.q[i];
        if (glm::dot(posed.q[i], full) < 0.0f) full = -full;
        const glm::quat q = glm::normalize(posed.q[i] + share * (full - posed.q[i]));
        s.v[i] = (x - (before.x[i] - travel)) / dt;
        const glm::quat dq = positive_w(q * glm::conjugate(before.q[i]));
        s.omega[i] = (2.0f / dt) * glm::vec3(dq.x, dq.y, dq.z);
        s.x[i] = x;
        s.q[i] = q;
    }
}

}  // namespace kodawari::rods
