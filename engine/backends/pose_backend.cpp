// What every pose backend shares: the clip time, the placement matrix, the checks of the
// instances, and the choice of backend.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "backends/pose_backends.hpp"

namespace kodawari {

float clip_time(const gltf::Animation& clip, const PoseInstance& instance, float time) {
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

Result<void> check_instances(const gltf::Character& character, std::span<const PoseInstance> instances) {
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

Result<std::unique_ptr<PoseBackend>> make_pose_backend(BackendKind kind, const BackendOptions& options) {
    switch (kind) {
        case BackendKind::CpuReference: return make_cpu_pose_backend(true, 1);
        case BackendKind::Cpu: return make_cpu_pose_backend(false, options.threads);
        case BackendKind::Vulkan: return make_vulkan_pose_backend(options);
    }
    return make_error(Error::Kind::Internal, "unknown backend");
}

}  // namespace kodawari
