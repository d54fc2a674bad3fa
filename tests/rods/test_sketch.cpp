// Sketching a shape from a view (SPEC A.6): the algorithm, and the end-to-end effect on the
// chain's rest shape seen from the sketching camera (the save-back: test_sketch_save.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "kodawari/core/atomic_file.hpp"
#include "kodawari/vulkan/backend_factory.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/rods/sketch.hpp"
#include "kodawari/scene/scene_edit.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

using rods::ImageCamera;
using rods::SketchInput;
using rods::SketchResult;
using Json = nlohmann::ordered_json;

constexpr double kPi = 3.14159265358979323846;

std::string ahoge_path() { return std::string(KODAWARI_SOURCE_DIR) + "/scenes/ahoge.json"; }

// A chain of 9 joints, 2 cm segments, at a head-like height, turned, seen from 2 m.
SketchInput base_input(rods::Camera::Projection projection) {
    SketchInput in;
    in.camera.projection = projection;
    in.camera.position = {0.3f, 1.7f, 2.0f};
    in.camera.target = {0.0f, 1.6f, 0.0f};
    in.camera.fov_deg = 40.0f;
    in.camera.width = 1280;
    in.camera.height = 720;
    in.root.position = {0.05f, 1.65f, 0.02f};
    in.root.rotation = glm::angleAxis(0.7f, glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f)));
    in.reference.position = {0.0f, 1.5f, 0.0f};
    in.reference.rotation = glm::angleAxis(0.4f, glm::vec3(0.0f, 1.0f, 0.0f));
    in.lengths.assign(8, 0.02f);
    in.influence = 6.0f;
    return in;
}

// A curl drawn over the picture, starting `start` away from the root's projection.
std::vector<glm::dvec2> curl(glm::dvec2 from, double radius_px, double turn, int points) {
    std::vector<glm::dvec2> s;
    for (int i = 0; i < points; ++i) {
        const double a = turn * i / (points - 1);
        s.push_back(from + radius_px * glm::dvec2(1.0 - std::cos(a), -std::sin(a)));
    }
    return s;
}

glm::dvec2 root_pixel(const SketchInput& in) {
    return glm::dvec2(rods::project_to_pixels(in.camera, glm::dvec3(in.root.position)));
}

// Checks shared by every successful sketch: root fixed, lengths kept, the root-frame
// shape is the world result, default orientations, finite.
void expect_consistent(const SketchInput& in, const SketchResult& r) {
    const std::size_t n = in.lengths.size() + 1;
    ASSERT_EQ(r.shape.positions.size(), n);
    ASSERT_EQ(r.shape.orientations.size(), n);
    ASSERT_EQ(r.world_positions.size(), n);
    EXPECT_EQ(r.shape.positions[0], glm::vec3(0.0f));
    EXPECT_LT(glm::length(r.world_positions[0] - glm::dvec3(in.root.position)), 1e-9);
    for (std::size_t i = 1; i < n; ++i) {
        const double l = glm::length(glm::dvec3(r.shape.positions[i] - r.shape.positions[i - 1]));
        EXPECT_NEAR(l / static_cast<double>(in.lengths[i - 1]), 1.0, 1e-5) << "segment " << i - 1;
        const glm::vec3 world = in.root.position + in.root.rotation * r.shape.positions[i];
        EXPECT_LT(glm::length(glm::dvec3(world) - r.world_positions[i]), 1e-5) << "joint " << i;
        for (int k = 0; k < 3; ++k) EXPECT_TRUE(std::isfinite(r.shape.positions[i][k]));
    }
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t seg = std::min(i, n - 2);
        const glm::vec3 dir = glm::normalize(r.shape.positions[seg + 1] - r.shape.positions[seg]);
        EXPECT_LT(glm::length(r.shape.orientations[i] * glm::vec3(0.0f, 1.0f, 0.0f) - dir), 1e-4f) << "joint " << i;
    }
    EXPECT_NEAR(glm::length(r.view.direction), 1.0f, 1e-5f);
    EXPECT_EQ(r.view.influence, in.influence);
}

