// Key reduction for compact glTF animations: see key_reduction.hpp.
#include "export/key_reduction.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace kodawari::gltf {
namespace {

// The parameter of frame i between kept frames a and b, as a player computes it from
// the key times (§3.11: t = (t_i - t_a) / (t_b - t_a)).
double parameter(std::span<const float> times, std::uint32_t a, std::uint32_t b, std::uint32_t i) {
    const double ta = times[a];
    return (static_cast<double>(times[i]) - ta) / (static_cast<double>(times[b]) - ta);
}

// The greedy scheme of key_reduction.hpp over a check `span_error(a, b)`: the largest
// error of the keys strictly between a and b when a and b are kept (+infinity when the
// span is not allowed at all), against `bound`. `key_error(k)`: a kept key's own error.
template <class SpanError, class KeyError>
Reduction reduce(std::uint32_t frames, double bound, const SpanError& span_error, const KeyError& key_error) {
    Reduction r;
    if (frames == 0) return r;
    const std::uint32_t last = frames - 1;
    r.kept.push_back(0);
    r.max_error = key_error(0);
    if (last == 0) return r;
    // The whole channel at once first: constant and straight channels keep their ends
    // in O(frames), whatever kMaxSpan.
    if (const double whole = span_error(0, last); whole <= bound) {
        r.kept.push_back(last);
        r.max_error = std::max({r.max_error, whole, key_error(last)});
        return r;
    }
    std::uint32_t a = 0;
    while (a < last) {
        // a + 1 is always allowed (nothing in between).
        std::uint32_t good = a + 1;
        double good_error = 0.0;
        std::uint32_t bad = 0;  // 0: none found
        const std::uint32_t limit = std::min(last, a + kMaxSpan);
        for (std::uint32_t span = 2; good < limit; span *= 2) {
            const std::uint32_t b = std::min(limit, a + span);
            const double e = span_error(a, b);
            if (!(e <= bound)) {
                bad = b;
                break;
            }
            good = b;
            good_error = e;
        }
        while (bad != 0 && bad - good > 1) {
            const std::uint32_t mid = good + (bad - good) / 2;
            const double e = span_error(a, mid);
            if (e <= bound) {
                good = mid;
                good_error = e;
            } else {
                bad = mid;
            }
        }
        r.kept.push_back(good);
        r.max_error = std::max({r.max_error, good_error, key_error(good)});
        a = good;
    }
    return r;
}

// The least dot product of two consecutive kept rotations (unit quaternions): 1e-4 is
// 0.0002 rad short of a half turn, far above a float player's rounding of the dot.
constexpr double kMinKeyDot = 1e-4;

double dot4(const double a[4], const double b[4]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]; }

void normalize4(double q[4]) {
    const double n = std::sqrt(dot4(q, q));
    if (n > 0.0) {
        for (int c = 0; c < 4; ++c) q[c] /= n;
    }
}

}  // namespace

Reduction reduce_vec3(std::span<const float> times, std::span<const float> values, double bound, VectorMetric metric) {
    return reduce_vec3(times, values, values, bound, metric);
}

Reduction reduce_vec3(std::span<const float> times, std::span<const float> values, std::span<const float> written,
                      double bound, VectorMetric metric) {
    const auto frames = static_cast<std::uint32_t>(times.size());
    assert(values.size() == std::size_t{frames} * 3 && written.size() == values.size());
    // The error of `at` (written keys a and b interpolated at t) against frame i.
    const auto error_of = [&](auto&& at, std::uint32_t i) {
        double distance = 0.0;
        double relative = 0.0;
        for (std::size_t c = 0; c < 3; ++c) {
            const double v = values[i * 3 + c];
            const double d = std::abs(at(c) - v);
            distance += d * d;
            if (d > 0.0) relative = std::max(relative, std::abs(v) > 0.0 ? d / std::abs(v) : std::numeric_limits<double>::infinity());
        }
        return metric == VectorMetric::Distance ? std::sqrt(distance) : relative;
    };
    const auto error_at = [&](std::uint32_t a, std::uint32_t b, std::uint32_t i) {
        const double t = parameter(times, a, b, i);
        return error_of(
            [&](std::size_t c) {
                const double va = written[a * 3 + c];
                const double vb = written[b * 3 + c];
                return va + (vb - va) * t;
            },
            i);
    };
    const bool exact = written.data() == values.data();
    const auto key_error = [&](std::uint32_t k) {
        return exact ? 0.0 : error_of([&](std::size_t c) { return static_cast<double>(written[k * 3 + c]); }, k);
    };
    const auto span_error = [&](std::uint32_t a, std::uint32_t b) {
        double worst = 0.0;
        for (std::uint32_t i = a + 1; i < b; ++i) {
            worst = std::max(worst, error_at(a, b, i));
            if (worst > bound) break;  // fails already: no need for the rest
        }
        return worst;
    };
    return reduce(frames, bound, span_error, key_error);
}

