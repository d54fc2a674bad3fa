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
/// As above, but the keys are written as `written` (the same layout as `values`: the
/// values a quantizing filter gives back, docs/compact.md's `--meshopt`): a player
/// interpolates those, and the error is measured against `values`, so a kept key's own
/// error is its rounding and max_error counts it.
[[nodiscard]] KODAWARI_INTERNAL Reduction reduce_vec3(std::span<const float> times, std::span<const float> values,
                                                      std::span<const float> written, double bound, VectorMetric metric);

/// How rotation components are stored: glTF 2.0 §3.11 ("Animations", the table of
/// channel outputs) allows rotation outputs as floats or as normalized signed bytes
/// (componentType 5120) and shorts (5122), decoded as §3.11 gives: f = max(c / 127, -1)
/// and f = max(c / 32767, -1).
enum class RotationBits : std::uint8_t { Short = 16, Byte = 8 };

/// The largest code of a normalized signed component of `bits`: 32767 or 127.
[[nodiscard]] constexpr int unit_scale(RotationBits bits) { return bits == RotationBits::Byte ? 127 : 32767; }

/// The worst-case angle (radians) by which rounding a unit quaternion's components to
/// `bits` turns the rotation: each of the four components off by at most half a step,
/// 1 / (2 x scale), the error vector is at most 1 / scale long, so the quaternion turns by
/// at most asin(1 / scale) and the rotation, twice that: 6.1e-5 rad for shorts, 0.01575
/// rad (0.90 degrees) for bytes. (Normalizing the decoded quaternion does not turn it.)
[[nodiscard]] KODAWARI_INTERNAL double worst_rounding(RotationBits bits);

/// A glTF normalized signed component of `bits` (§3.11, accessors with normalized true:
/// f = max(c / scale, -1)) nearest to `value` in [-1, 1], held in an int16 either way.
[[nodiscard]] KODAWARI_INTERNAL std::int16_t quantize_unit(float value, RotationBits bits = RotationBits::Short);
[[nodiscard]] inline double dequantize_unit(std::int16_t value, RotationBits bits = RotationBits::Short) {
    const double v = static_cast<double>(value) / unit_scale(bits);
    return v < -1.0 ? -1.0 : v;
}

/// Rounds unit quaternions (x, y, z, w per frame) to normalized components of `bits`,
/// component by component. Rounding keeps each component's sign, so keys kept in one
/// hemisphere stay there. The rounding turns a rotation by at most worst_rounding(bits).
KODAWARI_INTERNAL void quantize_rotations(std::span<const float> xyzw, std::span<std::int16_t> out,
                                          RotationBits bits = RotationBits::Short);

/// Reduces a rotation channel: `xyzw` the original unit quaternions (4 floats per frame,
/// consecutive ones in one hemisphere), `quantized` quantize_rotations() of them at
/// `bits`, as written. Between kept keys a player slerps the decoded components; the
/// error is the angle between that (normalized) and the original rotation, kept keys'
/// rounding included, so max_error is at least the rounding. Two consecutive kept keys
/// are in one hemisphere (their dot product is at least 1e-4, so never a half turn
/// apart, where the short way is ambiguous), so that players which
/// slerp without taking the short way (not as the spec's Appendix C does) turn the same
/// way. `bound` >= 0 radians; a bound below the rounding keeps every key rounding changes.
/// `either_sign`: the written keys need not be in one hemisphere (meshopt's QUATERNION
/// filter gives each key back with its largest component positive): two consecutive kept
/// keys then need |dot| >= 1e-4, and a player takes the short way between them, as the
/// spec's Appendix C slerp does.
[[nodiscard]] KODAWARI_INTERNAL Reduction reduce_rotations(std::span<const float> times, std::span<const float> xyzw,
                                                           std::span<const std::int16_t> quantized, double bound,
                                                           RotationBits bits = RotationBits::Short, bool either_sign = false);

/// The largest angle (radians) by which rounding to `bits` turned a key: the error of a
/// rotation channel that keeps every key.
[[nodiscard]] KODAWARI_INTERNAL double rounding_error(std::span<const float> xyzw, std::span<const std::int16_t> quantized,
                                                      RotationBits bits = RotationBits::Short);

/// The spec's slerp (Appendix C: along the short arc) between unit quaternions a and b
/// at t in [0, 1]; lerp where they are nearly equal.
KODAWARI_INTERNAL void slerp(const double a[4], const double b[4], double t, double out[4]);

/// The angle (radians, in [0, pi]) of the rotation taking one rotation to the other;
/// the quaternions need not be unit.
[[nodiscard]] KODAWARI_INTERNAL double rotation_angle(const double a[4], const double b[4]);

}  // namespace kodawari::gltf
