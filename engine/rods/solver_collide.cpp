// The colliders of the scalar rods solver (SPEC A.4, collisions): a particle pushed out of
// (or kept inside) each collider of solver.hpp ColliderKind, and what each keeps.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rods/solver_internal.hpp"

namespace kodawari::rods {
namespace {

using detail::closest_on_segment;

// Moves p out of the ball of `radius` around `center` (SPEC A.4, collisions).
void push_out(glm::vec3& p, glm::vec3 center, float radius) {
    const glm::vec3 d = p - center;
    const float len2 = glm::dot(d, d);
    if (len2 >= radius * radius) return;
    const float len = std::sqrt(len2);
    // A particle exactly at the centre has no outward direction; +Y is as good as any
    // and keeps the result deterministic.
    const glm::vec3 n = len > 1e-9f ? d / len : glm::vec3(0.0f, 1.0f, 0.0f);
    p = center + radius * n;
}

// Keeps p within `radius` of `center` (an inside collider; VRMC_springBone_extended_collider
// 1.0: the joint's sphere of hitRadius stays inside the collider's, so `radius` is the
// collider's minus the particle's, at least 0).
void pull_in(glm::vec3& p, glm::vec3 center, float radius) {
    const glm::vec3 d = p - center;
    const float len2 = glm::dot(d, d);
    if (len2 <= radius * radius) return;
    const float len = std::sqrt(len2);
    p = center + radius * (d / len);  // len > radius >= 0: a direction exists
}

// One collider on one particle of radius `thickness` (SPEC A.4, collisions; the kinds of
// solver.hpp ColliderKind). `a` and `b` are the collider's, relative to the frame's
// origin (a plane's b is its unit normal, a direction); `reach` is what the kind keeps:
// radius + thickness outside, max(radius - thickness, 0) inside, thickness for a plane
// (collider_reach()).
void collide(glm::vec3& p, glm::vec3 a, glm::vec3 b, float reach, ColliderKind kind) {
    if (kind == ColliderKind::Plane) {
        const glm::vec3 n = b;  // unit
        const float s = glm::dot(p - a, n);
        if (s < reach) p += (reach - s) * n;
        return;
    }
    const glm::vec3 c = closest_on_segment(p, a, b);
    if (kind == ColliderKind::Inside) {
        pull_in(p, c, reach);
    } else {
        push_out(p, c, reach);
    }
}

}  // namespace

namespace detail {

// World position of the point of segment [a, b] nearest to p.
glm::vec3 closest_on_segment(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
    const glm::vec3 ab = b - a;
    const float len2 = glm::dot(ab, ab);
    if (len2 <= 0.0f) return a;
    const float t = std::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f);
    return a + t * ab;
}

// One particle against every collider, kColliderPasses times (solver_internal.hpp).
void collide_all(glm::vec3& p, const SubstepColliders& c) {
    for (std::uint32_t pass = 0; pass < kColliderPasses; ++pass) {
        for (std::size_t k = 0; k < c.count; ++k) collide(p, c.a[k], c.b[k], c.reach[k], c.kind[k]);
    }
}

}  // namespace detail

float collider_reach(const Collider& c, float thickness) {
    switch (c.kind) {
        case ColliderKind::Inside: return std::max(c.radius - thickness, 0.0f);
        case ColliderKind::Plane: return thickness;
        case ColliderKind::Outside: break;
    }
    return c.radius + thickness;
}

float collider_gap(const Collider& c, glm::vec3 p, float thickness) {
    const float reach = collider_reach(c, thickness);
    if (c.kind == ColliderKind::Plane) return glm::dot(p - c.a, c.b) - reach;
    const float distance = glm::length(p - closest_on_segment(p, c.a, c.b));
    return c.kind == ColliderKind::Inside ? reach - distance : distance - reach;
}

}  // namespace kodawari::rods
