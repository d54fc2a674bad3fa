// SPEC A.2-A.5: chain shapes and blending, view weights, the oriented-particles solver.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "kodawari/rods/shape.hpp"
#include "kodawari/rods/solver.hpp"
#include "kodawari/rods/view.hpp"
#include "rod_measures.hpp"

using namespace kodawari::rods;

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

glm::vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<float> g(0.0f, 1.0f);
    for (;;) {
        const glm::vec3 v(g(rng), g(rng), g(rng));
        if (glm::length(v) > 1e-3f) return glm::normalize(v);
    }
}

glm::quat random_rotation(std::mt19937& rng) {
    std::normal_distribution<float> g(0.0f, 1.0f);
    return glm::normalize(glm::quat(g(rng), g(rng), g(rng), g(rng)));
}

// A shape through the given segment directions and lengths, joint 0 at the origin, each
// joint's local +Y along its segment (the last joint's along the last one).
ChainShape shape_from(const std::vector<glm::vec3>& dirs, const std::vector<float>& lengths) {
    ChainShape s;
    s.positions.push_back(glm::vec3(0.0f));
    for (std::size_t i = 0; i < dirs.size(); ++i) s.positions.push_back(s.positions.back() + lengths[i] * dirs[i]);
    for (std::size_t i = 0; i <= dirs.size(); ++i) {
        s.orientations.push_back(shortest_arc(glm::vec3(0, 1, 0), dirs[std::min(i, dirs.size() - 1)]));
    }
    return s;
}

// A planar arc of `joints` joints and length `length` leaving the root along `start`,
// turning by `turn` radians per segment about `axis` (0 = straight).
ChainShape arc_shape(std::uint32_t joints, float length, glm::vec3 start, glm::vec3 axis, float turn) {
    std::vector<glm::vec3> dirs;
    std::vector<float> lengths(joints - 1, length / static_cast<float>(joints - 1));
    glm::vec3 d = start;
    for (std::uint32_t i = 0; i + 1 < joints; ++i) {
        dirs.push_back(d);
        d = glm::normalize(glm::angleAxis(turn, axis) * d);
    }
    return shape_from(dirs, lengths);
}

float chain_length(const ChainShape& s) {
    float len = 0.0f;
    for (std::size_t i = 0; i + 1 < s.positions.size(); ++i) len += glm::length(s.positions[i + 1] - s.positions[i]);
    return len;
}

float max_position_error(const ChainShape& a, const ChainShape& b) {
    float e = 0.0f;
    for (std::size_t i = 0; i < a.positions.size(); ++i) e = std::max(e, glm::length(a.positions[i] - b.positions[i]));
    return e;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Shapes (SPEC A.2)

// Tolerance: 1e-5 of the chain length. Forward kinematics sums n-1 = 12 segments, each
// direction off by a few float ulps (6e-8) per rotation; the worst case stays well
// below 1e-6 relative, so 1e-5 leaves a margin while a wrong r_i (even by 0.01 rad)
// would fail by orders of magnitude.
TEST(RodShape, RoundTripPositionsRotationsPositions) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> len(0.01f, 0.2f);
    for (int trial = 0; trial < 50; ++trial) {
        std::vector<glm::vec3> dirs;
        std::vector<float> lengths;
        for (int i = 0; i < 12; ++i) {
            dirs.push_back(random_unit(rng));
            lengths.push_back(len(rng));
        }
        const ChainShape base = shape_from(dirs, lengths);
        auto basis = make_basis(base);
        ASSERT_TRUE(basis.ok());
        ASSERT_EQ(basis.value().joint_count(), 13u);
        // The base itself and another shape with the same segment lengths.
        for (int k = 0; k < 2; ++k) {
            if (k == 1) std::generate(dirs.begin(), dirs.end(), [&] { return random_unit(rng); });
            const ChainShape shape = shape_from(dirs, lengths);
            auto rotations = to_rotations(basis.value(), shape);
            ASSERT_TRUE(rotations.ok());
            const ChainShape back = to_positions(basis.value(), rotations.value());
            EXPECT_LT(max_position_error(back, shape), 1e-5f * chain_length(shape));
        }
    }
}

