// Chain shapes as segment rotations, and their blending (SPEC A.2).
#include "kodawari/rods/shape.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

namespace kodawari::rods {
namespace {

// Below this a segment has no direction; far below any strand a character has.
constexpr float kMinSegmentLength = 1e-6f;

Result<void> check_sizes(const ChainShape& shape, std::size_t joints) {
    if (shape.positions.size() != joints || shape.orientations.size() != joints) {
        return make_error(Error::Kind::InvalidInput,
                          "chain shape: expected " + std::to_string(joints) + " positions and orientations, got " +
                              std::to_string(shape.positions.size()) + " and " +
                              std::to_string(shape.orientations.size()));
    }
    return {};
}

Result<glm::vec3> segment_direction(const ChainShape& shape, std::size_t i) {
    const glm::vec3 s = shape.positions[i + 1] - shape.positions[i];
    const float len = glm::length(s);
    if (!(len >= kMinSegmentLength)) {  // also rejects NaN
        return make_error(Error::Kind::InvalidInput,
                          "chain shape: segment " + std::to_string(i) + " is shorter than 1e-6 m");
    }
    return s / len;
}

}  // namespace

Result<ShapeBasis> make_basis(const ChainShape& base) {
    const std::size_t n = base.positions.size();
    if (n < 2 || n > kMaxChainJoints) {
        return make_error(Error::Kind::InvalidInput, "chain shape: needs 2 to " + std::to_string(kMaxChainJoints) +
                                                         " joints, got " + std::to_string(n));
    }
    KW_TRY(check_sizes(base, n));
    for (std::size_t i = 0; i < n; ++i) {
        if (!(std::abs(glm::length(base.orientations[i]) - 1.0f) < 1e-3f)) {
            return make_error(Error::Kind::InvalidInput,
                              "chain shape: orientation " + std::to_string(i) + " is not a unit quaternion");
        }
    }
    ShapeBasis basis;
    basis.lengths.resize(n - 1);
    for (std::size_t i = 0; i + 1 < n; ++i) {
        auto dir = segment_direction(base, i);
        if (!dir) return dir.error();
        if (i == 0) basis.first_direction = dir.value();
        basis.lengths[i] = glm::length(base.positions[i + 1] - base.positions[i]);
    }
    return basis;
}

glm::quat shortest_arc(glm::vec3 from, glm::vec3 to) {
    // The half-way vector h = from + to gives q = (from . h^, from x h^) without the
    // cancellation of 1 + dot(from, to) near a half turn: h's components keep their
    // absolute precision, so the angle stays accurate until |h| reaches rounding level.
    const glm::vec3 h = from + to;
    const float h_len = glm::length(h);
    if (h_len < 1e-6f) {
        // Opposite vectors: half turn about the axis perpendicular to `from` built from
        // the coordinate axis least aligned with it (never parallel, so never zero).
        const glm::vec3 a = glm::abs(from);
        const glm::vec3 other = (a.x <= a.y && a.x <= a.z) ? glm::vec3(1, 0, 0)
                                : (a.y <= a.z)              ? glm::vec3(0, 1, 0)
                                                            : glm::vec3(0, 0, 1);
        const glm::vec3 axis = glm::normalize(glm::cross(from, other));
        return glm::quat(0.0f, axis.x, axis.y, axis.z);
    }
    const glm::vec3 hn = h / h_len;
    const glm::vec3 c = glm::cross(from, hn);
    return glm::normalize(glm::quat(glm::dot(from, hn), c.x, c.y, c.z));
}

void default_orientations(ChainShape& shape) {
    const std::size_t n = shape.positions.size();
    assert(n >= 2);
    shape.orientations.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t seg = std::min(i, n - 2);
        const glm::vec3 dir = glm::normalize(shape.positions[seg + 1] - shape.positions[seg]);
        shape.orientations[i] = shortest_arc(glm::vec3(0.0f, 1.0f, 0.0f), dir);
    }
}

Result<RotationShape> to_rotations(const ShapeBasis& basis, const ChainShape& shape) {
    const std::size_t n = basis.joint_count();
    KW_TRY(check_sizes(shape, n));
    RotationShape out;
    out.rotations.resize(n - 1);
    out.orientations = shape.orientations;
    glm::vec3 previous = basis.first_direction;
    for (std::size_t i = 0; i + 1 < n; ++i) {
        auto dir = segment_direction(shape, i);
        if (!dir) return dir.error();
        out.rotations[i] = shortest_arc(previous, dir.value());
        previous = dir.value();
    }
    return out;
}

ChainShape to_positions(const ShapeBasis& basis, const RotationShape& shape) {
    const std::size_t n = basis.joint_count();
    assert(shape.rotations.size() == n - 1 && shape.orientations.size() == n);
    ChainShape out;
    out.positions.resize(n);
    out.orientations = shape.orientations;
    out.positions[0] = glm::vec3(0.0f);
    glm::vec3 dir = basis.first_direction;
    for (std::size_t i = 0; i + 1 < n; ++i) {
        // Renormalized every segment so that rounding in a long product of rotations
        // cannot change the segment lengths (SPEC A.2: lengths are exactly the base's).
        dir = glm::normalize(shape.rotations[i] * dir);
        out.positions[i + 1] = out.positions[i] + basis.lengths[i] * dir;
    }
    return out;
}

namespace {

// Normalized weighted sum of hemisphere-aligned quaternions (SPEC A.2, resolved).
glm::quat blend_one(std::span<const RotationShape> shapes, std::span<const float> weights, bool rotations,
                    std::size_t i) {
    auto pick = [&](std::size_t k) { return rotations ? shapes[k].rotations[i] : shapes[k].orientations[i]; };
    const glm::quat base = pick(0);
    glm::quat sum(0.0f, 0.0f, 0.0f, 0.0f);
    for (std::size_t k = 0; k < shapes.size(); ++k) {
        const glm::quat q = pick(k);
        const float sign = glm::dot(q, base) < 0.0f ? -1.0f : 1.0f;
        sum = sum + (sign * weights[k]) * q;
    }
    const float len = glm::length(sum);
    if (!(len > 1e-12f)) return base;
    return sum / len;
}

}  // namespace

RotationShape blend(std::span<const RotationShape> shapes, std::span<const float> weights) {
    assert(!shapes.empty() && shapes.size() == weights.size());
    const std::size_t segments = shapes[0].rotations.size();
    const std::size_t joints = shapes[0].orientations.size();
    for (const RotationShape& s : shapes) {
        assert(s.rotations.size() == segments && s.orientations.size() == joints);
        (void)s;
    }
    RotationShape out;
    out.rotations.reserve(segments);
    out.orientations.reserve(joints);
    for (std::size_t i = 0; i < segments; ++i) out.rotations.push_back(blend_one(shapes, weights, true, i));
    for (std::size_t i = 0; i < joints; ++i) out.orientations.push_back(blend_one(shapes, weights, false, i));
    return out;
}

}  // namespace kodawari::rods