TEST(Sketch, JointsProjectOntoTheStrokeWithTheirLengths) {
    SketchInput in = base_input(rods::Camera::Projection::Perspective);
    // Drawn 12 px off the root: the stroke is translated to start there.
    const glm::dvec2 start = root_pixel(in) + glm::dvec2(12.0, -7.0);
    in.stroke = curl(start, 80.0, 2.5, 40);
    auto r = rods::sketch_view_example(in);
    ASSERT_TRUE(r.ok()) << r.error().message;
    const SketchResult& s = r.value();
    expect_consistent(in, s);
    EXPECT_NEAR(s.stroke_offset.x, -12.0, 1e-6);
    EXPECT_NEAR(s.stroke_offset.y, 7.0, 1e-6);
    // The stroke (about 200 px) is longer than the chain (16 cm at 2 m: about 80 px).
    EXPECT_EQ(s.joints_on_stroke, 9u);
    EXPECT_GT(s.stroke_used, 0.1);
    EXPECT_LT(s.stroke_used, 0.9);
    // Each projected joint lies on the drawn stroke (moved by the offset) within a pixel,
    // measured here independently of the diagnostics.
    std::vector<glm::dvec2> moved;
    for (glm::dvec2 p : in.stroke) moved.push_back(p + glm::dvec2(-12.0, 7.0));
    for (std::size_t i = 0; i < s.world_positions.size(); ++i) {
        const glm::dvec2 px(rods::project_to_pixels(in.camera, s.world_positions[i]));
        EXPECT_LT(rods::distance_to_polyline(px, moved), 1.0) << "joint " << i;
    }
    EXPECT_LT(s.max_error_px, 1e-3);
    EXPECT_EQ(s.max_overrun_px, 0.0);
    // The joints lie on the plane through the root parallel to the image (SPEC A.6).
    const glm::dvec3 fwd = glm::normalize(glm::dvec3(in.camera.target - in.camera.position));
    for (const glm::dvec3& p : s.world_positions) {
        EXPECT_NEAR(glm::dot(p - glm::dvec3(in.root.position), fwd), 0.0, 1e-9);
    }
    // d of SPEC A.3: from the reference joint towards the camera, in its frame.
    const glm::vec3 d = glm::normalize(glm::inverse(in.reference.rotation) * (in.camera.position - in.reference.position));
    EXPECT_LT(glm::length(s.view.direction - d), 1e-5f);
}

TEST(Sketch, JointsWalkAlongTheStrokeInOrder) {
    // A stroke that goes right and comes back 2 px lower: "the first point along the
    // stroke" puts the first joints on the way out and the later ones on the way back,
    // not across the gap.
    SketchInput in = base_input(rods::Camera::Projection::Perspective);
    const glm::dvec2 r0 = root_pixel(in);
    in.stroke = {r0, r0 + glm::dvec2(50.0, 0.0), r0 + glm::dvec2(50.0, 2.0), r0 + glm::dvec2(-100.0, 2.0)};
    auto r = rods::sketch_view_example(in);
    ASSERT_TRUE(r.ok()) << r.error().message;
    expect_consistent(in, r.value());
    EXPECT_EQ(r.value().joints_on_stroke, 9u);
    EXPECT_LT(r.value().max_error_px, 1e-3);
    // x of the projections rises to the turn, then falls.
    const auto& px = r.value().pixels;
    EXPECT_GT(px[2].x, px[1].x);
    EXPECT_LT(px[8].x, px[6].x);
    EXPECT_NEAR(px[8].y, r0.y + 2.0, 1e-6);
}

TEST(Sketch, AStrokeShorterThanTheChainContinuesAlongItsLastDirection) {
    SketchInput in = base_input(rods::Camera::Projection::Perspective);
    const glm::dvec2 r0 = root_pixel(in);
    // About 2.5 segments long on screen, ending in a direction (1, -1)/sqrt(2).
    const double seg_px = glm::length(glm::dvec2(rods::project_to_pixels(
                                          in.camera, glm::dvec3(in.root.position) + glm::dvec3(0.02, 0.0, 0.0))) -
                                      r0);
    in.stroke = {r0, r0 + glm::dvec2(0.0, -1.2 * seg_px), r0 + glm::dvec2(0.0, -1.2 * seg_px) + glm::dvec2(1.0, -1.0) * (0.9 * seg_px)};
    auto r = rods::sketch_view_example(in);
    ASSERT_TRUE(r.ok()) << r.error().message;
    const SketchResult& s = r.value();
    expect_consistent(in, s);
    EXPECT_GE(s.joints_on_stroke, 2u);
    EXPECT_LE(s.joints_on_stroke, 4u);
    EXPECT_DOUBLE_EQ(s.stroke_used, 1.0);
    EXPECT_GT(s.max_overrun_px, seg_px);  // the tip is well past the drawn end
    // The joints past the end lie on the line of the last stroke piece, beyond its end.
    const glm::dvec2 a = in.stroke[1], b = in.stroke[2];
    const glm::dvec2 dir = glm::normalize(b - a);
    for (std::size_t i = s.joints_on_stroke; i < s.pixels.size(); ++i) {
        const glm::dvec2 v = s.pixels[i] - a;
        EXPECT_LT(std::abs(v.x * dir.y - v.y * dir.x), 1e-3) << "joint " << i << " off the extension";
        EXPECT_GT(glm::dot(v, dir), glm::length(b - a)) << "joint " << i;
    }
}

