// Issue 39's physics checks of the rods solver (SPEC A.4): results that do not depend on
// the frame rate, an inextensibility step that adds no energy, colliders that move with
// the root through a frame's substeps and leave neither stretch nor penetration.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "kodawari/rods/shape.hpp"
#include "kodawari/rods/solver.hpp"
#include "kodawari/rods/world.hpp"
#include "rod_measures.hpp"

using namespace kodawari::rods;

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// A straight shape of `joints` joints and `length` m along `dir`, each joint's +Y along it.
ChainShape straight(std::uint32_t joints, float length, glm::vec3 dir) {
    ChainShape s;
    const float l = length / static_cast<float>(joints - 1);
    for (std::uint32_t i = 0; i < joints; ++i) {
        s.positions.push_back(static_cast<float>(i) * l * dir);
        s.orientations.push_back(shortest_arc(glm::vec3(0, 1, 0), dir));
    }
    return s;
}

Chain chain_of(const ChainShape& shape, float thickness = 0.005f, float mass = 0.01f) {
    auto chain = make_chain(shape, thickness, mass);
    EXPECT_TRUE(chain.ok());
    return chain.value();
}

// Kinetic plus potential energy of the simulated particles, J: the kinetic energy of their
// motion over the last step (displacement / h: DFTL's velocities hold a term along the
// segments that the next sweep takes back, solver.hpp kFollowTheLeaderDamping), the
// potential measured from the lowest a particle can hang (the root's height minus the
// chain's length L; a horizontal 16-joint 0.4 m chain of 10 g particles starts at
// 15 m g L = 0.589 J).
float total_energy(const Chain& chain, const ChainState& before, const ChainState& after, float h, float length, float g) {
    float e = 0.0f;
    for (std::uint32_t i = 1; i < chain.joint_count; ++i) {
        const glm::vec3 v = (after.x[i] - before.x[i]) / h;
        e += 0.5f * chain.mass[i] * glm::dot(v, v) + chain.mass[i] * g * (after.x[i].y - after.x[0].y + length);
    }
    return e;
}

using kodawari::testing_support::max_stretch;

}  // namespace

// SPEC A.4: results do not depend on the caller's frame rate. A horizontal 16-joint, 0.4 m
// strand with default settings rests with a sag (the tip's drop below its rest position)
// that, before the stiffnesses were converted as compliances, was 6.03 mm at 24, 30, 60
// and 120 fps but 3.87 at 50, 2.19 at 100, 1.55 at 119 and 4.20 at 144 (the substep, and
// with it the per-substep fractions, changed with the fps). Bound: every fps within 5% of
// the others (the issue's). 6 s at damping 1/s leave e^-6 of the initial swing.
TEST(RodPhysics, RestingSagIsTheSameAtEveryFrameRate) {
    const ChainShape shape = straight(16, 0.4f, glm::vec3(1, 0, 0));
    const Chain chain = chain_of(shape);
    const Transform root{glm::vec3(0, 1.5f, 0), glm::quat(1, 0, 0, 0)};
    // Defaults, and what the VRM mapping makes of sphere-collider.gltf's spring with
    // gravityPower 0.5 (vrm.hpp: no shape matching, rest_stiffness 0.0083, damping
    // 30.6/s, gravity 30 m/s^2), where damping applied after gravity scaled the sag by
    // exp(-damping h): 0.77 at 1/120 s, 0.81 at 1/144 s.
    SolverParams vrm;
    vrm.stiffness = 0.0f;
    vrm.rest_stiffness = 0.008264f;
    vrm.damping = 30.649f;
    vrm.gravity = glm::vec3(0.0f, -30.0f, 0.0f);
    for (const SolverParams& params : {SolverParams{}, vrm}) {
        float lo = 1e9f, hi = 0.0f;
        for (const float fps : {24.0f, 30.0f, 50.0f, 60.0f, 100.0f, 119.0f, 120.0f, 144.0f}) {
            ChainState s = initial_state(chain, root, shape);
            const int frames = static_cast<int>(6.0f * fps);
            for (int f = 0; f < frames; ++f) step(chain, params, root, shape, {}, 1.0f / fps, s);
            const float sag = -s.x[15].y;
            lo = std::min(lo, sag);
            hi = std::max(hi, sag);
            std::printf("[ measured ] %s, %g fps: sag %.3f mm\n", params.damping > 1.0f ? "VRM-mapped" : "defaults",
                        static_cast<double>(fps), static_cast<double>(sag * 1e3f));
        }
        EXPECT_GT(lo, 0.0f);
        EXPECT_LE(hi, 1.05f * lo) << (params.damping > 1.0f ? "VRM-mapped" : "defaults");
    }
}

