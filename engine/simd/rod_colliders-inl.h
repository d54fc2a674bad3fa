// The colliders of the cpu rod kernel (simd/rods_simd.cpp) for one Highway target: each
// collider's rows, its placement by a substep's root and solver_collide.cpp's collision of
// a particle with it, lane by lane in the reference's order of operations. Included after
// foreach_target.h, once per target, like Highway's own -inl.h files.

#if defined(KODAWARI_SIMD_ROD_COLLIDERS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef KODAWARI_SIMD_ROD_COLLIDERS_INL_H_
#undef KODAWARI_SIMD_ROD_COLLIDERS_INL_H_
#else
#define KODAWARI_SIMD_ROD_COLLIDERS_INL_H_
#endif

#include <cstddef>
#include <cstdint>

#include <hwy/highway.h>

#include "simd/vecmath-inl.h"

HWY_BEFORE_NAMESPACE();
namespace kodawari::simd {
namespace HWY_NAMESPACE {

// Per collider: a (3), b (3), its reach (rods::collider_reach), and 1 in the row of its
// kind (outside, inside, plane) where the lane's chain has it.
enum ColliderRow : std::uint32_t {
    kCapA = 0, kCapB = 3, kCapR = 6, kCapOutside = 7, kCapInside = 8, kCapPlane = 9, kColliderRows = 10
};

// One collider of a batch in the end root's frame (solver.cpp step: la = R_to^-1 (a - to),
// lb likewise, a plane's lb its turned normal), the lanes whose chain has it as each kind,
// and, per substep, where the substep's root places it: a relative to the frame's origin,
// ab = b - a (a plane's lanes: its normal b) and len2 = dot(ab, ab) (the same for every
// joint of the substep, computed once), and its reach.
struct CollidersK {
    V3 la, lb;
    V3 a, ab;
    V len2, reach;
    M outside, inside, plane;
    bool any_capsule, any_inside, any_plane;  // some lane has it as a capsule (outside or inside), inside, a plane
};

// A collider's kinds per lane (the rows gather_inputs() wrote), which of them any lane
// has, and its reach.
inline void load_kinds(const float* rows, std::size_t off, CollidersK& c) {
    c.outside = hn::Gt(load(rows, kCapOutside, off), Z());
    c.inside = hn::Gt(load(rows, kCapInside, off), Z());
    c.plane = hn::Gt(load(rows, kCapPlane, off), Z());
    c.reach = load(rows, kCapR, off);
    c.any_capsule = !hn::AllFalse(D(), hn::Or(c.outside, c.inside));
    c.any_inside = !hn::AllFalse(D(), c.inside);
    c.any_plane = !hn::AllFalse(D(), c.plane);
}

// solver.cpp step 3: the collider placed by the substep's root (r_p, r_q).
inline void place(CollidersK& c, const V3& r_p, const Q4& r_q) {
    c.a = add(r_p, rotate(r_q, c.la));
    const V3 turned = rotate(r_q, c.lb);
    c.ab = select(c.plane, turned, sub(add(r_p, turned), c.a));
    c.len2 = dot(c.ab, c.ab);
}

// solver_collide.cpp collide(): closest_on_segment() then push_out() (outside lanes) or pull_in()
// (inside lanes), and the plane's half-space (plane lanes), each kind's expressions as
// the reference writes them.
inline void collide(V3& p, const CollidersK& c) {
    if (c.any_capsule) {
        V t = hn::Div(dot(sub(p, c.a), c.ab), c.len2);
        t = hn::IfThenElse(hn::Lt(t, Z()), Z(), hn::IfThenElse(hn::Lt(S(1.0f), t), S(1.0f), t));  // std::clamp
        const V3 center = select(hn::Le(c.len2, Z()), c.a, add(c.a, mul(t, c.ab)));
        const V3 d = sub(p, center);
        const V d2 = dot(d, d);
        const V r2 = hn::Mul(c.reach, c.reach);
        const M push = hn::And(c.outside, hn::Not(hn::Ge(d2, r2)));
        const V len = hn::Sqrt(d2);
        const V3 unit = div(d, len);
        const V3 out_n = select(hn::Gt(len, S(1e-9f)), unit, V3{Z(), S(1.0f), Z()});
        if (c.any_inside) {
            const M pull = hn::And(c.inside, hn::Not(hn::Le(d2, r2)));
            p = select(hn::Or(push, pull), add(center, mul(c.reach, select(push, out_n, unit))), p);
        } else {
            p = select(push, add(center, mul(c.reach, out_n)), p);
        }
    }
    if (c.any_plane) {
        const V s = dot(sub(p, c.a), c.ab);
        const M below = hn::And(c.plane, hn::Lt(s, c.reach));
        p = select(below, add(p, mul(hn::Sub(c.reach, s), c.ab)), p);
    }
}

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::simd
HWY_AFTER_NAMESPACE();

#endif  // KODAWARI_SIMD_ROD_COLLIDERS_INL_H_
