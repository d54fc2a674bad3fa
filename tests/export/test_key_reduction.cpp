// The key reducer of compact .glb files (engine/export/key_reduction.hpp): every dropped
// key is reproduced within the bound by interpolating the kept ones, evaluated here
// independently (glm's slerp in double on the decoded shorts or bytes, lerp on the
// floats); first and last frames kept; constant channels; hemispheres; the 16-bit and
// 8-bit rounding counted, and its worst case; bound 0; long channels in O(frames log span).

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "export/key_reduction.hpp"

namespace kodawari {
namespace {

using gltf::Reduction;
using gltf::VectorMetric;

std::vector<float> times_of(std::uint32_t frames, float fps = 60.0f) {
    std::vector<float> t(frames);
    for (std::uint32_t f = 0; f < frames; ++f) t[f] = static_cast<float>(f) / fps;
    return t;
}

// The kept frames are ascending and unique, from the first to the last.
void expect_well_formed(const Reduction& r, std::uint32_t frames) {
    ASSERT_FALSE(r.kept.empty());
    EXPECT_EQ(r.kept.front(), 0u);
    EXPECT_EQ(r.kept.back(), frames - 1);
    for (std::size_t k = 1; k < r.kept.size(); ++k) EXPECT_LT(r.kept[k - 1], r.kept[k]);
}

// The kept segment [a, b] around frame f.
std::pair<std::uint32_t, std::uint32_t> segment(const Reduction& r, std::uint32_t f) {
    const auto it = std::upper_bound(r.kept.begin(), r.kept.end(), f);
    if (it == r.kept.end()) return {r.kept.back(), r.kept.back()};
    return {*(it - 1), *it};
}

// The largest error of a reduced vec3 channel, evaluated independently.
double vec3_error(const Reduction& r, const std::vector<float>& times, const std::vector<float>& v, VectorMetric metric) {
    double worst = 0.0;
    for (std::uint32_t f = 0; f < times.size(); ++f) {
        const auto [a, b] = segment(r, f);
        const double ta = times[a];
        const double t = a == b ? 0.0 : (static_cast<double>(times[f]) - ta) / (static_cast<double>(times[b]) - ta);
        const glm::dvec3 va(v[a * 3], v[a * 3 + 1], v[a * 3 + 2]);
        const glm::dvec3 vb(v[b * 3], v[b * 3 + 1], v[b * 3 + 2]);
        const glm::dvec3 o(v[f * 3], v[f * 3 + 1], v[f * 3 + 2]);
        const glm::dvec3 d = glm::abs(glm::mix(va, vb, t) - o);
        if (metric == VectorMetric::Distance) {
            worst = std::max(worst, glm::length(d));
        } else {
            for (int c = 0; c < 3; ++c) {
                if (d[c] > 0.0) worst = std::max(worst, d[c] / std::abs(o[c]));
            }
        }
    }
    return worst;
}

using gltf::RotationBits;

glm::dquat decoded(const std::vector<std::int16_t>& s, std::uint32_t k, RotationBits bits = RotationBits::Short) {
    const double scale = bits == RotationBits::Byte ? 127.0 : 32767.0;  // §3.11: max(c / scale, -1)
    auto c = [&](int i) { return std::max(static_cast<double>(s[k * 4 + static_cast<std::uint32_t>(i)]) / scale, -1.0); };
    return glm::normalize(glm::dquat(c(3), c(0), c(1), c(2)));  // glm: w first
}

double angle_between(const glm::dquat& a, const glm::dquat& b) {
    return 2.0 * std::acos(std::min(1.0, std::abs(glm::dot(glm::normalize(a), glm::normalize(b)))));
}

// The largest error of a reduced rotation channel: glm's slerp (short path) of the
// decoded kept shorts against the original floats.
double rotation_error(const Reduction& r, const std::vector<float>& times, const std::vector<float>& q,
                      const std::vector<std::int16_t>& s, RotationBits bits = RotationBits::Short) {
    double worst = 0.0;
    for (std::uint32_t f = 0; f < times.size(); ++f) {
        const auto [a, b] = segment(r, f);
        const double ta = times[a];
        const double t = a == b ? 0.0 : (static_cast<double>(times[f]) - ta) / (static_cast<double>(times[b]) - ta);
        const glm::dquat value = glm::slerp(decoded(s, a, bits), decoded(s, b, bits), t);
        const glm::dquat original(q[f * 4 + 3], q[f * 4], q[f * 4 + 1], q[f * 4 + 2]);
        worst = std::max(worst, angle_between(value, original));
    }
    return worst;
}

// A smooth path plus, when `noise` > 0, uniform noise of that size per component.
std::vector<float> vec3_channel(std::uint32_t frames, float noise, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> v(std::size_t{frames} * 3);
    for (std::uint32_t f = 0; f < frames; ++f) {
        const float t = static_cast<float>(f) / 60.0f;
        v[f * 3] = 3.0f * std::sin(0.7f * t) + 0.02f * std::sin(2.0f * t);
        v[f * 3 + 1] = 1.5f + 0.1f * std::cos(2.3f * t);
        v[f * 3 + 2] = 12.0f * t;
        for (int c = 0; c < 3; ++c) v[f * 3 + static_cast<std::uint32_t>(c)] += noise * u(rng);
    }
    return v;
}

// Unit quaternions (x, y, z, w) turning smoothly (plus noise), consecutive ones in one
// hemisphere as the writers make them.
std::vector<float> rotation_channel(std::uint32_t frames, float noise, std::uint32_t seed, float speed = 1.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> q(std::size_t{frames} * 4);
    glm::quat previous(1.0f, 0.0f, 0.0f, 0.0f);
    for (std::uint32_t f = 0; f < frames; ++f) {
        const float t = static_cast<float>(f) / 60.0f;
        const glm::vec3 axis = glm::normalize(glm::vec3(1.0f + 0.3f * std::sin(t), 0.5f, std::cos(0.5f * t)));
        glm::quat r = glm::angleAxis(speed * (0.8f * t + 0.05f * std::sin(2.0f * t)), axis);
        if (noise > 0.0f) r = glm::normalize(r * glm::angleAxis(noise * u(rng), glm::normalize(glm::vec3(u(rng), u(rng), 1.0f))));
        if (f > 0 && glm::dot(previous, r) < 0.0f) r = -r;
        previous = r;
        q[f * 4] = r.x;
        q[f * 4 + 1] = r.y;
        q[f * 4 + 2] = r.z;
        q[f * 4 + 3] = r.w;
    }
    return q;
}

std::vector<std::int16_t> quantized(const std::vector<float>& q, RotationBits bits = RotationBits::Short) {
    std::vector<std::int16_t> s(q.size());
    gltf::quantize_rotations(q, s, bits);
    return s;
}

TEST(KeyReduction, TranslationBoundHoldsOnSmoothAndNoisyChannels) {
    const std::uint32_t frames = 601;
    const auto times = times_of(frames);
    for (const float noise : {0.0f, 1e-4f, 5e-3f}) {
        const auto v = vec3_channel(frames, noise, 7);
        for (const double bound : {1e-4, 1e-3, 1e-2, 0.1}) {
            const Reduction r = gltf::reduce_vec3(times, v, bound, VectorMetric::Distance);
            SCOPED_TRACE("noise " + std::to_string(noise) + ", bound " + std::to_string(bound));
            expect_well_formed(r, frames);
            const double error = vec3_error(r, times, v, VectorMetric::Distance);
            EXPECT_LE(error, bound * (1 + 1e-9));
            EXPECT_NEAR(r.max_error, error, 1e-12);
            if (noise == 0.0f && bound >= 1e-3) {
                EXPECT_LT(r.kept.size(), frames / 3u);
            }
            if (static_cast<double>(noise) > 10 * bound) {
                EXPECT_GT(r.kept.size(), frames * 9u / 10u);
            }
        }
    }
}

TEST(KeyReduction, ScaleBoundIsRelativePerAxis) {
    const std::uint32_t frames = 300;
    const auto times = times_of(frames);
    std::vector<float> v(std::size_t{frames} * 3);
    for (std::uint32_t f = 0; f < frames; ++f) {
        const float t = static_cast<float>(f) / 60.0f;
        v[f * 3] = 1.0f + 0.3f * std::sin(3.0f * t);
        v[f * 3 + 1] = 0.01f * (1.0f + 0.3f * std::sin(3.0f * t));  // small axis: relative to itself
        v[f * 3 + 2] = 2.0f;
    }
    const Reduction r = gltf::reduce_vec3(times, v, 1e-3, VectorMetric::Relative);
    expect_well_formed(r, frames);
    EXPECT_LE(vec3_error(r, times, v, VectorMetric::Relative), 1e-3 * (1 + 1e-9));
    EXPECT_LT(r.kept.size(), frames / 2u);
}

TEST(KeyReduction, ConstantAndStraightChannelsKeepTheirEnds) {
    const auto times = times_of(500);
    std::vector<float> constant(500 * 3, 0.25f);
    const Reduction c = gltf::reduce_vec3(times, constant, 0.0, VectorMetric::Distance);
    EXPECT_EQ(c.kept, (std::vector<std::uint32_t>{0, 499}));
    EXPECT_EQ(c.max_error, 0.0);
    std::vector<float> straight(500 * 3);
    for (std::uint32_t f = 0; f < 500; ++f) straight[f * 3] = straight[f * 3 + 1] = straight[f * 3 + 2] = 2.0f * times[f];
    EXPECT_EQ(gltf::reduce_vec3(times, straight, 1e-6, VectorMetric::Distance).kept.size(), 2u);
    // One frame: one key; two: both.
    EXPECT_EQ(gltf::reduce_vec3(times_of(1), std::vector<float>(3, 1.0f), 0.1, VectorMetric::Distance).kept,
              std::vector<std::uint32_t>{0});
    EXPECT_EQ(gltf::reduce_vec3(times_of(2), std::vector<float>(6, 1.0f), 0.1, VectorMetric::Distance).kept,
              (std::vector<std::uint32_t>{0, 1}));
    // A constant rotation, identity (exact in 16 bits) even at bound 0.
    std::vector<float> identity(500 * 4, 0.0f);
    for (std::size_t f = 0; f < 500; ++f) identity[f * 4 + 3] = 1.0f;
    const Reduction ri = gltf::reduce_rotations(times, identity, quantized(identity), 0.0);
    EXPECT_EQ(ri.kept, (std::vector<std::uint32_t>{0, 499}));
}

TEST(KeyReduction, BoundZeroKeepsEveryKeyThatIsNotExact) {
    const std::uint32_t frames = 200;
    const auto times = times_of(frames);
    const auto v = vec3_channel(frames, 1e-3f, 3);
    EXPECT_EQ(gltf::reduce_vec3(times, v, 0.0, VectorMetric::Distance).kept.size(), frames);
    const auto q = rotation_channel(frames, 0.0f, 3);
    const Reduction r = gltf::reduce_rotations(times, q, quantized(q), 0.0);
    EXPECT_EQ(r.kept.size(), frames);
}

TEST(KeyReduction, RotationBoundHoldsWithTheQuantizedKeys) {
    const std::uint32_t frames = 601;
    const auto times = times_of(frames);
    for (const float noise : {0.0f, 2e-4f, 2e-2f}) {
        const auto q = rotation_channel(frames, noise, 11);
        const auto s = quantized(q);
        for (const double bound : {2e-4, 1e-3, 1e-2, 0.1}) {
            SCOPED_TRACE("noise " + std::to_string(noise) + ", bound " + std::to_string(bound));
            const Reduction r = gltf::reduce_rotations(times, q, s, bound);
            expect_well_formed(r, frames);
            const double error = rotation_error(r, times, q, s);
            EXPECT_LE(error, bound + 1e-9);
            EXPECT_NEAR(r.max_error, error, 1e-9);
            if (noise == 0.0f && bound >= 1e-3) {
                EXPECT_LT(r.kept.size(), frames / 3u);
            }
        }
    }
}

// Below the 16-bit rounding nothing can be dropped, and the error left is the rounding's:
// at most 6.1e-5 rad, more than zero.
TEST(KeyReduction, QuantizationCountsInTheBound) {
    const std::uint32_t frames = 120;
    const auto times = times_of(frames);
    const auto q = rotation_channel(frames, 0.0f, 5);
    const auto s = quantized(q);
    const Reduction r = gltf::reduce_rotations(times, q, s, 1e-7);
    EXPECT_EQ(r.kept.size(), frames);
    EXPECT_GT(r.max_error, 0.0);
    EXPECT_LE(r.max_error, 6.2e-5);
    EXPECT_NEAR(r.max_error, rotation_error(r, times, q, s), 1e-9);
    EXPECT_EQ(gltf::quantize_unit(1.0f), 32767);
    EXPECT_EQ(gltf::quantize_unit(-1.0f), -32767);
    EXPECT_EQ(gltf::quantize_unit(2.0f), 32767);
    EXPECT_EQ(gltf::quantize_unit(0.5f), 16384);
    EXPECT_EQ(gltf::dequantize_unit(-32768), -1.0);
}

// 8-bit rotations (normalized signed bytes, glTF 2.0 §3.11): codes and decoding, and the
// worst case of rounding a unit quaternion, 2 asin(1/127) = 0.01575 rad (0.90 degrees),
// bounds what a million random ones and the worst axis-aligned ones measure; 16-bit,
// 2 asin(1/32767) = 6.1e-5 rad.
TEST(KeyReduction, ByteRoundingStaysWithinItsWorstCase) {
    EXPECT_EQ(gltf::quantize_unit(1.0f, RotationBits::Byte), 127);
    EXPECT_EQ(gltf::quantize_unit(-1.0f, RotationBits::Byte), -127);
    EXPECT_EQ(gltf::quantize_unit(2.0f, RotationBits::Byte), 127);
    EXPECT_EQ(gltf::quantize_unit(0.5f, RotationBits::Byte), 64);
    EXPECT_EQ(gltf::dequantize_unit(-128, RotationBits::Byte), -1.0);
    EXPECT_EQ(gltf::dequantize_unit(127, RotationBits::Byte), 1.0);
    const double worst8 = gltf::worst_rounding(RotationBits::Byte);
    const double worst16 = gltf::worst_rounding(RotationBits::Short);
    EXPECT_NEAR(worst8, 0.015749, 1e-6);
    EXPECT_NEAR(worst16, 6.1037e-5, 1e-9);
    std::mt19937 rng(7);
    std::normal_distribution<float> n(0.0f, 1.0f);
    std::vector<float> q(std::size_t{1'000'000} * 4);
    for (std::size_t k = 0; k < q.size(); k += 4) {
        const glm::vec4 v = glm::normalize(glm::vec4(n(rng), n(rng), n(rng), n(rng)));
        for (int c = 0; c < 4; ++c) q[k + static_cast<std::size_t>(c)] = v[c];
    }
    const double measured8 = gltf::rounding_error(q, quantized(q, RotationBits::Byte), RotationBits::Byte);
    const double measured16 = gltf::rounding_error(q, quantized(q), RotationBits::Short);
    std::printf("rounding of 1e6 random unit quaternions: 8-bit %.6f rad (worst case %.6f), 16-bit %.3g rad (worst case %.3g)\n",
                measured8, worst8, measured16, worst16);
    EXPECT_LE(measured8, worst8);
    EXPECT_GT(measured8, 0.5 * worst8);
    EXPECT_LE(measured16, worst16);
    EXPECT_GT(measured16, 0.5 * worst16);
}

// A channel stored in bytes: the bound holds on the decoded bytes, the rounding counted;
// the keys' rounding alone is above 1 mrad, so a 1 mrad bound keeps every key and is
// exceeded (the writers store such channels in shorts).
TEST(KeyReduction, ByteRotationBoundHolds) {
    const std::uint32_t frames = 601;
    const auto times = times_of(frames);
    for (const float noise : {0.0f, 2e-3f}) {
        const auto q = rotation_channel(frames, noise, 13);
        const auto b = quantized(q, RotationBits::Byte);
        const double rounding = gltf::rounding_error(q, b, RotationBits::Byte);
        EXPECT_GT(rounding, 1e-3);
        EXPECT_LE(rounding, gltf::worst_rounding(RotationBits::Byte));
        for (const double bound : {0.02, 0.05, 0.2}) {
            SCOPED_TRACE("noise " + std::to_string(noise) + ", bound " + std::to_string(bound));
            const Reduction r = gltf::reduce_rotations(times, q, b, bound, RotationBits::Byte);
            expect_well_formed(r, frames);
            const double error = rotation_error(r, times, q, b, RotationBits::Byte);
            EXPECT_LE(error, bound + 1e-9);
            EXPECT_NEAR(r.max_error, error, 1e-9);
            EXPECT_GE(r.max_error, 0.0);
        }
        const Reduction tight = gltf::reduce_rotations(times, q, b, 1e-3, RotationBits::Byte);
        EXPECT_GT(tight.max_error, 1e-3);
    }
}

// A spin of two full turns: the quaternion crosses hemispheres, the writers' keys follow
// it by sign. With a loose bound kept neighbours are still in one hemisphere, so a
// player that does not take the short way turns the same way.
TEST(KeyReduction, KeptRotationsStayInOneHemisphere) {
    const std::uint32_t frames = 400;
    const auto times = times_of(frames);
    std::vector<float> q(std::size_t{frames} * 4);
    glm::quat previous(1.0f, 0.0f, 0.0f, 0.0f);
    for (std::uint32_t f = 0; f < frames; ++f) {
        glm::quat r = glm::angleAxis(4.0f * 3.14159265f * static_cast<float>(f) / (frames - 1), glm::vec3(0.0f, 0.0f, 1.0f));
        if (glm::dot(previous, r) < 0.0f) r = -r;
        previous = r;
        q[f * 4] = r.x;
        q[f * 4 + 1] = r.y;
        q[f * 4 + 2] = r.z;
        q[f * 4 + 3] = r.w;
    }
    const auto s = quantized(q);
    const Reduction r = gltf::reduce_rotations(times, q, s, 0.5);
    expect_well_formed(r, frames);
    EXPECT_GE(r.kept.size(), 5u);  // two turns: no span can be 180 degrees or more
    for (std::size_t k = 1; k < r.kept.size(); ++k) {
        EXPECT_GE(glm::dot(decoded(s, r.kept[k - 1]), decoded(s, r.kept[k])), 0.0) << "keys " << k - 1 << ", " << k;
    }
    EXPECT_LE(rotation_error(r, times, q, s), 0.5 + 1e-9);
}

// A steady spin of pi/20 per frame: slerp reproduces any span of it, but keys exactly a
// half turn apart (20 frames) round to bytes whose dot product is exactly 0, where the
// short way is either way: no kept span reaches that far.
TEST(KeyReduction, NoSpanIsAHalfTurn) {
    const std::uint32_t frames = 81;
    const auto times = times_of(frames);
    std::vector<float> q(std::size_t{frames} * 4);
    glm::quat previous(1.0f, 0.0f, 0.0f, 0.0f);
    for (std::uint32_t f = 0; f < frames; ++f) {
        glm::quat r = glm::angleAxis(3.14159265f / 20.0f * static_cast<float>(f), glm::vec3(0.0f, 0.0f, 1.0f));
        if (glm::dot(previous, r) < 0.0f) r = -r;
        previous = r;
        q[f * 4] = r.x;
        q[f * 4 + 1] = r.y;
        q[f * 4 + 2] = r.z;
        q[f * 4 + 3] = r.w;
    }
    for (const RotationBits bits : {RotationBits::Short, RotationBits::Byte}) {
        const auto s = quantized(q, bits);
        const Reduction r = gltf::reduce_rotations(times, q, s, 0.05, bits);
        expect_well_formed(r, frames);
        for (std::size_t k = 1; k < r.kept.size(); ++k) {
            EXPECT_LT(r.kept[k] - r.kept[k - 1], 20u);
            EXPECT_GT(glm::dot(decoded(s, r.kept[k - 1], bits), decoded(s, r.kept[k], bits)), 1e-4);
        }
        EXPECT_LE(rotation_error(r, times, q, s, bits), 0.05 + 1e-9);
    }
}

// Long channels: a span is at most kMaxSpan frames and each check costs its span, so
// 200 000 frames take well under a second per channel.
TEST(KeyReduction, LongChannelsAreNotQuadratic) {
    const std::uint32_t frames = 200'000;
    const auto times = times_of(frames, 1000.0f);
    std::vector<float> v(std::size_t{frames} * 3);
    for (std::uint32_t f = 0; f < frames; ++f) {
        v[f * 3] = std::sin(static_cast<float>(f) * 1e-4f);
        v[f * 3 + 1] = 0.0f;
        v[f * 3 + 2] = 1.0f;
    }
    const auto start = std::chrono::steady_clock::now();
    const Reduction r = gltf::reduce_vec3(times, v, 1e-3, VectorMetric::Distance);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    expect_well_formed(r, frames);
    for (std::size_t k = 1; k < r.kept.size(); ++k) EXPECT_LE(r.kept[k] - r.kept[k - 1], gltf::kMaxSpan);
    EXPECT_LE(vec3_error(r, times, v, VectorMetric::Distance), 1e-3 * (1 + 1e-9));
    EXPECT_LT(seconds, 2.0);
}

TEST(KeyReduction, IsDeterministic) {
    const auto times = times_of(300);
    const auto q = rotation_channel(300, 1e-3f, 9);
    const auto s = quantized(q);
    EXPECT_EQ(gltf::reduce_rotations(times, q, s, 1e-3).kept, gltf::reduce_rotations(times, q, s, 1e-3).kept);
}

}  // namespace
}  // namespace kodawari