// The distance constraints' follow-the-leader sweep moves a child onto its parent without
// moving the parent; without the dynamic follow-the-leader velocity correction a slack
// chain gained energy (the issue measured 0.48 J -> 2.00 J at 1/120 s substeps, 41 J at
// 1 ms, on 8 g particles; here 10 g: 0.589 J -> 2.38 J at 1/120 s). A 16-joint,
// 0.4 m chain released horizontal with stiffness 0, rest_stiffness 0 and damping 0: its
// total energy may never exceed its start by more than 1% (the bound), at 1 ms,
// 1/120 s and 1/20 s substeps, over 4 s of swinging.
TEST(RodPhysics, InextensibilityAddsNoEnergy) {
    const float length = 0.4f;
    const ChainShape shape = straight(16, length, glm::vec3(1, 0, 0));
    const Chain chain = chain_of(shape);
    const Transform root{glm::vec3(0, 1.5f, 0), glm::quat(1, 0, 0, 0)};
    for (const float h : {0.001f, 1.0f / 120.0f, 1.0f / 20.0f}) {
        SolverParams params;
        params.stiffness = 0.0f;
        params.rest_stiffness = 0.0f;
        params.damping = 0.0f;
        params.max_substep = h;
        ChainState s = initial_state(chain, root, shape);
        const float g = -params.gravity.y;
        const float start = total_energy(chain, s, s, h, length, g);
        float peak = start, end = start;
        const int steps = static_cast<int>(4.0f / h);
        for (int k = 0; k < steps; ++k) {
            const ChainState before = s;
            step(chain, params, root, shape, {}, h, s);
            end = total_energy(chain, before, s, h, length, g);
            peak = std::max(peak, end);
        }
        EXPECT_LE(peak, 1.01f * start) << "substep " << h;
        std::printf("[ measured ] substep %.4g s: start %.4g J, peak %.4g J, end %.4g J\n", static_cast<double>(h),
                    static_cast<double>(start), static_cast<double>(peak), static_cast<double>(end));
    }
}

// Shape matching alone (stiffness 0.5, rest_stiffness 0) with damping 2/s: before the
// velocity correction the chain never settled, even at damping 5/s. It must come to rest
// at every frame rate: every particle's speed over a frame (its displacement / dt; the
// state's velocities include DFTL's correction, which is not a motion) below 1 mm/s
// within 10 s.
TEST(RodPhysics, ShapeMatchingAloneSettles) {
    const ChainShape shape = straight(16, 0.4f, glm::vec3(1, 0, 0));
    const Chain chain = chain_of(shape);
    const Transform root{glm::vec3(0, 1.5f, 0), glm::quat(1, 0, 0, 0)};
    SolverParams params;
    params.stiffness = 0.5f;
    params.rest_stiffness = 0.0f;
    params.damping = 2.0f;
    for (const float fps : {5.0f, 24.0f, 60.0f, 144.0f}) {
        ChainState s = initial_state(chain, root, shape);
        const float dt = 1.0f / fps;
        float speed = 0.0f;
        float settled_at = -1.0f;
        const int frames = static_cast<int>(10.0f * fps);
        for (int f = 0; f < frames; ++f) {
            const ChainState before = s;
            step(chain, params, root, shape, {}, dt, s);
            speed = 0.0f;
            for (std::uint32_t i = 1; i < chain.joint_count; ++i) speed = std::max(speed, glm::length(s.x[i] - before.x[i]) / dt);
            if (speed >= 1e-3f) settled_at = -1.0f;
            else if (settled_at < 0.0f) settled_at = static_cast<float>(f + 1) * dt;
        }
        EXPECT_LT(speed, 1e-3f) << fps << " fps";
        EXPECT_GE(settled_at, 0.0f) << fps << " fps";
        std::printf("[ measured ] %g fps: at rest (< 1 mm/s) from %.2f s, last speed %.3g m/s\n", static_cast<double>(fps),
                    static_cast<double>(settled_at), static_cast<double>(speed));
    }
}

