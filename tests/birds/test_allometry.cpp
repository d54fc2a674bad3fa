// Flight from the wing (docs/wing-types.md "Flight from the wing"): each formula against
// a value worked by hand for a real bird, its trends, and the built-in wing types.
#include <gtest/gtest.h>

#include <cmath>

#include "kodawari/birds/allometry.hpp"
#include "kodawari/birds/rig.hpp"

using namespace kodawari::birds;

namespace {

constexpr double kDeg = 0.017453292519943295;

// The measures of docs/wing-types.md (pigeon and gull tables; hummingbird table; starling
// table: area = mean chord 0.060 m * span 0.40 m).
constexpr WingMeasure kPigeon{0.67f, 0.065f, 0.31f, 0.33f};
constexpr WingMeasure kGull{1.40f, 0.20f, 1.0f, 0.60f};
constexpr WingMeasure kHummingbird{0.11f, 0.00154f, 0.0034f, 0.09f};
constexpr WingMeasure kStarling{0.40f, 0.024f, 0.082f, 0.215f};

// The hand values below carry 4-5 significant digits and the model runs in double
// precision from float inputs (relative rounding ~1e-7): 0.1 % covers the hand
// rounding and nothing else, so a wrong exponent or constant (a few per cent at least) fails.
void expect_near_relative(double got, double want, const char* what) {
    EXPECT_NEAR(got, want, 1e-3 * std::fabs(want)) << what;
}

}  // namespace

TEST(Allometry, WingbeatFrequencyIsPennycuicks1996) {
    // Pigeon: f = m^(3/8) g^(1/2) b^(-23/24) S^(-1/3) rho^(-3/8)
    //   = 0.31^0.375 * 9.81^0.5 * 0.67^-0.95833 * 0.065^-0.33333 * 1.225^-0.375
    //   = 0.64460 * 3.13209 * 1.46782 * 2.48713 * 0.92672 = 6.830 Hz
    // (docs/wing-types.md quotes the same P96 estimate, 6.8 Hz, against a field 5.5 Hz.)
    expect_near_relative(derive_flight(kPigeon).flap_frequency, 6.830, "pigeon");
    // Gull: 1 * 3.13209 * 1.4^-0.95833 (0.72437) * 0.2^-0.33333 (1.70998) * 0.92672 = 3.595 Hz.
    expect_near_relative(derive_flight(kGull).flap_frequency, 3.595, "gull");
    // Hummingbird: 0.11865 * 3.13209 * 8.2920 * 8.6654 * 0.92672 = 24.73 Hz, half of the
    // ruby-throated hummingbird's ~53 Hz: P96 was fitted to cruising birds, not hoverers.
    expect_near_relative(derive_flight(kHummingbird).flap_frequency, 24.73, "hummingbird");
}

TEST(Allometry, GlideRatioFromAspectRatioAndDrag) {
    // Gull: AR = 1.4^2 / 0.2 = 9.8; C_D0 = 0.02 + 0.1 * 0.00813 * 1^(2/3) / 0.2 = 0.024065;
    // K = 1.2 / (pi * 9.8) = 0.038977; (L/D)max = 0.5 / sqrt(K C_D0) = 0.5 / 0.030627 = 16.33.
    const DerivedFlight gull = derive_flight(kGull);
    expect_near_relative(gull.aspect_ratio, 9.8, "aspect ratio");
    expect_near_relative(gull.glide_ratio, 16.33, "gull");
    // Pigeon: AR 6.9062, C_D0 = 0.02 + 0.1 * 0.00813 * 0.45803 / 0.065 = 0.025729,
    // K = 0.055309: 0.5 / sqrt(0.0014231) = 13.25.
    expect_near_relative(derive_flight(kPigeon).glide_ratio, 13.25, "pigeon");
}

TEST(Allometry, CruiseSpeedIsTheMinimumDragSpeed) {
    // Pigeon: sqrt(2 * 0.31 * 9.81 / (1.225 * 0.065)) = 8.7399 m/s times
    // (K / C_D0)^(1/4) = (0.055309 / 0.025729)^0.25 = 1.21085: 10.58 m/s, within the
    // 8-23 m/s of Alerstam et al. (2007) and below the homing pigeon's 19.7 m/s.
    expect_near_relative(derive_flight(kPigeon).cruise_speed, 10.58, "pigeon");
    // Gull: sqrt(2 * 9.81 / (1.225 * 0.2)) = 8.9489 * (0.038977 / 0.024065)^0.25 (1.12812) = 10.10 m/s.
    expect_near_relative(derive_flight(kGull).cruise_speed, 10.10, "gull");
}