TEST(Sketch, AStrokeShorterThanOneSegmentLaysTheChainStraight) {
    // No joint can be placed on a stroke half a pixel long: every joint is on its
    // extension, reported as such, and the chain is still whole and finite.
    SketchInput in = base_input(rods::Camera::Projection::Perspective);
    const glm::dvec2 r0 = root_pixel(in) + glm::dvec2(300.0, 200.0);  // far from the root: moved there
    in.stroke = {r0, r0 + glm::dvec2(0.3, -0.4)};
    auto r = rods::sketch_view_example(in);
    ASSERT_TRUE(r.ok()) << r.error().message;
    const SketchResult& s = r.value();
    expect_consistent(in, s);
    EXPECT_EQ(s.joints_on_stroke, 1u);
    EXPECT_EQ(s.stroke_used, 1.0);  // all of it, and more
    EXPECT_GT(s.max_overrun_px, 10.0);
    const glm::dvec3 tip = s.world_positions.back() - s.world_positions.front();
    EXPECT_NEAR(glm::length(tip), 0.16, 1e-6);  // straight: the full length
}

TEST(Sketch, OrthographicCamera) {
    SketchInput in = base_input(rods::Camera::Projection::Orthographic);
    in.camera.ortho_height = 0.5f;
    in.stroke = curl(root_pixel(in), 200.0, 2.0, 30);
    auto r = rods::sketch_view_example(in);
    ASSERT_TRUE(r.ok()) << r.error().message;
    const SketchResult& s = r.value();
    expect_consistent(in, s);
    EXPECT_EQ(s.joints_on_stroke, 9u);
    for (const glm::dvec2& px : s.pixels) EXPECT_LT(rods::distance_to_polyline(px, s.stroke), 1.0);
    // 720 px per 0.5 m, the same everywhere on the plane: consecutive joints, 0.02 m apart
    // on a plane parallel to the image, are 0.02 m * 1440 px/m = 28.8 px apart.
    EXPECT_NEAR(glm::length(s.pixels[1] - s.pixels[0]), 28.8, 1e-3);
    // d = -R_ref^T forward for an orthographic camera (SPEC A.3).
    const glm::vec3 fwd = glm::normalize(in.camera.target - in.camera.position);
    EXPECT_LT(glm::length(s.view.direction - glm::inverse(in.reference.rotation) * -fwd), 1e-5f);
}

