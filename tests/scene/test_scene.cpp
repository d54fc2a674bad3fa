// The scene format (docs/scene-format.md): the shipped scenes load and build, the
// build is deterministic, and every kind of bad input is reported with the file, the
// exact JSON path and what was expected.

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <kodawari/scene/scene.hpp>
#include "test_paths.hpp"

namespace {

using kodawari::Error;
using kodawari::Result;
using kodawari::Scene;
using nlohmann::json;

std::string source_path(const std::string& relative) { return std::string(KODAWARI_SOURCE_DIR) + "/" + relative; }

// A small valid scene that the error tests break one key at a time.
json valid_scene() {
    return json::parse(R"({
      "format": "kodawari-scene",
      "version": 1,
      "flocks": [
        {
          "wing_type": "gull",
          "count": 10,
          "route": {"points": [[0, 10, 0], [10, 10, 0], [20, 12, 5], [30, 12, 10],
                               [40, 12, 15], [50, 10, 20], [60, 10, 20]]}
        }
      ]
    })");
}

std::string error_of(const Result<Scene>& result) {
    if (result.ok()) return "(no error)";
    EXPECT_EQ(result.error().kind, Error::Kind::InvalidInput);
    return result.error().message;
}

std::string parse_error(const json& scene) { return error_of(kodawari::parse_scene(scene.dump(), "test.json")); }

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

template <typename T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Every bird's constants lie in the ranges its flock allows.
void expect_birds_within_flocks(const Scene& scene, const kodawari::birds::BirdWorld& world) {
    std::size_t first = 0;
    for (const kodawari::FlockSpec& flock : scene.flocks) {
        const auto& wing = kodawari::birds::wing_type_spec(flock.wing_type);
        const float speed = flock.speed.value_or(wing.cruise_speed);
        const float frequency = flock.frequency.value_or(wing.flap_frequency);
        for (std::size_t b = first; b < first + flock.count; ++b) {
            const auto& bird = world.birds[b];
            ASSERT_LT(bird.ids.x, world.routes.size()) << "bird " << b;
            EXPECT_EQ(bird.ids.y, static_cast<std::uint32_t>(flock.wing_type)) << "bird " << b;
            EXPECT_LE(std::fabs(bird.motion.x / speed - 1.0f), flock.speed_jitter + 1e-6f) << "bird " << b;
            EXPECT_LE(std::fabs(bird.motion.y / frequency - 1.0f), flock.frequency_jitter + 1e-6f) << "bird " << b;
            EXPECT_GT(bird.motion.z, 0.0f);
            EXPECT_GE(bird.motion.w, 0.0f);
            EXPECT_LT(bird.motion.w, 1.0f);
            EXPECT_GE(bird.offset.w, 0.0f);
            EXPECT_LE(bird.offset.w, flock.formation.trail);
            for (int i = 0; i < 3; ++i) {
                const float offset = i == 0 ? bird.offset.x : (i == 1 ? bird.offset.y : bird.offset.z);
                EXPECT_LE(std::fabs(offset), flock.formation.spread[static_cast<std::size_t>(i)]) << "bird " << b;
            }
        }
        first += flock.count;
    }
}

TEST(SceneFormat, ShippedFlockLoadsAndBuilds) {
    const auto scene = kodawari::load_scene(source_path("scenes/flock.json"));
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_EQ(scene.value().flocks.size(), 3u);
    EXPECT_EQ(scene.value().frame_count(), 600u);
    const auto world = kodawari::build_bird_world(scene.value());
    ASSERT_TRUE(world.ok()) << world.error().message;
    EXPECT_EQ(world.value().birds.size(), 270u);
    EXPECT_NE(world.value().birds.size() % 64, 0u) << "the shipped flock should exercise a partial workgroup";
    EXPECT_EQ(world.value().frames, 600u);
    // All three wing types fly.
    std::vector<int> per_type(3, 0);
    for (const auto& bird : world.value().birds) ++per_type.at(bird.ids.y);
    EXPECT_GT(per_type[0], 0);
    EXPECT_GT(per_type[1], 0);
    EXPECT_GT(per_type[2], 0);
    expect_birds_within_flocks(scene.value(), world.value());
}

