// Driven birds told to fly their route (KW_MOTION_ROUTE, the contract in
// shaders/shared/birds.h above BirdMotionGpu): on every bird backend (cpu-reference, cpu at
// every instruction set of the machine, vulkan) such a bird flies its route as its twin,
// the same bird as a plain route bird, does, plus the cubic Hermite correction that eases
// it from where its motion left it; in batches that mix such lanes with flown ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "backends/bird_backend_test.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/backends/compare.hpp"
#include "kodawari/birds/flight.hpp"
#include "kodawari/vulkan/backend_factory.hpp"

using namespace kodawari;

namespace {

// Not a multiple of any SIMD lane count (16, 8, 4) nor of the workgroup size (64): the
// last batch and workgroup are partial.
constexpr std::uint32_t kBirds = 37;
constexpr std::uint32_t kFrames = 360;  // 6 s: the latest bird has landed and folded its wings
constexpr std::uint32_t kChunk = 64;    // several simulate() calls: the state carries over

// How bird i is driven: along a motion of its own (flown), on its route from frame 0, or
// flown until its t0 and then on its route, eased from where the motion left it (joins).
enum class Lane { Route, Flown, Joins };
Lane lane_of(std::uint32_t i, bool joins) {
    if (i % 4 == 1) return Lane::Flown;
    if (joins && i % 4 == 3) return Lane::Joins;
    return Lane::Route;
}

// An open route with arc-length timing that takes off from a perch, climbs and turns, and
// lands on another: every mode a route sample can decide.
birds::BirdWorld twin_world() {
    birds::BirdWorld world;
    world.frames = kFrames;
    birds::RouteSpec r;
    r.points = {{0, 0, 0},  {0, 1, 3},  {0, 3, 6},  {0, 4, 9},  {0, 5, 12},
                {4, 6, 15}, {8, 6, 16}, {12, 6, 17}, {15, 4, 17}, {18, 3, 17}};
    r.modes = {birds::SegmentMode::TakeOff, birds::SegmentMode::Auto, birds::SegmentMode::Landing};
    EXPECT_TRUE(world.add_route(r, "perch to perch").ok());
    const birds::WingType types[] = {birds::WingType::Pigeon, birds::WingType::Gull, birds::WingType::Hawk,
                                     birds::WingType::Starling};
    for (std::uint32_t i = 0; i < kBirds; ++i) {
        const birds::WingTypeSpec& spec = birds::wing_type_spec(types[i % 4]);
        gpu::BirdParams b{};
        const auto f = static_cast<float>(i);
        // A later bird leaves its perch later (a negative time offset), as flocks do.
        b.offset = {0.4f * static_cast<float>(i % 5), 0.3f * static_cast<float>(i % 3), -0.2f * static_cast<float>(i % 7),
                    -0.013f * f};
        b.motion = {12.0f + 0.1f * static_cast<float>(i % 9), spec.flap_frequency, spec.amplitude, 0.027f * f};
        b.ids = {0, static_cast<std::uint32_t>(types[i % 4]), 0, 0};
        b.flight = birds::flight_params(spec);
        b.shape = birds::shape_params(spec);
        world.birds.push_back(b);
    }
    return world;
}

// The same birds, driven (motion slot i for bird i). Their own time offset and speed are
// not their twins': on the route they fly the motion's (KW_MOTION_ROUTE), which are.
birds::BirdWorld driven_world(const birds::BirdWorld& twins) {
    birds::BirdWorld world = twins;
    for (std::uint32_t i = 0; i < kBirds; ++i) {
        world.birds[i].ids.z = i;
        world.birds[i].ids.w = KW_BIRD_DRIVEN;
        world.birds[i].offset.w += 0.37f;
        world.birds[i].motion.x += 5.0f;
    }
    world.driven = kBirds;
    return world;
}

// Bird i's correction: t0 on one of its frames (so s is exactly 0 there), T of 0.5 to 2 s.
std::uint32_t first_frame_of(std::uint32_t i) { return 60 + 3 * i; }
float inv_span_of(std::uint32_t i) {
    const float inv[] = {2.0f, 1.0f, 0.8f, 0.5f};
    return inv[(i / 4) % 4];
}

// A flown bird's motion: a level circle of its own, with a time offset and speed slot
// holding values no route would be flown at (unused, as for a flocking domain's birds).
gpu::BirdMotionGpu circle(std::uint32_t i, float t) {
    const float w = 0.5f, radius = 20.0f, x0 = 0.3f * static_cast<float>(i);
    gpu::BirdMotionGpu m{};
    m.position = {x0 + radius * std::sin(w * t), 10.0f, radius * std::cos(w * t), static_cast<float>(KW_MOTION_FLOWN)};
    m.velocity = {radius * w * std::cos(w * t), 0.0f, -radius * w * std::sin(w * t), -1e6f};
    m.acceleration = {-radius * w * w * std::sin(w * t), 0.0f, -radius * w * w * std::cos(w * t), 0.0f};
    return m;
}

// frames x birds of motion. Without `corrected` the birds on their route get 1/T = 0 (no
// correction) and an e_p, e_v and t0 that must then be ignored; with it, a correction each,
// and the joining birds leave their circle at t0 onto the route, from where they were.
std::vector<gpu::BirdMotionGpu> motion_of(const birds::BirdWorld& twins, bool corrected) {
    const float dt = twins.uniforms().physics.z;
    std::vector<gpu::BirdMotionGpu> out(std::size_t{kFrames} * kBirds);
    for (std::uint32_t i = 0; i < kBirds; ++i) {
        const gpu::BirdParams& twin = twins.birds[i];
        const Lane lane = lane_of(i, corrected);
        const float t0 = static_cast<float>(first_frame_of(i)) * dt;
        gpu::BirdMotionGpu route{};
        route.position = {0.7f, -0.4f, 1.1f, static_cast<float>(KW_MOTION_ROUTE)};
        route.velocity = {0.5f, 1.0f, -2.0f, twin.offset.w};
        route.acceleration = {t0, corrected ? inv_span_of(i) : 0.0f, twin.motion.x, 0.0f};
        if (lane == Lane::Joins) {  // from the circle's position and velocity at t0
            const birds::RouteSample at = birds::sample_route(twins, twin.ids.x, t0 + twin.offset.w, twin.motion.x);
            const gpu::BirdMotionGpu left = circle(i, t0);
            route.position = {left.position.x - (at.position.x + twin.offset.x), left.position.y - (at.position.y + twin.offset.y),
                              left.position.z - (at.position.z + twin.offset.z), static_cast<float>(KW_MOTION_ROUTE)};
            route.velocity = {left.velocity.x - at.velocity.x, left.velocity.y - at.velocity.y, left.velocity.z - at.velocity.z,
                              twin.offset.w};
        }
        for (std::uint32_t k = 0; k < kFrames; ++k) {
            const float now = static_cast<float>(k) * dt;
            const bool flown = lane == Lane::Flown || (lane == Lane::Joins && now < t0);
            out[std::size_t{k} * kBirds + i] = flown ? circle(i, now) : route;
        }
    }
    return out;
}

struct Frames {
    std::vector<gpu::BirdPose> poses;
    std::vector<gpu::BirdDiag> diag;
    const gpu::BirdPose& pose(std::uint32_t k, std::uint32_t i) const { return poses[std::size_t{k} * kBirds + i]; }
    const gpu::BirdDiag& at(std::uint32_t k, std::uint32_t i) const { return diag[std::size_t{k} * kBirds + i]; }
};

Frames fly(BirdBackend& backend, const birds::BirdWorld& world, std::span<const gpu::BirdMotionGpu> motion = {}) {
    Frames r;
    r.poses.resize(std::size_t{kFrames} * kBirds);
    r.diag.resize(r.poses.size());
    EXPECT_TRUE(backend.load(world).ok());
    for (std::uint32_t done = 0; done < kFrames;) {
        const std::uint32_t n = std::min(kChunk, kFrames - done);
        const std::size_t first = std::size_t{done} * kBirds, count = std::size_t{n} * kBirds;
        if (!motion.empty()) {
            EXPECT_TRUE(backend.drive(motion.subspan(first, count)).ok());
        }
        const auto step = backend.simulate(n, {std::span(r.poses).subspan(first, count), std::span(r.diag).subspan(first, count)});
        EXPECT_TRUE(step.ok()) << (step.ok() ? "" : step.error().message);
        done += n;
    }
    return r;
}

double wide(float x) { return static_cast<double>(x); }
double distance(const gpu::vec4& a, const gpu::vec4& b) {
    const double dx = wide(a.x) - wide(b.x), dy = wide(a.y) - wide(b.y), dz = wide(a.z) - wide(b.z);
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}
bool same_bits(const void* a, const void* b, std::size_t bytes) { return std::memcmp(a, b, bytes) == 0; }

// The correction of shared/birds.h in double, written from its formulas (the polynomial
// forms, not the kernels' Horner forms): c, c' and c'' at s for 1/T = inv.
struct Correction {
    double p[3], v[3], a[3];
};
Correction correction(const gpu::BirdMotionGpu& m, double s) {
    const double inv = m.acceleration.y, span = 1.0 / inv;
    const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
    const double d00 = 6 * s * s - 6 * s, d10 = 3 * s * s - 4 * s + 1;
    const double dd00 = s >= 1.0 ? 0.0 : 12 * s - 6, dd10 = s >= 1.0 ? 0.0 : 6 * s - 4;
    const double ep[3] = {m.position.x, m.position.y, m.position.z}, ev[3] = {m.velocity.x, m.velocity.y, m.velocity.z};
    Correction c{};
    for (int j = 0; j < 3; ++j) {
        c.p[j] = ep[j] * h00 + span * ev[j] * h10;
        c.v[j] = ep[j] * d00 * inv + ev[j] * d10;
        c.a[j] = ep[j] * dd00 * inv * inv + ev[j] * dd10 * inv;
    }
    return c;
}

class RouteMotion : public testing_support::BirdBackendTest {
protected:
    // The driven world on this backend against cpu-reference with compare.hpp's
    // BirdTolerances (positions within 1e-5 of the route's length, rotations, phase and
    // blend within 1e-4, modes exactly); on the cpu backend, which repeats flight.cpp's
    // arithmetic but for the wingbeat's sines, the kinematics, the attitude and the speed
    // fraction are moreover the reference's bits (tests/backends/test_backends.cpp).
    void expect_reference_parity(const birds::BirdWorld& world, const Frames& got, std::span<const gpu::BirdMotionGpu> motion) {
        const Frames ref = fly(*reference_, world, motion);
        BirdComparison comparison(world);
        comparison.add(0, kFrames, ref.poses, got.poses, ref.diag, got.diag);
        for (const Deviation& d : comparison.results()) {
            EXPECT_TRUE(d.within()) << d.quantity << ": max " << d.max << " " << d.unit << " (bird " << d.worst_bird << ", frame "
                                    << d.worst_frame << ") over tolerance " << d.tolerance;
        }
        if (GetParam() == BackendKind::CpuReference) {
            EXPECT_TRUE(same_bits(ref.poses.data(), got.poses.data(), ref.poses.size() * sizeof(gpu::BirdPose)));
        } else if (GetParam() == BackendKind::Cpu) {
            std::size_t differ = 0, first = 0;
            for (std::size_t e = 0; e < ref.diag.size(); ++e) {
                const gpu::BirdDiag &a = ref.diag[e], &b = got.diag[e];
                const bool same = same_bits(&a.velocity, &b.velocity, 2 * sizeof(gpu::vec4)) &&
                                  same_bits(&a.attitude, &b.attitude, sizeof(gpu::vec4)) &&
                                  same_bits(&a.flight.x, &b.flight.x, sizeof(float));
                // The position's x and z (route, offset and correction; y adds the bob,
                // which takes the wingbeat's sine).
                const bool placed = same_bits(&ref.poses[e].position.x, &got.poses[e].position.x, sizeof(float)) &&
                                    same_bits(&ref.poses[e].position.z, &got.poses[e].position.z, sizeof(float));
                if ((!same || !placed) && differ++ == 0) first = e;
            }
            EXPECT_EQ(differ, 0u) << "bird-frames whose exact quantities differ from cpu-reference's; first: frame "
                                  << first / kBirds << ", bird " << first % kBirds;
        }
    }

};

}  // namespace