double worst_rounding(RotationBits bits) { return 2.0 * std::asin(1.0 / unit_scale(bits)); }

std::int16_t quantize_unit(float value, RotationBits bits) {
    const double v = std::clamp(static_cast<double>(value), -1.0, 1.0);
    return static_cast<std::int16_t>(std::lround(v * unit_scale(bits)));
}

void quantize_rotations(std::span<const float> xyzw, std::span<std::int16_t> out, RotationBits bits) {
    assert(out.size() == xyzw.size());
    for (std::size_t i = 0; i < xyzw.size(); ++i) out[i] = quantize_unit(xyzw[i], bits);
}

void slerp(const double a[4], const double b[4], double t, double out[4]) {
    double d = dot4(a, b);
    const double s = d < 0.0 ? -1.0 : 1.0;  // the short way round
    d = std::min(1.0, std::abs(d));
    const double angle = std::acos(d);
    double wa = 1.0 - t;
    double wb = t;
    if (angle > 1e-9) {
        const double sine = std::sin(angle);
        wa = std::sin(angle * (1.0 - t)) / sine;
        wb = std::sin(angle * t) / sine;
    }
    for (int c = 0; c < 4; ++c) out[c] = wa * a[c] + s * wb * b[c];
}

double rotation_angle(const double a[4], const double b[4]) {
    double ua[4] = {a[0], a[1], a[2], a[3]};
    double ub[4] = {b[0], b[1], b[2], b[3]};
    normalize4(ua);
    normalize4(ub);
    // With a . b = cos(phi) (phi the angle between the unit quaternions, half the
    // rotation's), |a - s b| = 2 sin(phi / 2) and |a + s b| = 2 cos(phi / 2): so
    // 4 atan2(|a - s b|, |a + s b|) is 2 phi = 2 acos(|a . b|), without the precision
    // acos loses near 1 for small angles.
    const double s = dot4(ua, ub) < 0.0 ? -1.0 : 1.0;
    double minus = 0.0;
    double plus = 0.0;
    for (int c = 0; c < 4; ++c) {
        minus += (ua[c] - s * ub[c]) * (ua[c] - s * ub[c]);
        plus += (ua[c] + s * ub[c]) * (ua[c] + s * ub[c]);
    }
    return 4.0 * std::atan2(std::sqrt(minus), std::sqrt(plus));
}

double rounding_error(std::span<const float> xyzw, std::span<const std::int16_t> quantized, RotationBits bits) {
    assert(quantized.size() == xyzw.size());
    double worst = 0.0;
    for (std::size_t k = 0; k + 4 <= xyzw.size(); k += 4) {
        double q[4];
        double o[4];
        for (std::size_t c = 0; c < 4; ++c) {
            q[c] = dequantize_unit(quantized[k + c], bits);
            o[c] = xyzw[k + c];
        }
        worst = std::max(worst, rotation_angle(q, o));
    }
    return worst;
}

Reduction reduce_rotations(std::span<const float> times, std::span<const float> xyzw, std::span<const std::int16_t> quantized,
                           double bound, RotationBits bits, bool either_sign) {
    const auto frames = static_cast<std::uint32_t>(times.size());
    assert(xyzw.size() == std::size_t{frames} * 4 && quantized.size() == xyzw.size());
    const auto decoded = [&](std::uint32_t k, double q[4]) {
        for (std::size_t c = 0; c < 4; ++c) q[c] = dequantize_unit(quantized[k * 4 + c], bits);
        normalize4(q);
    };
    const auto original = [&](std::uint32_t k, double q[4]) {
        for (std::size_t c = 0; c < 4; ++c) q[c] = xyzw[k * 4 + c];
    };
    const auto key_error = [&](std::uint32_t k) {
        double q[4];
        double o[4];
        decoded(k, q);
        original(k, o);
        return rotation_angle(q, o);
    };
    const auto span_error = [&](std::uint32_t a, std::uint32_t b) {
        double qa[4];
        double qb[4];
        decoded(a, qa);
        decoded(b, qb);
        // Not across hemispheres, nor at their border: keys a half turn apart (dot 0,
        // which rounding to integers makes exact) leave the direction to each player's
        // arithmetic (the spec's "negate when negative" meets a dot of -0 or 1e-17), so
        // a span must be clearly within one hemisphere.
        const double dot = dot4(qa, qb);
        if ((either_sign ? std::abs(dot) : dot) < kMinKeyDot) return std::numeric_limits<double>::infinity();
        double worst = 0.0;
        for (std::uint32_t i = a + 1; i < b; ++i) {
            double q[4];
            double o[4];
            slerp(qa, qb, parameter(times, a, b, i), q);
            original(i, o);
            worst = std::max(worst, rotation_angle(q, o));
            if (worst > bound) break;
        }
        return worst;
    };
    return reduce(frames, bound, span_error, key_error);
}

}  // namespace kodawari::gltf