TEST(SceneFormat, ShippedMurmurationLoadsAndBuilds) {
    const auto scene = kodawari::load_scene(source_path("scenes/murmuration.json"));
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const auto world = kodawari::build_bird_world(scene.value());
    ASSERT_TRUE(world.ok()) << world.error().message;
    EXPECT_EQ(world.value().birds.size(), 12000u);
    ASSERT_EQ(world.value().routes.size(), 16u);
    for (const auto& route : world.value().routes) EXPECT_NE(route.flags.x & KW_ROUTE_LOOP, 0u);
    // Birds are spread over all variants.
    std::vector<int> per_route(16, 0);
    for (const auto& bird : world.value().birds) ++per_route.at(bird.ids.x);
    for (int n : per_route) EXPECT_EQ(n, 12000 / 16);
    expect_birds_within_flocks(scene.value(), world.value());
}

TEST(SceneFormat, BuildIsDeterministic) {
    for (const char* file : {"scenes/flock.json", "scenes/murmuration.json"}) {
        const auto scene = kodawari::load_scene(source_path(file));
        ASSERT_TRUE(scene.ok()) << scene.error().message;
        const auto a = kodawari::build_bird_world(scene.value());
        const auto b = kodawari::build_bird_world(scene.value());
        ASSERT_TRUE(a.ok() && b.ok());
        EXPECT_TRUE(same_bytes(a.value().birds, b.value().birds)) << file;
        EXPECT_TRUE(same_bytes(a.value().control_points, b.value().control_points)) << file;
        EXPECT_TRUE(same_bytes(a.value().arc_samples, b.value().arc_samples)) << file;
        EXPECT_TRUE(same_bytes(a.value().routes, b.value().routes)) << file;
    }
}

TEST(SceneFormat, SeedChangesTheBirds) {
    json doc = valid_scene();
    doc["flocks"][0]["speed_jitter"] = 0.1;
    const auto a = kodawari::parse_scene(doc.dump(), "test.json");
    doc["flocks"][0]["seed"] = 2;
    const auto b = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(a.ok() && b.ok());
    const auto wa = kodawari::build_bird_world(a.value());
    const auto wb = kodawari::build_bird_world(b.value());
    ASSERT_TRUE(wa.ok() && wb.ok());
    EXPECT_FALSE(same_bytes(wa.value().birds, wb.value().birds));
}

// formation.shape "ellipsoid": every offset inside the ellipsoid of the spread's
// semi-axes, filling it (some beyond the inscribed ball's radius along the long axis);
// the box (the default) puts some outside that ellipsoid. A bad shape is named.
TEST(SceneFormat, EllipsoidFormationKeepsOffsetsInside) {
    json doc = valid_scene();
    doc["flocks"][0]["count"] = 2001;
    doc["flocks"][0]["formation"] = {{"spread", {8, 2, 4}}};
    const auto outside = [](const kodawari::birds::BirdWorld& w, float& longest) {
        std::size_t n = 0;
        longest = 0.0f;
        for (const auto& b : w.birds) {
            const float r = (b.offset.x / 8.0f) * (b.offset.x / 8.0f) + (b.offset.y / 2.0f) * (b.offset.y / 2.0f) +
                            (b.offset.z / 4.0f) * (b.offset.z / 4.0f);
            n += r > 1.0f + 1e-6f ? 1 : 0;
            longest = std::max(longest, std::fabs(b.offset.x));
        }
        return n;
    };
    const auto box = kodawari::parse_scene(doc.dump(), "test.json");
    doc["flocks"][0]["formation"]["shape"] = "ellipsoid";
    const auto ellipsoid = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(box.ok() && ellipsoid.ok());
    const auto wb = kodawari::build_bird_world(box.value());
    const auto we = kodawari::build_bird_world(ellipsoid.value());
    ASSERT_TRUE(wb.ok() && we.ok());
    float longest_box = 0.0f, longest = 0.0f;
    EXPECT_GT(outside(wb.value(), longest_box), 500u);  // 1 - pi/6 of a box lies outside: about 960 of 2 001
    EXPECT_EQ(outside(we.value(), longest), 0u);
    EXPECT_GT(longest, 7.0f);  // the long axis is filled, not a ball of the short one
    doc["flocks"][0]["formation"]["shape"] = "sphere";
    EXPECT_TRUE(contains(parse_error(doc), "$.flocks[0].formation.shape: expected one of \"box\", \"ellipsoid\"")) << parse_error(doc);
}

