// Flight from the wing (docs/wing-types.md). Placeholder until the allometric model lands:
// it scales the nearest built-in wing type's figures.
#include "kodawari/birds/allometry.hpp"

#include <cmath>

#include "kodawari/birds/rig.hpp"

namespace kodawari::birds {

DerivedFlight derive_flight(const WingMeasure& m) {
    DerivedFlight d;
    d.aspect_ratio = m.wingspan * m.wingspan / m.wing_area;
    const WingTypeSpec& s = wing_type_spec(d.aspect_ratio > 9.0f ? WingType::Gull : WingType::Pigeon);
    d.mass = m.mass > 0 ? m.mass : s.mass * std::pow(m.wingspan / s.wingspan, 3.0f);
    d.flap_frequency = s.flap_frequency * s.wingspan / m.wingspan;
    d.amplitude = s.amplitude;
    d.glide_ratio = s.glide_ratio;
    d.cruise_speed = s.cruise_speed;
    d.max_climb = s.max_climb;
    d.max_dive = s.max_dive;
    d.max_speed_change = s.max_speed_change;
    d.flap_glide_beats = s.flap_glide_beats;
    d.flap_glide_seconds = s.flap_glide_seconds;
    return d;
}

}  // namespace kodawari::birds
