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

#include "kodawari/birds/flight.hpp"
#include "simd/birds_simd.hpp"
#include "simd/bird_route-inl.h"
#include "simd/scalar_math.hpp"
#include "simd/vecmath-inl.h"

HWY_BEFORE_NAMESPACE();
namespace kodawari::simd {
namespace HWY_NAMESPACE {
namespace {


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

// flight.cpp half_angle(): (cos(x/2), sin(x/2)) from (cos x, sin x), cos x >= 0.
HWY_INLINE void half_angle(V c, V s, V& half_c, V& half_s) {
    half_c = hn::Sqrt(hn::Mul(S(0.5f), hn::Add(S(1.0f), c)));
    half_s = hn::Div(s, hn::Mul(S(2.0f), half_c));
}

// flight.cpp body_frame() with the coordinated bank (the seed's rule is lane by lane).
struct BodyFrame {
    Q4 yaw, pitch, bank;
    M moving;
};
BodyFrame body_frame(const gpu::FlightUniforms& uniforms, const V3& v, const V3& a) {
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
    if (uniforms.rules.x != KW_BANK_SEED) {  // the seed's bank comes lane by lane (seed_bank_lanes)
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
    const M moving = hn::Gt(speed, Z());
    return {select(moving, yaw, identity), select(moving, pitch, identity), select(moving, bank, identity), moving};
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

// flight.cpp arm_rotation() for a mode whose wings only pitch (level, ascend: heading 0)
// or only sweep (descend: pitch 0): one turn, one sine and cosine instead of two.
Q4 arm_rotation_about(V angle, bool about_y) {
    V s, c;
    sin_cos(hn::Mul(S(0.5f), angle), s, c);
    return about_y ? Q4{Z(), s, Z(), c} : Q4{Z(), Z(), s, c};
}

// flight.cpp arm_rotation(): quat_z(pitch) quat_y(heading), expanded.
Q4 arm_rotation(V pitch, V heading) {
    V sp, cp, sh, ch;
    sin_cos(hn::Mul(S(0.5f), pitch), sp, cp);
    sin_cos(hn::Mul(S(0.5f), heading), sh, ch);
    return quat_mul(Q4{Z(), Z(), sp, cp}, Q4{Z(), sh, Z(), ch});
}

// flight.cpp flight_mode(): docs/flight-modes.md F.1, exact. Priority: the segment's own
// mode, then hover, then the flap-glide rhythm.
V flight_mode(const Q4& flight, V cruise, V previous, V glided, V beats, const Sample& r, V climb_mode) {
    const M rhythm = hn::And(hn::And(hn::Eq(climb_mode, S(KW_MODE_LEVEL)), hn::Gt(flight.y, Z())), hn::Le(r.direction.y, Z()));
    const M was_gliding = hn::Eq(previous, S(KW_MODE_GLIDE));
    const M glide = hn::Or(hn::And(was_gliding, hn::Lt(glided, flight.z)), hn::AndNot(was_gliding, hn::Ge(beats, flight.y)));
    V mode = hn::IfThenElse(hn::And(rhythm, glide), S(KW_MODE_GLIDE), climb_mode);
    mode = hn::IfThenElse(hn::And(hn::Gt(flight.w, Z()), hn::Lt(cruise, S(birds::kHoverBelowSpeed))), S(KW_MODE_HOVER), mode);
    return hn::IfThenElse(hn::Ge(r.segment_mode, Z()), r.segment_mode, mode);
}

// wingbeat.cpp mode_look(), one mode for all lanes (docs/flight-modes.md F.3, F.5).
struct Look {
    Wings wings;
    V pitch, spread, bob;
};
HWY_INLINE V smoothstep(float e0, float e1, V x) {
    const V u = hn::Min(hn::Max(hn::Div(hn::Sub(x, S(e0)), S(e1 - e0)), Z()), S(1.0f));
    return hn::Mul(hn::Mul(u, u), hn::Sub(S(3.0f), hn::Mul(S(2.0f), u)));
}
HWY_INLINE V mix(V a, V b, V w) { return hn::Add(a, hn::Mul(hn::Sub(b, a), w)); }
HWY_INLINE Wings mix(const Wings& a, const Wings& b, V w) {
    return {mix(a.arm1_pitch, b.arm1_pitch, w), mix(a.arm2_pitch, b.arm2_pitch, w), mix(a.arm1_heading, b.arm1_heading, w),
            mix(a.arm2_heading, b.arm2_heading, w)};
}
HWY_INLINE Wings splat(const birds::WingAngles& w) { return {S(w.arm1_pitch), S(w.arm2_pitch), S(w.arm1_heading), S(w.arm2_heading)}; }

Look mode_look(int mode, V t, V sin_t, V cos_t, V amplitude, const Sample& r) {
    Look l{{Z(), Z(), Z(), Z()}, Z(), Z(), Z()};
    switch (mode) {
        case KW_MODE_LEVEL:
        case KW_MODE_ASCEND:
        case KW_MODE_DESCEND:
            l.wings = wing_angles(mode, t, sin_t, amplitude);
            l.spread = S(mode == KW_MODE_LEVEL ? 0.15f : mode == KW_MODE_ASCEND ? 0.35f : 0.1f);
            l.bob = S(mode == KW_MODE_DESCEND ? 0.3f : 1.0f);
            break;
        case KW_MODE_GLIDE:
            l.wings = splat(birds::kGlideWings);
            l.spread = S(0.25f);
            break;
        case KW_MODE_TAKEOFF: {
            const V open = smoothstep(0.0f, birds::kLeapSeconds, r.since_crouch);
            const Wings level = wing_angles(KW_MODE_LEVEL, t, sin_t, amplitude);
            const Wings beats{hn::Mul(S(1.3f), level.arm1_pitch), hn::Mul(S(1.3f), level.arm2_pitch),
                              hn::Mul(hn::Mul(S(0.3f), amplitude), cos_t), Z()};
            l.wings = mix(splat(birds::kFoldedWings), beats, open);
            l.pitch = mix(S(-0.2f), hn::Mul(S(0.45f), hn::Sub(S(1.0f), r.speed_fraction)), open);
            l.spread = hn::Mul(S(0.8f), open);
            l.bob = open;
            break;
        }
        case KW_MODE_LANDING: {
            const V flare = smoothstep(0.4f, 1.0f, hn::Sub(S(1.0f), r.speed_fraction));
            const V fold = smoothstep(0.0f, birds::kFoldSeconds, r.since_touchdown);
            const Wings level = wing_angles(KW_MODE_LEVEL, t, sin_t, amplitude);
            const Wings beats{hn::Mul(S(0.6f), level.arm1_pitch), hn::Mul(S(0.6f), level.arm2_pitch),
                              hn::Add(S(-0.25f), hn::Mul(hn::Mul(S(0.25f), amplitude), cos_t)), Z()};
            l.wings = mix(mix(beats, splat(birds::kFlareWings), flare), splat(birds::kFoldedWings), fold);
            const V unfolded = hn::Sub(S(1.0f), fold);
            l.pitch = hn::Mul(hn::Mul(S(0.8f), flare), unfolded);
            l.spread = hn::Mul(hn::Add(S(0.3f), hn::Mul(S(0.6f), flare)), unfolded);
            l.bob = hn::Mul(hn::Sub(S(1.0f), flare), unfolded);
            break;
        }
        default: {  // hover: figure-eight strokes
            V sin_2t, cos_2t;
            sin_cos(hn::Add(t, t), sin_2t, cos_2t);
            l.wings = {hn::Mul(hn::Mul(S(0.2f), amplitude), sin_2t), hn::Mul(hn::Mul(S(-0.1f), amplitude), sin_t),
                       hn::Mul(hn::Mul(S(0.95f), amplitude), cos_t), Z()};
            l.pitch = S(0.6f);
            l.spread = S(0.5f);
            l.bob = S(0.5f);
            break;
        }
    }
    return l;
}

// wingbeat.cpp beat_factor(), exact.
V beat_factor(V mode, const Sample& r) {
    V k = S(1.0f);
    k = hn::IfThenElse(hn::Eq(mode, S(KW_MODE_GLIDE)), Z(), k);
    k = hn::IfThenElse(hn::Eq(mode, S(KW_MODE_TAKEOFF)), hn::IfThenElse(hn::Lt(r.since_crouch, Z()), Z(), S(1.25f)), k);
    k = hn::IfThenElse(hn::Eq(mode, S(KW_MODE_LANDING)), hn::IfThenElse(hn::Ge(r.since_touchdown, Z()), Z(), S(1.25f)), k);
    return k;
}

HWY_INLINE Q4 nlerp_turn(const Q4& q, float k) {  // flight.cpp nlerp_turn()
    const Q4 p{hn::Mul(S(k), q.x), hn::Mul(S(k), q.y), hn::Mul(S(k), q.z), hn::Add(S(1.0f - k), hn::Mul(S(k), q.w))};
    const V inv = hn::Div(S(1.0f), hn::Sqrt(quat_dot(p, p)));
    return {hn::Mul(p.x, inv), hn::Mul(p.y, inv), hn::Mul(p.z, inv), hn::Mul(p.w, inv)};
}
HWY_INLINE Q4 nose_up(V angle) {  // flight.cpp nose_up()
    V s, c;
    sin_cos(hn::Mul(S(0.5f), angle), s, c);
    return {hn::Neg(s), Z(), Z(), c};
}
HWY_INLINE Q4 conj4(const Q4& q) { return {hn::Neg(q.x), hn::Neg(q.y), hn::Neg(q.z), q.w}; }

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
    const Q4 flight = load4(rows, kBirdFlight, off);  // glide ratio, flap-glide beats and seconds, hover
    const V body_length = load(rows, kBirdShape, off);
    V weights[KW_MODE_COUNT];
    for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) weights[m] = load(rows, kBirdBlend + m, off);
    V alpha = load(rows, kBirdAlpha, off);
    V phase = load(rows, kBirdPhase, off);
    V glided = load(rows, kBirdGlided, off);
    V beats = load(rows, kBirdBeats, off);
    V mode_state = load(rows, kBirdMode, off);
    V roll_w = load(rows, kBirdRoll, off), roll_z = load(rows, kBirdRoll + 1, off), roll_lateral = load(rows, kBirdRoll + 2, off);
    const V roll_keep = S(u.bank_limit.z);  // the roll filter's e^(-dt/tau)
    const V dt = S(u.physics.z);
    const std::size_t valid = std::min(hn::Lanes(D()), batch.count - off);
    const float rates[KW_MODE_COUNT] = {u.blend_rates.x,  u.blend_rates.y,  u.blend_rates.z, u.blend_rates2.x,
                                        u.blend_rates2.y, u.blend_rates2.z, u.blend_rates2.w};

    RouteCache cache;
    // A driven batch flies its motion (flight.cpp motion_sample(), no offset added) or,
    // lane by lane, its route (KW_MOTION_ROUTE: route_motion_sample(), the offset added).
    const bool driven = a.params != nullptr && a.params[batch.bird[off]].ids.w == KW_BIRD_DRIVEN;
    std::array<std::uint32_t, kBatchLanes> slots{};
    if (driven) {
        for (std::size_t l = 0; l < hn::Lanes(D()); ++l) slots[l] = a.params[batch.bird[off + std::min(l, valid - 1)]].ids.z;
    }
    for (std::uint32_t k = 0; k < a.frames; ++k) {
        const std::uint32_t frame = a.first_frame + k;
        const V previous = mode_state;
        const M first = hn::Lt(previous, Z());  // KW_MODE_UNSET
        const V now = hn::Mul(S(static_cast<float>(frame)), dt);
        Sample sample;
        M flown = hn::FirstN(D(), 0);  // the lanes whose position is the motion's (no offset)
        if (driven) {
            const Motion m = gather_motion(a.motion + std::size_t{k} * a.driven, slots);
            sample = motion_sample(m);
            flown = hn::Not(m.on_route);
            // The route only where a lane flies it: a flock without perches pays one test.
            if (!hn::AllFalse(D(), m.on_route)) {
                // The flown lanes sample the route where the first lane on it does (their
                // motion's w and z are no time offset and speed): a valid point, and the
                // route cache is not lost to them.
                const std::size_t lead = static_cast<std::size_t>(hn::FindKnownFirstTrue(D(), m.on_route));
                const V lead_offset = hn::Set(D(), hn::ExtractLane(m.time_offset, lead));
                const V lead_speed = hn::Set(D(), hn::ExtractLane(m.acceleration.z, lead));
                const V time = hn::Add(now, hn::IfThenElse(m.on_route, m.time_offset, lead_offset));
                Sample routed = sample_route(a, route, time, hn::IfThenElse(m.on_route, m.acceleration.z, lead_speed), cache);
                route_correction(routed, m, now);
                sample = select(m.on_route, routed, sample);
            }
        } else {
            sample = sample_route(a, route, hn::Add(now, offset.w), motion.x, cache);
        }

        // Mode (SPEC B.5; docs/flight-modes.md F.1): the climb rule keeps its hysteresis
        // through a glide and decides afresh after the other modes.
        const V climb_previous = hn::IfThenElse(hn::Le(previous, S(KW_MODE_DESCEND)), previous,
                                                hn::IfThenElse(hn::Eq(previous, S(KW_MODE_GLIDE)), S(KW_MODE_LEVEL), S(-1.0f)));
        const V mode = flight_mode(flight, motion.x, previous, glided, beats, sample, next_mode(u, climb_previous, sample));

        // Transition (SPEC B.6) over the seven modes' weights.
        const M changed = hn::AndNot(first, hn::Ne(mode, previous));
        const M steady = hn::AndNot(hn::Or(first, changed), hn::Lt(alpha, S(1.0f)));
        V rate = Z();
        for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) rate = hn::IfThenElse(hn::Eq(mode, S(static_cast<float>(m))), S(rates[m]), rate);
        const V advanced = hn::Add(alpha, hn::Mul(rate, S(u.physics.w)));
        const M settle = hn::Or(first, hn::And(steady, hn::Ge(advanced, S(1.0f))));
        const V keep = hn::Sub(S(1.0f), alpha);
        for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) {
            const V which = S(static_cast<float>(m));
            const V from = hn::Add(hn::Mul(keep, weights[m]), hn::IfThenElseZero(hn::Eq(previous, which), alpha));
            const V settled = hn::IfThenElseZero(hn::Eq(mode, which), S(1.0f));
            weights[m] = hn::IfThenElse(changed, from, hn::IfThenElse(settle, settled, weights[m]));
        }
        alpha = hn::IfThenElse(changed, Z(), hn::IfThenElse(settle, S(1.0f), hn::IfThenElse(steady, advanced, alpha)));