TEST(Sketch, BadInputIsReported) {
    SketchInput in = base_input(rods::Camera::Projection::Perspective);
    in.stroke = {root_pixel(in)};
    auto one = rods::sketch_view_example(in);
    ASSERT_FALSE(one.ok());
    EXPECT_EQ(one.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(one.error().message.find("at least 2 points"), std::string::npos) << one.error().message;

    in.stroke = {root_pixel(in), {std::nan(""), 3.0}};
    auto nan = rods::sketch_view_example(in);
    ASSERT_FALSE(nan.ok());
    EXPECT_NE(nan.error().message.find("point 1"), std::string::npos) << nan.error().message;

    in.stroke = {{5.0, 5.0}, {5.0, 5.0}, {5.0, 5.0}};
    auto still = rods::sketch_view_example(in);
    ASSERT_FALSE(still.ok());
    EXPECT_NE(still.error().message.find("no length"), std::string::npos) << still.error().message;

    in.stroke = {{5.0, 5.0}, {50.0, 5.0}};
    in.root.position = {0.0f, 1.7f, 3.0f};  // behind the camera
    auto behind = rods::sketch_view_example(in);
    ASSERT_FALSE(behind.ok());
    EXPECT_NE(behind.error().message.find("behind the camera"), std::string::npos) << behind.error().message;
}

// ---- end to end: the sketched example is what the chain shows from that camera

struct Seen {
    rods::RestShape rest;
    std::vector<glm::dvec2> pixels;
};

// The chain's rest shape (SPEC A.3 + A.2) at frame 0 under `camera`, and its projection.
Seen rest_seen(const RodScene& rs, const ImageCamera& camera) {
    rods::RodFrame f = rs.frame(0);
    f.camera = camera.view_camera();
    Seen s;
    s.rest = rods::rest_shape(rs.world, 0, f);
    for (const glm::vec3& p : s.rest.shape.positions) {
        const glm::vec3 world = f.roots[0].position + f.roots[0].rotation * p;
        s.pixels.push_back(glm::dvec2(rods::project_to_pixels(camera, glm::dvec3(world))));
    }
    return s;
}

double max_distance(const std::vector<glm::dvec2>& pixels, const std::vector<glm::dvec2>& stroke) {
    double e = 0.0;
    for (const glm::dvec2& p : pixels) e = std::max(e, rods::distance_to_polyline(p, stroke));
    return e;
}

TEST(SketchEndToEnd, TheRestShapeSeenFromTheCameraFollowsTheStroke) {
    // ahoge with only its "back" example: from the front camera of frame 0 that example's
    // weight is ((d_back . d + 1) / 2)^4 < 1e-6, so after the sketch (influence 50, weight
    // 1 at its own direction) the blend is the sketched shape up to that weight, the 6
    // written digits (1e-6 m on 0.14 m) and float rounding: far below 0.5 px.
    Json json = Json::parse(testing_support::file_bytes(ahoge_path()));
    Json& views = json["characters"][0]["chains"][0]["views"];
    views = Json::array({views[1]});
    const std::string text = json.dump(2) + "\n";
    auto scene = parse_scene(text, ahoge_path());
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    auto rod_scene = build_rod_scene(scene.value());
    ASSERT_TRUE(rod_scene.ok()) << rod_scene.error().message;
    const RodScene& rs = rod_scene.value();
    ASSERT_EQ(rs.world.templates[0].name, "girl/ahoge");

    const ImageCamera camera = ImageCamera::from_pose(rs.camera_pose(0), rs.fov_deg, 1280, 720);
    const rods::RodFrame f = rs.frame(0);
    SketchInput in;
    in.camera = camera;
    in.root = f.roots[0];
    in.reference = f.reference[0];
    in.lengths = rs.world.templates[0].basis.lengths;
    in.influence = 50.0f;
    // A lock swept to the picture's left and down, unlike the base curl (up, then over to
    // the right).
    const glm::dvec2 r0 = root_pixel(in);
    for (int i = 0; i < 30; ++i) {
        const double t = i / 29.0;
        in.stroke.push_back(r0 + glm::dvec2(-150.0 * t, 40.0 * std::sin(0.5 * kPi * t)));
    }
    auto sketched = rods::sketch_view_example(in);
    ASSERT_TRUE(sketched.ok()) << sketched.error().message;
    ASSERT_EQ(sketched.value().joints_on_stroke, 12u);

    const Seen before = rest_seen(rs, camera);
    const double before_px = max_distance(before.pixels, sketched.value().stroke);
    EXPECT_GT(before_px, 20.0) << "the base shape should not already follow the stroke";

    ViewSpec view;
    view.view = sketched.value().view;
    view.shape = sketched.value().shape;
    auto edit = add_view_example(text, "ahoge.json", "girl/ahoge", view);
    ASSERT_TRUE(edit.ok()) << edit.error().message;
    auto scene2 = parse_scene(edit.value().text, ahoge_path());
    ASSERT_TRUE(scene2.ok()) << scene2.error().message;
    auto rs2 = build_rod_scene(scene2.value());
    ASSERT_TRUE(rs2.ok()) << rs2.error().message;
    const Seen after = rest_seen(rs2.value(), camera);
    EXPECT_GT(after.rest.weights[2], 0.999f);
    const double after_px = max_distance(after.pixels, sketched.value().stroke);
    EXPECT_LT(after_px, 0.5) << "before the sketch: " << before_px << " px";

    // The simulated chain settles towards the new shape too: step the CPU backend for a
    // second from rest and compare the tips on screen. Gravity and the solver's finite
    // stiffness keep it off the exact rest shape, so this only checks the direction of
    // the change (the tip moves more than halfway towards the sketched tip).
    const auto tip_after_a_second = [&](const RodScene& r) {
        auto backend = make_rod_backend(BackendKind::Cpu, BackendOptions{});
        EXPECT_TRUE(backend.ok());
        rods::RodFrame frame = r.frame(0);
        frame.camera = camera.view_camera();
        EXPECT_TRUE(backend.value()->load(r.world, frame).ok());
        for (std::uint32_t i = 1; i <= 60; ++i) {
            r.frame(i, frame);
            frame.camera = camera.view_camera();
            EXPECT_TRUE(backend.value()->step(frame).ok());
        }
        ChainSnapshot snap;
        EXPECT_TRUE(backend.value()->read(snap).ok());
        return glm::dvec2(rods::project_to_pixels(camera, glm::dvec3(snap.positions.at(11))));
    };
    const glm::dvec2 tip_before = tip_after_a_second(rs);
    const glm::dvec2 tip_after = tip_after_a_second(rs2.value());
    const glm::dvec2 sketched_tip = sketched.value().pixels.back();
    EXPECT_LT(glm::length(tip_after - sketched_tip), 0.5 * glm::length(tip_before - sketched_tip))
        << "tip before " << tip_before.x << "," << tip_before.y << " after " << tip_after.x << "," << tip_after.y
        << " sketched " << sketched_tip.x << "," << sketched_tip.y;
}

}  // namespace
}  // namespace kodawari
