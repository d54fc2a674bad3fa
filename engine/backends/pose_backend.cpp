// What every pose backend shares: the checks of the instances (the clip time and the
// placement matrix: animation/pose_instance.cpp; the choice of backend: backend.cpp and
// backend_factory.cpp).
#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>

#include "backends/pose_backends.hpp"

namespace kodawari {

Result<void> check_instances(const animation::Character& character, std::span<const PoseInstance> instances) {
    const std::size_t clips = character.animations.size();
    for (std::size_t i = 0; i < instances.size(); ++i) {
        const PoseInstance& instance = instances[i];
        const std::string which = "instance " + std::to_string(i) + ": ";
        if (instance.clip < -1 || (instance.clip >= 0 && static_cast<std::size_t>(instance.clip) >= clips)) {
            return make_error(Error::Kind::InvalidInput,
                              which + "clip " + std::to_string(instance.clip) + " does not exist; the character has " +
                                  std::to_string(clips) + (clips == 1 ? " animation" : " animations") +
                                  " (-1 is the rest pose)");
        }
        if (!std::isfinite(instance.time_offset)) {
            return make_error(Error::Kind::InvalidInput, which + "the time offset is not finite");
        }
        const glm::vec3& p = instance.placement.position;
        const glm::quat& q = instance.placement.rotation;
        const float parts[7] = {p.x, p.y, p.z, q.x, q.y, q.z, q.w};
        if (!std::all_of(std::begin(parts), std::end(parts), [](float v) { return std::isfinite(v); })) {
            return make_error(Error::Kind::InvalidInput, which + "the placement is not finite");
        }
    }
    return {};
}

}  // namespace kodawari