        // Phase by the mode's beat factor; completed beats drive the flap-glide rhythm.
        phase = hn::IfThenElse(first, motion.w, hn::Add(phase, hn::Mul(hn::Mul(motion.y, dt), beat_factor(mode, sample))));
        const V whole = hn::Floor(phase);
        phase = hn::Sub(phase, whole);
        const M gliding = hn::Eq(mode, S(KW_MODE_GLIDE));
        glided = hn::IfThenElse(gliding, hn::Add(hn::IfThenElseZero(hn::Eq(previous, S(KW_MODE_GLIDE)), glided), dt), Z());
        beats = hn::IfThenElse(gliding, Z(), hn::IfThenElse(first, beats, hn::Add(beats, whole)));
        mode_state = mode;

        // The looks of the modes that take part (the target of some lane, or a weight in
        // some lane's blend source), and the SPEC B.6 blend of the wings.
        V t = hn::Mul(phase, S(kTwoPi));
        t = hn::IfThenElse(hn::Ge(t, S(kTwoPi)), Z(), t);
        V sin_t, cos_t;
        sin_cos(t, sin_t, cos_t);
        const M blending = hn::Lt(alpha, S(1.0f));
        const bool any_blending = !hn::AllFalse(D(), blending);
        Wings target{Z(), Z(), Z(), Z()};
        Q4 arm1[KW_MODE_COUNT], arm2[KW_MODE_COUNT];
        Look looks[KW_MODE_COUNT];
        bool used[KW_MODE_COUNT] = {};
        Q4 left1{Z(), Z(), Z(), S(1.0f)}, left2 = left1;
        V pitch = Z(), spread = Z(), bob = Z();
        for (int m = 0; m < static_cast<int>(KW_MODE_COUNT); ++m) {
            const M is_target = hn::Eq(mode, S(static_cast<float>(m)));
            const bool needed = !hn::AllFalse(D(), is_target) ||
                                (any_blending && !hn::AllFalse(D(), hn::And(blending, hn::Ne(weights[m], Z()))));
            if (!needed) continue;
            used[m] = true;
            looks[m] = mode_look(m, t, sin_t, cos_t, motion.z, sample);
            if (m == KW_MODE_LEVEL || m == KW_MODE_ASCEND || m == KW_MODE_DESCEND) {
                const bool sweep = m == KW_MODE_DESCEND;
                arm1[m] = arm_rotation_about(sweep ? looks[m].wings.arm1_heading : looks[m].wings.arm1_pitch, sweep);
                arm2[m] = arm_rotation_about(sweep ? looks[m].wings.arm2_heading : looks[m].wings.arm2_pitch, sweep);
            } else {
                arm1[m] = arm_rotation(looks[m].wings.arm1_pitch, looks[m].wings.arm1_heading);
                arm2[m] = arm_rotation(looks[m].wings.arm2_pitch, looks[m].wings.arm2_heading);
            }
            target = {hn::IfThenElse(is_target, looks[m].wings.arm1_pitch, target.arm1_pitch),
                      hn::IfThenElse(is_target, looks[m].wings.arm2_pitch, target.arm2_pitch),
                      hn::IfThenElse(is_target, looks[m].wings.arm1_heading, target.arm1_heading),
                      hn::IfThenElse(is_target, looks[m].wings.arm2_heading, target.arm2_heading)};
            left1 = select(is_target, arm1[m], left1);
            left2 = select(is_target, arm2[m], left2);
            const V w = hn::Add(hn::IfThenElseZero(is_target, alpha), hn::IfThenElseZero(blending, hn::Mul(hn::Sub(S(1.0f), alpha), weights[m])));
            pitch = hn::Add(pitch, hn::Mul(w, looks[m].pitch));
            spread = hn::Add(spread, hn::Mul(w, looks[m].spread));
            bob = hn::Add(bob, hn::Mul(w, looks[m].bob));
        }
        if (any_blending) {
            Q4 sum1{hn::Mul(alpha, left1.x), hn::Mul(alpha, left1.y), hn::Mul(alpha, left1.z), hn::Mul(alpha, left1.w)};
            Q4 sum2{hn::Mul(alpha, left2.x), hn::Mul(alpha, left2.y), hn::Mul(alpha, left2.z), hn::Mul(alpha, left2.w)};
            const V rest = hn::Sub(S(1.0f), alpha);
            for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) {
                if (!used[m]) continue;
                const V w = hn::Mul(rest, weights[m]);
                const V s1 = hn::IfThenElse(hn::Lt(quat_dot(arm1[m], left1), Z()), hn::Neg(w), w);
                const V s2 = hn::IfThenElse(hn::Lt(quat_dot(arm2[m], left2), Z()), hn::Neg(w), w);
                sum1 = {hn::Add(sum1.x, hn::Mul(s1, arm1[m].x)), hn::Add(sum1.y, hn::Mul(s1, arm1[m].y)),
                        hn::Add(sum1.z, hn::Mul(s1, arm1[m].z)), hn::Add(sum1.w, hn::Mul(s1, arm1[m].w))};
                sum2 = {hn::Add(sum2.x, hn::Mul(s2, arm2[m].x)), hn::Add(sum2.y, hn::Mul(s2, arm2[m].y)),
                        hn::Add(sum2.z, hn::Mul(s2, arm2[m].z)), hn::Add(sum2.w, hn::Mul(s2, arm2[m].w))};
            }
            const V inv1 = hn::Div(S(1.0f), hn::Sqrt(quat_dot(sum1, sum1)));
            const V inv2 = hn::Div(S(1.0f), hn::Sqrt(quat_dot(sum2, sum2)));
            left1 = select(blending, Q4{hn::Mul(sum1.x, inv1), hn::Mul(sum1.y, inv1), hn::Mul(sum1.z, inv1), hn::Mul(sum1.w, inv1)}, left1);
            left2 = select(blending, Q4{hn::Mul(sum2.x, inv2), hn::Mul(sum2.y, inv2), hn::Mul(sum2.z, inv2), hn::Mul(sum2.w, inv2)}, left2);
        }