TEST_P(RouteMotion, WithoutACorrectionADrivenBirdFliesItsRouteAsItsTwin) {
    const birds::BirdWorld twins = twin_world();
    const birds::BirdWorld driven = driven_world(twins);
    const std::vector<gpu::BirdMotionGpu> motion = motion_of(twins, false);
    const Frames twin = fly(*backend_, twins);
    const Frames got = fly(*backend_, driven, motion);

    // The route is flown whole: take-off, cruise, landing, and the bird perched again.
    bool took_off = false, landed = false, folded = false;
    for (std::uint32_t k = 0; k < kFrames; ++k) {
        const gpu::BirdDiag& d = twin.at(k, 0);
        took_off = took_off || d.acceleration.w == static_cast<float>(KW_MODE_TAKEOFF);
        landed = landed || d.acceleration.w == static_cast<float>(KW_MODE_LANDING);
        folded = folded || (d.acceleration.w == static_cast<float>(KW_MODE_LANDING) && d.flight.x == 0.0f);
    }
    EXPECT_TRUE(took_off && landed && folded) << "take-off " << took_off << ", landing " << landed << ", perched " << folded;

    // Lane by lane the route's bits wherever a kernel's lanes do not depend on each other
    // (cpu-reference bird by bird; the cpu backend's lanes, flown ones beside them). The
    // vulkan pipelines with and without driven birds are two compilations: BirdTolerances.
    const BirdTolerances tol;
    const double position_tol = tol.position_fraction_of_route * std::max(1.0, double{twins.max_route_length()});
    std::size_t route_lanes = 0;
    for (std::uint32_t i = 0; i < kBirds; ++i) {
        if (lane_of(i, false) != Lane::Route) continue;
        ++route_lanes;
        for (std::uint32_t k = 0; k < kFrames; ++k) {
            const gpu::BirdPose &a = twin.pose(k, i), &b = got.pose(k, i);
            const gpu::BirdDiag &da = twin.at(k, i), &db = got.at(k, i);
            ASSERT_EQ(da.acceleration.w, db.acceleration.w) << "mode, frame " << k << ", bird " << i;
            ASSERT_EQ(da.flight.x, db.flight.x) << "speed fraction, frame " << k << ", bird " << i;
            if (GetParam() == BackendKind::Vulkan) {
                ASSERT_LE(distance(a.position, b.position), position_tol) << "frame " << k << ", bird " << i;
                for (int p = 0; p < KW_PART_COUNT; ++p) {
                    ASSERT_LE(quaternion_angle(a.rotation[p], b.rotation[p]), tol.rotation_rad)
                        << "part " << p << ", frame " << k << ", bird " << i;
                }
            } else {
                ASSERT_TRUE(same_bits(&a, &b, sizeof(a))) << "pose, frame " << k << ", bird " << i;
                ASSERT_TRUE(same_bits(&da, &db, sizeof(da))) << "diagnostics, frame " << k << ", bird " << i;
            }
        }
    }
    EXPECT_EQ(route_lanes, 28u);
    expect_reference_parity(driven, got, motion);
}