// Tolerance: 1e-5 relative per segment: to_positions renormalizes each direction, so a
// segment is l_i times a unit vector to float rounding (~1e-7).
TEST(RodShape, AnyWeightsKeepSegmentLengths) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> len(0.01f, 0.2f), unit(0.0f, 1.0f);
    std::vector<float> lengths;
    for (int i = 0; i < 12; ++i) lengths.push_back(len(rng));
    auto make = [&] {
        std::vector<glm::vec3> dirs;
        for (int i = 0; i < 12; ++i) dirs.push_back(random_unit(rng));
        return shape_from(dirs, lengths);
    };
    const ChainShape base = make();
    auto basis = make_basis(base);
    ASSERT_TRUE(basis.ok());
    std::vector<RotationShape> shapes;
    for (int k = 0; k < 4; ++k) shapes.push_back(to_rotations(basis.value(), k == 0 ? base : make()).value());
    float worst = 0.0f;
    for (int trial = 0; trial < 1000; ++trial) {
        std::vector<float> w(shapes.size());
        float sum = 0.0f;
        for (float& x : w) sum += (x = unit(rng));
        for (float& x : w) x /= sum;
        const ChainShape out = to_positions(basis.value(), blend(shapes, w));
        for (std::size_t i = 0; i < lengths.size(); ++i) {
            const float l = glm::length(out.positions[i + 1] - out.positions[i]);
            worst = std::max(worst, std::abs(l - lengths[i]) / lengths[i]);
        }
    }
    EXPECT_LT(worst, 1e-5f);
}

// Tolerance: positions 1e-5 of the chain length (as the round trip); orientations
// |dot| > 1 - 1e-6 (within 2.8e-3 rad): a one-hot blend is the normalize of +-q, exact to
// rounding, while any real mix of two random orientations misses by far more.
TEST(RodShape, OneHotWeightReproducesTheExample) {
    std::mt19937 rng(5);
    const std::vector<float> lengths(12, 0.05f);
    auto make = [&] {
        std::vector<glm::vec3> dirs;
        for (int i = 0; i < 12; ++i) dirs.push_back(random_unit(rng));
        ChainShape s = shape_from(dirs, lengths);
        for (glm::quat& q : s.orientations) q = random_rotation(rng);
        return s;
    };
    std::vector<ChainShape> raw = {make(), make(), make(), make()};
    auto basis = make_basis(raw[0]);
    ASSERT_TRUE(basis.ok());
    std::vector<RotationShape> shapes;
    for (const ChainShape& s : raw) shapes.push_back(to_rotations(basis.value(), s).value());
    for (std::size_t k = 0; k < raw.size(); ++k) {
        std::vector<float> w(raw.size(), 0.0f);
        w[k] = 1.0f;
        const ChainShape out = to_positions(basis.value(), blend(shapes, w));
        EXPECT_LT(max_position_error(out, raw[k]), 1e-5f * chain_length(raw[k])) << "example " << k;
        for (std::size_t i = 0; i < out.orientations.size(); ++i) {
            EXPECT_GT(std::abs(glm::dot(out.orientations[i], raw[k].orientations[i])), 1.0f - 1e-6f);
        }
    }
}

// A hairpin: segment directions exactly and nearly opposite. Tolerances as the round trip.
TEST(RodShape, AntiparallelSegments) {
    for (const glm::vec3 a : {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, 1),
                              glm::normalize(glm::vec3(1, 2, 3)), glm::normalize(glm::vec3(-1e-4f, 1, 0))}) {
        const glm::quat q = shortest_arc(a, -a);
        EXPECT_NEAR(glm::length(q), 1.0f, 1e-6f);
        EXPECT_LT(glm::length(q * a + a), 1e-6f);
    }
    const glm::vec3 up(0, 1, 0), almost_down = glm::normalize(glm::vec3(1e-7f, -1, 0));
    const ChainShape shape = shape_from({up, -up, up, almost_down, up, glm::vec3(1, 0, 0)},
                                        {0.1f, 0.1f, 0.1f, 0.1f, 0.1f, 0.1f});
    auto basis = make_basis(shape);
    ASSERT_TRUE(basis.ok());
    auto rotations = to_rotations(basis.value(), shape);
    ASSERT_TRUE(rotations.ok());
    const ChainShape back = to_positions(basis.value(), rotations.value());
    EXPECT_LT(max_position_error(back, shape), 1e-5f * chain_length(shape));
    for (const glm::vec3& p : back.positions) EXPECT_TRUE(std::isfinite(glm::dot(p, p)));
}

