// SPEC B.3: Bezier routes, exact derivatives, arc-length and parametric timing.
#include <gtest/gtest.h>

#include <cmath>

#include "kodawari/birds/flight.hpp"

using namespace kodawari::birds;

namespace {

float dist(Vec3 a, Vec3 b) { return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z)); }

// Two segments, C1 at the junction but with handles of very different lengths, so u
// and arc length are far from proportional.
RouteSpec uneven_route() {
    RouteSpec r;
    r.points = {{0, 0, 0}, {2, 0, 10}, {20, 5, 30}, {40, 10, 40}, {80, 30, 60}, {100, 10, 120}, {60, 0, 150}};
    return r;
}

}  // namespace

TEST(Route, RejectsBadControlPoints) {
    BirdWorld world;
    RouteSpec r = uneven_route();
    r.points[2] = r.points[1];
    auto coincident = world.add_route(r, "s.json: $.route");
    ASSERT_FALSE(coincident.ok());
    EXPECT_NE(coincident.error().message.find("s.json: $.route.points[2]: coincides with points[1]"), std::string::npos)
        << coincident.error().message;

    r = uneven_route();
    r.points.pop_back();
    auto count = world.add_route(r, "s.json: $.route");
    ASSERT_FALSE(count.ok());
    EXPECT_NE(count.error().message.find("expected 3n+1"), std::string::npos);

    r = uneven_route();
    r.loop = true;
    EXPECT_FALSE(world.add_route(r, "x").ok()) << "a loop must be closed";

    r = uneven_route();
    r.points[3][1] = std::nanf("");
    EXPECT_FALSE(world.add_route(r, "x").ok());

    // A cusp: the curve runs out and comes back along the same line.
    RouteSpec cusp;
    cusp.points = {{0, 0, 0}, {0, 0, 10}, {0, 0, -10}, {0, 0, 1}};
    EXPECT_FALSE(world.add_route(cusp, "x").ok());
    EXPECT_TRUE(world.routes.empty()) << "failed routes must not be added";
}

TEST(Route, ArcLengthTimingFliesAtConstantSpeed) {
    BirdWorld world;
    auto index = world.add_route(uneven_route(), "x");
    ASSERT_TRUE(index.ok());
    const float speed = 12.0f, dt = 1.0f / 240.0f;
    const float length = world.routes[0].info.x;
    // Float positions near 100 m carry ~1e-5 m of rounding: 2e-3 relative on a 5 cm step.
    for (float t = 0.0f; t + dt < length / speed; t += 0.37f) {
        const Vec3 a = sample_route(world, 0, t, speed).position;
        const Vec3 b = sample_route(world, 0, t + dt, speed).position;
        EXPECT_NEAR(dist(a, b) / dt, speed, 2e-3f * speed) << "t = " << t;
    }
    // The total length matches a fine polyline of the curve (evaluated here in double,
    // independently of the engine) within 1e-5 relative.
    const auto pts = uneven_route().points;
    double polyline = 0.0;
    double px = 0, py = 0, pz = 0;
    for (int seg = 0; seg < 2; ++seg) {
        const auto* b = &pts[3 * seg];
        for (int i = (seg == 0 ? 0 : 1); i <= 20000; ++i) {
            const double u = i / 20000.0, v = 1.0 - u;
            double q[3];
            for (int c = 0; c < 3; ++c) q[c] = v * v * v * double{b[0][c]} + 3 * u * v * v * double{b[1][c]} + 3 * u * u * v * double{b[2][c]} + u * u * u * double{b[3][c]};
            if (seg > 0 || i > 0) polyline += std::sqrt((q[0] - px) * (q[0] - px) + (q[1] - py) * (q[1] - py) + (q[2] - pz) * (q[2] - pz));
            px = q[0], py = q[1], pz = q[2];
        }
    }
    EXPECT_NEAR(length, polyline, 1e-5 * polyline);
    // The end of the arc is the last control point.
    const Vec3 end = sample_route(world, 0, length / speed, speed).position;
    EXPECT_LT(dist(end, {60, 0, 150}), 1e-3f);
}

TEST(Route, VelocityAndAccelerationAreTheTimeDerivativesOfPosition) {
    BirdWorld world;
    ASSERT_TRUE(world.add_route(uneven_route(), "x").ok());
    RouteSpec parametric = uneven_route();
    parametric.timing = RouteTiming::Parametric;
    parametric.segment_duration = 3.0f;
    ASSERT_TRUE(world.add_route(parametric, "x").ok());
    const float speed = 10.0f, h = 1e-2f;
    for (std::uint32_t route : {0u, 1u}) {
        for (float t : {0.5f, 1.7f, 2.9f, 4.2f, 5.5f}) {
            const RouteSample s = sample_route(world, route, t, speed);
            const Vec3 a = sample_route(world, route, t - h, speed).position, b = sample_route(world, route, t + h, speed).position;
            const Vec3 fd{(b.x - a.x) / (2 * h), (b.y - a.y) / (2 * h), (b.z - a.z) / (2 * h)};
            // Central differences: O(h^2) error plus float rounding of ~1e-5 m / h.
            EXPECT_LT(dist(fd, s.velocity), 2e-2f) << "route " << route << " t " << t;
            const Vec3 va = sample_route(world, route, t - h, speed).velocity, vb = sample_route(world, route, t + h, speed).velocity;
            const Vec3 fa{(vb.x - va.x) / (2 * h), (vb.y - va.y) / (2 * h), (vb.z - va.z) / (2 * h)};
            EXPECT_LT(dist(fa, s.acceleration), 5e-2f) << "route " << route << " t " << t;
        }
    }
}

TEST(Route, ParametricTimingIsTheSeeds) {
    BirdWorld world;
    RouteSpec r = uneven_route();
    r.timing = RouteTiming::Parametric;
    r.segment_duration = 2.0f;
    ASSERT_TRUE(world.add_route(r, "x").ok());
    // u = t / duration: after one segment's duration the bird is at the junction point.
    EXPECT_LT(dist(sample_route(world, 0, 2.0f, 0.0f).position, {40, 10, 40}), 1e-4f);
    EXPECT_LT(dist(sample_route(world, 0, 0.0f, 0.0f).position, {0, 0, 0}), 1e-6f);
}

TEST(Route, LoopsWrapAndOpenRoutesFlyOnStraight) {
    BirdWorld world;
    RouteSpec loop;
    loop.points = {{0, 0, 0}, {30, 0, 0}, {30, 0, 30}, {0, 0, 30}, {-30, 0, 30}, {-30, 0, 0}, {0, 0, 0}};
    loop.loop = true;
    ASSERT_TRUE(world.add_route(loop, "x").ok());
    ASSERT_TRUE(world.add_route(uneven_route(), "x").ok());
    const float length = world.routes[0].info.x;
    const float speed = 10.0f;
    EXPECT_LT(dist(sample_route(world, 0, 1.3f, speed).position, sample_route(world, 0, 1.3f + length / speed, speed).position), 1e-3f);
    // Past the end of an open route: straight on along the end tangent at full speed.
    const float open_length = world.routes[1].info.x;
    const RouteSample end = sample_route(world, 1, open_length / speed, speed);
    const RouteSample after = sample_route(world, 1, open_length / speed + 1.0f, speed);
    EXPECT_NEAR(dist(end.position, after.position), speed, 1e-3f);
    EXPECT_LT(dist(end.velocity, after.velocity), 1e-3f);
}
