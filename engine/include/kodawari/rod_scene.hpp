#pragma once
/// @file
/// From a scene's characters to what the rod backends run (SPEC A, C): build_rod_scene
/// (kodawari::io) makes the RodScene of kodawari/rods/rod_scene.hpp (kodawari::sim).

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "kodawari/api.hpp"
#include "gltf/character.hpp"
#include "result.hpp"
#include "rods/kinematics.hpp"
#include "rods/rod_scene.hpp"
#include "rods/world.hpp"
#include "scene.hpp"

namespace kodawari {

/// Builds the rod data of `scene`'s characters and crowds. Deterministic: the same scene
/// gives the same bits (on the same build and platform: the motions use the C library's
/// sin and cos). A scene without characters gives an empty RodScene (no chains).
/// Errors (InvalidInput) name the file and the JSON path.
[[nodiscard]] KODAWARI_API Result<RodScene> build_rod_scene(const Scene& scene);

}  // namespace kodawari