TEST(Allometry, AmplitudeFromTheStrouhalNumber) {
    // Hummingbird: V = 6.6051 m/s, f = 24.731 Hz; tip excursion A = St V / f = 0.3 * 6.6051 /
    // 24.731 = 0.080122 m; the seed's is (b/2) sin 60 deg = 0.055 * 0.86603 = 0.047631 m: 1.682.
    expect_near_relative(derive_flight(kHummingbird).amplitude, 1.682, "hummingbird");
    // Pigeon: 0.3 * 10.583 / 6.8300 = 0.46484 m against 0.335 * 0.86603 = 0.29012 m: 1.602.
    expect_near_relative(derive_flight(kPigeon).amplitude, 1.602, "pigeon");
}

TEST(Allometry, MassFromSpanAndArea) {
    // Pigeon without its mass: (0.67 / 1.17)^(1/0.39) = 0.23944 kg from the span,
    // (0.065 / 0.16)^(1/0.72) = 0.28619 kg from the area; geometric mean 0.2618 kg
    // (the bird weighs 0.31 kg: the fit is a trend across birds, not a species).
    WingMeasure pigeon = kPigeon;
    pigeon.mass = 0.0f;
    expect_near_relative(derive_flight(pigeon).mass, 0.2618, "pigeon");
    // A given mass is kept.
    EXPECT_EQ(derive_flight(kPigeon).mass, 0.31f);
}

TEST(Allometry, RouteLimitsFromThePowerMargin) {
    // Gull: sustained climb rate 0.65 m^-0.307 (Hedenström & Alerstam 1992) = 0.64926 m/s at
    // 1 kg, four times for a manoeuvre: 2.5970 m/s; at 10.095 m/s: sin(climb) = 0.25726,
    // climb 14.91 deg; speed change g * 0.25726 = 2.524 m/s^2; dive: sin = 0.25726 + 1/16.326
    // = 0.31851, 18.57 deg.
    const DerivedFlight gull = derive_flight(kGull);
    expect_near_relative(gull.max_climb, 14.91 * kDeg, "climb");
    expect_near_relative(gull.max_speed_change, 2.524, "speed change");
    expect_near_relative(gull.max_dive, 18.57 * kDeg, "dive");
    // Flap-gliding (1 kg >= 0.5 kg): round(3.5953 * 2 s) = 7 beats; the glide then lasts
    // 7 / 3.5953 * 0.64926 * 16.326 / 10.095 = 2.044 s.
    EXPECT_EQ(gull.flap_glide_beats, 7.0f);
    expect_near_relative(gull.flap_glide_seconds, 2.044, "glide seconds");
    // A pigeon (0.31 kg) flaps continuously; a hummingbird's margin exceeds its speed: it
    // can climb straight up.
    EXPECT_EQ(derive_flight(kPigeon).flap_glide_beats, 0.0f);
    EXPECT_EQ(derive_flight(kHummingbird).max_climb, static_cast<float>(90.0 * kDeg));
}

TEST(Allometry, LongerWingsGlideFartherAndBiggerBirdsBeatSlower) {
    // Longer wings of the same chord: higher aspect ratio, higher glide ratio.
    float previous = 0.0f;
    for (float span = 0.4f; span <= 2.0f; span += 0.2f) {
        const float glide = derive_flight({span, 0.12f * span, 0.5f, 0.4f}).glide_ratio;
        EXPECT_GT(glide, previous) << span;
        previous = glide;
    }
    // Heavier birds of the same shape (span ~ m^(1/3), area ~ m^(2/3)) beat slower: P96
    // gives f ~ m^(-1/6) for geometric similarity.
    previous = 1e9f;
    for (float mass = 0.01f; mass <= 10.0f; mass *= 2.0f) {
        const float scale = std::cbrt(mass / 0.31f);
        const float f = derive_flight({0.67f * scale, 0.065f * scale * scale, mass, 0.33f * scale}).flap_frequency;
        EXPECT_LT(f, previous) << mass;
        previous = f;
    }
    // Heavier on the same wings (more load): faster and beating faster, f ~ m^(3/8).
    EXPECT_GT(derive_flight({0.67f, 0.065f, 0.40f, 0.33f}).flap_frequency, derive_flight(kPigeon).flap_frequency);
}

TEST(Allometry, BadMeasuresAreTheCallersBug) {
    // Callers validate user input (docs/wing-types.md); a zero span reaching the model is
    // a programmer error, caught by its assert in debug builds.
    EXPECT_DEBUG_DEATH((void)derive_flight({0.0f, 0.065f, 0.31f, 0.33f}), "wingspan");
    EXPECT_DEBUG_DEATH((void)derive_flight({0.67f, -1.0f, 0.31f, 0.33f}), "wing_area");
    EXPECT_DEBUG_DEATH((void)derive_flight({0.67f, 0.065f, NAN, 0.33f}), "mass");
}

