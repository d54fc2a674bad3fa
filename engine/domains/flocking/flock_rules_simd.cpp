// The cpu backend's rules for every instruction set (flock_rules.hpp): flock_rules() of
// shaders/lib/flock_body.glsl for a vector of birds, line for line; each step below names
// the body's line it mirrors. A branch of the body is a mask here, every side computed and
// the lanes that take it selected, so the operations a lane's result goes through are the
// body's, in its order.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "domains/flocking/flock_rules_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/cache_control.h>
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>

#include "domains/flocking/flock_rules.hpp"
#include "simd/vecmath-inl.h"

HWY_BEFORE_NAMESPACE();
namespace kodawari::flocking {
namespace HWY_NAMESPACE {
namespace {

// simd/vecmath-inl.h: glm's operations for lanes, operation for operation (dot, length,
// cross, select, add, sub, mul, div; min, max and clamp as glm's comparisons).
using simd::HWY_NAMESPACE::D;
using simd::HWY_NAMESPACE::M;
using simd::HWY_NAMESPACE::V;
using simd::HWY_NAMESPACE::V3;
namespace hn = hwy::HWY_NAMESPACE;
namespace vm = simd::HWY_NAMESPACE;

// The body's vec3 arithmetic written as it is there.
V3 splat(const D d, float x, float y, float z) { return {hn::Set(d, x), hn::Set(d, y), hn::Set(d, z)}; }
V3 operator+(const V3& a, const V3& b) { return vm::add(a, b); }
V3 operator-(const V3& a, const V3& b) { return vm::sub(a, b); }
V3 operator*(V s, const V3& a) { return vm::mul(s, a); }
V3 operator/(const V3& a, V s) { return vm::div(a, s); }
using vm::cross;
using vm::dot;
using vm::length;
using vm::select;

// The body's flock_facing() and flock_round(), lane by lane.
V3 facing_of(const V3& forward, const V3& axis, V small) {
    const V3 flat_forward = forward - dot(forward, axis) * axis;
    const V fl = length(flat_forward);
    return select(hn::Gt(fl, small), flat_forward / fl, forward);
}
V3 round_of(const D d, const V3& across, const V3& facing, const V3& up, V small) {
    const V cl = length(across);
    const V3 side = cross(facing, up);
    const V sl = length(side);
    return select(hn::Gt(cl, small), across / cl, select(hn::Gt(sl, small), side / sl, splat(d, 1.0f, 0.0f, 0.0f)));
}

constexpr std::size_t kMaxLanes = HWY_MAX_BYTES / sizeof(float);

// A vector of birds' inputs, lane by lane (lanes past the call's birds repeat its last).
struct Lanes {
    HWY_ALIGN float px[kMaxLanes], py[kMaxLanes], pz[kMaxLanes], vx[kMaxLanes], vy[kMaxLanes], vz[kMaxLanes];
    HWY_ALIGN float v0[kMaxLanes], smin[kMaxLanes], smax[kMaxLanes], dv[kMaxLanes];
    HWY_ALIGN float lateral[kMaxLanes], climb[kMaxLanes], dive[kMaxLanes];
    HWY_ALIGN float offx[kMaxLanes], offy[kMaxLanes], offz[kMaxLanes];
    HWY_ALIGN float radius[kMaxLanes], rsep[kMaxLanes], rroute[kMaxLanes], rcol[kMaxLanes], ahead[kMaxLanes];
    HWY_ALIGN float wsep[kMaxLanes], walign[kMaxLanes], wcoh[kMaxLanes], wroute[kMaxLanes];
    HWY_ALIGN float clear[kMaxLanes], ground[kMaxLanes], tau[kMaxLanes], front[kMaxLanes];
    HWY_ALIGN float tx[kMaxLanes], ty[kMaxLanes], tz[kMaxLanes];
    HWY_ALIGN float found[kMaxLanes];
    // Neighbour n of each lane: its position and velocity, distance^2 from the search.
    HWY_ALIGN float ox[KW_FLOCK_MAX_NEIGHBOURS][kMaxLanes], oy[KW_FLOCK_MAX_NEIGHBOURS][kMaxLanes],
        oz[KW_FLOCK_MAX_NEIGHBOURS][kMaxLanes];
    HWY_ALIGN float wx[KW_FLOCK_MAX_NEIGHBOURS][kMaxLanes], wy[KW_FLOCK_MAX_NEIGHBOURS][kMaxLanes],
        wz[KW_FLOCK_MAX_NEIGHBOURS][kMaxLanes];
    HWY_ALIGN float nd2[KW_FLOCK_MAX_NEIGHBOURS][kMaxLanes];
    HWY_ALIGN float scratch[kMaxLanes];
};

void rules(const RulesArgs& args, std::uint32_t first_slot, std::uint32_t count, const glsl::Kernel::FlockNeighbours* found_in,
           glsl::Kernel::FlockStep* out) {
    const D d;
    const std::size_t lanes = hn::Lanes(d);
    const glsl::Kernel& kernel = *args.kernel;
    const SortedBirds& sorted = *args.sorted;
    const V zero = hn::Zero(d), one = hn::Set(d, 1.0f), tiny = hn::Set(d, 1e-6f), small = hn::Set(d, 1e-3f);
    const V dt = hn::Set(d, args.dt);
    Lanes in;
    for (std::uint32_t b0 = 0; b0 < count; b0 += static_cast<std::uint32_t>(lanes)) {
        const std::size_t live = std::min<std::size_t>(lanes, count - b0);
        std::uint32_t most = 0;  // the most neighbours a lane has: the slots filled below
        for (std::size_t m = b0; m < b0 + live; ++m) most = std::max(most, found_in[m].found);
        // The next vector's birds' constants, read by index (scattered in the grid's order:
        // a cache miss each, nearly a fifth of the rules' time before): fetched now, ready
        // when their turn comes.
        for (std::size_t m = b0 + lanes; m < std::min<std::size_t>(count, b0 + 2 * lanes); ++m) {
            const gpu::FlockBirdGpu* next = &kernel.birds_in[sorted.index[first_slot + m]];
            hwy::Prefetch(next);
            hwy::Prefetch(reinterpret_cast<const char*>(next) + sizeof *next - 1);
            // And its neighbours' slots (by index: a miss each at a million birds).
            for (std::uint32_t n = 0; n < found_in[m].found; ++n) hwy::Prefetch(&sorted.slot_of[found_in[m].j[n]]);
        }
        // The flock's parameters: set once where every lane's bird is of one flock (a
        // scene's flocks rarely share a cell), per lane otherwise.
        const std::uint32_t flock0 = kernel.birds_in[sorted.index[first_slot + b0]].ids.x;
        bool one_flock = true;
        for (std::size_t l = 1; l < live; ++l) one_flock = one_flock && kernel.birds_in[sorted.index[first_slot + b0 + l]].ids.x == flock0;
        for (std::size_t l = 0; l < lanes; ++l) {
            const std::size_t m = b0 + std::min(l, live - 1);
            const std::size_t slot = first_slot + m;
            const gpu::FlockBirdGpu& bird = kernel.birds_in[sorted.index[slot]];
            // The bird's state and its neighbours' from the grid's copy (kw_state's
            // values): in the grid's order, neighbours are near in memory too.
            in.px[l] = sorted.x[slot], in.py[l] = sorted.y[slot], in.pz[l] = sorted.z[slot];
            in.vx[l] = sorted.vx[slot], in.vy[l] = sorted.vy[slot], in.vz[l] = sorted.vz[slot];
            in.v0[l] = bird.speed.x, in.smin[l] = bird.speed.y, in.smax[l] = bird.speed.z, in.dv[l] = bird.speed.w;
            in.lateral[l] = bird.turn.x, in.climb[l] = bird.turn.y, in.dive[l] = bird.turn.z;
            in.offx[l] = bird.offset.x, in.offy[l] = bird.offset.y, in.offz[l] = bird.offset.z;
            if (!one_flock) {
                const gpu::FlockParamsGpu& flock = kernel.flocks[bird.ids.x];
                in.radius[l] = flock.radii.x, in.rsep[l] = flock.radii.y, in.rroute[l] = flock.radii.w;
                in.wsep[l] = flock.weights.x, in.walign[l] = flock.weights.y, in.wcoh[l] = flock.weights.z, in.wroute[l] = flock.weights.w;
                in.clear[l] = flock.ground.x, in.ground[l] = flock.ground.y, in.tau[l] = flock.ground.z, in.front[l] = flock.ground.w;
                in.tx[l] = flock.target.x, in.ty[l] = flock.target.y, in.tz[l] = flock.target.z;
                in.rcol[l] = flock.collision.x, in.ahead[l] = flock.collision.y;
            }
            const glsl::Kernel::FlockNeighbours& nb = found_in[m];
            in.found[l] = static_cast<float>(nb.found);
            for (std::uint32_t n = 0; n < nb.found; ++n) {
                const std::uint32_t o = sorted.slot_of[nb.j[n]];
                in.ox[n][l] = sorted.x[o], in.oy[n][l] = sorted.y[o], in.oz[n][l] = sorted.z[o];
                in.wx[n][l] = sorted.vx[o], in.wy[n][l] = sorted.vy[o], in.wz[n][l] = sorted.vz[o];
                in.nd2[n][l] = nb.d2[n];
            }
            // Slots past the lane's neighbours: itself, at rest (masked off below; finite).
            for (std::uint32_t n = nb.found; n < most; ++n) {
                in.ox[n][l] = in.px[l], in.oy[n][l] = in.py[l], in.oz[n][l] = in.pz[l];
                in.wx[n][l] = 0.0f, in.wy[n][l] = 0.0f, in.wz[n][l] = 0.0f;
                in.nd2[n][l] = 0.0f;
            }
        }
        const gpu::FlockParamsGpu& flock0_params = kernel.flocks[flock0];
        // A flock parameter: flock0's in every lane, or each lane's own.
        const auto param = [&](float shared, const float* each) { return one_flock ? hn::Set(d, shared) : hn::Load(d, each); };
        const V f_radius = param(flock0_params.radii.x, in.radius);
        const V f_rsep = param(flock0_params.radii.y, in.rsep);
        const V f_rroute = param(flock0_params.radii.w, in.rroute);
        const V f_wsep = param(flock0_params.weights.x, in.wsep);
        const V f_walign = param(flock0_params.weights.y, in.walign);
        const V f_wcoh = param(flock0_params.weights.z, in.wcoh);
        const V f_wroute = param(flock0_params.weights.w, in.wroute);
        const V f_clear = param(flock0_params.ground.x, in.clear);
        const V f_ground = param(flock0_params.ground.y, in.ground);
        const V f_tau = param(flock0_params.ground.z, in.tau);
        const V f_front = param(flock0_params.ground.w, in.front);
        const V f_tx = param(flock0_params.target.x, in.tx);
        const V f_ty = param(flock0_params.target.y, in.ty);
        const V f_tz = param(flock0_params.target.z, in.tz);
        const V f_rcol = param(flock0_params.collision.x, in.rcol);
        const V f_ahead = param(flock0_params.collision.y, in.ahead);
        const V3 p{hn::Load(d, in.px), hn::Load(d, in.py), hn::Load(d, in.pz)};
        const V3 v{hn::Load(d, in.vx), hn::Load(d, in.vy), hn::Load(d, in.vz)};
        // speed = length(v); forward = flock_forward(v).
        const V speed = length(v);
        const V3 forward = select(hn::Gt(speed, tiny), v / speed, splat(d, 0.0f, 0.0f, 1.0f));
        const V radius = f_radius;
        const V found = hn::Load(d, in.found);

        // Reynolds' rules over the neighbours, nearest first.
        V3 separation{zero, zero, zero}, heading{zero, zero, zero}, centre{zero, zero, zero}, collide{zero, zero, zero};
        const V r_sep = f_rsep, front = f_front;
        const V r_col = f_rcol, lookahead = f_ahead, lateral_most = hn::Load(d, in.lateral);
        for (std::uint32_t n = 0; n < most; ++n) {
            const M live_n = hn::Lt(hn::Set(d, static_cast<float>(n)), found);
            const V3 other{hn::Load(d, in.ox[n]), hn::Load(d, in.oy[n]), hn::Load(d, in.oz[n])};
            const V3 dn = other - p;
            const V dist = hn::Sqrt(hn::Load(d, in.nd2[n]));
            const M apart = hn::Gt(dist, tiny);
            // along_axis = dist > 1e-6 ? dot(d, forward) / dist : 0
            const V along_axis = hn::IfThenElse(apart, hn::Div(dot(dn, forward), dist), zero);
            // r_here = r_sep * (1 + front along_axis along_axis)
            const V r_here = hn::Mul(r_sep, hn::Add(one, hn::Mul(hn::Mul(front, along_axis), along_axis)));
            const V over = hn::Div(vm::glm_max(hn::Sub(dist, r_here), zero), r_here);
            // g = exp(-(over over)): libm's, lane by lane, as the body's std::exp.
            hn::Store(hn::Neg(hn::Mul(over, over)), d, in.scratch);
            for (std::size_t l = 0; l < lanes; ++l) in.scratch[l] = std::exp(in.scratch[l]);
            const V g = hn::Load(d, in.scratch);
            separation = select(hn::And(live_n, apart), separation + hn::Div(g, dist) * dn, separation);
            const V3 w{hn::Load(d, in.wx[n]), hn::Load(d, in.wy[n]), hn::Load(d, in.wz[n])};
            const V ws = length(w);
            heading = select(hn::And(live_n, hn::Gt(ws, tiny)), heading + w / ws, heading);
            centre = select(live_n, centre + dn, centre);
            // Collision avoidance, predicted: t* = rel2 > 0 ? clamp(-dot(d, rel) / rel2, 0,
            // lookahead) : 0; d* = d + t* rel; within r_col, turn.x (|d*| / r_col - 1) along
            // d* / |d*| (or d / dist, or nothing).
            const V3 rel = w - v;
            const V rel2 = dot(rel, rel);
            const V t_near = hn::IfThenElse(hn::Gt(rel2, zero), vm::glm_clamp(hn::Div(hn::Neg(dot(dn, rel)), rel2), zero, lookahead), zero);
            const V3 near_d = dn + t_near * rel;
            const V near_dist = length(near_d);
            const V3 from = select(hn::Gt(near_dist, tiny), near_d / near_dist, select(apart, dn / dist, V3{zero, zero, zero}));
            collide = select(hn::And(live_n, hn::Lt(near_dist, r_col)),
                             collide + hn::Mul(lateral_most, hn::Sub(hn::Div(near_dist, r_col), one)) * from, collide);
        }

        // Agents, in one pass (the same for every lane: their kinds are branches here).
        V3 fled{zero, zero, zero}, avoid{zero, zero, zero};
        V panic = zero;
        for (std::uint32_t a = 0; a < args.agents; ++a) {
            const gpu::FlockAgentGpu agent = kernel.kw_agent(a);
            const float kind = agent.kind_weight.x;
            const V weight = hn::Set(d, agent.kind_weight.y);
            if (kind == KW_FLOCK_AGENT_PLANE) {
                const V3 normal = splat(d, agent.velocity.x, agent.velocity.y, agent.velocity.z);
                const V margin = vm::glm_max(hn::Set(d, agent.kind_weight.z), small);
                const V depth = hn::Sub(margin, dot(p - splat(d, agent.position.x, agent.position.y, agent.position.z), normal));
                const M inside = hn::Gt(depth, zero);
                if (hn::AllFalse(d, inside)) continue;  // no bird of the vector within its margin
                // Flying into it: steered across the flight and the plane's upright (the
                // body's rule and fallbacks); the upright is the same in every lane.
                const glm::vec3 n(agent.velocity.x, agent.velocity.y, agent.velocity.z);
                const glm::vec3 upright = glm::vec3(0.0f, 1.0f, 0.0f) - n.y * n;
                const float ul = glm::length(upright);
                const glm::vec3 axis = upright / ul;
                const V3 facing = ul > 1e-3f ? facing_of(forward, splat(d, axis.x, axis.y, axis.z), small) : forward;
                const V3 round = round_of(d, normal - dot(normal, facing) * facing, facing, splat(d, 0.0f, 1.0f, 0.0f), small);
                const V s = hn::Mul(weight, vm::glm_min(hn::Div(depth, margin), one));
                const V toward = dot(forward, normal);
                const M into = hn::Lt(toward, zero);
                const V3 away = select(into, round, normal);
                const V brake = hn::IfThenElse(into, hn::Mul(s, toward), zero);
                avoid = select(inside, avoid + (s * away + brake * forward), avoid);
                continue;
            }
            V3 at = splat(d, agent.position.x, agent.position.y, agent.position.z);
            V3 facing = forward;
            V3 up = splat(d, 0.0f, 1.0f, 0.0f);
            if (kind == KW_FLOCK_AGENT_CAPSULE) {
                const V3 ab = splat(d, agent.velocity.x, agent.velocity.y, agent.velocity.z) - at;
                const V ab2 = dot(ab, ab);  // the same in every lane
                const M has_axis = hn::Gt(ab2, zero);
                const V t = hn::IfThenElse(has_axis, vm::glm_clamp(hn::Div(dot(p - at, ab), ab2), zero, one), zero);
                at = at + t * ab;
                const V3 axis_up = ab / hn::Sqrt(ab2);
                facing = select(has_axis, facing_of(forward, axis_up, small), facing);
                up = select(has_axis, axis_up, up);
            }
            const V3 dp = p - at;
            const V dist = length(dp);
            const V reach = hn::Set(d, agent.position.w);
            const M near = hn::Not(hn::Lt(dist, tiny));  // `if (dist < 1e-6) continue;`
            if (kind == KW_FLOCK_AGENT_SPHERE || kind == KW_FLOCK_AGENT_CAPSULE) {
                const V margin = vm::glm_max(hn::Set(d, agent.kind_weight.z), small);
                const V depth = hn::Sub(hn::Add(reach, margin), dist);
                const M within = hn::And(near, hn::Gt(depth, zero));
                if (hn::AllFalse(d, within)) continue;  // no bird of the vector within its margin
                const V s = hn::Mul(weight, vm::glm_min(hn::Div(depth, margin), one));
                const V along = dot(dp, facing);
                const V3 round = round_of(d, dp - along * facing, facing, up, small);
                const V3 away = select(hn::And(hn::Lt(along, zero), hn::Gt(dist, reach)), round, dp / dist);
                avoid = select(within, avoid + s * away, avoid);
            } else {
                const M inside = hn::And(near, hn::Lt(dist, reach));
                const V closeness = hn::Sub(one, hn::Div(dist, reach));
                const V s = hn::Mul(weight, closeness);
                if (kind == KW_FLOCK_AGENT_REPELLER) {
                    if (agent.kind_weight.y > 0.0f) panic = hn::IfThenElse(inside, vm::glm_max(panic, closeness), panic);
                    // The predator's side, the same in every lane: its path's crossing with the vertical.
                    const glm::vec3 u(agent.velocity.x, agent.velocity.y, agent.velocity.z);
                    const glm::vec3 side = glm::cross(u, glm::vec3(0.0f, 1.0f, 0.0f));
                    const float sl = glm::length(side);
                    V3 away;
                    if (sl > 1e-3f) {
                        const V3 side_v = splat(d, side.x, side.y, side.z);
                        const V scale = hn::IfThenElse(hn::Ge(dot(dp, side_v), zero), hn::Set(d, 1.0f / sl), hn::Set(d, -1.0f / sl));
                        away = scale * side_v;
                    } else {
                        const V3 flat_d{dp.x, zero, dp.z};
                        const V fl = length(flat_d);
                        away = select(hn::Gt(fl, small), flat_d / fl, splat(d, 1.0f, 0.0f, 0.0f));
                    }
                    fled = select(inside, fled + s * away, fled);
                } else {
                    fled = select(inside, fled - hn::Div(s, dist) * dp, fled);
                }
            }
        }
        avoid = avoid + collide;
        const V calm = hn::Sub(one, panic);
        V3 acc{zero, zero, zero};
        {
            const M any = hn::Gt(found, zero);
            const V inv_n = hn::Div(one, found);
            V3 with = acc + hn::Mul(hn::Neg(f_wsep), inv_n) * separation;
            const V hl = length(heading);
            with = select(hn::Gt(hl, tiny), with + f_walign * (heading / hl - forward), with);
            with = with + hn::Div(hn::Mul(hn::Mul(calm, f_wcoh), inv_n), radius) * centre;
            acc = select(any, with, acc);
        }
        // The route: to the leader's place plus the bird's formation offset.
        const V3 to_target =
            (V3{f_tx, f_ty, f_tz} + V3{hn::Load(d, in.offx), hn::Load(d, in.offy), hn::Load(d, in.offz)}) - p;
        acc = acc + hn::Div(hn::Mul(calm, f_wroute), vm::glm_max(length(to_target), f_rroute)) * to_target;
        // Cruise speed.
        acc = acc + hn::Div(hn::Sub(hn::Load(d, in.v0), speed), f_tau) * forward;
        // The ground.
        const V clear = f_clear;
        acc.y = hn::IfThenElse(hn::Lt(p.y, clear), hn::Add(acc.y, hn::Div(hn::Mul(f_ground, hn::Sub(clear, p.y)), clear)),
                               acc.y);
        acc = acc + fled;

        // What the wing allows.
        const V dv = hn::Load(d, in.dv);
        const V a_ahead = dot(acc, forward);
        // Without obstacles to avoid:
        const V along_plain = vm::glm_clamp(a_ahead, hn::Neg(dv), dv);
        V3 lateral_plain = acc - a_ahead * forward;
        const V ll = length(lateral_plain);
        lateral_plain = select(hn::Gt(ll, lateral_most), hn::Div(lateral_most, ll) * lateral_plain, lateral_plain);
        // With them: the avoidance's lateral part first (Reynolds' prioritized allocation).
        const V3 total = acc + avoid;
        const V along_avoid = vm::glm_clamp(dot(total, forward), hn::Neg(dv), dv);
        V3 first = avoid - dot(avoid, forward) * forward;
        const V fl = length(first);
        first = select(hn::Gt(fl, lateral_most), hn::Div(lateral_most, fl) * first, first);
        V3 rest = acc - a_ahead * forward;
        const V budget = hn::Sub(lateral_most, vm::glm_min(fl, lateral_most));
        const V rl = length(rest);
        rest = select(hn::Gt(rl, budget), hn::Div(budget, rl) * rest, rest);
        const M plain = hn::Eq(dot(avoid, avoid), zero);
        const V along = hn::IfThenElse(plain, along_plain, along_avoid);
        const V3 lateral = select(plain, lateral_plain, first + rest);
        const V3 a = along * forward + lateral;

        // Semi-implicit Euler; speed within [min, max], climb and dive within the wing's.
        V3 v1 = v + dt * a;
        const V s1 = length(v1);
        const V s = vm::glm_clamp(s1, hn::Load(d, in.smin), hn::Load(d, in.smax));
        v1 = select(hn::Gt(s1, tiny), hn::Div(s, s1) * v1, s * forward);
        const V sin_pitch = hn::Div(v1.y, s);
        const V limited = vm::glm_clamp(sin_pitch, hn::Neg(hn::Load(d, in.dive)), hn::Load(d, in.climb));
        {
            const V3 h_raw{v1.x, zero, v1.z};
            const V hl = length(h_raw);
            const V3 h = select(hn::Gt(hl, tiny), h_raw / hl, splat(d, 1.0f, 0.0f, 0.0f));
            const V cos_pitch = hn::Sqrt(vm::glm_max(hn::Sub(one, hn::Mul(limited, limited)), zero));
            const V s_cos = hn::Mul(s, cos_pitch);
            const V3 pitched{hn::Mul(s_cos, h.x), hn::Mul(s, limited), hn::Mul(s_cos, h.z)};
            // The body's `limited != sin_pitch`, true for a NaN (0 / 0 at no speed): not
            // Highway's Ne, which is an ordered comparison (false for a NaN) on AVX2 and AVX-512.
            v1 = select(hn::Not(hn::Eq(limited, sin_pitch)), pitched, v1);
        }
        const V3 position = p + dt * v1;
        const V3 acceleration = (v1 - v) / dt;

        HWY_ALIGN float r[9][kMaxLanes];
        const V3* results[] = {&position, &v1, &acceleration};
        for (int q = 0; q < 3; ++q) {
            hn::Store(results[q]->x, d, r[3 * q]);
            hn::Store(results[q]->y, d, r[3 * q + 1]);
            hn::Store(results[q]->z, d, r[3 * q + 2]);
        }
        for (std::size_t l = 0; l < live; ++l) {
            glsl::Kernel::FlockStep& step = out[b0 + l];
            step.position = glm::vec3(r[0][l], r[1][l], r[2][l]);
            step.velocity = glm::vec3(r[3][l], r[4][l], r[5][l]);
            step.acceleration = glm::vec3(r[6][l], r[7][l], r[8][l]);
        }
    }
}

}  // namespace

RulesFn flock_rules_kernel() { return &rules; }

}  // namespace HWY_NAMESPACE
}  // namespace kodawari::flocking
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "simd/dispatch.hpp"

namespace kodawari::flocking {

RulesFn flock_rules_kernel(std::int64_t target) { KW_SIMD_SELECT(target, flock_rules_kernel) }

}  // namespace kodawari::flocking
#endif
