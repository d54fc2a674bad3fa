#pragma once
// Quaternion arithmetic of the bird tests, written out independently of the engine's so
// that a test checks the engine rather than repeating it. (x, y, z, w), glTF order.

#include "kodawari/birds/flight.hpp"

namespace kodawari::birds::test_math {

/// v rotated by the unit quaternion q: v + 2 w (q x v) + 2 q x (q x v).
inline Vec3 rotate(const gpu::vec4& q, Vec3 v) {
    const Vec3 u{q.x, q.y, q.z};
    auto cross = [](Vec3 a, Vec3 b) { return Vec3{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; };
    const Vec3 t = cross(u, v);
    const Vec3 t2 = cross(u, t);
    return {v.x + 2 * q.w * t.x + 2 * t2.x, v.y + 2 * q.w * t.y + 2 * t2.y, v.z + 2 * q.w * t.z + 2 * t2.z};
}

/// p q.
inline gpu::vec4 mul(const gpu::vec4& p, const gpu::vec4& q) {
    return {p.w * q.x + p.x * q.w + p.y * q.z - p.z * q.y, p.w * q.y - p.x * q.z + p.y * q.w + p.z * q.x,
            p.w * q.z + p.x * q.y - p.y * q.x + p.z * q.w, p.w * q.w - p.x * q.x - p.y * q.y - p.z * q.z};
}

}  // namespace kodawari::birds::test_math
