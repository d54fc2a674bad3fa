// The clip time and placement matrix of a crowd instance, the same on every pose backend and in the rod scene.
#include "kodawari/animation/pose_instance.hpp"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace kodawari {

float clip_time(const animation::Animation& clip, const PoseInstance& instance, float time) {
    const float t = time + instance.time_offset;
    if (!instance.loop) return t;
    const float d = clip.end - clip.start;
    if (d == 0.0f) return clip.start;
    // shaders/pose_eval.comp computes the same expression with the same roundings (its
    // division in integer arithmetic, correctly rounded like this one); this library
    // builds with -ffp-contract=off, so d * floor(...) is not fused into the subtraction.
    return clip.start + (t - clip.start) - d * std::floor((t - clip.start) / d);
}

glm::mat4 placement_matrix(const rods::Transform& placement) {
    return glm::translate(glm::mat4(1.0f), placement.position) * glm::mat4_cast(placement.rotation);
}

}  // namespace kodawari
