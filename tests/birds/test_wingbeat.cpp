// SPEC B.2: the seed's wingbeat functions (eqs. 4.1-4.5).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "kodawari/birds/wingbeat.hpp"

using namespace kodawari::birds;
namespace {
constexpr float kPi = std::numbers::pi_v<float>;
// Float evaluation of closed forms: a few ulps of values up to ~2.
constexpr float kTol = 1e-6f;
}  // namespace

TEST(Wingbeat, LevelArm1IsTheSeedsTrapezoid) {
    EXPECT_NEAR(level_arm1_pitch(0.0f), 0.0f, kTol);
    EXPECT_NEAR(level_arm1_pitch(0.25f * kPi), 0.0f, kTol);
    EXPECT_NEAR(level_arm1_pitch(0.75f * kPi), -kPi / 6.0f, kTol);  // -(2/3)t + pi/3
    EXPECT_NEAR(level_arm1_pitch(1.25f * kPi), -kPi / 3.0f, kTol);
    EXPECT_NEAR(level_arm1_pitch(1.75f * kPi), -kPi / 6.0f, kTol);  // +(2/3)t - 4pi/3 (resolved sign)
}

TEST(Wingbeat, LevelArm1IsContinuousAtEveryBreakpointAndAcrossTheCycle) {
    // The resolved last piece is what makes 3pi/2 and 2pi continuous (SPEC B.2).
    const float eps = 1e-4f;
    for (float b : {0.5f * kPi, kPi, 1.5f * kPi}) {
        EXPECT_NEAR(level_arm1_pitch(b - eps), level_arm1_pitch(b + eps), 1e-3f) << "breakpoint " << b;
    }
    EXPECT_NEAR(level_arm1_pitch(2.0f * kPi - eps), level_arm1_pitch(0.0f), 1e-3f);
}

TEST(Wingbeat, HalfCyclePiecesUseTheirOwnAmplitudes) {
    EXPECT_NEAR(level_arm2_pitch(0.5f * kPi), -kPi / 3.0f, kTol);
    EXPECT_NEAR(level_arm2_pitch(1.5f * kPi), (3.0f / 18.0f) * kPi, kTol);
    EXPECT_NEAR(ascend_arm2_pitch(0.5f * kPi), -(4.0f / 9.0f) * kPi, kTol);
    EXPECT_NEAR(ascend_arm2_pitch(1.5f * kPi), (5.0f / 18.0f) * kPi, kTol);
    EXPECT_NEAR(descend_arm1_heading(0.5f * kPi), kPi / 180.0f, kTol);
    EXPECT_NEAR(descend_arm2_heading(0.5f * kPi), -kPi / 36.0f, kTol);
    EXPECT_NEAR(descend_arm2_heading(1.5f * kPi), kPi / 90.0f, kTol);
}

TEST(Wingbeat, ModesUseTheirOwnFunctionsAndAmplitudeScalesAll) {
    const float t = 0.6f * kPi;
    const WingAngles level = wing_angles(FlightMode::Level, t, 1.0f);
    EXPECT_EQ(level.arm1_pitch, level_arm1_pitch(t));
    EXPECT_EQ(level.arm2_pitch, level_arm2_pitch(t));
    EXPECT_EQ(level.arm1_heading, 0.0f);
    const WingAngles ascend = wing_angles(FlightMode::Ascend, t, 1.0f);
    EXPECT_EQ(ascend.arm1_pitch, level_arm2_pitch(t));  // the seed reuses eq. 4.2 for arm1
    EXPECT_EQ(ascend.arm2_pitch, ascend_arm2_pitch(t));
    const WingAngles descend = wing_angles(FlightMode::Descend, t, 1.0f);
    EXPECT_EQ(descend.arm1_pitch, 0.0f);
    EXPECT_EQ(descend.arm1_heading, descend_arm1_heading(t));
    EXPECT_EQ(descend.arm2_heading, descend_arm2_heading(t));
    const WingAngles half = wing_angles(FlightMode::Ascend, t, 0.5f);
    EXPECT_NEAR(half.arm2_pitch, 0.5f * ascend.arm2_pitch, kTol);
}