TEST(RodShape, RejectsBadShapes) {
    ChainShape one{{glm::vec3(0)}, {glm::quat(1, 0, 0, 0)}};
    EXPECT_FALSE(make_basis(one).ok());
    ChainShape zero_segment{{glm::vec3(0), glm::vec3(0)}, {glm::quat(1, 0, 0, 0), glm::quat(1, 0, 0, 0)}};
    EXPECT_FALSE(make_basis(zero_segment).ok());
    const ChainShape too_long = arc_shape(kMaxChainJoints + 1, 1.0f, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.0f);
    EXPECT_FALSE(make_basis(too_long).ok());
    const ChainShape ok = arc_shape(kMaxChainJoints, 1.0f, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.1f);
    ASSERT_TRUE(make_basis(ok).ok());
    ChainShape mismatch = ok;
    mismatch.orientations.pop_back();
    EXPECT_FALSE(to_rotations(make_basis(ok).value(), mismatch).ok());
}

// ---------------------------------------------------------------------------------------
// View direction and weights (SPEC A.3)

TEST(RodView, ViewDirectionIsInTheReferenceFrame) {
    // Head turned 90 degrees left (about +Y): a camera straight ahead in the world (+Z)
    // is seen on the head's right (-X in the head frame)... R^T (0,0,1) = (-1,0,0).
    const glm::quat head = glm::angleAxis(0.5f * kPi, glm::vec3(0, 1, 0));
    Camera cam;
    cam.position = glm::vec3(0, 1, 6);
    const glm::vec3 d = view_direction(cam, glm::vec3(0, 1, 1), head);
    EXPECT_NEAR(d.x, -1.0f, 1e-6f);
    EXPECT_NEAR(d.y, 0.0f, 1e-6f);
    EXPECT_NEAR(d.z, 0.0f, 1e-6f);
    cam.projection = Camera::Projection::Orthographic;
    cam.forward = glm::vec3(0, 0, -1);
    const glm::vec3 o = view_direction(cam, glm::vec3(50, 0, 0), head);
    EXPECT_NEAR(glm::length(o - d), 0.0f, 1e-6f);
    // A perspective camera on the joint falls back to the orthographic direction.
    cam.projection = Camera::Projection::Perspective;
    cam.position = glm::vec3(0, 1, 1);
    EXPECT_NEAR(glm::length(view_direction(cam, glm::vec3(0, 1, 1), head) - d), 0.0f, 1e-6f);
}

TEST(RodView, NoExamplesGiveTheBaseShape) {
    const std::vector<float> w = view_weights(glm::vec3(0, 0, 1), {});
    ASSERT_EQ(w.size(), 1u);
    EXPECT_EQ(w[0], 1.0f);
}

// Tolerances: the seed's algorithm makes w_0 = 1 - S with S <= 1 exactly after the
// renormalization, so only float rounding of the sum (~1e-6 for 8 terms) can show.
TEST(RodView, WeightsSumToOneAndStayNonNegative) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> influence(0.05f, 10.0f);
    std::uniform_int_distribution<int> count(1, 8);
    for (int trial = 0; trial < 10000; ++trial) {
        std::vector<ViewExample> examples(static_cast<std::size_t>(count(rng)));
        for (ViewExample& e : examples) e = {random_unit(rng), influence(rng)};
        const std::vector<float> w = view_weights(random_unit(rng), examples);
        ASSERT_EQ(w.size(), examples.size() + 1);
        float examples_sum = 0.0f;
        for (std::size_t k = 1; k < w.size(); ++k) {
            ASSERT_GE(w[k], 0.0f);
            examples_sum += w[k];
        }
        EXPECT_LE(examples_sum, 1.0f + 1e-6f);
        EXPECT_GE(w[0], 0.0f);
        EXPECT_NEAR(w[0] + examples_sum, 1.0f, 1e-6f);
    }
}

