#pragma once
// The flocks of the scene format (docs/scene-format.md, "Flocks"): routes, formations and
// flocking. Used by scene_loader.cpp; errors follow its style (file, JSON path, what was
// expected).

#include <vector>

#include <kodawari/scene/scene.hpp>

#include "scene/json_reader.hpp"

namespace kodawari::scene_detail {

/// Reads `$.flocks` (a non-empty array) into `out`: every flock's keys checked, at most
/// 10 000 000 birds in all, names unique and predators naming a flock without flocking.
[[nodiscard]] Result<void> read_flocks(const JsonReader& r, const JsonNode& flocks, std::vector<FlockSpec>& out);

}  // namespace kodawari::scene_detail
