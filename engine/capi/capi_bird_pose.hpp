#pragma once
// A bird's pose (gpu::BirdPose: Body's world position, every part's rotation relative to
// its parent) as the C API hands it out: per part a position and a rotation, relative to
// the parent (the rig's offset) or in world space. Shared by the bird worlds
// (capi_birds.cpp) and the scene simulations (capi_simulation.cpp), which must write the
// same floats for the same pose.

#include <array>
#include <cstddef>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/birds/rig.hpp"
#include "kodawari/kodawari.h"
#include "kodawari/shared/birds.h"

namespace kodawari::capi {

using PartOffsets = std::array<std::array<float, 3>, birds::kPartCount>;
/// Floats per bird in kodawari_bird_output's arrays.
inline constexpr std::size_t kFloatsPerBird = KODAWARI_BIRD_PARTS * KODAWARI_TRANSFORM_FLOATS;
static_assert(KODAWARI_BIRD_PARTS == birds::kPartCount && KODAWARI_PART_RIGHT_ARM2 == KW_PART_RIGHT_ARM2,
              "kodawari.h's parts are the rig's, in BirdPose order");

/// Every wing type's rig offsets (birds::part_offsets), indexed by wing type.
inline std::array<PartOffsets, birds::kWingTypeCount> all_part_offsets() {
    std::array<PartOffsets, birds::kWingTypeCount> offsets{};
    for (std::size_t t = 0; t < birds::kWingTypeCount; ++t) offsets[t] = birds::part_offsets(static_cast<birds::WingType>(t));
    return offsets;
}

namespace detail {
inline void put_transform(float* out, const glm::vec3& p, const glm::quat& q) {
    out[0] = p.x;
    out[1] = p.y;
    out[2] = p.z;
    out[3] = q.x;
    out[4] = q.y;
    out[5] = q.z;
    out[6] = q.w;
}
}  // namespace detail

/// One bird's parts: relative to the parent (rig offset, rotation; Body in world space)
/// and in world space (composed down the rig, parents first). Either output may be null.
inline void part_transforms(const gpu::BirdPose& pose, const PartOffsets& offsets, float* local, float* world) {
    std::array<glm::vec3, birds::kPartCount> position{};
    std::array<glm::quat, birds::kPartCount> orientation{};
    for (std::size_t k = 0; k < birds::kPartCount; ++k) {
        const glm::vec3 offset = k == KW_PART_BODY ? glm::vec3(pose.position.x, pose.position.y, pose.position.z)
                                                   : glm::vec3(offsets[k][0], offsets[k][1], offsets[k][2]);
        const gpu::vec4& r = pose.rotation[k];
        const glm::quat q{r.w, r.x, r.y, r.z};
        if (local != nullptr) detail::put_transform(local + k * KODAWARI_TRANSFORM_FLOATS, offset, q);
        const int parent = birds::kPartParents[k];
        if (parent < 0) {
            position[k] = offset;
            orientation[k] = q;
        } else {
            const auto p = static_cast<std::size_t>(parent);
            position[k] = position[p] + orientation[p] * offset;
            orientation[k] = glm::normalize(orientation[p] * q);
        }
        if (world != nullptr) detail::put_transform(world + k * KODAWARI_TRANSFORM_FLOATS, position[k], orientation[k]);
    }
}

}  // namespace kodawari::capi
