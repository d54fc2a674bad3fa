#pragma once
// The spacing of a drawn grid's lines: the ground grid's (render::add_ground_grid) and a
// flock's plane obstacles' (domains/flocking/flock_draw.cpp).

#include <cmath>

namespace kodawari::render {

/// A round spacing (1, 2 or 5 times a power of ten) that gives 10 to 25 lines over
/// `width` (> 0).
inline float grid_spacing(float width) {
    const float rough = width / 10.0f;
    const float decade = std::pow(10.0f, std::floor(std::log10(rough)));
    float spacing = decade;
    for (const float m : {1.0f, 2.0f, 5.0f, 10.0f}) {
        if (m * decade <= rough) spacing = m * decade;
    }
    return spacing;
}

}  // namespace kodawari::render
