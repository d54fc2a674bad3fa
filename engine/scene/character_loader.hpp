#pragma once
/// @file
/// The version-2 parts of the scene format (docs/scene-format.md): characters, crowds
/// and the moving camera. Used by scene_loader.cpp; errors follow its style (file, JSON
/// path, what was expected).

#include <kodawari/scene.hpp>

#include "scene/json_reader.hpp"

namespace kodawari::scene_detail {

/// The most character instances and chain instances one scene may hold (they bound the
/// memory of the rod state: about 3.5 kB per chain).
inline constexpr std::uint64_t kMaxCharacterInstances = 100'000;
inline constexpr std::uint64_t kMaxChainInstances = 1'000'000;

/// Reads `characters` (a non-empty array) and `crowds` (absent: one instance of every
/// character at the origin) into `scene`.
[[nodiscard]] Result<void> read_characters(const JsonReader& r, const JsonNode& characters, const JsonNode& crowds,
                                           Scene& scene);

/// Reads the camera's version-2 keys (`projection`, `orbit`, `path`, `keyframes`) into
/// camera.motion, after read_camera has read `position`, `target` and `fov_deg`.
[[nodiscard]] Result<void> read_camera_motion(const JsonReader& r, const JsonNode& node, CameraSpec& camera);

}  // namespace kodawari::scene_detail
