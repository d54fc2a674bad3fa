// The scalar reference of the rods physics (SPEC A.4, A.5). Single precision throughout,
// as the GPU path will be.
#include "kodawari/rods/solver.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstddef>

#include "rods/solver_internal.hpp"

namespace kodawari::rods {
namespace {

using detail::collide_all;
using detail::positive_w;
using detail::SubstepColliders;

constexpr glm::quat kIdentity{1.0f, 0.0f, 0.0f, 0.0f};

// Steps of the rotation extraction per group and projection iteration, always taken (no
// early exit, so the result is a smooth function of the input and the GPU, which runs
// it unrolled, computes the same thing). Warm-started from the group's rotation of the
// previous iteration, as Mueller et al. 2016 recommend, the extraction gets
// `iterations` steps per substep and more over the following substeps; the solver
// tests measured no difference between 1, 2 and 3 steps (stretch, settling, shape
// holding, suppression), and each step costs about a third of the projection.
constexpr int kExtractIterations = 1;

// The kinematic root's weight in shape matching, in multiples of its mass. In PBD the
// root has infinite mass; with an infinite weight its two groups would be clamped rigid
// to the root's frame, with its plain mass the chain's overall direction is held only
// through the root's small ellipsoid term (a straight strand bent by sideways gravity then
// recovered ~85% of the way in 4 s). Ten times makes the root dominate its own group, so
// the strand leaves the root along its rest direction like a hair from its follicle,
// while every weight stays finite and A well conditioned.
constexpr float kRootShapeWeight = 10.0f;

// The rotation by `fraction` of `q`'s angle about its axis, the short way. The angle is
// 2 atan2(|xyz|, w), well conditioned everywhere; glm::slerp's acos of a dot product
// near 1 loses half the digits of small angles, and the GPU's acos differs from the
// CPU's there by far more than rounding (shaders/rods_step.comp uses the same formula).
glm::quat partial(glm::quat q, float fraction) {
    if (fraction >= 1.0f) return q;
    if (fraction <= 0.0f) return kIdentity;
    q = positive_w(q);
    const glm::vec3 v(q.x, q.y, q.z);
    const float sn = glm::length(v);
    if (!(sn > 0.0f)) return kIdentity;
    const float half = fraction * std::atan2(sn, q.w);
    const glm::vec3 axis = v / sn;
    return glm::normalize(glm::quat(std::cos(half), std::sin(half) * axis.x, std::sin(half) * axis.y, std::sin(half) * axis.z));
}

// Spherical interpolation from a to b (t in [0, 1]) by partial(): a (a^-1 b)^t.
glm::quat interpolate(glm::quat a, glm::quat b, float t) {
    return glm::normalize(a * partial(glm::conjugate(a) * b, t));
}

// Rotational part of A by the iterative method of Mueller, Bender, Chentanez, Macklin,
// "A Robust Method to Extract the Rotational Part of Deformations" (MIG 2016), Algorithm
// 1, warm-started from `q`. It turns q by the torque-like vector
// omega = sum_i r_i x a_i / |sum_i r_i . a_i| (r_i, a_i the columns of R(q) and A),
// kExtractIterations times; it stays a rotation and never fails, even for a singular A.
// The turn exp(omega) is taken in its first-order form normalize(q + (omega, 0) q / 2):
// about the same axis by 2 atan(|omega| / 2) instead of |omega|, so the same fixed point
// (omega = 0) and never further than the exact step, without the sine and cosine that
// dominated the GPU kernel's cost.
glm::quat extract_rotation(const glm::mat3& a, glm::quat q) {
    for (int iter = 0; iter < kExtractIterations; ++iter) {
        const glm::mat3 r = glm::mat3_cast(q);
        const glm::vec3 torque = glm::cross(r[0], a[0]) + glm::cross(r[1], a[1]) + glm::cross(r[2], a[2]);
        const float alignment = std::abs(glm::dot(r[0], a[0]) + glm::dot(r[1], a[1]) + glm::dot(r[2], a[2]));
        const glm::vec3 half_omega = torque * (0.5f / (alignment + 1e-9f));
        q = glm::normalize(q + glm::quat(0.0f, half_omega.x, half_omega.y, half_omega.z) * q);
    }
    return q;
}

// A.5 momentum suppression: the change of rest shape since the last step, applied
// kinematically. Each segment of the current chain is turned by `suppression` of the
// turn that takes its old rest direction to its new one (both placed by the current
// root), walking out from the root; each orientation likewise by the change of its rest
// orientation. A chain resting on the old shape so lands exactly on the new one, segment
// lengths are kept, and velocities are left alone, so the switch injects no momentum.
void suppress_momentum(const Chain& chain, const ChainShape& rest, float suppression, ChainState& s) {
    if (suppression <= 0.0f) return;
    const std::uint32_t n = chain.joint_count;
    const glm::quat root = s.root.rotation;
    const glm::quat root_inv = glm::conjugate(root);
    glm::vec3 previous_old = s.x[0];
    for (std::uint32_t i = 0; i + 1 < n; ++i) {
        const glm::vec3 old_dir = glm::normalize(s.rest_position[i + 1] - s.rest_position[i]);
        const glm::vec3 new_dir = glm::normalize(rest.positions[i + 1] - rest.positions[i]);
        const glm::quat turn = partial(root * shortest_arc(old_dir, new_dir) * root_inv, suppression);
        const glm::vec3 segment = s.x[i + 1] - previous_old;
        previous_old = s.x[i + 1];
        s.x[i + 1] = s.x[i] + turn * segment;
    }
    for (std::uint32_t i = 1; i < n; ++i) {
        const glm::quat change = positive_w(rest.orientations[i] * glm::conjugate(s.rest_orientation[i]));
        s.q[i] = glm::normalize(partial(root * change * root_inv, suppression) * s.q[i]);
    }
}

}  // namespace

std::uint32_t settle(const Chain& chain, const SolverParams& params, const Transform& root, const ChainShape& rest,
                     std::span<const Collider> colliders, ChainState& s, const glm::vec3& air) {
    // First quasi-static: every velocity set to 0 after each substep, so the particles
    // slide down their potential and never overshoot, until no particle moves by the
    // tolerance in a substep. Then
    // kSettleDynamicSubsteps as step() runs, because step()'s rest state is not still:
    // the follow-the-leader velocity correction leaves velocities along the segments that
    // the next sweep takes back (kFollowTheLeaderDamping), and a chain released from the
    // quasi-static state alone drifted at up to 0.12 m/s (scenes/ahoge.json) towards the
    // state with them.
    //
    // The quasi-static substeps are kSettleSubstep long: the stiffnesses are compliances
    // (substep_stiffness), so the equilibrium, where a substep's fall g h^2 is what the
    // projection takes back, (d + g h^2)(1 - k_h) = d, is d = g / K whatever h; a long h
    // takes a larger share k_h of the remaining distance each substep (0.8 against 0.1
    // for the default rest_stiffness), reaching it in a tenth of the substeps.
    SolverParams coarse = params;
    coarse.max_substep = std::max(params.max_substep, kSettleSubstep);
    // The tolerance grows with the distance from the origin, where a float's spacing
    // (and so a substep's rounding noise) grows: 1e-6 m at the origin is 4e-5 m 40 m away
    // (scenes/crowd.json), about 8 float spacings there.
    const float tolerance = kSettleTolerance * (1.0f + glm::length(root.position));
    std::uint32_t taken = 0;
    for (std::uint32_t k = 0; k < kMaxSettleSubsteps; ++k) {
        const std::array<glm::vec3, kMaxChainJoints> before = s.x;
        step(chain, coarse, root, rest, colliders, coarse.max_substep, s, air);
        ++taken;
        float moved = 0.0f;
        for (std::uint32_t i = 0; i < chain.joint_count; ++i) {
            moved = std::max(moved, glm::length(s.x[i] - before[i]));
            s.v[i] = glm::vec3(0.0f);
            s.omega[i] = glm::vec3(0.0f);
        }
        if (moved < tolerance) break;
    }
    for (std::uint32_t k = 0; k < kSettleDynamicSubsteps; ++k) {
        step(chain, params, root, rest, colliders, params.max_substep, s, air);
        ++taken;
    }
    s.started = false;  // settling is not the chain's first step
    return taken;
}

float substep_stiffness(float k, float h) {
    // k per kReferenceSubstep is a compliance: K = k / ((1 - k) h_ref^2) (1/s^2), and a
    // substep h covers k_h = K h^2 / (1 + K h^2) = r k / ((1 - k) + r k), r = (h / h_ref)^2,
    // the XPBD step of one constraint (Macklin, Mueller, Chentanez, "XPBD: Position-Based
    // Simulation of Compliant Constrained Dynamics", MIG 2016, eq. 18 with alpha~ = 1/(K h^2)
    // and lambda reset every substep). Under a constant acceleration g a particle held by it
    // then rests where k_h s = (1 - k_h) g h^2, s = g / K, whatever h: the sag no longer
    // depends on the substep. k = 1 stays 1 (rigid), k = 0 stays 0.
    if (!(k > 0.0f)) return 0.0f;
    if (!(k < 1.0f)) return 1.0f;
    const float r = (h / kReferenceSubstep) * (h / kReferenceSubstep);
    return (r * k) / ((1.0f - k) + r * k);
}

float iteration_stiffness(float k_substep, std::uint32_t iterations) {
    // (1 - k')^iterations = 1 - k_substep: `iterations` moves compound to k_substep.
    return 1.0f - std::pow(1.0f - k_substep, 1.0f / static_cast<float>(iterations));
}

void step(const Chain& chain, const SolverParams& params, const Transform& root, const ChainShape& rest,
          std::span<const Collider> colliders, float dt, ChainState& s, const glm::vec3& air) {
    assert(validate(params).ok());
    assert(dt > 0.0f && std::isfinite(dt));
    const std::uint32_t n = chain.joint_count;
    assert(n >= 2 && n <= kMaxChainJoints);
    assert(rest.positions.size() == n && rest.orientations.size() == n);
    // A cut or a respawn moves the root farther than any motion would in a frame: the
    // chain is carried across the gap with it rather than dragged (SolverParams).
    follow_teleport(params, root, dt, s);
    if (!s.started && params.settle_start) start_moving(root, dt, s);
    s.started = true;

    const std::uint32_t substeps = std::max(1u, static_cast<std::uint32_t>(std::ceil(dt / params.max_substep)));
    const float h = dt / static_cast<float>(substeps);
    // The stiffnesses are fractions per kReferenceSubstep, converted to this substep as
    // compliances (substep_stiffness()) and then to one iteration (iteration_stiffness()).
    const float k_iter = iteration_stiffness(substep_stiffness(params.stiffness, h), params.iterations);
    const float k_rest = iteration_stiffness(substep_stiffness(params.rest_stiffness, h), params.iterations);
    const float decay = std::exp(-params.damping * h);
    const glm::vec3 acceleration = params.gravity + params.wind;
    const bool drag = params.normal_drag > 0.0f || params.tangent_drag > 0.0f;
    const float normal_decay = std::exp(-params.normal_drag * h);
    const float tangent_decay = std::exp(-params.tangent_drag * h);

    // A.5, once per frame: the rest shape changes at frame boundaries only.
    suppress_momentum(chain, rest, params.momentum_suppression, s);
    for (std::uint32_t i = 0; i < n; ++i) {
        s.rest_position[i] = rest.positions[i];
        s.rest_orientation[i] = rest.orientations[i];
    }

    // The frame is solved relative to the previous root position (s.x already is): the
    // root moves by `travel`. Far from the world origin, world coordinates would round to
    // ~1e-6 m at 10 m, as coarse as the solver's own corrections on a small strand.
    const Transform from = s.root;
    const glm::vec3 travel = root.position - from.position;
    // The colliders are given at the end of the frame; within it they move with the
    // interpolated root, as the rest shape does: held in the end root's frame here, placed
    // by each substep's root below. A collider left at its end pose would sit up to a
    // frame's travel ahead of the root in the early substeps and shove the strand.
    std::array<glm::vec3, kMaxChainColliders> collider_a{}, collider_b{};
    SubstepColliders placed;
    assert(colliders.size() <= kMaxChainColliders);
    placed.count = colliders.size();
    const glm::quat to_root = glm::conjugate(root.rotation);
    for (std::size_t k = 0; k < colliders.size(); ++k) {
        collider_a[k] = to_root * (colliders[k].a - root.position);
        collider_b[k] = colliders[k].kind == ColliderKind::Plane ? to_root * colliders[k].b
                                                                  : to_root * (colliders[k].b - root.position);
        placed.reach[k] = collider_reach(colliders[k], chain.thickness);
        placed.kind[k] = colliders[k].kind;
    }
    std::array<glm::vec3, kMaxChainJoints> p{}, xbar{}, goal_sum{}, obar_axis{};
    const float b2 = chain.thickness * chain.thickness;
    std::array<glm::quat, kMaxChainJoints> qs{}, obar{}, q_new{};
    std::array<glm::mat3, kMaxChainJoints> ellipsoid{};
    auto weight = [&](std::uint32_t j) { return j == 0 ? kRootShapeWeight * chain.mass[0] : chain.mass[j]; };
    // Angle limits (set_limits(); VRMC_springBone_limit 1.0 draft): the parent bone's turn
    // from its rest, carried down each sweep (the draft's parent.worldRotation: a bone
    // turns by the shortest arc from its carried rest direction to its child, as VRM's
    // spring joints do), so that a limit's frame is its rest frame turned with its parent.
    glm::quat swing(1.0f, 0.0f, 0.0f, 0.0f);
    for (std::uint32_t sub = 1; sub <= substeps; ++sub) {
        const float t = static_cast<float>(sub) / static_cast<float>(substeps);
        const Transform r{t * travel, interpolate(from.rotation, root.rotation, t)};

        // 1-2. Kinematic root and the rest shape placed by the root (SPEC A.4).
        for (std::uint32_t i = 0; i < n; ++i) {
            xbar[i] = r.position + r.rotation * rest.positions[i];
            obar[i] = glm::normalize(r.rotation * rest.orientations[i]);
            obar_axis[i] = obar[i] * chain.bone_axis[i];  // Rbar_i u_i
        }
        p[0] = xbar[0];
        qs[0] = obar[0];
        // 3. The colliders placed by the root (a plane's normal turned by it).
        for (std::size_t k = 0; k < placed.count; ++k) {
            placed.a[k] = r.position + r.rotation * collider_a[k];
            placed.b[k] = placed.kind[k] == ColliderKind::Plane ? r.rotation * collider_b[k]
                                                                : r.position + r.rotation * collider_b[k];
        }
        // The distance constraints' corrections of each particle this substep (DFTL below).
        std::array<glm::vec3, kMaxChainJoints> pulled{};
        // And what the colliders moved each particle (its net push, contact normal below).
        std::array<glm::vec3, kMaxChainJoints> pushed{};
        auto collide_counted = [&](std::uint32_t j) {
            const glm::vec3 before = p[j];
            collide_all(p[j], placed);
            pushed[j] += p[j] - before;
        };
        // Child i + 1 turned about particle i, at the same distance, to the nearest
        // direction joint i's limit allows in its frame (limits.hpp), then the swing
        // carried past it.
        auto limit_child = [&](std::uint32_t i) {
            const glm::vec3 d = p[i + 1] - p[i];
            const float len = glm::length(d);
            if (!(len > 1e-9f)) return;
            glm::vec3 dir = d / len;
            if (chain.limit[i].kind != LimitKind::None) {
                const glm::quat frame = (swing * obar[i]) * chain.limit_frame[i];
                const glm::vec3 local = glm::conjugate(frame) * dir;
                const glm::vec3 allowed = limit_direction(chain.limit[i].kind, chain.limit_trig[i], local);
                if (allowed != local) {
                    dir = frame * allowed;
                    p[i + 1] = p[i] + len * dir;
                }
            }
            swing = glm::normalize(shortest_arc(swing * obar_axis[i], dir) * swing);
        };
        // Child i + 1 placed on its parent's segment length, follow-the-leader, its
        // correction kept for DFTL (no direction to correct along when it sits on it).
        auto place_on_parent = [&](std::uint32_t i) {
            const glm::vec3 d = p[i + 1] - p[i];
            const float len = glm::length(d);
            if (!(len > 1e-9f)) return;
            const glm::vec3 placed_child = p[i] + (chain.segment_length[i] / len) * d;
            pulled[i + 1] += placed_child - p[i + 1];
            p[i + 1] = placed_child;
        };

        // 4. Predict: damping, then the external acceleration (damping the velocity the
        // substep starts with, not the acceleration's share: a held particle then rests at
        // g / K of its attraction whatever h and damping are, where damping after
        // gravity scaled the sag by exp(-damping h)), explicit position update, and the
        // orientation update of SPEC A.4, q* = [w^ sin(|w| h/2), cos(|w| h/2)] q (Mueller &
        // Chentanez 2011, sec. 3), in its first-order form q* = normalize(q + h/2 [w, 0] q)
        // (Mueller et al., "Detailed Rigid Body Simulation with Extended Position Based
        // Dynamics", 2020, eq. 8). The two differ by O((|w| h)^3) and the first-order one
        // turns by 2 atan(|w| h / 2), never more than |w| h; without sine and cosine it is
        // several times cheaper on the GPU, whose transcendentals dominated the frame.
        // Damping and drag act on the velocity relative to the air (rods::WindField): in
        // calm air (air = 0) this is decay * v exactly. Drag splits it across and along the
        // particle's segment, from its parent at the substep's start (a thin cylinder's
        // cross-flow drag, Hoerner, "Fluid-Dynamic Drag", 1965, ch. 3), each part decaying
        // at its own rate, exactly integrated like the damping.
        for (std::uint32_t i = 1; i < n; ++i) {
            glm::vec3 relative = decay * (s.v[i] - air);
            if (drag) {
                const glm::vec3 segment = s.x[i] - s.x[i - 1];
                const float length = glm::length(segment);
                if (length > 1e-9f) {
                    const glm::vec3 axis = segment / length;
                    const glm::vec3 along = glm::dot(relative, axis) * axis;
                    relative = normal_decay * (relative - along) + tangent_decay * along;
                }
            }
            s.v[i] = air + relative + h * acceleration;
            s.omega[i] = decay * s.omega[i];
            p[i] = s.x[i] + h * s.v[i];
            const glm::vec3 half_turn = (0.5f * h) * s.omega[i];
            qs[i] = glm::normalize(s.q[i] + glm::quat(0.0f, half_turn.x, half_turn.y, half_turn.z) * s.q[i]);
        }

        // 5. Project.
        for (std::uint32_t it = 0; it < params.iterations; ++it) {
            // Shape matching, Jacobi over the groups G_i = {i-1, i, i+1}: every particle
            // moves toward the mean of its goals, so the result does not depend on the
            // order of the groups.
            // A_j = (m_j/5) R_j diag(a^2, b^2, c^2) Rbar_j^T (Mueller & Chentanez 2011, eq. 11)
            // with b = c = thickness and a along the bone axis u_j: diag = b^2 I +
            // (a^2 - b^2) u u^T in the particle frame, so A_j = (m_j/5)(b^2 R_j Rbar_j^T +
            // (a^2 - b^2)(R_j u)(Rbar_j u)^T). Once per particle: each is in three groups.
            // R_j Rbar_j^T is the matrix of q_j obar_j^-1, cheaper as a quaternion product.
            for (std::uint32_t j = 0; j < n; ++j) {
                const float a2 = chain.half_length[j] * chain.half_length[j];
                const glm::mat3 relative = glm::mat3_cast(qs[j] * glm::conjugate(obar[j]));
                ellipsoid[j] = (weight(j) / 5.0f) *
                               (b2 * relative + (a2 - b2) * glm::outerProduct(qs[j] * chain.bone_axis[j], obar_axis[j]));
                goal_sum[j] = glm::vec3(0.0f);
            }
            for (std::uint32_t i = 0; i < n; ++i) {
                const std::uint32_t lo = i == 0 ? 0 : i - 1;
                const std::uint32_t hi = std::min(i + 1, n - 1);
                float group_mass = 0.0f;
                glm::vec3 c(0.0f), cbar(0.0f);
                for (std::uint32_t j = lo; j <= hi; ++j) {
                    group_mass += weight(j);
                    c += weight(j) * p[j];
                    cbar += weight(j) * xbar[j];
                }
                c /= group_mass;
                cbar /= group_mass;
                // A = sum_j (m_j p_j xbar_j^T + A_j) - M c cbar^T (Mueller & Chentanez 2011,
                // eq. 9), summed in the centred form sum_j m_j (p_j - c)(xbar_j - cbar)^T,
                // equal but free of the cancellation of world coordinates in float.
                glm::mat3 a(0.0f);
                for (std::uint32_t j = lo; j <= hi; ++j) {
                    a += weight(j) * glm::outerProduct(p[j] - c, xbar[j] - cbar);
                    a += ellipsoid[j];
                }
                // Warm start: the centre's orientation is R obar_i after every iteration,
                // so q_i obar_i^-1 is the group's last rotation (turned on by the
                // prediction at a new substep), with no state of its own.
                const glm::quat rot = extract_rotation(a, qs[i] * glm::conjugate(obar[i]));
                for (std::uint32_t j = lo; j <= hi; ++j) goal_sum[j] += c + rot * (xbar[j] - cbar);  // g_j = c + R (xbar_j - cbar)
                q_new[i] = glm::normalize(rot * obar[i]);  // the centre's orientation: R obar_i
            }
            for (std::uint32_t i = 1; i < n; ++i) {
                // Groups containing particle i: 2 at either end, 3 inside.
                const float goal_count = i + 1 == n ? 2.0f : 3.0f;
                p[i] += k_iter * (goal_sum[i] / goal_count - p[i]);
                qs[i] = q_new[i];
            }

            // Rest-pose attraction: every particle moves k_rest' of the way to its rest
            // position placed by the root (the global shape constraint of Han & Harada,
            // "Real-Time Hair Simulation with Efficient Hair Style Preservation", VRIPHYS
            // 2012). The overlapping groups above cannot hold a bend (solver.hpp); this
            // does, and as a projection towards a fixed target it never adds energy.
            for (std::uint32_t i = 1; i < n; ++i) p[i] += k_rest * (xbar[i] - p[i]);

            // Distance constraints (SPEC A.4), one sweep from the root outward in which
            // each child takes the whole correction: the parent counts as kinematic with
            // respect to its child, as the root (inverse mass 0) does for joint 1. This is
            // the follow-the-leader order of Mueller, Kim, Chentanez, "Fast Simulation of
            // Inextensible Hair and Fur" (VRIPHYS 2012): one sweep leaves every segment at
            // its length, where mass-weighted Gauss-Seidel needs many iterations on a long
            // chain and lets a violently shaken one stretch by several times its length.
            // Its corrections are not symmetric and would add energy; the velocity update
            // below takes it back (DFTL).
            // Collisions inside the sweep: each child is pushed out of the colliders right
            // after it is placed, so its own children are placed from where it ends.
            swing = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
            for (std::uint32_t i = 0; i + 1 < n; ++i) {
                place_on_parent(i);
                collide_counted(i + 1);
                if (chain.limited) limit_child(i);
            }
        }
        // A last sweep that leaves neither stretch nor penetration: each child is placed
        // on its parent's segment length, pushed out of the colliders, and the two
        // repeated (alternating projections onto the sphere of the segment's length and
        // the colliders' free space, which converge where they meet), ending with the
        // push. What is left is a stretch second order in what the last push moved
        // (measured: at most 0.11% of a segment on a strand draped over a shaking head);
        // ending with a placement instead handed a parent's push back into the collider
        // (1.6 mm into a capsule, and 5 mm out of an inside sphere, tests/rods).
        // The limits last (the draft applies them after the colliders).
        swing = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
        for (std::uint32_t i = 0; i + 1 < n; ++i) {
            place_on_parent(i);
            if (placed.count > 0) {
                collide_counted(i + 1);
                place_on_parent(i);
                collide_counted(i + 1);
                place_on_parent(i);
                collide_counted(i + 1);
            }
            if (chain.limited) limit_child(i);
        }

        // Dynamic follow-the-leader (Mueller et al. 2012, sec. 4, eq. 9): particle i's
        // velocity gives back s_damping of its child's distance corrections d_{i+1} this
        // substep, v_i = (p_i - x_i) / h - s_damping d_{i+1} / h, the pull the child
        // would have exerted on it; without it each sweep hands the parent's motion to
        // the child for free (a slack chain fell with 3.4x its potential energy).
        // What the colliders undid is not the parent's to give back: a child placed into a
        // collider's forbidden side (a strand longer than the inside sphere it hangs in,
        // one draped over a skull) is pushed back out by it, so the part of its distance
        // corrections that went against the colliders' push (along their net push
        // direction, and only into them) was absorbed by the collider, as a contact's
        // reaction is. Returned to the parent, it kicked the parent back every substep and
        // a chain pressed into an inside sphere shook: 17 mm/frame^2 RMS of second
        // differences against 1.0 without DFTL (tests/backends, collider kinds; 1.1 now).
        for (std::uint32_t i = 1; i < n; ++i) {
            const float pl = glm::length(pushed[i]);
            if (pl > 0.0f) {
                const glm::vec3 nn = pushed[i] / pl;
                const float along = glm::dot(pulled[i], nn);
                if (along < 0.0f) pulled[i] -= std::max(along, -pl) * nn;
            }
        }
        for (std::uint32_t i = 0; i < n; ++i) {
            s.v[i] = (p[i] - s.x[i]) / h;
            if (i > 0 && i + 1 < n) s.v[i] -= (kFollowTheLeaderDamping / h) * pulled[i + 1];
            // omega from q* q^-1 taken the short way, first-order as the prediction (Mueller
            // et al. 2020, eq. 9): w = 2 [dq.x, dq.y, dq.z] / h.
            const glm::quat dq = positive_w(qs[i] * glm::conjugate(s.q[i]));
            s.omega[i] = (2.0f / h) * glm::vec3(dq.x, dq.y, dq.z);
            s.x[i] = p[i];
            s.q[i] = qs[i];
        }
    }
    for (std::uint32_t i = 0; i < n; ++i) s.x[i] -= travel;
    s.root = root;
}

ChainPose pose(const Chain& chain, const ChainState& s) {
    const std::uint32_t n = chain.joint_count;
    ChainPose out;
    std::array<glm::quat, kMaxChainJoints> bone{};
    for (std::uint32_t i = 0; i < n; ++i) {
        out.position[i] = position(s, i);
        out.orientation[i] = s.q[i];
        bone[i] = s.q[i];
        if (i + 1 < n) {
            const glm::vec3 d = s.x[i + 1] - s.x[i];
            const float len = glm::length(d);
            if (len > 1e-9f) {
                const glm::vec3 axis = glm::normalize(s.q[i] * chain.bone_axis[i]);
                bone[i] = glm::normalize(shortest_arc(axis, d / len) * s.q[i]);
            }
        }
        const glm::quat parent = i == 0 ? s.root.rotation : bone[i - 1];
        out.local_rotation[i] = glm::normalize(glm::conjugate(parent) * bone[i]);
    }
    return out;
}

glm::vec3 position(const ChainState& s, std::uint32_t joint) { return s.root.position + s.x[joint]; }

float kinetic_energy(const Chain& chain, const ChainState& s) {
    float e = 0.0f;
    for (std::uint32_t i = 1; i < chain.joint_count; ++i) e += 0.5f * chain.mass[i] * glm::dot(s.v[i], s.v[i]);
    return e;
}

}  // namespace kodawari::rods
