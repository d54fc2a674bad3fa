#pragma once
/// @file
/// The state of a rod world after a frame, as a rod backend hands it back; below the
/// backends so that its readers (the exporters, the renderer) need no backend.

#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace kodawari {

/// What a caller reads back after a frame. Per-joint arrays hold RodWorld::joint_count
/// entries, chain c's joints from chains[c].joint_begin.
struct ChainSnapshot {
    std::vector<glm::vec3> positions;        ///< world
    std::vector<glm::quat> orientations;     ///< world, the particles' own
    std::vector<glm::vec3> rest;             ///< the blended rest shape of the frame, placed by the chain root (world)
    std::vector<glm::vec3> view_directions;  ///< per chain: d, in its reference joint's frame (SPEC A.3)
    /// Per chain, rods::kMaxViewExamples + 1 entries: w_0 (the base's) .. w_m, then zeros.
    std::vector<float> weights;
};

}  // namespace kodawari