TEST(RodView, AFarReachingExampleDominatesAtItsDirection) {
    const std::vector<glm::vec3> dirs = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (std::size_t k = 0; k < dirs.size(); ++k) {
        std::vector<ViewExample> examples;
        for (std::size_t j = 0; j < dirs.size(); ++j) examples.push_back({dirs[j], j == k ? 0.1f : 8.0f});
        const std::vector<float> w = view_weights(dirs[k], examples);
        // Expected: w_k = 1 / (1 + 4 * 0.5^8) = 0.985, each perpendicular one 0.0038,
        // the opposite one 0, w_0 = 0.
        EXPECT_NEAR(w[k + 1], 1.0f / (1.0f + 4.0f * std::pow(0.5f, 8.0f)), 1e-5f);
        for (std::size_t j = 0; j < dirs.size(); ++j) {
            if (j != k) {
                EXPECT_LT(w[j + 1], 0.01f);
            }
        }
        EXPECT_NEAR(w[0], 0.0f, 1e-6f);
    }
}

// Bound: each s_k^p_k = cos^(2p)(phi/2) changes by at most p_k * dtheta for p_k >= 1/2
// (its derivative in the angle is p cos^(2p-1) sin <= p), and the renormalization by
// S >= 1 at most doubles a change, so a jump is below 2 (sum p_k) dtheta = 0.037 here.
// (Influences below 1/2 give weights that are continuous but not Lipschitz at the
// antipode of their example, so they are left out of this test.)
TEST(RodView, WeightsAreContinuousOverAFullCircle) {
    const std::vector<ViewExample> examples = {{glm::vec3(0, 0, 1), 0.5f},
                                               {glm::normalize(glm::vec3(1, 0.2f, 0)), 2.0f},
                                               {glm::normalize(glm::vec3(-1, -0.3f, -1)), 8.0f},
                                               {glm::vec3(0, 1, 0), 0.1f + 0.5f}};
    float influence_sum = 0.0f;
    for (const ViewExample& e : examples) influence_sum += e.influence;
    constexpr int kSteps = 3600;
    const float dtheta = 2.0f * kPi / static_cast<float>(kSteps);
    std::vector<float> previous;
    float max_jump = 0.0f;
    for (int i = 0; i <= kSteps; ++i) {
        const float t = static_cast<float>(i) * dtheta;
        const std::vector<float> w = view_weights(glm::vec3(std::sin(t), 0.0f, std::cos(t)), examples);
        for (std::size_t k = 0; k < w.size() && !previous.empty(); ++k) {
            max_jump = std::max(max_jump, std::abs(w[k] - previous[k]));
        }
        previous = w;
    }
    EXPECT_LT(max_jump, 2.0f * influence_sum * dtheta);
    EXPECT_GT(max_jump, 0.0f);
    RecordProperty("max_jump", std::to_string(max_jump));
}

// ---------------------------------------------------------------------------------------
// Solver (SPEC A.4, A.5)

namespace {

struct Rig {
    Chain chain;
    ChainShape rest;
};

Rig make_rig(const ChainShape& rest, float thickness = 0.005f, float mass = 0.01f) {
    auto chain = make_chain(rest, thickness, mass);
    EXPECT_TRUE(chain.ok());
    return {chain.value(), rest};
}

using kodawari::testing_support::max_stretch;

// Largest distance of a joint from where `rest` placed by `root` puts it.
float rest_error(const Chain& chain, const ChainState& s, const Transform& root, const ChainShape& rest) {
    float e = 0.0f;
    for (std::uint32_t i = 0; i < chain.joint_count; ++i) {
        e = std::max(e, glm::length(position(s, i) - (root.position + root.rotation * rest.positions[i])));
    }
    return e;
}

bool finite(const Chain& chain, const ChainState& s) {
    for (std::uint32_t i = 0; i < chain.joint_count; ++i) {
        const float sum = glm::dot(s.x[i], s.x[i]) + glm::dot(s.v[i], s.v[i]) + glm::dot(s.q[i], s.q[i]) +
                          glm::dot(s.omega[i], s.omega[i]);
        if (!std::isfinite(sum)) return false;
    }
    return true;
}

}  // namespace

