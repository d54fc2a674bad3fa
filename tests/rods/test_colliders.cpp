// VRM's collider model in the solver (issue 18): the three kinds of rods::Collider
// (outside, inside, plane; VRMC_springBone 1.0 and VRMC_springBone_extended_collider 1.0)
// and the center frame (rods::follow_center). Each is checked against distances computed
// here from the definitions, with a control run that shows the check can fail.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/rods/solver.hpp"

namespace kodawari::rods {
namespace {

// A straight strand of `joints` joints and `length` m hanging along -Y from its root.
ChainShape hanging(std::uint32_t joints, float length) {
    ChainShape s;
    for (std::uint32_t i = 0; i < joints; ++i) {
        s.positions.push_back(glm::vec3(0.0f, -length * static_cast<float>(i) / static_cast<float>(joints - 1), 0.0f));
        s.orientations.push_back(glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
    }
    return s;
}

struct Strand {
    Chain chain;
    ChainShape rest;
};

Strand strand(ChainShape rest, float thickness = 0.005f) {
    auto chain = make_chain(rest, thickness, 0.01f);
    EXPECT_TRUE(chain.ok()) << (chain.ok() ? "" : chain.error().message);
    return {chain.value(), std::move(rest)};
}

// The closest point of segment ab to p, written out again.
glm::vec3 closest(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
    const glm::vec3 ab = b - a;
    const float len2 = glm::dot(ab, ab);
    if (len2 == 0.0f) return a;
    return a + std::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f) * ab;
}

// Runs `frames` frames of 1/60 s of a strand whose root sweeps sideways, with `colliders`.
ChainState run(const Strand& s, const SolverParams& params, std::span<const Collider> colliders, int frames) {
    Transform root{glm::vec3(0.0f, 1.0f, 0.0f), glm::quat(1.0f, 0.0f, 0.0f, 0.0f)};
    ChainState state = initial_state(s.chain, root, s.rest);
    for (int f = 1; f <= frames; ++f) {
        root.position.x = 0.05f * std::sin(static_cast<float>(f) / 10.0f);
        step(s.chain, params, root, s.rest, colliders, 1.0f / 60.0f, state);
    }
    return state;
}

TEST(Colliders, GapMatchesHandComputedDistances) {
    const float t = 0.01f;
    // Outside sphere of radius 0.2 at the origin; a point 0.5 m away: 0.5 - 0.21.
    const Collider sphere{glm::vec3(0.0f), glm::vec3(0.0f), 0.2f, ColliderKind::Outside};
    EXPECT_NEAR(collider_gap(sphere, glm::vec3(0.3f, 0.4f, 0.0f), t), 0.29f, 1e-6f);
    // Inside the same sphere: 0.19 - 0.1 at 0.1 m from the centre; beyond it, negative.
    Collider inside = sphere;
    inside.kind = ColliderKind::Inside;
    EXPECT_NEAR(collider_gap(inside, glm::vec3(0.0f, 0.1f, 0.0f), t), 0.09f, 1e-6f);
    EXPECT_NEAR(collider_gap(inside, glm::vec3(0.0f, 0.3f, 0.0f), t), -0.11f, 1e-6f);
    // An inside capsule along X from -1 to 1, radius 0.2: the point (2, 0.1, 0) is 1.005 m
    // from the end (1, 0, 0).
    const Collider capsule{glm::vec3(-1.0f, 0.0f, 0.0f), glm::vec3(1.0f, 0.0f, 0.0f), 0.2f, ColliderKind::Inside};
    EXPECT_NEAR(collider_gap(capsule, glm::vec3(2.0f, 0.1f, 0.0f), t), 0.19f - std::sqrt(1.01f), 1e-6f);
    // A plane through (0, 1, 0) with normal +Y: a point at y = 1.5 is 0.49 clear of it.
    const Collider plane{glm::vec3(0.0f, 1.0f, 0.0f), glm::vec3(0.0f, 1.0f, 0.0f), 0.0f, ColliderKind::Plane};
    EXPECT_NEAR(collider_gap(plane, glm::vec3(7.0f, 1.5f, -3.0f), t), 0.49f, 1e-6f);
    EXPECT_NEAR(collider_gap(plane, glm::vec3(0.0f, 0.5f, 0.0f), t), -0.51f, 1e-6f);
    // The reach each kind keeps.
    EXPECT_FLOAT_EQ(collider_reach(sphere, t), 0.21f);
    EXPECT_FLOAT_EQ(collider_reach(inside, t), 0.19f);
    EXPECT_FLOAT_EQ(collider_reach(Collider{glm::vec3(0.0f), glm::vec3(0.0f), 0.005f, ColliderKind::Inside}, t), 0.0f);
    EXPECT_FLOAT_EQ(collider_reach(plane, t), t);
}

// A 0.5 m strand hanging from (0, 1, 0) inside a sphere of radius 0.3 around its root: its
// lower joints would hang 0.5 m down, and the inside collider keeps every particle within
// 0.3 - thickness of the centre (VRMC_springBone_extended_collider: the joint's sphere
// stays inside the collider's). Tolerance 1e-6 m: the projection puts a particle on the
// bound exactly; only float rounding of centre + r d/|d| remains (~1e-7 m at 1 m).
TEST(Colliders, InsideSphereKeepsTheStrandWithinIt) {
    const Strand s = strand(hanging(8, 0.5f));
    SolverParams params;
    const glm::vec3 centre(0.0f, 1.0f, 0.0f);
    const Collider inside{centre, centre, 0.3f, ColliderKind::Inside};
    const float bound = 0.3f - s.chain.thickness;
    for (const bool with : {true, false}) {
        SCOPED_TRACE(with ? "with the collider" : "without (control)");
        const ChainState state = with ? run(s, params, std::span(&inside, 1), 120) : run(s, params, {}, 120);
        float farthest = 0.0f;
        for (std::uint32_t i = 1; i < s.chain.joint_count; ++i) {
            // The sphere moves with nothing: its centre is fixed while the root sways.
            farthest = std::max(farthest, glm::length(position(state, i) - centre));
        }
        if (with) {
            EXPECT_LE(farthest, bound + 1e-6f);
            EXPECT_GT(farthest, bound - 1e-3f) << "the strand should be pressed against the inside of the sphere";
        } else {
            EXPECT_GT(farthest, 0.45f) << "without the collider the strand hangs its whole length";
        }
    }
}

// The same strand inside a capsule along X through its root (radius 0.25): held within
// 0.25 - thickness of the segment.
TEST(Colliders, InsideCapsuleKeepsTheStrandWithinIt) {
    const Strand s = strand(hanging(8, 0.5f));
    const Collider capsule{glm::vec3(-0.4f, 1.0f, 0.0f), glm::vec3(0.4f, 1.0f, 0.0f), 0.25f, ColliderKind::Inside};
    const ChainState state = run(s, SolverParams{}, std::span(&capsule, 1), 120);
    float deepest = 0.0f;
    for (std::uint32_t i = 1; i < s.chain.joint_count; ++i) {
        const glm::vec3 p = position(state, i);
        deepest = std::max(deepest, glm::length(p - closest(p, capsule.a, capsule.b)));
    }
    EXPECT_LE(deepest, 0.25f - s.chain.thickness + 1e-6f);
    EXPECT_GT(deepest, 0.25f - s.chain.thickness - 1e-3f);
}

// A plane below the root (through (0, 0.8, 0)), level and then tilted 45 degrees about Z:
// every particle stays on the normal's side by at least the thickness (signed distance
// dot(p - a, n) >= thickness, computed here from a point and the normal).
TEST(Colliders, PlaneKeepsTheStrandOnItsNormalSide) {
    const Strand s = strand(hanging(8, 0.5f));
    for (const glm::vec3 normal : {glm::vec3(0.0f, 1.0f, 0.0f), glm::normalize(glm::vec3(1.0f, 1.0f, 0.0f))}) {
        SCOPED_TRACE(normal.x);
        const glm::vec3 point(0.0f, 0.8f, 0.0f);
        const Collider plane{point, normal, 0.0f, ColliderKind::Plane};
        for (const bool with : {true, false}) {
            const ChainState state = with ? run(s, SolverParams{}, std::span(&plane, 1), 120) : run(s, SolverParams{}, {}, 120);
            float lowest = 1e9f;
            for (std::uint32_t i = 1; i < s.chain.joint_count; ++i) {
                lowest = std::min(lowest, glm::dot(position(state, i) - point, normal));
            }
            if (with) {
                EXPECT_GE(lowest, s.chain.thickness - 1e-6f);
                EXPECT_LT(lowest, s.chain.thickness + 1e-3f) << "the strand should rest on the plane";
            } else {
                EXPECT_LT(lowest, 0.0f) << "without the plane the strand hangs through it";
            }
        }
    }
}

// follow_center() with a pure translation keeps the root-relative state and moves the
// last root by it; with a rotation R about the center, every root-relative quantity turns
// by R (the definitions in solver.hpp), computed here independently.
TEST(Colliders, FollowCenterCarriesTheStateRigidly) {
    const Strand s = strand(hanging(5, 0.4f));
    ChainState state = initial_state(s.chain, Transform{glm::vec3(1.0f, 2.0f, 3.0f), glm::quat(1, 0, 0, 0)}, s.rest);
    state.v[2] = glm::vec3(0.5f, 0.0f, 0.0f);
    state.omega[3] = glm::vec3(0.0f, 0.0f, 2.0f);
    const Transform from{glm::vec3(1.0f, 1.0f, 1.0f), glm::angleAxis(0.3f, glm::vec3(0, 1, 0))};

    ChainState moved = state;
    follow_center(from, Transform{from.position + glm::vec3(0.5f, 0.0f, -1.0f), from.rotation}, moved);
    EXPECT_NEAR(glm::length(moved.root.position - (state.root.position + glm::vec3(0.5f, 0.0f, -1.0f))), 0.0f, 1e-6f);
    for (std::uint32_t i = 0; i < s.chain.joint_count; ++i) {
        EXPECT_NEAR(glm::length(moved.x[i] - state.x[i]), 0.0f, 1e-6f);
        EXPECT_NEAR(glm::length(moved.v[i] - state.v[i]), 0.0f, 1e-6f);
    }

    const glm::quat turn = glm::angleAxis(0.7f, glm::normalize(glm::vec3(0.0f, 1.0f, 1.0f)));
    ChainState turned = state;
    follow_center(from, Transform{from.position, turn * from.rotation}, turned);
    // World positions P turn about the center's position: P' = c + R (P - c).
    for (std::uint32_t i = 0; i < s.chain.joint_count; ++i) {
        const glm::vec3 want = from.position + turn * (position(state, i) - from.position);
        EXPECT_NEAR(glm::length(position(turned, i) - want), 0.0f, 1e-5f) << i;
        EXPECT_NEAR(glm::length(turned.v[i] - turn * state.v[i]), 0.0f, 1e-6f) << i;
        EXPECT_NEAR(glm::length(turned.omega[i] - turn * state.omega[i]), 0.0f, 1e-6f) << i;
    }
}

// UniVRM's center: a spring's inertia is measured in its center node's space. A strand on
// a root that moves and turns, with the center = the root, must move exactly as one on a
// root at rest (seen from the root): the frames differ by a rigid motion that the center
// takes out. Gravity off (it would turn with the root's frame otherwise). Tolerance 1e-4
// of the strand's 0.4 m: float rounding of the state turned every frame, over 90 frames
// (measured below it, printed); the control, without the center, swings by centimetres.
TEST(Colliders, CenterMakesARigidlyCarriedStrandMoveAsOneAtRest) {
    const Strand s = strand(hanging(6, 0.4f));
    SolverParams params;
    params.gravity = glm::vec3(0.0f);
    // Both strands start still (the control's lag is what the center takes out; a start
    // moving with the root would hide part of it).
    params.settle_start = false;
    // A rest shape that differs from the initial one, so that the strand moves at all.
    ChainShape bent = s.rest;
    for (std::size_t i = 1; i < bent.positions.size(); ++i) bent.positions[i].x += 0.02f * static_cast<float>(i);

    const Transform still{glm::vec3(0.0f, 1.0f, 0.0f), glm::quat(1, 0, 0, 0)};
    ChainState at_rest = initial_state(s.chain, still, s.rest);
    const auto carried_root = [&](int f) {
        const float t = static_cast<float>(f) / 60.0f;
        return Transform{glm::vec3(3.0f * t, 1.0f + 0.5f * std::sin(4.0f * t), -2.0f * t * t),
                         glm::angleAxis(2.0f * t, glm::normalize(glm::vec3(0.2f, 1.0f, 0.1f)))};
    };
    for (const bool center : {true, false}) {
        SCOPED_TRACE(center ? "center = the root" : "no center (control)");
        ChainState reference = at_rest;
        ChainState moving = initial_state(s.chain, carried_root(0), s.rest);
        Transform last = carried_root(0);
        float worst = 0.0f;
        for (int f = 1; f <= 90; ++f) {
            step(s.chain, params, still, bent, {}, 1.0f / 60.0f, reference);
            const Transform root = carried_root(f);
            if (center) follow_center(last, root, moving);
            step(s.chain, params, root, bent, {}, 1.0f / 60.0f, moving);
            last = root;
            for (std::uint32_t i = 0; i < s.chain.joint_count; ++i) {
                // Both in their root's frame.
                const glm::vec3 a = glm::conjugate(still.rotation) * (position(reference, i) - still.position);
                const glm::vec3 b = glm::conjugate(root.rotation) * (position(moving, i) - root.position);
                worst = std::max(worst, glm::length(a - b));
            }
        }
        std::printf("[ measured ] %s: max %.3g m from the strand at rest\n", center ? "center" : "no center",
                    static_cast<double>(worst));
        if (center) {
            EXPECT_LT(worst, 1e-4f * 0.4f);
        } else {
            EXPECT_GT(worst, 0.01f);
        }
    }
}

}  // namespace
}  // namespace kodawari::rods