        // Body attitude (SPEC B.4), the mode's extra pitch and the wingbeat's oscillation
        // and bob, head and tail (docs/flight-modes.md F.5; flight.cpp step_bird()).
        const V3 v = sample.attitude_velocity, acc = sample.acceleration;
        BodyFrame frame_parts = body_frame(u, v, acc);
        HWY_ALIGN float kinematics[6 * kBatchLanes];
        const bool seed_bank = u.rules.x == KW_BANK_SEED;
        if (seed_bank || a.diag != nullptr) {
            store3(v, kinematics, 0, 0);
            store3(acc, kinematics, 3, 0);
        }
        if (seed_bank) {
            HWY_ALIGN float bank[4 * kBatchLanes];
            seed_bank_lanes(u, kinematics, kBatchLanes, bank, hn::Lanes(D()));
            frame_parts.bank = load4(bank, 0, 0);
        }
        // The roll filter (flight.cpp step_bird(), docs/flight-modes.md F.6).
        const V horizontal = hn::Sqrt(hn::Add(hn::Mul(v.x, v.x), hn::Mul(v.z, v.z)));
        const V lateral = hn::IfThenElseZero(hn::Gt(horizontal, S(1e-3f)),
                                             hn::Div(hn::Add(hn::Mul(acc.x, hn::Neg(v.z)), hn::Mul(acc.z, v.x)), horizontal));
        const Q4 bank_target = frame_parts.bank;
        roll_w = hn::IfThenElse(first, bank_target.w, hn::Add(bank_target.w, hn::Mul(roll_keep, hn::Sub(roll_w, bank_target.w))));
        roll_z = hn::IfThenElse(first, bank_target.z, hn::Add(bank_target.z, hn::Mul(roll_keep, hn::Sub(roll_z, bank_target.z))));
        roll_lateral = hn::IfThenElse(first, lateral, hn::Add(lateral, hn::Mul(roll_keep, hn::Sub(roll_lateral, lateral))));
        const V roll_inv = hn::Div(S(1.0f), hn::Sqrt(hn::Add(hn::Mul(roll_w, roll_w), hn::Mul(roll_z, roll_z))));
        const Q4 identity{Z(), Z(), Z(), S(1.0f)};
        frame_parts.bank = select(frame_parts.moving, Q4{Z(), Z(), hn::Mul(roll_z, roll_inv), hn::Mul(roll_w, roll_inv)}, identity);
        const Q4 body_base =
            select(frame_parts.moving, quat_mul(quat_mul(frame_parts.yaw, frame_parts.pitch), frame_parts.bank), identity);
        const V oscillation = hn::Mul(hn::Mul(hn::Mul(S(birds::kBobPitch), motion.z), sin_t), bob);
        const V extra = hn::Add(pitch, oscillation);
        const Q4 body = quat_mul(body_base, nose_up(extra));
        const V bob_height = hn::Mul(hn::Mul(hn::Mul(hn::Mul(S(-birds::kBobHeight), body_length), motion.z), cos_t), bob);
        const V sin_bank = hn::Mul(hn::Mul(S(2.0f), frame_parts.bank.z), frame_parts.bank.w);
        V look = hn::Div(hn::Mul(S(-birds::kLookAhead), roll_lateral), horizontal);
        look = hn::Min(hn::Max(look, S(-birds::kMaxLook)), S(birds::kMaxLook));
        look = hn::IfThenElseZero(hn::Gt(horizontal, S(1e-3f)), look);
        V look_s, look_c;
        sin_cos(hn::Mul(S(0.5f), look), look_s, look_c);
        const Q4 head = quat_mul(
            quat_mul(quat_mul(nose_up(hn::Neg(hn::Add(hn::Mul(S(birds::kHeadPitchHold), pitch), hn::Mul(S(birds::kHeadBobHold), oscillation)))),
                              nlerp_turn(conj4(frame_parts.bank), birds::kHeadBankHold)),
                     nlerp_turn(conj4(frame_parts.pitch), birds::kHeadClimbHold)),
            Q4{Z(), look_s, Z(), look_c});
        const Q4 tail = quat_mul(quat_mul(nlerp_turn(frame_parts.pitch, birds::kTailClimb), nose_up(hn::Mul(S(birds::kTailPitch), pitch))),
                                 nlerp_turn(frame_parts.bank, birds::kTailBank));
        const V tail_spread = hn::Add(spread, hn::Mul(S(birds::kTailBankSpread), hn::Abs(sin_bank)));

