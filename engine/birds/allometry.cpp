// Flight from the wing. Every formula and constant, with its source, is in
// docs/wing-types.md ("Flight from the wing"); the step numbers below are that section's.
// Double precision throughout: the result is a handful of constants per bird type, and
// the built-in types' figures are compared with it in tests/birds/test_allometry.cpp.
#include "kodawari/birds/allometry.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

namespace kodawari::birds {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kGravity = 9.81;     // m/s^2, as in Pennycuick (1996)
constexpr double kAirDensity = 1.225;  // kg/m^3, sea level (ISA); P96 uses rho explicitly

// (1) Mass from span and area (Rayner 1988, as quoted by Norberg 1990): b = 1.17 m^0.39,
// S = 0.16 m^0.72 across birds. The two inversions disagree for any real bird (a gull's
// long wings say heavier than its area does), so we take their geometric mean.
double estimated_mass(double span, double area) {
    const double from_span = std::pow(span / 1.17, 1.0 / 0.39);
    const double from_area = std::pow(area / 0.16, 1.0 / 0.72);
    return std::sqrt(from_span * from_area);
}

// (2) Drag polar. Induced power factor k = 1.2 (Pennycuick 2008), so the span efficiency
// e = 1/k; zero-lift drag = wing profile drag (C_Dpro = 0.02) plus body drag (C_Db = 0.1 on
// the frontal area S_b = 0.00813 m^(2/3), Pennycuick 2008) referred to the wing area.
constexpr double kInducedFactor = 1.2;
constexpr double kProfileDrag = 0.02;
constexpr double kBodyDrag = 0.1;
double zero_lift_drag(double mass, double area) {
    const double frontal = 0.00813 * std::pow(mass, 2.0 / 3.0);
    return kProfileDrag + kBodyDrag * frontal / area;
}

// (5) Strouhal number of cruising flight: Taylor, Nudds & Thomas (2003) find
// 0.2 < St < 0.4; we take the middle.
constexpr double kStrouhal = 0.3;

// (6) Sustained climb rate, a two-point power law through the extremes Hedenström &
// Alerstam (1992) measured by radar: 1.63 m/s (dunlin, ~0.05 kg) and 0.32 m/s (mute
// swan, ~10 kg): v_z = 0.65 m^-0.307.
double sustained_climb_rate(double mass) {
    const double exponent = std::log(0.32 / 1.63) / std::log(10.0 / 0.05);
    const double coefficient = 1.63 / std::pow(0.05, exponent);
    return coefficient * std::pow(mass, exponent);
}
// A route's climbs and turns last seconds, not the minutes of a migratory climb; over
// that time a bird spends more than its sustained margin. Ours, unverified: four times.
constexpr double kManoeuvreFactor = 4.0;

// (8) Flap-gliding: Rayner (1985) finds it pays for large birds (small ones bound
// instead); we take 0.5 kg as the line, and a flapping phase of about 2 s (ours).
constexpr double kFlapGlideMass = 0.5;
constexpr double kFlapPhaseSeconds = 2.0;

}  // namespace

DerivedFlight derive_flight(const WingMeasure& m) {
    assert(std::isfinite(m.wingspan) && m.wingspan > 0.0f);
    assert(std::isfinite(m.wing_area) && m.wing_area > 0.0f);
    assert(std::isfinite(m.mass) && m.mass >= 0.0f);
    const double b = m.wingspan;
    const double S = m.wing_area;
    const double mass = m.mass > 0.0f ? double{m.mass} : estimated_mass(b, S);
    const double aspect = b * b / S;
    const double weight = mass * kGravity;

    // (3) Wingbeat frequency, Pennycuick (1996): f = m^(3/8) g^(1/2) b^(-23/24) S^(-1/3) rho^(-3/8).
    const double frequency = std::pow(mass, 3.0 / 8.0) * std::sqrt(kGravity) * std::pow(b, -23.0 / 24.0) *
                             std::pow(S, -1.0 / 3.0) * std::pow(kAirDensity, -3.0 / 8.0);

    // (4) Glide ratio and cruise speed from the parabolic polar C_D = C_D0 + K C_L^2 with
    // K = k / (pi AR): (L/D)max = 0.5 sqrt(pi e AR / C_D0), reached at the minimum-drag
    // speed V = sqrt(2 W / (rho S)) (K / C_D0)^(1/4), which is also the maximum-range
    // speed at which Pennycuick (2008) and Alerstam et al. (2007) find birds cruise.
    const double cd0 = zero_lift_drag(mass, S);
    const double induced = kInducedFactor / (kPi * aspect);
    const double glide_ratio = 0.5 * std::sqrt(1.0 / (induced * cd0));
    const double cruise = std::sqrt(2.0 * weight / (kAirDensity * S)) * std::pow(induced / cd0, 0.25);

    // (5) Amplitude: the tip excursion St U / f against the seed's, whose level-flight
    // arm1 stroke takes the tip from level to pi/3 below (SPEC B.2 eq. 4.1): (b/2) sin(pi/3).
    const double excursion = kStrouhal * cruise / frequency;
    const double amplitude = excursion / (0.5 * b * std::sin(kPi / 3.0));

    // (6) Climb: the power margin lifts the weight at v_z, so at the cruise speed the
    // steepest climb is asin(v_z / V). (7) The same margin spent on speed instead,
    // m a V = m g v_z, gives the largest speed change; in a dive at constant speed the bird
    // must shed g sin(gamma) per unit mass: its glide drag (g / (L/D)) and the same margin.
    const double climb_rate = kManoeuvreFactor * sustained_climb_rate(mass);
    const double climb_sine = std::min(1.0, climb_rate / cruise);
    const double dive_sine = std::min(1.0, climb_sine + 1.0 / glide_ratio);

    DerivedFlight d;
    d.mass = static_cast<float>(mass);
    d.aspect_ratio = static_cast<float>(aspect);
    d.flap_frequency = static_cast<float>(frequency);
    d.amplitude = static_cast<float>(amplitude);
    d.glide_ratio = static_cast<float>(glide_ratio);
    d.cruise_speed = static_cast<float>(cruise);
    d.max_climb = static_cast<float>(std::asin(climb_sine));
    d.max_dive = static_cast<float>(std::asin(dive_sine));
    d.max_speed_change = static_cast<float>(kGravity * climb_sine);
    if (mass >= kFlapGlideMass) {
        // (8) The glide loses height at V / (L/D); the beats regain it at the sustained climb
        // rate: t_glide V / (L/D) = (n / f) v_z.
        const double beats = std::max(1.0, std::round(frequency * kFlapPhaseSeconds));
        d.flap_glide_beats = static_cast<float>(beats);
        d.flap_glide_seconds =
            static_cast<float>(beats / frequency * sustained_climb_rate(mass) * glide_ratio / cruise);
    }
    return d;
}

}  // namespace kodawari::birds
