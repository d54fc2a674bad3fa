#include "kodawari/birds/wingbeat.hpp"

#include <cassert>
#include <cmath>
#include <numbers>

namespace kodawari::birds {
namespace {
constexpr float kPi = std::numbers::pi_v<float>;
}

const char* mode_name(FlightMode mode) {
    switch (mode) {
        case FlightMode::Level: return "level";
        case FlightMode::Ascend: return "ascend";
        case FlightMode::Descend: return "descend";
        case FlightMode::Glide: return "glide";
        case FlightMode::TakeOff: return "takeoff";
        case FlightMode::Landing: return "landing";
        case FlightMode::Hover: return "hover";
    }
    return "level";
}

// SPEC B.2, eq. 4.1, with the continuous last piece (+2/3 t - 4/3 pi).
float level_arm1_pitch(float t) {
    if (t < 0.5f * kPi) return 0.0f;
    if (t < kPi) return -(2.0f / 3.0f) * t + kPi / 3.0f;
    if (t < 1.5f * kPi) return -kPi / 3.0f;
    return (2.0f / 3.0f) * t - (4.0f / 3.0f) * kPi;
}

// SPEC B.2, eq. 4.2.
float level_arm2_pitch(float t) {
    return t < kPi ? -(kPi / 3.0f) * std::sin(t) : -(3.0f / 18.0f) * kPi * std::sin(t);
}

// SPEC B.2, eq. 4.3.
float ascend_arm2_pitch(float t) {
    return t < kPi ? -(4.0f / 9.0f) * kPi * std::sin(t) : -(5.0f / 18.0f) * kPi * std::sin(t);
}

// SPEC B.2, eq. 4.4.
float descend_arm1_heading(float t) { return (kPi / 180.0f) * std::sin(t); }

// SPEC B.2, eq. 4.5.
float descend_arm2_heading(float t) {
    return t < kPi ? -(kPi / 36.0f) * std::sin(t) : -(kPi / 90.0f) * std::sin(t);
}

WingAngles wing_angles(FlightMode mode, float t, float amplitude) {
    WingAngles a;
    switch (mode) {
        case FlightMode::Level:
            a.arm1_pitch = level_arm1_pitch(t);
            a.arm2_pitch = level_arm2_pitch(t);
            break;
        case FlightMode::Ascend:  // arm1 takes eq. 4.2, arm2 eq. 4.3
            a.arm1_pitch = level_arm2_pitch(t);
            a.arm2_pitch = ascend_arm2_pitch(t);
            break;
        case FlightMode::Descend:  // wings held out flat, the outer feathers flutter
            a.arm1_heading = descend_arm1_heading(t);
            a.arm2_heading = descend_arm2_heading(t);
            break;
        default: assert(false && "wing_angles() takes the seed's modes; mode_look() the others"); break;
    }
    a.arm1_pitch *= amplitude;
    a.arm2_pitch *= amplitude;
    a.arm1_heading *= amplitude;
    a.arm2_heading *= amplitude;
    return a;
}

namespace {

float smoothstep(float edge0, float edge1, float x) {
    const float u = std::fmin(std::fmax((x - edge0) / (edge1 - edge0), 0.0f), 1.0f);
    return u * u * (3.0f - 2.0f * u);
}
float mix(float a, float b, float w) { return a + (b - a) * w; }
WingAngles mix(const WingAngles& a, const WingAngles& b, float w) {
    return {mix(a.arm1_pitch, b.arm1_pitch, w), mix(a.arm2_pitch, b.arm2_pitch, w), mix(a.arm1_heading, b.arm1_heading, w),
            mix(a.arm2_heading, b.arm2_heading, w)};
}

}  // namespace

// docs/flight-modes.md F.3 (poses) and F.5 (tail spread, bob).
ModeLook mode_look(FlightMode mode, float t, float amplitude, const PerchProgress& p) {
    ModeLook look;
    switch (mode) {
        case FlightMode::Level:
        case FlightMode::Ascend:
        case FlightMode::Descend:
            look.wings = wing_angles(mode, t, amplitude);
            look.spread = mode == FlightMode::Level ? 0.15f : mode == FlightMode::Ascend ? 0.35f : 0.1f;
            look.bob = mode == FlightMode::Descend ? 0.3f : 1.0f;
            break;
        case FlightMode::Glide:
            look.wings = kGlideWings;
            look.spread = 0.25f;
            break;
        case FlightMode::TakeOff: {
            // Strong low-speed beats: the level stroke 1.3 times as deep, swept forward on
            // the downstroke (F.3), opened from the folded wings by the leap.
            const float open = smoothstep(0.0f, kLeapSeconds, p.since_crouch);
            WingAngles beats{1.3f * amplitude * level_arm1_pitch(t), 1.3f * amplitude * level_arm2_pitch(t),
                             0.3f * amplitude * std::cos(t), 0.0f};
            look.wings = mix(kFoldedWings, beats, open);
            look.pitch = mix(-0.2f, 0.45f * (1.0f - p.speed_fraction), open);
            look.spread = 0.8f * open;
            look.bob = open;
            break;
        }
        case FlightMode::Landing: {
            // Braking beats, then the flare as the speed runs out, then the wings fold.
            const float flare = smoothstep(0.4f, 1.0f, 1.0f - p.speed_fraction);
            const float fold = smoothstep(0.0f, kFoldSeconds, p.since_touchdown);
            WingAngles beats{0.6f * amplitude * level_arm1_pitch(t), 0.6f * amplitude * level_arm2_pitch(t),
                             -0.25f + 0.25f * amplitude * std::cos(t), 0.0f};
            look.wings = mix(mix(beats, kFlareWings, flare), kFoldedWings, fold);
            look.pitch = 0.8f * flare * (1.0f - fold);
            look.spread = (0.3f + 0.6f * flare) * (1.0f - fold);
            look.bob = (1.0f - flare) * (1.0f - fold);
            break;
        }
        case FlightMode::Hover:
            // Figure-eight strokes in the (pitched-up) body's horizontal plane.
            look.wings = {0.2f * amplitude * std::sin(2.0f * t), -0.1f * amplitude * std::sin(t), 0.95f * amplitude * std::cos(t),
                          0.0f};
            look.pitch = 0.6f;
            look.spread = 0.5f;
            look.bob = 0.5f;
            break;
    }
    return look;
}

float beat_factor(FlightMode mode, const PerchProgress& p) {
    switch (mode) {
        case FlightMode::Glide: return 0.0f;
        case FlightMode::TakeOff: return p.since_crouch < 0.0f ? 0.0f : 1.25f;
        case FlightMode::Landing: return p.since_touchdown >= 0.0f ? 0.0f : 1.25f;
        default: return 1.0f;
    }
}

}  // namespace kodawari::birds
