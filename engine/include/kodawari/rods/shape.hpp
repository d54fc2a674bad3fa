#pragma once
/// @file
/// Chain shapes and their blending (SPEC A.1, A.2). A shape is given as joint positions
/// and orientations in the chain root's frame; for blending it is re-expressed as one
/// rotation per segment so that any blend keeps the base shape's segment lengths.

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::rods {

/// The most joints one chain may have. Fixed so that the GPU path can keep a chain in
/// fixed-size arrays (one workgroup per chain).
inline constexpr std::uint32_t kMaxChainJoints = 32;

/// A shape C = (X, O) (SPEC A.1): joint positions and unit orientations in the chain
/// root's frame, joint 0 first. Joint 0 is at the origin of that frame.
struct ChainShape {
    std::vector<glm::vec3> positions;
    std::vector<glm::quat> orientations;
};

/// What every shape of a chain shares (SPEC A.2): the base shape's first segment
/// direction e and its segment lengths l_i, which blending never changes.
struct ShapeBasis {
    glm::vec3 first_direction{0.0f, 1.0f, 0.0f};  ///< e, unit
    std::vector<float> lengths;                   ///< l_0 .. l_{n-2}, m, all > 0
    [[nodiscard]] std::uint32_t joint_count() const { return static_cast<std::uint32_t>(lengths.size() + 1); }
};

/// A shape in the blending representation (SPEC A.2): `rotations[0]` = r_0 takes e to
/// segment 0's direction, `rotations[i]` = r_i takes segment i-1's direction to segment
/// i's (n-1 entries); `orientations` are the joint orientations o_i, unchanged (n entries).
struct RotationShape {
    std::vector<glm::quat> rotations;
    std::vector<glm::quat> orientations;
};

/// The basis of a chain from its base shape C_0. Fails on fewer than 2 or more than
/// kMaxChainJoints joints, mismatched array sizes, a segment shorter than 1e-6 m, or a
/// non-unit orientation.
[[nodiscard]] KODAWARI_API Result<ShapeBasis> make_basis(const ChainShape& base);

/// Sets `shape.orientations` to the default of the scene files and the C API: each joint's
/// local +Y along its segment (the last joint's along the last segment), by the shortest
/// arc from +Y. Needs at least 2 positions, consecutive ones apart (a segment of zero
/// length has no direction).
KODAWARI_API void default_orientations(ChainShape& shape);

/// The shortest-arc rotation taking unit vector `from` to unit vector `to`. For exactly
/// or nearly opposite vectors (where the arc is not unique) it is the half turn about
/// an axis perpendicular to `from`, chosen deterministically.
[[nodiscard]] KODAWARI_API glm::quat shortest_arc(glm::vec3 from, glm::vec3 to);

/// Positions -> rotations (SPEC A.2). Only segment directions are used: a shape whose
/// segment lengths differ from the basis' comes back with the basis' lengths from
/// to_positions(). Fails on a size mismatch with `basis` or a segment shorter than 1e-6 m.
[[nodiscard]] KODAWARI_API Result<RotationShape> to_rotations(const ShapeBasis& basis, const ChainShape& shape);

/// Rotations -> positions by forward kinematics (SPEC A.2): x_0 = 0, dir_0 = r_0 e,
/// dir_i = r_i dir_{i-1}, x_{i+1} = x_i + l_i dir_i. Orientations are copied.
[[nodiscard]] KODAWARI_API ChainShape to_positions(const ShapeBasis& basis, const RotationShape& shape);

/// The blend sum_k w_k C_k (SPEC A.2): for every r_i and o_i, the normalized weighted sum
/// of the shapes' quaternions, each first negated if needed into the hemisphere of the
/// base's (shapes[0]). `weights` has one entry per shape (weights[0] = w_0, the base's);
/// they are expected to sum to 1 (view_weights() does) but only their ratios matter.
/// Where a weighted sum cancels out (possible only with w_0 = 0 and examples half a turn
/// apart) the base's quaternion is used.
[[nodiscard]] KODAWARI_API RotationShape blend(std::span<const RotationShape> shapes, std::span<const float> weights);

}  // namespace kodawari::rods