TEST_P(RouteMotion, TheCorrectionEasesFromTheMotionOntoTheRoute) {
    const birds::BirdWorld twins = twin_world();
    const birds::BirdWorld driven = driven_world(twins);
    const std::vector<gpu::BirdMotionGpu> motion = motion_of(twins, true);
    const Frames twin = fly(*backend_, twins);
    const Frames got = fly(*backend_, driven, motion);
    const float dt = twins.uniforms().physics.z;
    const bool vulkan = GetParam() == BackendKind::Vulkan;

    // Float tolerances of the eased quantities: route and correction are a few tens of
    // metres (m/s, m/s^2) summed in float, a few ulp of 3e-6 m each; 1e-4 leaves room for
    // the vulkan compilation's own rounding (no `precise` on the route's position).
    constexpr double kTol = 1e-4;
    constexpr double kAngleTol = 1e-4;  // rad: compare.hpp's rotation tolerance
    std::size_t exact_frames = 0;
    for (std::uint32_t i = 0; i < kBirds; ++i) {
        const Lane lane = lane_of(i, true);
        if (lane == Lane::Flown) continue;
        const gpu::BirdParams& bird = driven.birds[i];
        const std::uint32_t f0 = first_frame_of(i);
        for (std::uint32_t k = lane == Lane::Joins ? f0 : 0; k < kFrames; ++k) {
            const gpu::BirdMotionGpu& m = motion[std::size_t{k} * kBirds + i];
            const float now = static_cast<float>(k) * dt;
            // s as the contract defines it (the frame's float time), so s = 1 exactly from
            // the frame the kernels stop correcting on.
            const float s = std::clamp((now - m.acceleration.x) * m.acceleration.y, 0.0f, 1.0f);
            const Correction c = correction(m, s);
            const gpu::BirdPose &a = twin.pose(k, i), &b = got.pose(k, i);
            const gpu::BirdDiag &da = twin.at(k, i), &db = got.at(k, i);
            const std::string where = "frame " + std::to_string(k) + ", bird " + std::to_string(i) + ", s " + std::to_string(s);
            if (lane == Lane::Route) {
                // Every exact decision is the route sample's: the mode and the speed
                // fraction, and with them the phase, the blend and the wings' looks.
                ASSERT_EQ(da.acceleration.w, db.acceleration.w) << "mode, " << where;
                ASSERT_EQ(da.flight.x, db.flight.x) << "speed fraction, " << where;
                ASSERT_EQ(da.attitude.w, db.attitude.w) << "phase, " << where;
                // The position is the twin's (route + offset, with the same wingbeat bob)
                // plus c: e_p at t0, 0 from t0 + T on.
                const double dp[3] = {wide(b.position.x) - wide(a.position.x), wide(b.position.y) - wide(a.position.y),
                                  wide(b.position.z) - wide(a.position.z)};
                for (int j = 0; j < 3; ++j) ASSERT_NEAR(dp[j], c.p[j], kTol) << "position " << j << ", " << where;
                // At cruise speed (fraction 1) the Body is aligned with the velocity: the
                // attitude's velocity takes c' too (diagnostics: yaw and climb, from the
                // reference's atan2 on every backend but vulkan's own).
                if (db.flight.x == 1.0f) {
                    const double vx = wide(db.velocity.x), vy = wide(db.velocity.y), vz = wide(db.velocity.z);
                    ASSERT_NEAR(wide(db.attitude.x), std::atan2(vx, vz), kAngleTol) << "yaw, " << where;
                    ASSERT_NEAR(wide(db.attitude.y), std::atan2(vy, std::sqrt(vx * vx + vz * vz)), kAngleTol) << "climb, " << where;
                }
            }
            // The velocity and acceleration (diagnostics: the sample's) are the route's
            // (the twin's) plus c' and c''. The joining birds' twins fly the same route
            // sample, so these hold for them too (their modes and looks differ).
            const double dv[3] = {wide(db.velocity.x) - wide(da.velocity.x), wide(db.velocity.y) - wide(da.velocity.y),
                                  wide(db.velocity.z) - wide(da.velocity.z)};
            const double dacc[3] = {wide(db.acceleration.x) - wide(da.acceleration.x),
                                    wide(db.acceleration.y) - wide(da.acceleration.y),
                                    wide(db.acceleration.z) - wide(da.acceleration.z)};
            for (int j = 0; j < 3; ++j) {
                ASSERT_NEAR(dv[j], c.v[j], kTol) << "velocity " << j << ", " << where;
                ASSERT_NEAR(dacc[j], c.a[j], kTol * (1.0 + std::fabs(c.a[j]))) << "acceleration " << j << ", " << where;
            }
            if (s >= 1.0f && !vulkan) {
                // Past t0 + T the kernels add nothing: the route's own bits.
                ASSERT_TRUE(same_bits(&da.velocity, &db.velocity, 3 * sizeof(float))) << "velocity, " << where;
                ASSERT_TRUE(same_bits(&da.acceleration, &db.acceleration, 3 * sizeof(float))) << "acceleration, " << where;
                if (lane == Lane::Route) {
                    ASSERT_TRUE(same_bits(&a.position, &b.position, 3 * sizeof(float))) << "position, " << where;
                }
                ++exact_frames;
            }
        }
        if (lane == Lane::Joins) {
            // Where the motion left it: at t0 the bird is where its circle was (x, z; y
            // also carries the wingbeat's bob, at most KW_BOB_HEIGHT body lengths) and
            // flies at its velocity.
            const gpu::BirdMotionGpu left = circle(i, static_cast<float>(f0) * dt);
            const gpu::BirdPose& p = got.pose(f0, i);
            const gpu::BirdDiag& d = got.at(f0, i);
            const double bob = KW_BOB_HEIGHT * wide(bird.shape.x) * wide(bird.motion.z);
            EXPECT_NEAR(p.position.x, left.position.x, kTol) << "bird " << i;
            EXPECT_NEAR(p.position.y, left.position.y, bob + kTol) << "bird " << i;
            EXPECT_NEAR(p.position.z, left.position.z, kTol) << "bird " << i;
            EXPECT_NEAR(d.velocity.x, left.velocity.x, kTol) << "bird " << i;
            EXPECT_NEAR(d.velocity.y, left.velocity.y, kTol) << "bird " << i;
            EXPECT_NEAR(d.velocity.z, left.velocity.z, kTol) << "bird " << i;
        }
    }
    if (!vulkan) {
        EXPECT_GT(exact_frames, 0u);
    }
    expect_reference_parity(driven, got, motion);
}

INSTANTIATE_TEST_SUITE_P(All, RouteMotion, testing_support::all_backend_kinds(), testing_support::backend_test_name);