        // Outputs: BirdPose (right wing mirrored) or, without one, the moving parts' rows.
        const V3 position = select(flown, sample.position, add(sample.position, V3{offset.x, offset.y, offset.z}));
        const Q4 placed{position.x, hn::Add(position.y, bob_height), position.z, tail_spread};
        if (a.poses != nullptr) {
            const Q4 parts[8] = {placed, body, head, tail, left1, left2,
                                 {left1.x, hn::Neg(left1.y), hn::Neg(left1.z), left1.w},
                                 {left2.x, hn::Neg(left2.y), hn::Neg(left2.z), left2.w}};
            gpu::BirdPose* poses = a.poses + std::size_t{k} * a.birds;
            store_parts(parts, 8, valid, [&](std::size_t l) { return &poses[batch.bird[off + l]].position.x; });
        } else {
            store4(placed, rows, kBirdPose, off);
            store4(body, rows, kBirdPose + 4, off);
            store4(head, rows, kBirdPose + 8, off);
            store4(tail, rows, kBirdPose + 12, off);
            store4(left1, rows, kBirdPose + 16, off);
            store4(left2, rows, kBirdPose + 20, off);
        }
        if (a.diag != nullptr) {
            HWY_ALIGN float angles[3 * kBatchLanes];
            attitude_lanes(u, kinematics, kBatchLanes, angles, hn::Lanes(D()));
            HWY_ALIGN float bank[2 * kBatchLanes];  // the Body's (filtered) bank, as the reference reports it
            hn::Store(frame_parts.bank.z, D(), bank);
            hn::Store(frame_parts.bank.w, D(), bank + kBatchLanes);
            half_angle_lanes(bank, bank + kBatchLanes, angles + 2 * kBatchLanes, hn::Lanes(D()));
            const Q4 parts[5] = {{sample.velocity.x, sample.velocity.y, sample.velocity.z, alpha},
                                 {acc.x, acc.y, acc.z, mode},
                                 {target.arm1_pitch, target.arm2_pitch, target.arm1_heading, target.arm2_heading},
                                 {load(angles, 0, 0), load(angles, 1, 0), load(angles, 2, 0), t},
                                 {sample.speed_fraction, extra, tail_spread, glided}};
            gpu::BirdDiag* diag = a.diag + std::size_t{k} * a.birds;
            store_parts(parts, 5, valid, [&](std::size_t l) { return &diag[batch.bird[off + l]].velocity.x; });
        }
    }
    for (std::uint32_t m = 0; m < KW_MODE_COUNT; ++m) store(weights[m], rows, kBirdBlend + m, off);
    store(alpha, rows, kBirdAlpha, off);
    store(phase, rows, kBirdPhase, off);
    store(glided, rows, kBirdGlided, off);
    store(beats, rows, kBirdBeats, off);
    store(mode_state, rows, kBirdMode, off);
    store(roll_w, rows, kBirdRoll, off);
    store(roll_z, rows, kBirdRoll + 1, off);
    store(roll_lateral, rows, kBirdRoll + 2, off);
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