namespace {

// A head (a 0.09 m sphere collider) with a 16-joint, 0.3 m strand rooted on its crown
// (0.1 m above its centre) whose rest shape leaves at 45 degrees down and outwards,
// through the head: the collider holds it draped over the head the whole time. The head
// shakes (±0.3 m at 3 Hz, turning ±0.8 rad about Y) for 1 s, sprints off at 8 m/s for
// 0.5 s and stops dead, then rests for 0.5 s. Returns the worst stretch (fraction of a
// segment) and penetration (m) after any frame at `fps`, and the closest approach to the
// head's surface of a particle (so that the test can see the strand never touched it).
struct ShakeResult {
    float stretch = 0.0f, penetration = 0.0f, closest = 1e9f;
};

Transform head_at(float t) {
    Transform head;
    if (t < 1.0f) {
        head.position = glm::vec3(0.3f * std::sin(2.0f * kPi * 3.0f * t), 1.6f, 0.0f);
        head.rotation = glm::angleAxis(0.8f * std::sin(2.0f * kPi * 3.0f * t), glm::vec3(0, 1, 0));
    } else {
        head.position = glm::vec3(8.0f * std::min(t - 1.0f, 0.5f), 1.6f, 0.0f);
    }
    return head;
}

ShakeResult shake_and_stop(float fps) {
    const float radius = 0.09f, thickness = 0.005f;
    const ChainShape shape = straight(16, 0.3f, glm::normalize(glm::vec3(1, -1, 0)));
    const Chain chain = chain_of(shape, thickness);
    const glm::vec3 root_offset(0.0f, 0.1f, 0.0f);  // outside radius + thickness
    SolverParams params;
    auto root_of = [&](const Transform& head) { return Transform{head.position + head.rotation * root_offset, head.rotation}; };
    ChainState s = initial_state(chain, root_of(head_at(0.0f)), shape);
    ShakeResult r;
    const float dt = 1.0f / fps;
    const int frames = static_cast<int>(std::lround(2.0f * fps));
    for (int f = 1; f <= frames; ++f) {
        const Transform head = head_at(static_cast<float>(f) * dt);
        const Collider sphere{head.position, head.position, radius, ColliderKind::Outside};
        step(chain, params, root_of(head), shape, std::span<const Collider>(&sphere, 1), dt, s);
        r.stretch = std::max(r.stretch, max_stretch(chain, s));
        for (std::uint32_t i = 1; i < chain.joint_count; ++i) {
            const float gap = collider_gap(sphere, position(s, i), thickness);
            r.penetration = std::max(r.penetration, -gap);
            r.closest = std::min(r.closest, gap);
        }
    }
    return r;
}

}  // namespace

// Collisions inside the constraint sweep and a last distance sweep: neither stretch nor
// penetration is left at a frame's end. Bounds (the issue's): at most 1% stretch and
// 0.5 mm penetration, at 5 to 120 fps. Before: collisions ran after the distance sweep,
// leaving segments stretched (the issue measured 0.8% stretch, 2.8% compression with
// defaults in such a test; 11.7% at 60 fps and 32.5% at 5 fps in an extreme one).
TEST(RodPhysics, NoStretchNorPenetrationInAHeadShakeAndStop) {
    for (const float fps : {5.0f, 10.0f, 30.0f, 60.0f, 120.0f}) {
        const ShakeResult r = shake_and_stop(fps);
        EXPECT_LE(r.stretch, 0.01f) << fps << " fps";
        EXPECT_LE(r.penetration, 5e-4f) << fps << " fps";
        EXPECT_LT(r.closest, 1e-4f) << fps << " fps: the strand must lie on the head";
        std::printf("[ measured ] %g fps: stretch %.3g, penetration %.3g mm\n", static_cast<double>(fps),
                    static_cast<double>(r.stretch), static_cast<double>(r.penetration * 1e3f));
    }
}

