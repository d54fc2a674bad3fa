// The bird kernel of the cpu backend (SPEC B.2-B.6), vectorized across the birds of a
// batch (birds_simd.hpp: layout, and what is exact). Compiled once per instruction set by
// Highway's foreach_target.h. Each step repeats the function of engine/birds/flight.cpp
// (and wingbeat.cpp) it names, in its order of operations; the SPEC sections are cited
// there.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "simd/birds_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <cstring>
#include <numbers>

#include "simd/birds_simd.hpp"
#include "simd/scalar_math.hpp"
#include "simd/vecmath-inl.h"

HWY_BEFORE_NAMESPACE();
namespace kodawari::simd {
namespace HWY_NAMESPACE {
namespace {

using DI = hn::RebindToSigned<D>;
using VI = hn::Vec<DI>;

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kTwoPi = 2.0f * kPi;  // flight.cpp's

// flight.cpp works with its own Vec3 whose dot is (x x' + y y') + z z', like glm's
// (vecmath-inl.h dot/length), but its quaternion product and dot have their own order.
HWY_INLINE Q4 quat_mul(const Q4& a, const Q4& b) {
    return {hn::Sub(hn::Add(hn::Add(hn::Mul(a.w, b.x), hn::Mul(a.x, b.w)), hn::Mul(a.y, b.z)), hn::Mul(a.z, b.y)),
            hn::Add(hn::Add(hn::Sub(hn::Mul(a.w, b.y), hn::Mul(a.x, b.z)), hn::Mul(a.y, b.w)), hn::Mul(a.z, b.x)),
            hn::Add(hn::Sub(hn::Add(hn::Mul(a.w, b.z), hn::Mul(a.x, b.y)), hn::Mul(a.y, b.x)), hn::Mul(a.z, b.w)),
            hn::Sub(hn::Sub(hn::Sub(hn::Mul(a.w, b.w), hn::Mul(a.x, b.x)), hn::Mul(a.y, b.y)), hn::Mul(a.z, b.z))};
}
HWY_INLINE V quat_dot(const Q4& a, const Q4& b) {
    return hn::Add(hn::Add(hn::Add(hn::Mul(a.x, b.x), hn::Mul(a.y, b.y)), hn::Mul(a.z, b.z)), hn::Mul(a.w, b.w));
}
HWY_INLINE V clamp01(V x) { return hn::IfThenElse(hn::Lt(x, Z()), Z(), hn::IfThenElse(hn::Lt(S(1.0f), x), S(1.0f), x)); }

struct Bezier {
    V3 p, d1, d2;
};

// What the lanes read of their route last frame, kept from frame to frame: a bird moves a
// little along its route each frame, so its Bezier segment and arc-length interval rarely
// change, and gathering them again (and the binary search) is most of the route's cost.
// The values are the same as read afresh, so the results do not change (the GPU kernel
// keeps the same cache).
struct RouteCache {
    bool segment_valid = false;
    VI segment;
    V3 b[4];
    bool interval_valid = false;
    VI lo;          // the interval [lo, lo + 1] of the arc-length samples
    V ax, ay, aw, next, bx, by, bz;
};

// flight.cpp bezier_global() and bezier(): segment min(u, n - 1) of the route at u.
Bezier bezier(const BirdStepArgs& a, const gpu::RouteHeader& route, V u, RouteCache& cache) {
    const DI di;
    const VI seg = hn::Min(hn::ConvertTo(di, hn::IfThenElse(hn::Lt(u, Z()), Z(), u)),
                           hn::Set(di, static_cast<std::int32_t>(route.extent.y) - 1));
    u = hn::Sub(u, hn::ConvertTo(D(), seg));
    if (!cache.segment_valid || !hn::AllTrue(di, hn::Eq(seg, cache.segment))) {
        const float* points = &a.control_points[0].x;
        const VI first = hn::Mul(hn::Add(hn::Set(di, static_cast<std::int32_t>(route.extent.x)), hn::Mul(seg, hn::Set(di, 3))),
                                 hn::Set(di, 4));
        for (int j = 0; j < 4; ++j) {
            const VI at = hn::Add(first, hn::Set(di, 4 * j));
            cache.b[j] = {hn::GatherIndex(D(), points, at), hn::GatherIndex(D(), points, hn::Add(at, hn::Set(di, 1))),
                          hn::GatherIndex(D(), points, hn::Add(at, hn::Set(di, 2)))};
        }
        cache.segment = seg;
        cache.segment_valid = true;
    }
    const V3* b = cache.b;
    const V v = hn::Sub(S(1.0f), u);
    const V three_u = hn::Mul(S(3.0f), u);
    Bezier r;
    r.p = add(add(add(mul(hn::Mul(hn::Mul(v, v), v), b[0]), mul(hn::Mul(hn::Mul(three_u, v), v), b[1])),
                  mul(hn::Mul(hn::Mul(three_u, u), v), b[2])),
              mul(hn::Mul(hn::Mul(u, u), u), b[3]));
    r.d1 = mul(S(3.0f), add(add(mul(hn::Mul(v, v), sub(b[1], b[0])), mul(hn::Mul(hn::Mul(S(2.0f), u), v), sub(b[2], b[1]))),
                            mul(hn::Mul(u, u), sub(b[3], b[2]))));
    r.d2 = mul(S(6.0f), add(mul(v, add(sub(b[2], mul(S(2.0f), b[1])), b[0])), mul(u, add(sub(b[3], mul(S(2.0f), b[2])), b[1]))));
    return r;
}

// flight.cpp route_parameter_at(): the interval a binary search over the arc-length
// samples finds (the last lo with s_lo <= s, at most last - 1), then the cubic Hermite
// interpolation of u(s). The cached interval is that one while s stays in it; the next
// one is the usual answer when it does not; the search, lane by lane in step, otherwise.
V route_parameter_at(const BirdStepArgs& a, const gpu::RouteHeader& route, V s, RouteCache& cache) {
    const DI di;
    const float* table = &a.arc_samples[route.extent.z].s_u_duds.x;
    constexpr int kStride = sizeof(gpu::ArcSample) / sizeof(float);
    const VI last = hn::Set(di, static_cast<std::int32_t>(route.extent.w) - 1), one = hn::Set(di, 1);
    auto s_at = [&](const VI& index) { return hn::GatherIndex(D(), table, hn::Mul(index, hn::Set(di, kStride))); };
    bool fresh = true;
    VI lo = hn::Zero(di);
    if (cache.interval_valid) {
        const M last_interval = hn::RebindMask(D(), hn::Eq(hn::Add(cache.lo, one), last));
        const M still = hn::And(hn::Le(cache.ax, s), hn::Or(hn::Lt(s, cache.bx), last_interval));
        if (hn::AllTrue(D(), still)) {
            fresh = false;
        } else {
            // Forward flight: the next interval, where it holds s.
            const VI lo2 = hn::Min(hn::Add(cache.lo, hn::Set(di, 2)), last);
            const M next_is_last = hn::RebindMask(D(), hn::Eq(hn::Add(cache.lo, hn::Set(di, 2)), last));
            const M can_step = hn::RebindMask(D(), hn::Lt(hn::Add(cache.lo, one), last));  // lo + 2 <= last
            const M forward = hn::And(hn::And(can_step, hn::Le(cache.bx, s)), hn::Or(hn::Lt(s, s_at(lo2)), next_is_last));
            if (hn::AllTrue(D(), hn::Or(still, forward))) {
                lo = hn::IfThenElse(hn::RebindMask(di, forward), hn::Add(cache.lo, one), cache.lo);
            } else {
                cache.interval_valid = false;
            }
        }
    }
    if (!cache.interval_valid) {
        VI hi = last;
        for (;;) {
            const auto active = hn::Gt(hn::Sub(hi, lo), one);
            if (hn::AllFalse(di, active)) break;
            const VI mid = hn::ShiftRight<1>(hn::Add(lo, hi));
            const auto below = hn::RebindMask(di, hn::Le(s_at(mid), s));
            lo = hn::IfThenElse(hn::And(active, below), mid, lo);
            hi = hn::IfThenElse(hn::AndNot(below, active), mid, hi);
        }
    }
    if (fresh) {
        const VI at_lo = hn::Mul(lo, hn::Set(di, kStride)), at_hi = hn::Add(at_lo, hn::Set(di, kStride));
        auto field = [&](const VI& at, int k) { return hn::GatherIndex(D(), table, hn::Add(at, hn::Set(di, k))); };
        cache.lo = lo;
        cache.ax = field(at_lo, 0);
        cache.ay = field(at_lo, 1);
        cache.aw = field(at_lo, 3);
        cache.next = field(at_lo, 4);
        cache.bx = field(at_hi, 0);
        cache.by = field(at_hi, 1);
        cache.bz = field(at_hi, 2);
        cache.interval_valid = true;
    }
    const V ax = cache.ax, ay = cache.ay, aw = cache.aw, next = cache.next, bx = cache.bx, by = cache.by, bz = cache.bz;
    const V h = hn::Sub(bx, ax);
    const V t = clamp01(hn::Mul(hn::Sub(s, ax), next));
    const V t2 = hn::Mul(t, t), t3 = hn::Mul(t2, t);
    const V c0 = hn::Mul(hn::Add(hn::Sub(hn::Mul(S(2.0f), t3), hn::Mul(S(3.0f), t2)), S(1.0f)), ay);
    const V c1 = hn::Mul(hn::Mul(hn::Add(hn::Sub(t3, hn::Mul(S(2.0f), t2)), t), h), aw);
    const V c2 = hn::Mul(hn::Add(hn::Mul(S(-2.0f), t3), hn::Mul(S(3.0f), t2)), by);
    const V c3 = hn::Mul(hn::Mul(hn::Sub(t3, t2), h), bz);
    return hn::Add(hn::Add(hn::Add(c0, c1), c2), c3);
}

struct Sample {
    V3 position, velocity, acceleration, direction;
    V lift, lift_scale;
};

// flight.cpp sample_route(): both ends' cases and the inside computed, one chosen per lane.
Sample sample_route(const BirdStepArgs& a, const gpu::RouteHeader& route, V time, V speed, RouteCache& cache) {
    const bool loop = (route.flags.x & KW_ROUTE_LOOP) != 0;
    const V n = S(static_cast<float>(route.extent.y));
    Sample out;
    if ((route.flags.x & KW_ROUTE_PARAMETRIC) != 0) {
        V u = hn::Mul(time, S(route.info.w));
        if (loop) {  // u mod n without a division, as the reference: in integers, lane by lane
            HWY_ALIGN float lanes[kBatchLanes];
            hn::Store(u, D(), lanes);
            const int segments = static_cast<int>(route.extent.y);
            for (std::size_t l = 0; l < hn::Lanes(D()); ++l) {
                const float whole = static_cast<float>(hn::GetLane(hn::Floor(hn::Set(D(), lanes[l]))));
                int wrapped = static_cast<int>(whole) % segments;
                if (wrapped < 0) wrapped += segments;
                lanes[l] = static_cast<float>(wrapped) + (lanes[l] - whole);
            }
            u = hn::Load(D(), lanes);
        }
        const M outside = hn::Or(hn::Lt(u, Z()), hn::Gt(u, n));
        const V end = hn::IfThenElse(hn::Lt(u, Z()), Z(), n);
        const Bezier e = bezier(a, route, hn::IfThenElse(outside, end, u), cache);
        out.position = select(outside, add(e.p, mul(hn::Sub(u, end), e.d1)), e.p);
        out.velocity = mul(S(route.info.w), e.d1);
        out.acceleration = select(outside, zero3(), mul(S(route.info.w * route.info.w), e.d2));
        out.direction = e.d1;
        out.lift = hn::IfThenElse(outside, Z(), e.d2.y);
        out.lift_scale = hn::IfThenElse(outside, S(1.0f), S(route.info.y * route.info.y));
        return out;
    }
    const float total = route.info.x;
    V s = hn::Mul(speed, time);
    if (loop) s = hn::Sub(s, hn::Mul(S(total), hn::Floor(hn::Mul(s, S(route.info.z)))));
    const M before = hn::Lt(s, Z());
    const M outside = hn::Or(before, hn::Gt(s, S(total)));
    const V clamped = hn::IfThenElse(before, Z(), hn::IfThenElse(hn::Gt(s, S(total)), S(total), s));
    const V u = hn::IfThenElse(outside, hn::IfThenElse(before, Z(), n), route_parameter_at(a, route, clamped, cache));
    const Bezier e = bezier(a, route, u, cache);
    const V d1_len = length(e.d1);
    const V3 tangent = mul(hn::Div(S(1.0f), d1_len), e.d1);
    const V end_s = hn::IfThenElse(before, Z(), S(total));
    out.position = select(outside, add(e.p, mul(hn::Sub(s, end_s), tangent)), e.p);
    out.velocity = mul(speed, tangent);
    const V3 normal = sub(e.d2, mul(dot(e.d2, tangent), tangent));
    out.acceleration = select(outside, zero3(), mul(hn::Div(hn::Mul(speed, speed), hn::Mul(d1_len, d1_len)), normal));
    out.direction = e.d1;
    const V dd = dot(e.d1, e.d1), d2d1 = dot(e.d2, e.d1);
    out.lift = hn::IfThenElse(outside, Z(), hn::Mul(hn::Mul(speed, speed), hn::Sub(hn::Mul(e.d2.y, dd), hn::Mul(d2d1, e.d1.y))));
    out.lift_scale = hn::IfThenElse(outside, S(1.0f), hn::Mul(dd, dd));
    return out;
}

// flight.cpp half_angle(): (cos(x/2), sin(x/2)) from (cos x, sin x), cos x >= 0.
HWY_INLINE void half_angle(V c, V s, V& half_c, V& half_s) {
    half_c = hn::Sqrt(hn::Mul(S(0.5f), hn::Add(S(1.0f), c)));
    half_s = hn::Div(s, hn::Mul(S(2.0f), half_c));
}

// flight.cpp body_rotation() with the coordinated bank (the seed's rule is lane by lane).
Q4 body_rotation(const gpu::FlightUniforms& uniforms, const V3& v, const V3& a) {
    const V horizontal = hn::Sqrt(hn::Add(hn::Mul(v.x, v.x), hn::Mul(v.z, v.z)));
    const V speed = hn::Sqrt(hn::Add(hn::Mul(horizontal, horizontal), hn::Mul(v.y, v.y)));
    const Q4 identity{Z(), Z(), Z(), S(1.0f)};
    Q4 yaw = identity;
    {
        const V c = hn::Div(v.z, horizontal), s = hn::Div(v.x, horizontal);
        V hc, hs;
        half_angle(c, s, hc, hs);
        const V back_y = hn::CopySign(hn::Sqrt(hn::Mul(S(0.5f), hn::Sub(S(1.0f), c))), s);  // near 180 degrees
        const V back_w = hn::Div(s, hn::Mul(S(2.0f), back_y));
        const M front = hn::Ge(c, Z());
        const M turned = hn::Gt(horizontal, Z());
        yaw.y = hn::IfThenElse(turned, hn::IfThenElse(front, hs, back_y), Z());
        yaw.w = hn::IfThenElse(turned, hn::IfThenElse(front, hc, back_w), S(1.0f));
    }
    Q4 pitch = identity;
    half_angle(hn::Div(horizontal, speed), hn::Div(hn::Neg(v.y), speed), pitch.w, pitch.x);
    V bc = S(1.0f), bs = Z();
    {
        const V lateral = hn::Div(hn::Add(hn::Mul(a.x, hn::Neg(v.z)), hn::Mul(a.z, v.x)), horizontal);
        const V g = S(uniforms.physics.x);
        const V norm = hn::Sqrt(hn::Add(hn::Mul(lateral, lateral), hn::Mul(g, g)));
        V c = hn::Div(g, norm), s = hn::Div(lateral, norm);
        const M limited = hn::Lt(c, S(uniforms.bank_limit.x));
        s = hn::IfThenElse(limited, hn::CopySign(S(uniforms.bank_limit.y), lateral), s);
        c = hn::IfThenElse(limited, S(uniforms.bank_limit.x), c);
        const M banked = hn::Gt(horizontal, hn::Mul(S(1e-6f), hn::Abs(v.y)));
        bc = hn::IfThenElse(banked, c, bc);
        bs = hn::IfThenElse(banked, s, bs);
    }
    Q4 bank = identity;
    half_angle(bc, bs, bank.w, bank.z);
    return select(hn::Le(speed, Z()), identity, quat_mul(quat_mul(yaw, pitch), bank));
}

// flight.cpp next_mode(), modes as floats (0 level, 1 ascend, 2 descend, -1 unset).
V next_mode(const gpu::FlightUniforms& u, V previous, const Sample& r) {
    const V level = S(KW_MODE_LEVEL), ascend = S(KW_MODE_ASCEND), descend = S(KW_MODE_DESCEND);
    if (u.rules.y == KW_MODE_RULE_SEED) {
        const V threshold = hn::Mul(S(u.blend_rates.w), r.lift_scale);
        return hn::IfThenElse(hn::Gt(r.lift, threshold), ascend,
                              hn::IfThenElse(hn::Lt(r.lift, hn::Neg(threshold)), descend, level));
    }
    const V3& d = r.direction;
    const V dd = dot(d, d);
    const V climb = hn::Mul(d.y, hn::Abs(d.y));
    auto above = [&](float k) { return hn::Gt(climb, hn::Mul(S(k), dd)); };
    auto below = [&](float k) { return hn::Lt(climb, hn::Mul(S(k), dd)); };
    V mode = previous;
    mode = hn::IfThenElse(hn::And(hn::Eq(mode, ascend), below(u.climb.y)), level, mode);
    mode = hn::IfThenElse(hn::And(hn::Eq(mode, descend), above(u.climb.w)), level, mode);
    const V fresh = hn::IfThenElse(above(u.climb.x), ascend, hn::IfThenElse(below(u.climb.z), descend, level));
    return hn::IfThenElse(hn::Le(mode, level), fresh, mode);  // level or unset
}

// wingbeat.cpp: the wing angles of each mode at phase t (sin_t = sin t), times the amplitude.
struct Wings {
    V arm1_pitch, arm2_pitch, arm1_heading, arm2_heading;
};
Wings wing_angles(int mode, V t, V sin_t, V amplitude) {
    const M first_half = hn::Lt(t, S(kPi));
    Wings w{Z(), Z(), Z(), Z()};
    const V eq_4_2 = hn::IfThenElse(first_half, hn::Mul(S(-(kPi / 3.0f)), sin_t), hn::Mul(S(-(3.0f / 18.0f) * kPi), sin_t));
    if (mode == KW_MODE_LEVEL) {
        const V rise = hn::Add(hn::Mul(S(-(2.0f / 3.0f)), t), S(kPi / 3.0f));
        const V fall = hn::Sub(hn::Mul(S(2.0f / 3.0f), t), S((4.0f / 3.0f) * kPi));
        w.arm1_pitch = hn::IfThenElse(hn::Lt(t, S(0.5f * kPi)), Z(),
                                      hn::IfThenElse(first_half, rise, hn::IfThenElse(hn::Lt(t, S(1.5f * kPi)), S(-kPi / 3.0f), fall)));
        w.arm2_pitch = eq_4_2;
    } else if (mode == KW_MODE_ASCEND) {
        w.arm1_pitch = eq_4_2;
        w.arm2_pitch =
            hn::IfThenElse(first_half, hn::Mul(S(-(4.0f / 9.0f) * kPi), sin_t), hn::Mul(S(-(5.0f / 18.0f) * kPi), sin_t));
    } else {
        w.arm1_heading = hn::Mul(S(kPi / 180.0f), sin_t);
        w.arm2_heading = hn::IfThenElse(first_half, hn::Mul(S(-(kPi / 36.0f)), sin_t), hn::Mul(S(-(kPi / 90.0f)), sin_t));
    }
    return {hn::Mul(w.arm1_pitch, amplitude), hn::Mul(w.arm2_pitch, amplitude), hn::Mul(w.arm1_heading, amplitude),
            hn::Mul(w.arm2_heading, amplitude)};
}

// sin x and cos x: Cody-Waite reduction by multiples of pi/2 and Cephes' single-precision
// polynomials (a few ulp from the C library's for the wings' |x| < 10). Only +, -, *,
// conversions and bit operations, no fused multiply-add: the same bits on every
// instruction set (Highway's own Sin and Cos fuse where the ISA has FMA), so the cpu
// backend's birds are one result wherever it runs and exports stay byte-identical.
void sin_cos(V x, V& sin_x, V& cos_x) {
    const DI di;
    const V ax = hn::Abs(x);
    VI j = hn::ConvertTo(di, hn::Mul(ax, S(1.27323954473516f)));  // 4 / pi
    j = hn::And(hn::Add(j, hn::Set(di, 1)), hn::Set(di, ~1));
    const V y = hn::ConvertTo(D(), j);
    const V r = hn::Sub(hn::Sub(hn::Sub(ax, hn::Mul(y, S(0.78515625f))), hn::Mul(y, S(2.4187564849853515625e-4f))),
                        hn::Mul(y, S(3.77489497744594108e-8f)));
    const V z = hn::Mul(r, r);
    const V sin_r = hn::Add(
        hn::Mul(hn::Mul(hn::Sub(hn::Mul(hn::Add(hn::Mul(S(-1.9515295891e-4f), z), S(8.3321608736e-3f)), z), S(1.6666654611e-1f)), z), r),
        r);
    const V cos_r = hn::Add(
        hn::Sub(hn::Mul(hn::Mul(hn::Add(hn::Mul(hn::Sub(hn::Mul(S(2.443315711809948e-5f), z), S(1.388731625493765e-3f)), z),
                                        S(4.166664568298827e-2f)),
                                z),
                        z),
                hn::Mul(S(0.5f), z)),
        S(1.0f));
    const VI q = hn::ShiftRight<1>(j);  // quadrant of ax
    const M swap = hn::RebindMask(D(), hn::Ne(hn::And(q, hn::Set(di, 1)), hn::Zero(di)));
    const M sin_negative = hn::RebindMask(D(), hn::Ne(hn::And(q, hn::Set(di, 2)), hn::Zero(di)));
    const M cos_negative = hn::RebindMask(D(), hn::Ne(hn::And(hn::Add(q, hn::Set(di, 1)), hn::Set(di, 2)), hn::Zero(di)));
    const V s = hn::IfThenElse(swap, cos_r, sin_r), c = hn::IfThenElse(swap, sin_r, cos_r);
    sin_x = hn::IfThenElse(hn::Xor(sin_negative, hn::Lt(x, Z())), hn::Neg(s), s);
    cos_x = hn::IfThenElse(cos_negative, hn::Neg(c), c);
}

// arm_rotation(pitch, heading) = quat_z(pitch) quat_y(heading), one of which is zero in
// every mode: a turn about z (pitch) or y (heading) by `angle`.
Q4 arm_rotation(V angle, M about_y) {
    V s, c;
    sin_cos(hn::Mul(S(0.5f), angle), s, c);
    return {Z(), hn::IfThenElseZero(about_y, s), hn::IfThenElse(about_y, Z(), s), c};
}

// SPEC B.6 (flight.cpp step_bird's blend): Q = ((1-a) Qa + a Qb) / |...|.
Q4 blend(const Q4 q[3], const Q4& target, const V weights[3], V alpha) {
    Q4 sum{hn::Mul(alpha, target.x), hn::Mul(alpha, target.y), hn::Mul(alpha, target.z), hn::Mul(alpha, target.w)};
    for (int m = 0; m < 3; ++m) {
        const V sign = hn::IfThenElse(hn::Lt(quat_dot(q[m], target), Z()), S(-1.0f), S(1.0f));
        const V w = hn::Mul(hn::Mul(hn::Sub(S(1.0f), alpha), weights[m]), sign);
        sum = {hn::Add(sum.x, hn::Mul(w, q[m].x)), hn::Add(sum.y, hn::Mul(w, q[m].y)), hn::Add(sum.z, hn::Mul(w, q[m].z)),
               hn::Add(sum.w, hn::Mul(w, q[m].w))};
    }
    const V inv = hn::Div(S(1.0f), hn::Sqrt(quat_dot(sum, sum)));
    const Q4 n{hn::Mul(sum.x, inv), hn::Mul(sum.y, inv), hn::Mul(sum.z, inv), hn::Mul(sum.w, inv)};
    return select(hn::Ge(alpha, S(1.0f)), target, n);
}

V pick(V mode, V level, V ascend, V descend) {
    return hn::IfThenElse(hn::Eq(mode, S(KW_MODE_LEVEL)), level, hn::IfThenElse(hn::Eq(mode, S(KW_MODE_ASCEND)), ascend, descend));
}

// Writes quaternion-sized parts of the lanes' birds: `parts` of 4 vectors each, lane l's
// part p to dst(l) + 4 p floats.
template <typename Dst>
void store_parts(const Q4* parts, std::size_t count, std::size_t lanes, Dst dst) {
    HWY_ALIGN float rows[8][4 * kBatchLanes];
    for (std::size_t p = 0; p < count; ++p) hn::StoreInterleaved4(parts[p].x, parts[p].y, parts[p].z, parts[p].w, D(), rows[p]);
    for (std::size_t l = 0; l < lanes; ++l) {
        float* out = dst(l);
        for (std::size_t p = 0; p < count; ++p) std::memcpy(out + 4 * p, rows[p] + 4 * l, 4 * sizeof(float));
    }
}

// The lanes [off, off + Lanes) of a batch through every frame of the call (step_bird).
void simulate_lanes(const BirdStepArgs& a, const BirdBatch& batch, std::size_t off) {
    const gpu::FlightUniforms& u = a.uniforms;
    const gpu::RouteHeader& route = a.routes[batch.route];
    float* rows = a.storage + (&batch - a.batches) * kBirdRows * kBatchLanes;
    const Q4 offset = load4(rows, kBirdOffset, off);
    const Q4 motion = load4(rows, kBirdMotion, off);  // speed, frequency, amplitude, initial phase
    Q4 blend_state = load4(rows, kBirdBlend, off);
    V phase = load(rows, kBirdPhase, off);
    V mode_state = load(rows, kBirdMode, off);
    const V dt = S(u.physics.z);
    const std::size_t valid = std::min(hn::Lanes(D()), batch.count - off);
    const V level = S(KW_MODE_LEVEL), ascend = S(KW_MODE_ASCEND), descend = S(KW_MODE_DESCEND);
    auto one_hot = [&](V mode, V which) { return hn::IfThenElse(hn::Eq(mode, which), S(1.0f), Z()); };

    RouteCache cache;
    for (std::uint32_t k = 0; k < a.frames; ++k) {
        const std::uint32_t frame = a.first_frame + k;
        const M first = hn::Lt(mode_state, Z());  // KW_MODE_UNSET
        phase = hn::IfThenElse(first, motion.w, hn::Add(phase, hn::Mul(motion.y, dt)));
        phase = hn::Sub(phase, hn::Floor(phase));
        const V time = hn::Add(hn::Mul(S(static_cast<float>(frame)), dt), offset.w);
        const Sample sample = sample_route(a, route, time, motion.x, cache);

        // SPEC B.5, B.6: mode and transition.
        const V mode = next_mode(u, mode_state, sample);
        const M changed = hn::AndNot(first, hn::Ne(mode, mode_state));
        const M steady = hn::AndNot(hn::Or(first, changed), hn::Lt(blend_state.w, S(1.0f)));
        {
            const V alpha = blend_state.w, keep = hn::Sub(S(1.0f), alpha);
            const Q4 from{hn::Add(hn::Mul(keep, blend_state.x), hn::IfThenElseZero(hn::Eq(mode_state, level), alpha)),
                          hn::Add(hn::Mul(keep, blend_state.y), hn::IfThenElseZero(hn::Eq(mode_state, ascend), alpha)),
                          hn::Add(hn::Mul(keep, blend_state.z), hn::IfThenElseZero(hn::Eq(mode_state, descend), alpha)), Z()};
            const V rate = pick(mode, S(u.blend_rates.x), S(u.blend_rates.y), S(u.blend_rates.z));
            const V advanced = hn::Add(alpha, hn::Mul(rate, S(u.physics.w)));
            const Q4 settled{one_hot(mode, level), one_hot(mode, ascend), one_hot(mode, descend), S(1.0f)};
            Q4 next = blend_state;
            next.w = hn::IfThenElse(steady, advanced, next.w);
            next = select(hn::Or(first, hn::And(steady, hn::Ge(advanced, S(1.0f)))), settled, next);
            blend_state = select(changed, from, next);
        }
        mode_state = mode;

        // SPEC B.2: the wings at phase t; all three modes' poses only while some lane blends.
        V t = hn::Mul(phase, S(kTwoPi));
        t = hn::IfThenElse(hn::Ge(t, S(kTwoPi)), Z(), t);
        V sin_t, cos_t;
        sin_cos(t, sin_t, cos_t);
        const V alpha = blend_state.w;
        const Wings w[3] = {wing_angles(KW_MODE_LEVEL, t, sin_t, motion.z), wing_angles(KW_MODE_ASCEND, t, sin_t, motion.z),
                            wing_angles(KW_MODE_DESCEND, t, sin_t, motion.z)};
        const M is_descend = hn::Eq(mode, descend);
        const Wings target{pick(mode, w[0].arm1_pitch, w[1].arm1_pitch, w[2].arm1_pitch),
                           pick(mode, w[0].arm2_pitch, w[1].arm2_pitch, w[2].arm2_pitch),
                           pick(mode, w[0].arm1_heading, w[1].arm1_heading, w[2].arm1_heading),
                           pick(mode, w[0].arm2_heading, w[1].arm2_heading, w[2].arm2_heading)};
        Q4 left1 = arm_rotation(hn::IfThenElse(is_descend, target.arm1_heading, target.arm1_pitch), is_descend);
        Q4 left2 = arm_rotation(hn::IfThenElse(is_descend, target.arm2_heading, target.arm2_pitch), is_descend);
        if (!hn::AllFalse(D(), hn::Lt(alpha, S(1.0f)))) {
            const M no = hn::FirstN(D(), 0), yes = hn::Not(no);
            const Q4 arm1[3] = {arm_rotation(w[0].arm1_pitch, no), arm_rotation(w[1].arm1_pitch, no),
                                arm_rotation(w[2].arm1_heading, yes)};
            const Q4 arm2[3] = {arm_rotation(w[0].arm2_pitch, no), arm_rotation(w[1].arm2_pitch, no),
                                arm_rotation(w[2].arm2_heading, yes)};
            const V weights[3] = {blend_state.x, blend_state.y, blend_state.z};
            left1 = blend(arm1, left1, weights, alpha);
            left2 = blend(arm2, left2, weights, alpha);
        }

        // Body attitude (SPEC B.4).
        Q4 body;
        HWY_ALIGN float kinematics[6 * kBatchLanes];
        const bool seed_bank = u.rules.x == KW_BANK_SEED;
        if (seed_bank || a.diag != nullptr) {
            store3(sample.velocity, kinematics, 0, 0);
            store3(sample.acceleration, kinematics, 3, 0);
        }
        if (seed_bank) {
            HWY_ALIGN float rotation[4 * kBatchLanes];
            seed_body_rotation_lanes(u, kinematics, kBatchLanes, rotation, hn::Lanes(D()));
            body = load4(rotation, 0, 0);
        } else {
            body = body_rotation(u, sample.velocity, sample.acceleration);
        }

        // Outputs: BirdPose (right wing mirrored) or, without one, the moving parts' rows.
        const V3 position = add(sample.position, V3{offset.x, offset.y, offset.z});
        if (a.poses != nullptr) {
            const Q4 identity{Z(), Z(), Z(), S(1.0f)};
            const Q4 parts[8] = {{position.x, position.y, position.z, Z()},
                                 body,
                                 identity,
                                 identity,
                                 left1,
                                 left2,
                                 {left1.x, hn::Neg(left1.y), hn::Neg(left1.z), left1.w},
                                 {left2.x, hn::Neg(left2.y), hn::Neg(left2.z), left2.w}};
            gpu::BirdPose* poses = a.poses + std::size_t{k} * a.birds;
            store_parts(parts, 8, valid, [&](std::size_t l) { return &poses[batch.bird[off + l]].position.x; });
        } else {
            store4({position.x, position.y, position.z, Z()}, rows, kBirdPose, off);
            store4(body, rows, kBirdPose + 4, off);
            store4(left1, rows, kBirdPose + 8, off);
            store4(left2, rows, kBirdPose + 12, off);
        }
        if (a.diag != nullptr) {
            HWY_ALIGN float angles[3 * kBatchLanes];
            attitude_lanes(u, kinematics, kBatchLanes, angles, hn::Lanes(D()));
            const Q4 parts[4] = {{sample.velocity.x, sample.velocity.y, sample.velocity.z, alpha},
                                 {sample.acceleration.x, sample.acceleration.y, sample.acceleration.z, mode},
                                 {target.arm1_pitch, target.arm2_pitch, target.arm1_heading, target.arm2_heading},
                                 {load(angles, 0, 0), load(angles, 1, 0), load(angles, 2, 0), t}};
            gpu::BirdDiag* diag = a.diag + std::size_t{k} * a.birds;
            store_parts(parts, 4, valid, [&](std::size_t l) { return &diag[batch.bird[off + l]].velocity.x; });
        }
    }
    store4(blend_state, rows, kBirdBlend, off);
    store(phase, rows, kBirdPhase, off);
    store(mode_state, rows, kBirdMode, off);
}

void simulate_batches(const BirdStepArgs& args, std::size_t begin, std::size_t end) {
    for (std::size_t b = begin; b < end; ++b) {
        for (std::size_t off = 0; off < args.batches[b].count; off += hn::Lanes(D())) simulate_lanes(args, args.batches[b], off);
    }
}

}  // namespace

BirdKernels bird_kernels() { return {&simulate_batches}; }

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "simd/dispatch.hpp"

namespace kodawari::simd {

BirdKernels bird_kernels(std::int64_t target) { KW_SIMD_SELECT(target, bird_kernels) }

}  // namespace kodawari::simd
#endif
