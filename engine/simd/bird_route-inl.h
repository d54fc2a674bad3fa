// The route sampling of the cpu bird kernel (simd/birds_simd.cpp) for one Highway target:
// engine/birds/flight.cpp sample_route() and what it calls (Bezier segments, the
// arc-length table, the take-off and landing timing of docs/flight-modes.md F.2), lane by
// lane in the reference's order of operations, with the route cache the kernel keeps from
// frame to frame. Included after foreach_target.h, once per target, like Highway's own
// -inl.h files.

#if defined(KODAWARI_SIMD_BIRD_ROUTE_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef KODAWARI_SIMD_BIRD_ROUTE_INL_H_
#undef KODAWARI_SIMD_BIRD_ROUTE_INL_H_
#else
#define KODAWARI_SIMD_BIRD_ROUTE_INL_H_
#endif

#include <hwy/highway.h>

#include "kodawari/birds/wingbeat.hpp"
#include "simd/birds_simd.hpp"
#include "simd/vecmath-inl.h"

HWY_BEFORE_NAMESPACE();
namespace kodawari::simd {
namespace HWY_NAMESPACE {

using DI = hn::RebindToSigned<D>;
using VI = hn::Vec<DI>;

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
    V segment_mode;  // the w of the segment's first control point (shared/birds.h)
    bool interval_valid = false;
    VI lo;          // the interval [lo, lo + 1] of the arc-length samples
    V ax, ay, aw, next, bx, by, bz;
};

// flight.cpp bezier_global() and bezier(): segment min(u, n - 1) of the route at u.
inline Bezier bezier(const BirdStepArgs& a, const gpu::RouteHeader& route, V u, RouteCache& cache) {
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
        cache.segment_mode = hn::GatherIndex(D(), points, hn::Add(first, hn::Set(di, 3)));
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
inline V route_parameter_at(const BirdStepArgs& a, const gpu::RouteHeader& route, V s, RouteCache& cache) {
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
    V3 position, velocity, acceleration, direction, attitude_velocity;
    V lift, lift_scale;
    V segment_mode, speed_fraction, since_crouch, since_touchdown;  // flight.hpp RouteSample
};

// The lanes' motions (slot per lane) gathered: a driven batch's input each frame.
struct Motion {
    V3 position, velocity, acceleration;  // as BirdMotionGpu's xyz
    M on_route;                           // position.w == KW_MOTION_ROUTE
    V time_offset;                        // velocity.w (on route)
};
inline Motion gather_motion(const gpu::BirdMotionGpu* motion, const std::array<std::uint32_t, kBatchLanes>& slots) {
    constexpr std::size_t kRows = 11;
    HWY_ALIGN float rows[kRows][kBatchLanes];
    for (std::size_t l = 0; l < hn::Lanes(D()); ++l) {
        const gpu::BirdMotionGpu& m = motion[slots[l]];
        const float values[kRows] = {m.position.x,     m.position.y,     m.position.z,     m.velocity.x,
                                     m.velocity.y,     m.velocity.z,     m.acceleration.x, m.acceleration.y,
                                     m.acceleration.z, m.position.w,     m.velocity.w};
        for (std::size_t r = 0; r < kRows; ++r) rows[r][l] = values[r];
    }
    Motion out;
    out.position = {hn::Load(D(), rows[0]), hn::Load(D(), rows[1]), hn::Load(D(), rows[2])};
    out.velocity = {hn::Load(D(), rows[3]), hn::Load(D(), rows[4]), hn::Load(D(), rows[5])};
    out.acceleration = {hn::Load(D(), rows[6]), hn::Load(D(), rows[7]), hn::Load(D(), rows[8])};
    out.on_route = hn::Eq(hn::Load(D(), rows[9]), S(static_cast<float>(KW_MOTION_ROUTE)));
    out.time_offset = hn::Load(D(), rows[10]);
    return out;
}

// flight.cpp motion_sample(): the lanes flown along their motion.
inline Sample motion_sample(const Motion& m) {
    Sample out;
    out.position = m.position;
    out.velocity = m.velocity;
    out.acceleration = m.acceleration;
    out.direction = out.velocity;
    out.attitude_velocity = out.velocity;
    out.lift = out.acceleration.y;
    out.lift_scale = S(1.0f);
    out.segment_mode = S(static_cast<float>(KW_SEGMENT_AUTO));
    out.speed_fraction = S(1.0f);
    out.since_crouch = S(1e9f);
    out.since_touchdown = S(-1.0f);
    return out;
}

// Lane by lane, a where m is true, else b.
inline Sample select(M m, const Sample& a, const Sample& b) {
    Sample out;
    out.position = select(m, a.position, b.position);
    out.velocity = select(m, a.velocity, b.velocity);
    out.acceleration = select(m, a.acceleration, b.acceleration);
    out.direction = select(m, a.direction, b.direction);
    out.attitude_velocity = select(m, a.attitude_velocity, b.attitude_velocity);
    out.lift = hn::IfThenElse(m, a.lift, b.lift);
    out.lift_scale = hn::IfThenElse(m, a.lift_scale, b.lift_scale);
    out.segment_mode = hn::IfThenElse(m, a.segment_mode, b.segment_mode);
    out.speed_fraction = hn::IfThenElse(m, a.speed_fraction, b.speed_fraction);
    out.since_crouch = hn::IfThenElse(m, a.since_crouch, b.since_crouch);
    out.since_touchdown = hn::IfThenElse(m, a.since_touchdown, b.since_touchdown);
    return out;
}

// flight.cpp route_motion_sample()'s correction (KW_MOTION_ROUTE, shared/birds.h): the
// cubic Hermite c(t) from (e_p, e_v) at t0 to 0 at t0 + T added to the route sample `r`
// at the frame's time `now`, in the reference's order of operations (the same bits), on
// the lanes that have one (1/T not 0, s < 1); the others keep the route's own bits.
inline void route_correction(Sample& r, const Motion& m, V now) {
    const V inv_t = m.acceleration.y;
    const V s = clamp01(hn::Mul(hn::Sub(now, m.acceleration.x), inv_t));
    const M apply = hn::AndNot(hn::Eq(inv_t, Z()), hn::Lt(s, S(1.0f)));
    if (hn::AllFalse(D(), apply)) return;
    const V span = hn::Div(S(1.0f), inv_t);
    const V h00 = hn::Add(hn::Mul(hn::Sub(hn::Mul(S(2.0f), s), S(3.0f)), hn::Mul(s, s)), S(1.0f));
    const V h10 = hn::Mul(hn::Add(hn::Mul(hn::Sub(s, S(2.0f)), s), S(1.0f)), s);
    const V d00 = hn::Mul(hn::Sub(hn::Mul(S(6.0f), s), S(6.0f)), s);
    const V d10 = hn::Add(hn::Mul(hn::Sub(hn::Mul(S(3.0f), s), S(4.0f)), s), S(1.0f));
    const V dd00 = hn::Sub(hn::Mul(S(12.0f), s), S(6.0f));
    const V dd10 = hn::Sub(hn::Mul(S(6.0f), s), S(4.0f));
    const V3 &ep = m.position, &ev = m.velocity;
    const V3 c = add(mul(h00, ep), mul(hn::Mul(span, h10), ev));
    const V3 c1 = add(mul(hn::Mul(d00, inv_t), ep), mul(d10, ev));
    const V3 c2 = add(mul(hn::Mul(hn::Mul(dd00, inv_t), inv_t), ep), mul(hn::Mul(dd10, inv_t), ev));
    r.position = select(apply, add(r.position, c), r.position);
    r.velocity = select(apply, add(r.velocity, c1), r.velocity);
    r.attitude_velocity = select(apply, add(r.attitude_velocity, c1), r.attitude_velocity);
    r.acceleration = select(apply, add(r.acceleration, c2), r.acceleration);
}

// flight.cpp sample_route(): both ends' cases and the inside computed, one chosen per lane.
inline Sample sample_route(const BirdStepArgs& a, const gpu::RouteHeader& route, V time, V speed, RouteCache& cache) {
    const bool loop = (route.flags.x & KW_ROUTE_LOOP) != 0;
    const V n = S(static_cast<float>(route.extent.y));
    Sample out;
    out.speed_fraction = S(1.0f);
    out.since_crouch = S(1e9f);
    out.since_touchdown = S(-1.0f);
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
        out.attitude_velocity = out.velocity;
        out.acceleration = select(outside, zero3(), mul(S(route.info.w * route.info.w), e.d2));
        out.direction = e.d1;
        out.lift = hn::IfThenElse(outside, Z(), e.d2.y);
        out.lift_scale = hn::IfThenElse(outside, S(1.0f), S(route.info.y * route.info.y));
        out.segment_mode = cache.segment_mode;
        return out;
    }
    const float total = route.info.x;
    const bool takeoff = (route.flags.x & KW_ROUTE_TAKEOFF) != 0, landing = (route.flags.x & KW_ROUTE_LANDING) != 0;
    V s, fraction = S(1.0f), along = Z();
    if (takeoff || landing) {  // docs/flight-modes.md F.2, flight.cpp's order of operations
        const V tau = takeoff ? hn::Sub(time, S(birds::kCrouchSeconds)) : time;
        const V d = hn::Mul(speed, tau);
        if (takeoff) out.since_crouch = tau;
        s = d;
        if (takeoff) {
            const M starting = hn::Lt(d, S(2.0f * route.perch.x));
            const M rest = hn::Lt(d, Z());
            const V k0 = S(0.25f * route.perch.y), k1 = S(0.5f * route.perch.y);
            const V accelerating = hn::Mul(hn::Mul(d, d), k0);
            s = hn::IfThenElse(starting, hn::IfThenElse(rest, Z(), accelerating), hn::Sub(d, S(route.perch.x)));
            fraction = hn::IfThenElse(starting, hn::IfThenElse(rest, Z(), hn::Mul(d, k1)), fraction);
            along = hn::IfThenElse(hn::AndNot(rest, starting), hn::Mul(hn::Mul(speed, speed), k1), along);
        }
        if (landing) {
            const float start = total - route.perch.z;
            const M in_landing = hn::Gt(s, S(start));
            const V dl = hn::Sub(s, S(start));
            const V two_ln = S(2.0f * route.perch.z);
            const M flying = hn::Lt(dl, two_ln);
            const V kn0 = S(0.25f * route.perch.w), kn1 = S(0.5f * route.perch.w);
            const V braking = hn::Sub(hn::Add(S(start), dl), hn::Mul(hn::Mul(dl, dl), kn0));
            s = hn::IfThenElse(in_landing, hn::IfThenElse(flying, braking, S(total)), s);
            fraction = hn::IfThenElse(in_landing, hn::IfThenElse(flying, hn::Sub(S(1.0f), hn::Mul(dl, kn1)), Z()), fraction);
            along = hn::IfThenElse(hn::And(in_landing, flying), hn::Neg(hn::Mul(hn::Mul(speed, speed), kn1)), along);
            out.since_touchdown =
                hn::IfThenElse(hn::AndNot(flying, in_landing), hn::Div(hn::Sub(dl, two_ln), speed), out.since_touchdown);
        }
    } else {
        s = hn::Mul(speed, time);
        if (loop) s = hn::Sub(s, hn::Mul(S(total), hn::Floor(hn::Mul(s, S(route.info.z)))));
    }
    out.speed_fraction = fraction;
    const V now = hn::Mul(fraction, speed);
    const M before = hn::Lt(s, Z());
    const M outside = hn::Or(before, hn::Gt(s, S(total)));
    const V clamped = hn::IfThenElse(before, Z(), hn::IfThenElse(hn::Gt(s, S(total)), S(total), s));
    const V u = hn::IfThenElse(outside, hn::IfThenElse(before, Z(), n), route_parameter_at(a, route, clamped, cache));
    const Bezier e = bezier(a, route, u, cache);
    out.segment_mode = cache.segment_mode;
    const V d1_len = length(e.d1);
    const V3 tangent = mul(hn::Div(S(1.0f), d1_len), e.d1);
    const V end_s = hn::IfThenElse(before, Z(), S(total));
    out.position = select(outside, add(e.p, mul(hn::Sub(s, end_s), tangent)), e.p);
    out.velocity = mul(hn::IfThenElse(outside, speed, now), tangent);
    out.attitude_velocity =
        select(outside, out.velocity, V3{hn::Mul(speed, tangent.x), hn::Mul(now, tangent.y), hn::Mul(speed, tangent.z)});
    const V3 normal = sub(e.d2, mul(dot(e.d2, tangent), tangent));
    V3 acceleration = mul(hn::Div(hn::Mul(now, now), hn::Mul(d1_len, d1_len)), normal);
    if (takeoff || landing) acceleration = select(hn::Eq(along, Z()), acceleration, add(acceleration, mul(along, tangent)));
    out.acceleration = select(outside, zero3(), acceleration);
    out.direction = e.d1;
    const V dd = dot(e.d1, e.d1), d2d1 = dot(e.d2, e.d1);
    out.lift = hn::IfThenElse(outside, Z(), hn::Mul(hn::Mul(now, now), hn::Sub(hn::Mul(e.d2.y, dd), hn::Mul(d2d1, e.d1.y))));
    out.lift_scale = hn::IfThenElse(outside, S(1.0f), hn::Mul(dd, dd));
    return out;
}

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::simd
HWY_AFTER_NAMESPACE();

#endif  // include guard toggle
