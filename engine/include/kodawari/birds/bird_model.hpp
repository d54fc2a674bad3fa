#pragma once
/// @file
/// A user's own rigged bird (issue 14, docs/bird-models.md): its glTF character, which of
/// its bones carries each of the 7-part rig's parts (SPEC B.1), how each bone's frame sits
/// against the rig's axes, and what was measured of it (span, area, chord, aspect ratio)
/// with the flight derived from that (allometry.hpp). Loaded by
/// gltf::load_bird_model() (kodawari/gltf/bird_model_import.hpp); the data lives here, on
/// the sim layer, so that the exporter and the renderer can read it without the importer.

#include <array>
#include <cstddef>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/birds/allometry.hpp"
#include "kodawari/birds/rig.hpp"
#include "kodawari/animation/character.hpp"

namespace kodawari::birds {

/// The keys of a mapping file and of the printed mapping, in Part order.
inline constexpr std::array<std::string_view, kPartCount> kModelPartKeys = {
    "body", "head", "tail", "left_upper_wing", "left_lower_wing", "right_upper_wing", "right_lower_wing"};

/// A rigged bird mapped onto the 7-part rig. The rig's axes in the model: glTF's, +Z
/// forward, +Y up, +X the bird's left (glTF 2.0 §3.4: an asset faces +Z).
struct KODAWARI_API BirdModel {
    std::string source;             ///< the file it came from, as given
    std::string name;               ///< the file's stem: the type's name in outputs
    animation::Character character;      ///< the file's nodes, skins, meshes (animation/character.hpp)
    int skin = 0;                   ///< index into character.skins of the bird's skin
    std::string mapped_by;          ///< "name patterns" or the mapping file's path
    /// The node of each part's bone, in Part order.
    std::array<int, kPartCount> bones{};
    /// Per part, the rotation C that takes vectors in the bone's rest frame to the rig
    /// part's axes: a part rotation q (rig axes) is conj(C) q C in the bone's frame.
    std::array<glm::quat, kPartCount> axes{};
    /// Rest translation of each part relative to its parent part, in the rig's axes
    /// (as part_offsets() of a wing type; Body: zero).
    std::array<std::array<float, 3>, kPartCount> offsets{};
    WingMeasure measure;            ///< span, area, mass (estimated when 0 was given), body length
    float mean_chord = 0;           ///< area / span (m)
    DerivedFlight flight;           ///< derive_flight(measure)
};

/// The local rotation of `part`'s bone for the part rotation `q` (in the rig's axes, as
/// BirdPose::rotation holds it): conj(C) q C on top of the bone's rest rotation.
[[nodiscard]] KODAWARI_API glm::quat model_bone_rotation(const BirdModel& model, std::size_t part, const glm::quat& q);

/// BirdParams::flight of a bird of this model (flight_params() of the derived figures).
[[nodiscard]] KODAWARI_API gpu::vec4 model_flight_params(const BirdModel& model);

}  // namespace kodawari::birds
