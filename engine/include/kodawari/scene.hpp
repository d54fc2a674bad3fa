#pragma once
/// @file
/// Scenes: the JSON format of docs/scene-format.md (birds now, characters later), its
/// loader with errors that name the file and the JSON path, and the step from a scene
/// to the data the backends run.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "birds/world.hpp"
#include "result.hpp"

namespace kodawari {

/// A fixed camera (the viewer and renderer use it; the birds ignore it).
struct CameraSpec {
    std::array<float, 3> position = {0.0f, 30.0f, -120.0f};
    std::array<float, 3> target = {0.0f, 30.0f, 0.0f};
    float fov_deg = 50.0f;
};

/// A leader route made from a seed: `segments` Bezier segments through random
/// waypoints inside a box around `center`, C1-continuous.
struct GeneratedRouteSpec {
    std::uint64_t seed = 1;
    std::uint32_t segments = 6;
    std::array<float, 3> center = {0.0f, 40.0f, 0.0f};
    std::array<float, 3> extent = {150.0f, 30.0f, 150.0f};  ///< half sizes of the box (m)
    bool loop = true;
};

/// How the birds of a flock spread around the leader route.
struct FormationSpec {
    std::array<float, 3> spread = {4.0f, 2.0f, 4.0f};  ///< half sizes of the offset box (m)
    std::uint32_t route_variants = 1;  ///< distinct jittered copies of the leader route
    float jitter = 0.0f;               ///< max displacement of the variants' junction points (m)
    float trail = 0.0f;                ///< time offsets spread over [0, trail] seconds
};

/// One flock: `count` birds of a wing type following a route.
struct FlockSpec {
    std::string name;
    birds::WingType wing_type = birds::WingType::Pigeon;
    std::uint32_t count = 1;
    std::uint64_t seed = 1;
    std::optional<float> speed;      ///< m/s; default: the wing type's cruise speed
    float speed_jitter = 0.0f;       ///< relative, uniform in [-j, j]
    std::optional<float> frequency;  ///< Hz; default: the wing type's
    float frequency_jitter = 0.0f;   ///< relative
    std::optional<float> amplitude;  ///< default: the wing type's
    float amplitude_jitter = 0.0f;   ///< relative
    float phase_jitter = 1.0f;       ///< initial phase uniform in [0, phase_jitter) cycles
    std::optional<birds::RouteSpec> route;            ///< explicit control points, or
    std::optional<GeneratedRouteSpec> generated_route;  ///< one made from a seed
    birds::RouteTiming timing = birds::RouteTiming::ArcLength;
    FormationSpec formation;
};

/// A whole scene file.
struct Scene {
    std::string path;  ///< where it was loaded from (for messages)
    std::string name;
    float fps = 60.0f;
    float duration = 10.0f;  ///< seconds
    CameraSpec camera;
    birds::FlightSettings flight;
    std::vector<FlockSpec> flocks;

    /// Number of frames: round(duration * fps), at least 1.
    [[nodiscard]] std::uint32_t frame_count() const;
};

/// Reads and checks a scene file. Errors name the file, the JSON path and what was
/// expected (Error::Kind::InvalidInput), or the I/O failure.
[[nodiscard]] Result<Scene> load_scene(const std::string& path);

/// Parses scene text; `path` is only used in messages.
[[nodiscard]] Result<Scene> parse_scene(const std::string& text, const std::string& path);

/// Builds the backends' data: routes, arc-length tables and every bird's constants.
/// Deterministic: the same scene gives the same bits.
[[nodiscard]] Result<birds::BirdWorld> build_bird_world(const Scene& scene);

}  // namespace kodawari