TEST(RodSolver, ValidatesParameters) {
    EXPECT_TRUE(validate(SolverParams{}).ok());
    SolverParams p;
    p.iterations = 0;
    EXPECT_FALSE(validate(p).ok());
    p = {};
    p.stiffness = 1.5f;
    EXPECT_FALSE(validate(p).ok());
    p = {};
    p.max_substep = 0.0f;
    EXPECT_FALSE(validate(p).ok());
    p = {};
    p.momentum_suppression = -0.1f;
    EXPECT_FALSE(validate(p).ok());
    EXPECT_FALSE(make_chain(arc_shape(5, 0.3f, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.1f), 0.0f, 1.0f).ok());
}

// A 16-joint, 0.5 m strand on a head shaking 2 m at 3 Hz (peak 38 m/s, 72 g), 60 fps
// frames, 4 iterations. Bound: every segment within 0.5% of its length after every frame.
TEST(RodSolver, InextensibleInAViolentHeadShake) {
    const Rig rig = make_rig(arc_shape(16, 0.5f, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.05f));
    SolverParams params;
    params.iterations = 4;
    Transform root;
    ChainState s = initial_state(rig.chain, root, rig.rest);
    const float dt = 1.0f / 60.0f;
    float worst = 0.0f;
    for (int frame = 1; frame <= 240; ++frame) {
        const float t = static_cast<float>(frame) * dt;
        root.position = glm::vec3(2.0f * std::sin(2.0f * kPi * 3.0f * t), 0.0f, 0.0f);
        root.rotation = glm::angleAxis(0.8f * std::sin(2.0f * kPi * 3.0f * t), glm::vec3(0, 1, 0));
        step(rig.chain, params, root, rig.rest, {}, dt, s);
        ASSERT_TRUE(finite(rig.chain, s));
        worst = std::max(worst, max_stretch(rig.chain, s));
    }
    EXPECT_LT(worst, 0.005f);
    RecordProperty("max_stretch", std::to_string(worst));
    std::printf("[ measured ] max stretch in the head shake: %.3g of a segment\n", static_cast<double>(worst));
}

// Without gravity an instant switch with full suppression lands on the new shape.
// Bound: 1e-3 of the chain length, after 2 s.
TEST(RodSolver, SettlesOntoANewRestShapeWithoutGravity) {
    const float length = 0.3f;
    const ChainShape a = arc_shape(7, length, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.3f);
    const ChainShape b = arc_shape(7, length, glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), -0.4f);
    const Rig rig = make_rig(a);
    SolverParams params;
    params.gravity = glm::vec3(0.0f);
    const Transform root{glm::vec3(0, 1.5f, 0), glm::angleAxis(0.3f, glm::vec3(0, 0, 1))};
    ChainState s = initial_state(rig.chain, root, a);
    for (int frame = 0; frame < 120; ++frame) step(rig.chain, params, root, b, {}, 1.0f / 60.0f, s);
    EXPECT_LT(rest_error(rig.chain, s, root, b), 1e-3f * length);
}

