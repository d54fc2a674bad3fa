// Wind (kodawari/rods/wind.hpp): the field's checks, and its air velocity from the one
// definition that rods_step.comp compiles too (shaders/lib/wind.glsl), here over GLM.
#include "kodawari/rods/wind.hpp"

#include <cmath>
#include <string>

namespace kodawari::rods {

namespace glsl {
// GLSL's names for shaders/lib/wind.glsl (inside this namespace only).
using namespace glm;
using uint = std::uint32_t;
#define KW_WIND_FN inline
#include "lib/wind.glsl"
#undef KW_WIND_FN
}  // namespace glsl

Result<void> validate(const WindField& wind, const char* what) {
    auto bad = [&](const std::string& field, const std::string& expected) {
        return make_error(Error::Kind::InvalidInput, std::string(what) + "." + field + ": expected " + expected);
    };
    for (int i = 0; i < 3; ++i) {
        if (!(std::abs(wind.velocity[i]) <= 100.0f)) return bad("velocity", "3 numbers in [-100, 100] m/s");
    }
    if (!(wind.gust >= 0.0f && wind.gust <= 4.0f)) return bad("gust", "a number in [0, 4]");
    if (!(wind.gust_period >= 0.05f && wind.gust_period <= 1000.0f)) return bad("gust_period", "a number in [0.05, 1000] s");
    if (!(wind.gust_size >= 0.05f && wind.gust_size <= 10000.0f)) return bad("gust_size", "a number in [0.05, 10000] m");
    return {};
}

glm::vec3 air_velocity(const WindField& wind, const glm::vec3& position, float time) {
    return glsl::wind_air_velocity(wind.velocity, wind.gust, 1.0f / wind.gust_period, 1.0f / wind.gust_size, wind.seed,
                                   position, time);
}

}  // namespace kodawari::rods
