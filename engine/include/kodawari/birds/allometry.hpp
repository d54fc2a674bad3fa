#pragma once
/// @file
/// Flight from the wing: wingbeat frequency and amplitude, glide ratio, cruise speed and
/// the limits a route is checked against, derived from a wing's span and area and the
/// bird's mass (sources in docs/wing-types.md). Used for a user's bird model and for the
/// built-in wing types alike.

#include "kodawari/core/api.hpp"

namespace kodawari::birds {

/// What is measured of a bird (SI units).
struct WingMeasure {
    float wingspan = 0;     ///< tip to tip, wings spread (m)
    float wing_area = 0;    ///< both wings, projected (m^2)
    float mass = 0;         ///< body mass (kg); 0 = estimate it from the span and area
    float body_length = 0;  ///< beak to tail tip (m)
};

/// What follows from it.
struct DerivedFlight {
    float mass = 0;                ///< kg (the measure's, or the estimate)
    float aspect_ratio = 0;        ///< span^2 / area
    float flap_frequency = 0;      ///< Hz, level flight
    float amplitude = 0;           ///< scale of the wingbeat angles (1 = the seed's)
    float glide_ratio = 0;         ///< best lift-to-drag ratio
    float cruise_speed = 0;        ///< m/s
    float max_climb = 0;           ///< rad
    float max_dive = 0;            ///< rad, positive
    float max_speed_change = 0;    ///< m/s^2
    float flap_glide_beats = 0;    ///< 0: flaps continuously
    float flap_glide_seconds = 0;  ///< s
};

/// Derives the flight of a bird from its measure. The measure must be positive and finite
/// (callers validate user input first).
[[nodiscard]] KODAWARI_API DerivedFlight derive_flight(const WingMeasure& measure);

}  // namespace kodawari::birds
