#include "kodawari/birds/rig.hpp"

#include <cassert>

namespace kodawari::birds {
namespace {

// Figures and their sources: docs/wing-types.md. Span, length, mass, frequency and
// cruise speed are field figures (frequencies of gull, hawk and starling are Pennycuick's
// (1996) estimate, as derive_flight gives them: no measured value was read); amplitude is
// ours (gull and buzzard beat shallower than a pigeon: "fast, stiff, shallow" in field
// guides; the starling, a short-winged flapper like the pigeon, keeps the seed's). Glide ratio,
// flap-glide rhythm and the route limits are derive_flight's (allometry.hpp) for each
// type's span, area and mass, to three digits; docs/wing-types.md has the table and
// tests/birds/test_allometry.cpp holds them to it.
constexpr float kDeg = 0.017453292f;
constexpr WingTypeSpec kSpecs[kWingTypeCount] = {
    {"pigeon", 0.67f, 0.33f, 0.31f, 0.10f, 5.5f, 19.7f, 1.0f, 0.45f, 13.1f, 0.0f, 0.0f, false, 20.7f * kDeg, 25.5f * kDeg, 3.47f},
    {"gull", 1.40f, 0.60f, 1.0f, 0.14f, 3.6f, 12.0f, 0.8f, 0.5f, 16.5f, 7.0f, 2.04f, false, 14.8f * kDeg, 18.5f * kDeg, 2.51f},
    {"hawk", 1.20f, 0.54f, 0.875f, 0.22f, 3.6f, 11.0f, 0.7f, 0.45f, 12.5f, 7.0f, 1.70f, false, 16.3f * kDeg, 21.1f * kDeg, 2.75f},
    {"hummingbird", 0.11f, 0.09f, 0.0034f, 0.014f, 53.0f, 8.0f, 1.0f, 0.45f, 12.7f, 0.0f, 0.0f, true, 90.0f * kDeg, 90.0f * kDeg, 9.81f},
    {"starling", 0.40f, 0.215f, 0.082f, 0.060f, 9.48f, 15.0f, 1.0f, 0.45f, 12.9f, 0.0f, 0.0f, false, 38.6f * kDeg, 44.5f * kDeg, 6.12f},
};

}  // namespace

const WingTypeSpec& wing_type_spec(WingType type) {
    const auto index = static_cast<std::size_t>(type);
    assert(index < kWingTypeCount);
    return kSpecs[index];
}

std::optional<WingType> parse_wing_type(std::string_view name) {
    for (std::size_t i = 0; i < kWingTypeCount; ++i) {
        if (kSpecs[i].name == name) return static_cast<WingType>(i);
    }
    return std::nullopt;
}

gpu::vec4 flight_params(const WingTypeSpec& spec) {
    return {spec.glide_ratio, spec.flap_glide_beats, spec.flap_glide_seconds, spec.can_hover ? 1.0f : 0.0f};
}

gpu::vec4 shape_params(const WingTypeSpec& spec) { return {spec.body_length, spec.wingspan, 0.0f, 0.0f}; }

std::array<std::array<float, 3>, kPartCount> part_offsets(WingType type) {
    const WingTypeSpec& spec = wing_type_spec(type);
    const float length = spec.body_length;
    // Shoulders sit a little forward of the centre of mass and on top of the body.
    const float shoulder_x = 0.06f * length;
    const float half_span = 0.5f * spec.wingspan - shoulder_x;
    const float arm1 = spec.arm1_fraction * half_span;
    std::array<std::array<float, 3>, kPartCount> offsets{};
    offsets[KW_PART_BODY] = {0.0f, 0.0f, 0.0f};
    offsets[KW_PART_HEAD] = {0.0f, 0.05f * length, 0.40f * length};
    offsets[KW_PART_TAIL] = {0.0f, 0.0f, -0.35f * length};
    offsets[KW_PART_LEFT_ARM1] = {shoulder_x, 0.05f * length, 0.08f * length};
    offsets[KW_PART_LEFT_ARM2] = {arm1, 0.0f, 0.0f};
    offsets[KW_PART_RIGHT_ARM1] = {-shoulder_x, 0.05f * length, 0.08f * length};
    offsets[KW_PART_RIGHT_ARM2] = {-arm1, 0.0f, 0.0f};
    return offsets;
}

}  // namespace kodawari::birds
