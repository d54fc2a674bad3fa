#pragma once
// Key reduction for compact glTF animations (`kodawari run --compact`, docs/compact.md):
// pure functions over one channel's keys at every frame that choose the frames to keep,
// so that a player interpolating LINEARly between the kept keys (glTF 2.0 §3.11
// "Animations" and Appendix C "Interpolation": lerp for vectors, slerp for rotations)
// reproduces every dropped key within a bound.
//
// The bounds:
// - translations: the Euclidean distance, in metres;
// - rotations: the angle of the rotation between the two, 2 acos(|q1 . q2|), in radians,
//   measured against the original (float) rotation while interpolating the 16-bit keys
//   actually written (quantize_rotations), so the rounding counts in the bound;
// - scales: relative, per axis: |interpolated - original| <= bound x |original|.
//
// The first and the last frame are always kept. A channel that LINEAR interpolation
// reproduces from its ends alone (a constant one among them) keeps those two keys, not
// one: every channel then spans the whole clip, as the uncompacted file's do, which is
// what importers that take a clip's or an action's length from its curves' ranges
// (Blender's importer, three.js's AnimationClip) need to see the same duration.
// One frame keeps one key.
//
// Greedy, deterministic: from a kept key the span to the next one grows by doubling
// while its end verifies (every key in between within the bound), then is bisected
// between the last verified and the first failing end; a span is at most kMaxSpan
// frames. Each check costs its span, so a channel costs O(frames log kMaxSpan), never
// frames squared, and memory is the channel's own keys.

#include <cstdint>
#include <span>
#include <vector>

#include "core/internal_api.hpp"

namespace kodawari::gltf {

/// The longest span between two kept keys, in frames.
inline constexpr std::uint32_t kMaxSpan = 4096;

/// How a vector channel's error is measured.
enum class VectorMetric {
    Distance,  ///< Euclidean distance (translations, metres)
    Relative,  ///< per axis, relative to the original value (scales)
};

/// The frames kept (ascending, first and last among them) and the largest error over
/// every frame of the channel (0 for an exact one).
struct Reduction {
    std::vector<std::uint32_t> kept;
    double max_error = 0.0;
};

/// Reduces a vec3 channel: `values` holds 3 floats per frame, `times` one per frame
/// (strictly increasing). Kept keys are written as they are (floats), so their own error
/// is 0. `bound` >= 0.
[[nodiscard]] KODAWARI_INTERNAL Reduction reduce_vec3(std::span<const float> times, std::span<const float> values,
                                                      double bound, VectorMetric metric);

/// A glTF normalized signed short (§3.11, accessors with normalized true: f = max(c /
/// 32767, -1)) nearest to `value` in [-1, 1].
[[nodiscard]] KODAWARI_INTERNAL std::int16_t quantize_unit(float value);
[[nodiscard]] inline double dequantize_unit(std::int16_t value) {
    const double v = static_cast<double>(value) / 32767.0;
    return v < -1.0 ? -1.0 : v;
}

/// Rounds unit quaternions (x, y, z, w per frame) to normalized shorts, component by
/// component. Rounding keeps each component's sign, so keys kept in one hemisphere stay
/// there. The rounding turns a rotation by at most about 6.1e-5 rad (each of four
/// components off by half of 1/32767).
KODAWARI_INTERNAL void quantize_rotations(std::span<const float> xyzw, std::span<std::int16_t> out);

/// Reduces a rotation channel: `xyzw` the original unit quaternions (4 floats per frame,
/// consecutive ones in one hemisphere), `quantized` quantize_rotations() of them, as
/// written. Between kept keys a player slerps the decoded shorts; the error is the angle
/// between that (normalized) and the original rotation, kept keys' rounding included,
/// so max_error is at least the rounding. Two consecutive kept keys are in one
/// hemisphere (their dot product is not negative), so that players which slerp without
/// taking the short way (not as the spec's Appendix C does) turn the same way.
/// `bound` >= 0 radians; a bound below the rounding keeps every key rounding changes.
[[nodiscard]] KODAWARI_INTERNAL Reduction reduce_rotations(std::span<const float> times, std::span<const float> xyzw,
                                                           std::span<const std::int16_t> quantized, double bound);

/// The largest angle (radians) by which rounding to shorts turned a key: the error of a
/// rotation channel that keeps every key.
[[nodiscard]] KODAWARI_INTERNAL double rounding_error(std::span<const float> xyzw, std::span<const std::int16_t> quantized);

/// The spec's slerp (Appendix C: along the short arc) between unit quaternions a and b
/// at t in [0, 1]; lerp where they are nearly equal.
KODAWARI_INTERNAL void slerp(const double a[4], const double b[4], double t, double out[4]);

/// The angle (radians, in [0, pi]) of the rotation taking one rotation to the other;
/// the quaternions need not be unit.
[[nodiscard]] KODAWARI_INTERNAL double rotation_angle(const double a[4], const double b[4]);

}  // namespace kodawari::gltf