namespace {

// Bangs in a sprint: a 10-joint, 0.15 m strand rooted on the forehead of a head (a 0.09 m
// sphere), hanging down in front of its face, the head accelerating from rest to 6 m/s
// along +Z (towards the face) in 0.5 s (smoothstep) and bobbing 3 cm at 2.5 Hz (a
// stride). Returns the tip's position relative to the head at every 0.2 s.
std::vector<glm::vec3> sprint_tip(float fps) {
    const float radius = 0.09f, thickness = 0.004f;
    const ChainShape shape = straight(10, 0.15f, glm::vec3(0, -1, 0));
    const Chain chain = chain_of(shape, thickness, 0.005f);
    const glm::vec3 root_offset(0.0f, 0.06f, 0.075f);  // |offset| 0.096 > 0.094
    auto head_at_t = [](float t) {
        const float ramp = std::min(t / 0.5f, 1.0f);
        // Position: the integral of 6 m/s x smoothstep(ramp) over [0, t].
        const float u = ramp;
        const float ramp_distance = 0.5f * 6.0f * (u * u * u - 0.5f * u * u * u * u);
        const float z = t < 0.5f ? ramp_distance : 0.5f * 6.0f * 0.5f + 6.0f * (t - 0.5f);
        return Transform{glm::vec3(0.0f, 1.6f + 0.03f * std::sin(2.0f * kPi * 2.5f * t), z), glm::quat(1, 0, 0, 0)};
    };
    SolverParams params;
    Transform head = head_at_t(0.0f);
    ChainState s = initial_state(chain, Transform{head.position + root_offset, head.rotation}, shape);
    std::vector<glm::vec3> tips;
    const int frames = static_cast<int>(std::lround(2.0f * fps));
    const int every = static_cast<int>(std::lround(0.2f * fps));
    for (int f = 1; f <= frames; ++f) {
        head = head_at_t(static_cast<float>(f) / fps);
        const Collider sphere{head.position, head.position, radius, ColliderKind::Outside};
        step(chain, params, Transform{head.position + root_offset, head.rotation}, shape,
             std::span<const Collider>(&sphere, 1), 1.0f / fps, s);
        if (f % every == 0) tips.push_back(position(s, 9) - head.position);
    }
    return tips;
}

}  // namespace

// The colliders move with the interpolated root in every substep: before, a collider sat
// at its end-of-frame pose for the whole frame, up to a frame's travel ahead of the root,
// and shoved the bangs in front of the face (the tip strayed 5.0 cm at 60 fps,
// 14.0 cm at 30, 16.5 cm at 10). The tip's trajectory at 5, 10, 30 and 120 fps must stay
// within 2 cm of the 60 fps one (the bound), sampled every 0.2 s.
TEST(RodPhysics, BangsInASprintDoNotDependOnTheFrameRate) {
    const std::vector<glm::vec3> want = sprint_tip(60.0f);
    for (const float fps : {5.0f, 10.0f, 30.0f, 120.0f}) {
        const std::vector<glm::vec3> got = sprint_tip(fps);
        ASSERT_EQ(got.size(), want.size());
        float worst = 0.0f;
        for (std::size_t k = 0; k < got.size(); ++k) worst = std::max(worst, glm::length(got[k] - want[k]));
        EXPECT_LE(worst, 0.02f) << fps << " fps";
        std::printf("[ measured ] %g fps: tip within %.3g cm of 60 fps\n", static_cast<double>(fps),
                    static_cast<double>(worst * 100.0f));
    }
}