TEST(Allometry, BuiltInWingTypesFollowTheModel) {
    // The figures no field measure gives (glide ratio, flap-glide rhythm, route limits)
    // are the model's for each type's span, area (mean chord * span) and mass, rounded
    // to three significant digits in engine/birds/rig.cpp: within 1 %, or 0.02 absolute
    // near zero. Frequency, speed and amplitude stay the field figures (the table of
    // docs/wing-types.md shows both).
    for (std::size_t i = 0; i < kWingTypeCount; ++i) {
        const WingTypeSpec& s = wing_type_spec(static_cast<WingType>(i));
        const DerivedFlight d = derive_flight({s.wingspan, s.mean_chord * s.wingspan, s.mass, s.body_length});
        const auto near = [&](double got, double want, const char* what) {
            EXPECT_NEAR(got, want, std::max(0.01 * std::fabs(want), 0.02)) << s.name << " " << what;
        };
        near(s.glide_ratio, d.glide_ratio, "glide ratio");
        near(s.flap_glide_beats, d.flap_glide_beats, "flap-glide beats");
        near(s.flap_glide_seconds, d.flap_glide_seconds, "flap-glide seconds");
        near(s.max_climb, d.max_climb, "max climb");
        near(s.max_dive, d.max_dive, "max dive");
        near(s.max_speed_change, d.max_speed_change, "max speed change");
        // Only the hummingbird hovers.
        EXPECT_EQ(s.can_hover, static_cast<WingType>(i) == WingType::Hummingbird) << s.name;
    }
}

TEST(Allometry, StarlingFlightIsTheDocsTable) {
    // docs/wing-types.md, section 5 and "The built-in types: derived and field figures",
    // worked by hand from b = 0.40 m, S = 0.024 m^2 (AR 6.667), m = 0.082 kg:
    const DerivedFlight d = derive_flight(kStarling);
    // f = 0.082^0.375 (0.39148) * 3.13209 * 0.40^-0.95833 (2.4062) * 0.024^-0.33333 (3.4668)
    //   * 0.92672 = 9.479 Hz (P96).
    expect_near_relative(d.flap_frequency, 9.479, "frequency");
    // C_D0 = 0.02 + 0.1 * 0.00813 * 0.082^(2/3) (0.18874) / 0.024 = 0.026394, K = 1.2 /
    // (pi * 6.6667) = 0.057296: (L/D)max = 0.5 / sqrt(K C_D0) = 12.86; V = sqrt(2 * 0.082 *
    // 9.81 / (1.225 * 0.024)) (7.3974) * (K / C_D0)^(1/4) (1.21383) = 8.979 m/s.
    expect_near_relative(d.glide_ratio, 12.86, "glide ratio");
    expect_near_relative(d.cruise_speed, 8.979, "cruise speed");
    // Tip excursion 0.3 * 8.979 / 9.479 = 0.28418 m against 0.2 * sin 60 deg = 0.17321 m.
    expect_near_relative(d.amplitude, 1.6407, "amplitude");
    // Sustained climb 0.64926 * 0.082^-0.30727 = 1.4001 m/s (the power law's coefficient and
    // exponent unrounded, as for the gull), four times 5.6006 m/s: sin(climb) = 5.6006 /
    // 8.979 = 0.62374, climb 38.59 deg, speed change 9.81 * 0.62374 = 6.119 m/s^2;
    // sin(dive) = 0.62374 + 1 / 12.86 = 0.70150, dive 44.55 deg.
    expect_near_relative(d.max_climb, 38.59 * kDeg, "max climb");
    expect_near_relative(d.max_speed_change, 6.119, "max speed change");
    expect_near_relative(d.max_dive, 44.55 * kDeg, "max dive");
    // 82 g is under the 0.5 kg of flap-gliding: it flaps continuously.
    EXPECT_EQ(d.flap_glide_beats, 0.0f);
    EXPECT_EQ(d.flap_glide_seconds, 0.0f);

    // The built-in type is that table: its frequency is the P96 estimate (no measured one was
    // read), its cruise speed the field 15 m/s (not the 8.98 m/s of maximum range), and its
    // limits the model's to three digits.
    const WingTypeSpec& s = wing_type_spec(WingType::Starling);
    EXPECT_EQ(s.name, "starling");
    EXPECT_EQ(parse_wing_type("starling"), WingType::Starling);
    EXPECT_EQ(s.wingspan, kStarling.wingspan);
    EXPECT_EQ(s.mass, kStarling.mass);
    EXPECT_EQ(s.body_length, kStarling.body_length);
    EXPECT_NEAR(s.mean_chord * s.wingspan, kStarling.wing_area, 1e-7);
    EXPECT_NEAR(s.flap_frequency, d.flap_frequency, 0.005);
    EXPECT_EQ(s.cruise_speed, 15.0f);
    EXPECT_EQ(s.amplitude, 1.0f);
    EXPECT_FLOAT_EQ(s.glide_ratio, 12.9f);
    EXPECT_FLOAT_EQ(s.max_climb, static_cast<float>(38.6 * kDeg));
    EXPECT_FLOAT_EQ(s.max_dive, static_cast<float>(44.5 * kDeg));
    EXPECT_FLOAT_EQ(s.max_speed_change, 6.12f);
    EXPECT_EQ(s.flap_glide_beats, 0.0f);
    EXPECT_FALSE(s.can_hover);
}
