// View direction and view weights (SPEC A.3).
#include "kodawari/rods/view.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace kodawari::rods {

glm::vec3 view_direction(const Camera& camera, glm::vec3 reference_position, glm::quat reference_rotation) {
    // R^T v = q^-1 v for a unit quaternion q.
    const glm::quat to_reference = glm::conjugate(reference_rotation);
    if (camera.projection == Camera::Projection::Perspective) {
        const glm::vec3 offset = camera.position - reference_position;
        const float len = glm::length(offset);
        if (len >= 1e-6f) return to_reference * (offset / len);
    }
    return glm::normalize(to_reference * -camera.forward);
}

std::vector<float> view_weights(glm::vec3 d, std::span<const ViewExample> examples) {
    std::vector<float> w(examples.size() + 1, 0.0f);
    float sum = 0.0f;
    for (std::size_t k = 0; k < examples.size(); ++k) {
        assert(examples[k].influence > 0.0f);
        // Clamped: rounding can put the dot of two unit vectors a hair outside [-1, 1],
        // and pow of a negative base is NaN.
        const float s = std::clamp((glm::dot(examples[k].direction, d) + 1.0f) * 0.5f, 0.0f, 1.0f);
        w[k + 1] = std::pow(s, examples[k].influence);
        sum += w[k + 1];
    }
    if (sum >= 1.0f) {
        for (std::size_t k = 1; k < w.size(); ++k) w[k] /= sum;
        sum = 1.0f;
    }
    w[0] = 1.0f - sum;
    return w;
}

}  // namespace kodawari::rods