// 100 000 substeps of random violent root motion on an 8-joint, 0.2 m chain: the root
// teleports (up to 2 sqrt(3) m) and spins at random every tenth step and shakes in between.
// No value may become NaN or infinite, and the kinetic energy stays bounded: no particle
// can move farther in one substep h than the root's jump J plus twice the chain length L
// (the distance constraints keep it near the root), so KE <= 1/2 M ((J_max + 2L)/h)^2.
TEST(RodSolver, StableUnderRandomViolentMotion) {
    const float length = 0.2f;
    const Rig rig = make_rig(arc_shape(8, length, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.1f));
    SolverParams params;
    params.damping = 0.0f;  // the harshest case: nothing but the solver removes energy
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> pos(-1.0f, 1.0f), small(-0.05f, 0.05f);
    Transform root;
    ChainState s = initial_state(rig.chain, root, rig.rest);
    const float h = params.max_substep;
    const float moving_mass = 7.0f * rig.chain.mass[1];
    const float bound = 0.5f * moving_mass * std::pow((2.0f * std::sqrt(3.0f) + 2.0f * length) / h, 2.0f);
    float peak = 0.0f, farthest = 0.0f;
    for (int i = 0; i < 100000; ++i) {
        if (i % 10 == 0) {
            root.position = glm::vec3(pos(rng), pos(rng), pos(rng));
            root.rotation = random_rotation(rng);
        } else {
            root.position += glm::vec3(small(rng), small(rng), small(rng));
            root.rotation = glm::normalize(glm::angleAxis(10.0f * small(rng), random_unit(rng)) * root.rotation);
        }
        step(rig.chain, params, root, rig.rest, {}, h, s);
        if (!finite(rig.chain, s)) FAIL() << "non-finite state at step " << i;
        peak = std::max(peak, kinetic_energy(rig.chain, s));
        for (std::uint32_t j = 0; j < rig.chain.joint_count; ++j) {
            farthest = std::max(farthest, glm::length(s.x[j] - s.x[0]));
        }
    }
    EXPECT_LT(peak, bound);
    EXPECT_LT(farthest, 2.0f * length);
    std::printf("[ measured ] peak KE %.3g J (bound %.3g J), farthest particle %.3g of L\n",
                static_cast<double>(peak), static_cast<double>(bound), static_cast<double>(farthest / length));
}

// A strand dragged across a sphere and a capsule by its root. Bound: no particle deeper
// than 1e-3 m inside a collider (radius + thickness) after any step; the collision pass
// is the last of every iteration, so only rounding should remain. The test also checks
// that the strand did touch each collider, so it can fail.
TEST(RodSolver, CollidersKeepParticlesOut) {
    const float length = 0.4f, thickness = 0.005f;
    const Rig rig = make_rig(arc_shape(13, length, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.0f), thickness);
    SolverParams params;
    params.stiffness = 0.1f;  // soft, so gravity drapes it over the collider
    const Collider sphere{glm::vec3(0, 1.25f, 0), glm::vec3(0, 1.25f, 0), 0.15f};
    const Collider capsule{glm::vec3(-0.3f, 1.3f, -0.1f), glm::vec3(0.3f, 1.2f, 0.1f), 0.08f};
    for (int which = 0; which < 2; ++which) {
        const std::span<const Collider> colliders(which == 0 ? &sphere : &capsule, 1);
        Transform root{glm::vec3(-0.05f, 1.6f, -0.3f), glm::quat(1, 0, 0, 0)};
        ChainState s = initial_state(rig.chain, root, rig.rest);
        float deepest = -1.0f;  // penetration depth, m (negative = outside)
        float closest = 1e9f;   // closest approach to the surface
        for (int frame = 0; frame < 240; ++frame) {
            // The root sweeps over the collider and back.
            const float t = static_cast<float>(frame) / 60.0f;
            root.position.z = -0.3f + 0.6f * std::sin(0.5f * kPi * t) * std::sin(0.5f * kPi * t);
            step(rig.chain, params, root, rig.rest, colliders, 1.0f / 60.0f, s);
            for (std::uint32_t i = 1; i < rig.chain.joint_count; ++i) {
                float gap;
                if (which == 0) {
                    gap = glm::length(position(s, i) - sphere.a) - sphere.radius - thickness;
                } else {
                    const glm::vec3 ab = capsule.b - capsule.a;
                    const float u = std::clamp(glm::dot(position(s, i) - capsule.a, ab) / glm::dot(ab, ab), 0.0f, 1.0f);
                    gap = glm::length(position(s, i) - (capsule.a + u * ab)) - capsule.radius - thickness;
                }
                deepest = std::max(deepest, -gap);
                closest = std::min(closest, gap);
            }
        }
        EXPECT_LT(deepest, 1e-3f) << (which == 0 ? "sphere" : "capsule");
        EXPECT_LT(closest, 2e-3f) << "the strand never touched the " << (which == 0 ? "sphere" : "capsule");
        std::printf("[ measured ] %s: deepest penetration %.3g m\n", which == 0 ? "sphere" : "capsule",
                    static_cast<double>(deepest));
    }
}