// Variants move each junction together with its two handles, so the handle vectors
// (and with them the C1 continuity) are the leader's, and a loop stays closed.
TEST(SceneFormat, RouteVariantsKeepHandlesAndClosure) {
    json doc = valid_scene();
    doc["flocks"][0].erase("route");
    doc["flocks"][0]["generated_route"] = {{"seed", 3}, {"segments", 6}, {"loop", true}};
    doc["flocks"][0]["formation"] = {{"route_variants", 4}, {"jitter", 2.0}};
    const auto scene = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const auto world = kodawari::build_bird_world(scene.value());
    ASSERT_TRUE(world.ok()) << world.error().message;
    const auto& w = world.value();
    ASSERT_EQ(w.routes.size(), 4u);
    const auto point = [&](std::size_t route, std::size_t i) { return w.control_points[w.routes[route].extent.x + i]; };
    const std::size_t last = 3 * w.routes[0].extent.y;
    for (std::size_t r = 0; r < 4; ++r) {
        EXPECT_EQ(point(r, 0).x, point(r, last).x);
        EXPECT_EQ(point(r, 0).y, point(r, last).y);
        EXPECT_EQ(point(r, 0).z, point(r, last).z);
    }
    bool moved = false;
    for (std::size_t k = 0; k + 1 <= last; k += 3) {
        const auto j0 = point(0, k);
        const auto j1 = point(1, k);
        moved = moved || j0.x != j1.x;
        const auto h0 = point(0, k + 1);
        const auto h1 = point(1, k + 1);
        EXPECT_NEAR(h1.x - j1.x, h0.x - j0.x, 1e-4f);
        EXPECT_NEAR(h1.y - j1.y, h0.y - j0.y, 1e-4f);
        EXPECT_NEAR(h1.z - j1.z, h0.z - j0.z, 1e-4f);
        EXPECT_LE(std::fabs(j1.x - j0.x), 2.0f + 1e-4f);
    }
    EXPECT_TRUE(moved);
}

