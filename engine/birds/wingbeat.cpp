#include "kodawari/birds/wingbeat.hpp"

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
    }
    a.arm1_pitch *= amplitude;
    a.arm2_pitch *= amplitude;
    a.arm1_heading *= amplitude;
    a.arm2_heading *= amplitude;
    return a;
}

}  // namespace kodawari::birds