// The skinning output: composing the local rotations from the root gives each bone a
// world rotation whose bone axis points at the next particle (within 1e-5 rad-ish:
// |cross| < 1e-4, float rounding over 12 products of rotations).
TEST(RodSolver, LocalRotationsPointBonesAtTheNextParticle) {
    const Rig rig = make_rig(arc_shape(13, 0.4f, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.2f));
    SolverParams params;
    Transform root{glm::vec3(0, 1.5f, 0), glm::angleAxis(0.4f, glm::vec3(0, 1, 0))};
    ChainState s = initial_state(rig.chain, root, rig.rest);
    for (int frame = 0; frame < 30; ++frame) {
        root.position.x = 0.3f * std::sin(static_cast<float>(frame) * 0.3f);
        step(rig.chain, params, root, rig.rest, {}, 1.0f / 60.0f, s);
    }
    const ChainPose p = pose(rig.chain, s);
    glm::quat world = root.rotation;
    for (std::uint32_t i = 0; i + 1 < rig.chain.joint_count; ++i) {
        world = world * p.local_rotation[i];
        const glm::vec3 axis = world * rig.chain.bone_axis[i];
        const glm::vec3 to_next = glm::normalize(p.position[i + 1] - p.position[i]);
        EXPECT_LT(glm::length(glm::cross(axis, to_next)), 1e-4f) << "bone " << i;
        EXPECT_GT(glm::dot(axis, to_next), 0.0f) << "bone " << i;
    }
}

// The result depends on the frame rate only through the substep count: one 1/30 s frame
// and two 1/60 s frames both run four 1/120 s substeps; with a root moving at constant
// velocity the interpolated roots coincide up to float rounding of the interpolation
// (~1e-7 m), which 240 substeps of chain dynamics amplify; bound 1e-4 m (0.025% of the
// chain length, measured 3.8e-5 m).
TEST(RodSolver, FrameRateIndependentAtEqualSubsteps) {
    const Rig rig = make_rig(arc_shape(13, 0.4f, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.1f));
    SolverParams params;
    Transform root{glm::vec3(0, 1.5f, 0), glm::quat(1, 0, 0, 0)};
    ChainState a = initial_state(rig.chain, root, rig.rest), b = a;
    for (int frame = 1; frame <= 60; ++frame) {
        Transform mid = root, end = root;
        mid.position.x = 1.0f * (static_cast<float>(2 * frame - 1) / 60.0f);
        end.position.x = 1.0f * (static_cast<float>(2 * frame) / 60.0f);
        step(rig.chain, params, end, rig.rest, {}, 1.0f / 30.0f, a);
        step(rig.chain, params, mid, rig.rest, {}, 1.0f / 60.0f, b);
        step(rig.chain, params, end, rig.rest, {}, 1.0f / 60.0f, b);
    }
    float diff = 0.0f;
    for (std::uint32_t i = 0; i < rig.chain.joint_count; ++i) diff = std::max(diff, glm::length(a.x[i] - b.x[i]));
    EXPECT_LT(diff, 1e-4f);
}