TEST(SceneFormat, DefaultsAndFrameCount) {
    const auto scene = kodawari::parse_scene(valid_scene().dump(), "dir/test.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const Scene& s = scene.value();
    EXPECT_EQ(s.name, "test");
    EXPECT_EQ(s.fps, 60.0f);
    EXPECT_EQ(s.duration, 10.0f);
    EXPECT_EQ(s.flocks[0].name, "flock0");
    EXPECT_EQ(s.flocks[0].seed, 1u);
    EXPECT_EQ(s.flocks[0].phase_jitter, 1.0f);
    EXPECT_EQ(s.flocks[0].timing, kodawari::birds::RouteTiming::ArcLength);
    EXPECT_FALSE(s.flocks[0].speed.has_value());
    Scene custom = s;
    custom.duration = 0.5f;
    custom.fps = 30.0f;
    EXPECT_EQ(custom.frame_count(), 15u);
    custom.duration = 0.001f;
    EXPECT_EQ(custom.frame_count(), 1u);
}

TEST(SceneFormat, FlightSettingsInDegrees) {
    json doc = valid_scene();
    doc["flight"] = {{"max_bank_deg", 45}, {"mode_rule", "seed"}, {"ascend_enter_deg", 20}, {"ascend_exit_deg", 12}};
    const auto scene = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    EXPECT_NEAR(scene.value().flight.max_bank, 0.785398f, 1e-6f);
    EXPECT_NEAR(scene.value().flight.ascend_enter, 0.349066f, 1e-6f);
    EXPECT_EQ(scene.value().flight.mode_rule, kodawari::birds::ModeRule::Seed);
}

TEST(SceneFormat, UnknownKey) {
    json doc = valid_scene();
    doc["flocks"][0]["colour"] = "red";
    EXPECT_EQ(parse_error(doc),
              "test.json: $.flocks[0].colour: unknown key (expected one of: name, wing_type, model, map, count, seed, speed, "
              "speed_jitter, frequency, frequency_jitter, amplitude, amplitude_jitter, phase_jitter, timing, route, "
              "generated_route, formation, flocking)");
    json top = valid_scene();
    top["odd key"] = 1;
    EXPECT_TRUE(contains(parse_error(top), "test.json: $[\"odd key\"]: unknown key (expected one of: format, version"));
}

// "$schema" points editors at docs/scene.schema.json; the loader takes it and ignores its
// value, but still wants the string an editor can follow.
TEST(SceneFormat, SchemaKey) {
    json doc = valid_scene();
    doc["$schema"] = "../docs/scene.schema.json";
    const auto scene = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    doc["$schema"] = 1;
    EXPECT_EQ(parse_error(doc), "test.json: $[\"$schema\"]: expected a non-empty string, got 1");
    json nested = valid_scene();
    nested["flocks"][0]["$schema"] = "../docs/scene.schema.json";
    EXPECT_TRUE(contains(parse_error(nested), "test.json: $.flocks[0][\"$schema\"]: unknown key"));
}

// The scene's name names its output files (out/<name>.glb): one file name, never a path
// out of the output folder. The default, the file's stem, is made one.
TEST(SceneFormat, SceneNameIsAFileName) {
    for (const char* bad : {"../../escape", "a/b", "a\\b", ".", "..", "tab\there"}) {
        json doc = valid_scene();
        doc["name"] = bad;
        EXPECT_TRUE(contains(parse_error(doc), "test.json: $.name: expected a file name")) << bad << ": " << parse_error(doc);
    }
    for (const char* good : {"birds", "birds.v2", "...", "a b", "鳥"}) {
        json doc = valid_scene();
        doc["name"] = good;
        const auto scene = kodawari::parse_scene(doc.dump(), "test.json");
        ASSERT_TRUE(scene.ok()) << good << ": " << scene.error().message;
        EXPECT_EQ(scene.value().name, good);
    }
    EXPECT_EQ(kodawari::as_scene_name("a/b\\c\x01", "x"), "a_b_c_");
    EXPECT_EQ(kodawari::as_scene_name("..", "x"), "x");
    EXPECT_EQ(kodawari::as_scene_name("", "x"), "x");
    const auto unnamed = kodawari::parse_scene(valid_scene().dump(), "dir/...json");
    ASSERT_TRUE(unnamed.ok()) << unnamed.error().message;
    EXPECT_EQ(unnamed.value().name, "scene");  // the stem "..": no file name
}

// A flock's name is one flock, and a predator that is a flock's bird names a flock
// without flocking: each refused at its JSON path.
TEST(SceneFormat, FlockNamesAndThePredatorsFlock) {
    json doc = valid_scene();
    doc["flocks"][0]["name"] = "gulls";
    doc["flocks"].push_back(doc["flocks"][0]);
    EXPECT_EQ(parse_error(doc), "test.json: $.flocks[1].name: \"gulls\" is already the name of flock 0 ($.flocks[0].name); "
                                "expected a name of its own");
    doc["flocks"][1].erase("name");
    doc["flocks"][0]["name"] = "flock1";  // the second one's default
    EXPECT_TRUE(contains(parse_error(doc), "test.json: $.flocks[1]: \"flock1\" is already the name of flock 0"));

    json chase = valid_scene();
    chase["flocks"][0]["name"] = "starlings";
    chase["flocks"].push_back(chase["flocks"][0]);
    chase["flocks"][1]["name"] = "falcon";
    chase["flocks"][0]["flocking"] = json::parse(R"({"predators": [{"from": [0, 10, 0], "to": [50, 10, 0]}, {"flock": "falcon"}]})");
    ASSERT_TRUE(kodawari::parse_scene(chase.dump(), "test.json").ok());
    chase["flocks"][0]["flocking"]["predators"][1]["flock"] = "hawk";
    EXPECT_EQ(parse_error(chase), "test.json: $.flocks[0].flocking.predators[1].flock: \"hawk\": the scene has no flock of that "
                                  "name (its flocks: \"starlings\", \"falcon\"); expected the name of a flock without \"flocking\"");
    chase["flocks"][0]["flocking"]["predators"][1]["flock"] = "starlings";
    EXPECT_TRUE(contains(parse_error(chase), "test.json: $.flocks[0].flocking.predators[1].flock: \"starlings\" flocks itself"));
}

// At most 10 000 000 birds in a scene: a flock past them is told how many are left, or,
// when none are, that the flocks before it hold them all (not "in [1, 0]").
TEST(SceneFormat, BirdsInAllAreBounded) {
    json doc = valid_scene();
    doc["flocks"][0]["count"] = 9999990;
    doc["flocks"].push_back(doc["flocks"][0]);
    doc["flocks"][1]["count"] = 11;
    EXPECT_TRUE(contains(parse_error(doc), "test.json: $.flocks[1].count: expected an integer in [1, 10] (a scene holds at most"))
        << parse_error(doc);
    doc["flocks"][0]["count"] = 10000000;
    EXPECT_EQ(parse_error(doc), "test.json: $.flocks[1].count: the flocks before it hold 10000000 birds, the most a scene "
                                "holds: expected no further flock, got 11 birds");
}

// A bound the loader holds as a float is printed as the float it is ("3.1", not the
// double 3.0999999046325684 it widens to).
TEST(SceneFormat, FloatBoundsPrintAsWritten) {
    json doc = valid_scene();
    doc["flocks"][0]["flocking"] = json::parse(R"({"metric": true, "search_radius": 3.1, "separation_distance": 3.3})");
    EXPECT_EQ(parse_error(doc), "test.json: $.flocks[0].flocking.separation_distance: expected at most search_radius (3.1 m), "
                                "got 3.3");
}

TEST(SceneFormat, WrongType) {
    json doc = valid_scene();
    doc["fps"] = "sixty";
    EXPECT_EQ(parse_error(doc), "test.json: $.fps: expected a finite number in [0.01, 1000], got \"sixty\"");
    json loop = valid_scene();
    loop["flocks"][0]["route"]["loop"] = 1;
    EXPECT_EQ(parse_error(loop), "test.json: $.flocks[0].route.loop: expected true or false, got 1");
    json point = valid_scene();
    point["flocks"][0]["route"]["points"][4][1] = "a";
    EXPECT_EQ(parse_error(point),
              "test.json: $.flocks[0].route.points[4][1]: expected a finite number in [-1000000, 1000000], got \"a\"");
}

// Values are stored as floats; a bound written as itself (0.01, 1e-5) is not a float, and
// must load all the same (found by the schema test's boundary scenes).
TEST(SceneFormat, DecimalBoundsAreInside) {
    json doc = valid_scene();
    doc["fps"] = 0.01;
    const auto scene = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    EXPECT_EQ(scene.value().fps, 0.01f);
    json tiny = valid_scene();
    tiny["duration"] = 1e-50;  // inside (0, 3600] as a double, 0 as a float
    EXPECT_EQ(parse_error(tiny), "test.json: $.duration: expected a finite number in (0, 3600] (as a 32-bit float), got 1e-50");
}

TEST(SceneFormat, OutOfRange) {
    json doc = valid_scene();
    doc["flocks"][0]["count"] = -3;
    EXPECT_EQ(parse_error(doc), "test.json: $.flocks[0].count: expected an integer in [1, 10000000], got -3");
    json jitter = valid_scene();
    jitter["flocks"][0]["speed_jitter"] = 0.95;
    EXPECT_EQ(parse_error(jitter), "test.json: $.flocks[0].speed_jitter: expected a finite number in [0, 0.9], got 0.95");
    json wing = valid_scene();
    wing["flocks"][0]["wing_type"] = "eagle";
    EXPECT_EQ(parse_error(wing),
              "test.json: $.flocks[0].wing_type: expected one of \"pigeon\", \"gull\", \"hawk\", \"hummingbird\", \"starling\", got \"eagle\"");
    json climb = valid_scene();
    climb["flight"] = {{"ascend_exit_deg", 15}};
    EXPECT_EQ(parse_error(climb), "test.json: $.flight.ascend_exit_deg: expected a number below ascend_enter_deg (10), got 15");
}

TEST(SceneFormat, NonFiniteNumbers) {
    json doc = valid_scene();
    doc["flocks"][0]["speed"] = 1.0;
    std::string text = doc.dump();
    const std::string key = "\"speed\":1.0";
    ASSERT_TRUE(contains(text, key));
    text.replace(text.find(key), key.size(), "\"speed\":1e999");
    EXPECT_EQ(error_of(kodawari::parse_scene(text, "test.json")),
              "test.json: $.flocks[0].speed: expected a finite number, got 1e999 (beyond the range of a double)");
    // Inside an array too.
    json points = valid_scene();
    points["flocks"][0]["route"]["points"][2][1] = 12345.0;
    std::string point_text = points.dump();
    point_text.replace(point_text.find("12345.0"), 7, "-1e400");
    EXPECT_EQ(error_of(kodawari::parse_scene(point_text, "test.json")),
              "test.json: $.flocks[0].route.points[2][1]: expected a finite number, got -1e400 (beyond the range of a double)");
    json nan_text = valid_scene();
    nan_text["flocks"][0]["speed"] = "NaN";
    EXPECT_EQ(parse_error(nan_text), "test.json: $.flocks[0].speed: expected a finite number in (0, 1000], got \"NaN\"");
    json nan_lower = valid_scene();
    nan_lower["duration"] = "nan";
    EXPECT_EQ(parse_error(nan_lower), "test.json: $.duration: expected a finite number in (0, 3600], got \"nan\"");
    // A bare NaN is not JSON at all.
    EXPECT_TRUE(contains(error_of(kodawari::parse_scene(R"({"fps": NaN})", "test.json")), "test.json:1:9: JSON syntax error"));
}

TEST(SceneFormat, MissingRequiredKey) {
    json doc = valid_scene();
    doc["flocks"][0].erase("wing_type");
    EXPECT_EQ(parse_error(doc),
              "test.json: $.flocks[0].wing_type: expected one of \"pigeon\", \"gull\", \"hawk\", \"hummingbird\", \"starling\", got nothing (required key "
              "missing)");
    json format = valid_scene();
    format.erase("format");
    EXPECT_EQ(parse_error(format), "test.json: $.format: expected \"kodawari-scene\", got nothing (required key missing)");
    json flocks = valid_scene();
    flocks["flocks"] = json::array();
    EXPECT_EQ(parse_error(flocks), "test.json: $.flocks: expected a non-empty array of flocks, got an empty array");
}

TEST(SceneFormat, WrongNumberOfPoints) {
    json doc = valid_scene();
    doc["flocks"][0]["route"]["points"].erase(6);
    doc["flocks"][0]["route"]["points"].erase(5);
    EXPECT_EQ(parse_error(doc),
              "test.json: $.flocks[0].route.points: expected an array of 3n+1 control points [x, y, z] (n >= 1 cubic "
              "Bezier segments: 4, 7, 10, ... points), got an array of 5 elements");
}

TEST(SceneFormat, RouteAndGeneratedRoute) {
    json doc = valid_scene();
    doc["flocks"][0]["generated_route"] = {{"seed", 1}};
    EXPECT_EQ(parse_error(doc),
              "test.json: $.flocks[0].generated_route: expected exactly one of \"route\" and \"generated_route\", got both");
    json neither = valid_scene();
    neither["flocks"][0].erase("route");
    EXPECT_EQ(parse_error(neither),
              "test.json: $.flocks[0]: expected exactly one of \"route\" and \"generated_route\", got neither");
}

TEST(SceneFormat, CoincidentControlPoints) {
    json doc = valid_scene();
    doc["flocks"].push_back(doc["flocks"][0]);
    doc["flocks"][1]["route"]["points"][2] = doc["flocks"][1]["route"]["points"][1];
    const auto scene = kodawari::parse_scene(doc.dump(), "test.json");
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const auto world = kodawari::build_bird_world(scene.value());
    ASSERT_FALSE(world.ok());
    EXPECT_EQ(world.error().kind, Error::Kind::InvalidInput);
    const std::string& message = world.error().message;
    EXPECT_EQ(message.rfind("test.json: $.flocks[1].route", 0), 0u) << message;
    EXPECT_TRUE(contains(message, "points[2]")) << message;
    EXPECT_TRUE(contains(message, "coincide")) << message;
}

TEST(SceneFormat, SyntaxErrorHasLineAndColumn) {
    const std::string text = "{\n  \"format\": \"kodawari-scene\",\n  \"version\": 1,,\n}";
    const std::string message = error_of(kodawari::parse_scene(text, "test.json"));
    EXPECT_EQ(message.rfind("test.json:3:16: JSON syntax error: ", 0), 0u) << message;
    const std::string truncated = error_of(kodawari::parse_scene("{\"flocks\": [", "test.json"));
    EXPECT_EQ(truncated.rfind("test.json:1:13: JSON syntax error: ", 0), 0u) << truncated;
}

TEST(SceneFormat, DuplicateKey) {
    const std::string text = R"({"format": "kodawari-scene", "version": 1, "flocks": [{"count": 1, "count": 2}]})";
    EXPECT_EQ(error_of(kodawari::parse_scene(text, "test.json")),
              "test.json: $.flocks[0].count: duplicate key (each key may appear once per object)");
}

TEST(SceneFormat, MissingFileIsBadInput) {
    // A missing input file is the caller's mistake: InvalidInput, the command line's exit 2
    // (issue 37's one exit-code policy; a read that fails half way stays Io).
    const auto scene = kodawari::load_scene(source_path("scenes/no-such-scene.json"));
    ASSERT_FALSE(scene.ok());
    EXPECT_EQ(scene.error().kind, Error::Kind::InvalidInput);
    EXPECT_TRUE(contains(scene.error().message, "no-such-scene.json")) << scene.error().message;
}

}  // namespace