// The order of a chain's colliders does not matter beyond what kColliderPasses leave: a
// strand falling onto two overlapping spheres (their crease runs under its root, so its
// particles are pushed by both) ends in the same place in either order, within 1 mm (was:
// each order kept a particle inside whichever sphere came first; the skirt
// particle ended 3.0 mm inside a leg collider at 5 fps), and outside both (0.5 mm, the
// issue's bound) at 5 fps.
TEST(RodPhysics, OverlappingCollidersInEitherOrder) {
    const float thickness = 0.005f;
    const ChainShape shape = straight(8, 0.3f, glm::vec3(1, 0, 0));
    const Chain chain = chain_of(shape, thickness);
    const Transform root{glm::vec3(0, 1.5f, 0), glm::quat(1, 0, 0, 0)};
    const Collider a{glm::vec3(0.15f, 1.38f, -0.05f), glm::vec3(0.15f, 1.38f, -0.05f), 0.08f};
    const Collider b{glm::vec3(0.17f, 1.39f, 0.05f), glm::vec3(0.17f, 1.39f, 0.05f), 0.08f};
    SolverParams params;  // limp, so that it drapes over both
    params.stiffness = 0.1f;
    params.rest_stiffness = 0.0f;
    float deepest[2] = {0.0f, 0.0f};
    float stretch = 0.0f;
    std::vector<glm::vec3> ends[2];
    bool touched = false;
    for (int order = 0; order < 2; ++order) {
        const Collider set[2] = {order == 0 ? a : b, order == 0 ? b : a};
        ChainState s = initial_state(chain, root, shape);
        for (int f = 0; f < 20; ++f) {
            step(chain, params, root, shape, set, 1.0f / 5.0f, s);
            for (std::uint32_t i = 1; i < chain.joint_count; ++i) {
                float gaps[2];
                for (int k = 0; k < 2; ++k) gaps[k] = collider_gap(set[k], position(s, i), thickness);
                deepest[order] = std::max({deepest[order], -gaps[0], -gaps[1]});
                touched = touched || (gaps[0] < 1e-3f && gaps[1] < 1e-3f);
            }
            stretch = std::max(stretch, max_stretch(chain, s));
        }
        for (std::uint32_t i = 0; i < chain.joint_count; ++i) ends[order].push_back(position(s, i));
    }
    float apart = 0.0f;
    for (std::size_t i = 0; i < ends[0].size(); ++i) apart = std::max(apart, glm::length(ends[0][i] - ends[1][i]));
    EXPECT_TRUE(touched) << "some particle must rest against both spheres";
    EXPECT_LE(deepest[0], 5e-4f);
    EXPECT_LE(deepest[1], 5e-4f);
    EXPECT_LE(apart, 1e-3f);
    std::printf("[ measured ] deepest: %.3g mm (a, b), %.3g mm (b, a); the orders' ends %.3g mm apart; stretch %.3g\n",
                static_cast<double>(deepest[0] * 1e3f), static_cast<double>(deepest[1] * 1e3f),
                static_cast<double>(apart * 1e3f), static_cast<double>(stretch));
}

// make_chain_template's limit on view examples through the C++ API: the GPU keeps a
// chain's weights in fixed arrays of kMaxViewExamples + 1 (shaders/shared/rods.h), so a
// template with 8 views must be refused, naming the chain and the limit, and one with 7
// accepted (the C API and the scene loader check it too, but not for C++ callers).
TEST(RodPhysics, ChainTemplatesTakeAtMostSevenViews) {
    static_assert(kMaxViewExamples == 7);
    const ChainShape base = straight(6, 0.2f, glm::vec3(0, -1, 0));
    std::vector<ChainShape> shapes;
    std::vector<ViewExample> views;
    for (int k = 0; k < 8; ++k) {
        const float a = 2.0f * kPi * static_cast<float>(k) / 8.0f;
        shapes.push_back(straight(6, 0.2f, glm::normalize(glm::vec3(0.2f * std::cos(a), -1.0f, 0.2f * std::sin(a)))));
        views.push_back({glm::vec3(std::cos(a), 0.0f, std::sin(a)), 2.0f});
    }
    const SolverParams params;
    const auto eight = make_chain_template("fringe", base, shapes, views, 0.003f, 0.002f, params);
    ASSERT_FALSE(eight.ok());
    EXPECT_NE(eight.error().message.find("fringe"), std::string::npos) << eight.error().message;
    EXPECT_NE(eight.error().message.find("at most 7"), std::string::npos) << eight.error().message;
    const auto seven = make_chain_template("fringe", base, std::span(shapes).first(7), std::span(views).first(7), 0.003f,
                                           0.002f, params);
    ASSERT_TRUE(seven.ok()) << seven.error().message;
    EXPECT_EQ(seven.value().views.size(), 7u);
}