// SPEC A.5's measured outcome, under gravity: an instant switch of rest shape (a
// straight hanging 13-joint strand told to curl by 0.3 rad per segment). With
// suppression on the switch is applied kinematically, so the peak kinetic energy must be
// at most a quarter of the peak without it (measured: ~3e-3 J against ~1.3 J), and the
// chain must still end on the new shape: within 5% of its length, the sag of the curl
// under gravity at the default rest_stiffness (measured 3.2%).
TEST(RodSolver, MomentumSuppressionQuartersThePeakKineticEnergy) {
    const float length = 0.3f;
    const ChainShape straight = arc_shape(13, length, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.0f);
    const ChainShape curl = arc_shape(13, length, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.3f);
    const Rig rig = make_rig(straight);
    const Transform root{glm::vec3(0, 1.5f, 0), glm::quat(1, 0, 0, 0)};
    float peak[2] = {0.0f, 0.0f};
    float final_error[2] = {0.0f, 0.0f};
    for (int on = 0; on < 2; ++on) {
        SolverParams params;
        params.momentum_suppression = on ? 1.0f : 0.0f;
        ChainState s = initial_state(rig.chain, root, straight);
        for (int frame = 0; frame < 60; ++frame) step(rig.chain, params, root, straight, {}, 1.0f / 60.0f, s);
        for (int frame = 0; frame < 600; ++frame) {
            step(rig.chain, params, root, curl, {}, 1.0f / 60.0f, s);
            peak[on] = std::max(peak[on], kinetic_energy(rig.chain, s));
        }
        final_error[on] = rest_error(rig.chain, s, root, curl);
    }
    EXPECT_GT(peak[0], 0.0f) << "without suppression the switch must set the chain moving";
    EXPECT_LE(peak[1], 0.25f * peak[0]);
    EXPECT_LT(final_error[1], 0.05f * length);
    EXPECT_LT(final_error[0], 0.05f * length);
    std::printf("[ measured ] switch under gravity: peak KE %.3g J with suppression, %.3g J without; final error %.3g of L\n",
                static_cast<double>(peak[1]), static_cast<double>(peak[0]), static_cast<double>(final_error[1] / length));
}

// A chain displaced from its rest shape, gravity off, no suppression: plain dynamics must
// bring it to rest on its rest shape. Bound: 1e-3 of the length after 10 s (measured
// ~1e-5: float rounding of the goals).
TEST(RodSolver, ConvergesToItsRestShapeWithoutGravity) {
    const float length = 0.3f;
    const ChainShape straight = arc_shape(13, length, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.0f);
    const ChainShape curl = arc_shape(13, length, glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), 0.3f);
    const Rig rig = make_rig(straight);
    const Transform root{glm::vec3(4, 1.5f, -3), glm::angleAxis(0.7f, glm::normalize(glm::vec3(1, 1, 0)))};
    SolverParams params;
    params.gravity = glm::vec3(0.0f);
    params.momentum_suppression = 0.0f;
    ChainState s = initial_state(rig.chain, root, straight);
    for (int frame = 0; frame < 600; ++frame) step(rig.chain, params, root, curl, {}, 1.0f / 60.0f, s);
    const float error = rest_error(rig.chain, s, root, curl);
    EXPECT_LT(error, 1e-3f * length);
    EXPECT_LT(kinetic_energy(rig.chain, s), 1e-9f);
    std::printf("[ measured ] displaced strand without gravity, after 10 s: %.3g of L\n", static_cast<double>(error / length));
}

// The artist's shape holds against gravity: a strand curling up and sideways (a bunny
// ear's shape) ends within 5% of its length of the rest shape at the default
// rest_stiffness (measured ~1-3%). Without the rest-pose attraction (rest_stiffness 0)
// it must sag far more (>= 30% of its length), which shows why solver.hpp adds it.
TEST(RodSolver, HoldsItsShapeAgainstGravity) {
    const float length = 0.3f;
    const ChainShape ear = arc_shape(12, length, glm::vec3(0.2f, 1, 0), glm::vec3(0, 0, 1), 0.08f);
    const Rig rig = make_rig(ear);
    const Transform root{glm::vec3(0, 1.7f, 0), glm::quat(1, 0, 0, 0)};
    float error[2] = {0.0f, 0.0f};
    for (int attract = 0; attract < 2; ++attract) {
        SolverParams params;
        if (!attract) params.rest_stiffness = 0.0f;
        ChainState s = initial_state(rig.chain, root, ear);
        for (int frame = 0; frame < 300; ++frame) step(rig.chain, params, root, ear, {}, 1.0f / 60.0f, s);
        error[attract] = rest_error(rig.chain, s, root, ear);
    }
    EXPECT_LT(error[1], 0.05f * length);
    EXPECT_GT(error[0], 0.3f * length);
    std::printf("[ measured ] upright ear under gravity: %.3g of L with rest_stiffness 0.1, %.3g without\n",
                static_cast<double>(error[1] / length), static_cast<double>(error[0] / length));
}
