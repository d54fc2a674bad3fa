// A user's bird on the 7-part rig (kodawari/birds/bird_model.hpp, docs/bird-models.md):
// the rig's part rotations carried into the bones' own frames.
#include "kodawari/birds/bird_model.hpp"

#include <cassert>

namespace kodawari::birds {

glm::quat model_bone_rotation(const BirdModel& model, std::size_t part, const glm::quat& q) {
    assert(part < kPartCount);
    const glm::quat& c = model.axes[part];
    const animation::Node& bone = model.character.nodes[static_cast<std::size_t>(model.bones[part])];
    // q turns vectors given in the rig part's axes; C takes the bone's frame to those axes,
    // so the same turn of the bone's own vectors is conj(C) q C, made after the bone's
    // rest rotation (its children and its vertices are in the rotated frame).
    return glm::normalize(bone.rotation * (glm::conjugate(c) * q * c));
}

gpu::vec4 model_flight_params(const BirdModel& model) {
    const DerivedFlight& f = model.flight;
    return {f.glide_ratio, f.flap_glide_beats, f.flap_glide_seconds, 0.0f};
}

}  // namespace kodawari::birds
