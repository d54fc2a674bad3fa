#pragma once
/// @file
/// The view direction and the blending weights of the view examples (SPEC A.3).

#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"

namespace kodawari::rods {

/// One view example's direction and influence (SPEC A.1); its shape is kept alongside
/// by the caller, in the same order.
struct ViewExample {
    glm::vec3 direction{0.0f, 0.0f, 1.0f};  ///< d_k, unit, in the reference joint's frame
    float influence = 1.0f;                 ///< p_k > 0: small reaches far, large stays local
};

/// The largest influence p_k scenes, the C API and sketches take: at 1000 an example's
/// weight s^p is below 1e-30 for every view more than 21 degrees off its direction, so a
/// larger one gives nothing a person could tell apart.
inline constexpr float kMaxInfluence = 1000.0f;

/// The camera, in world space.
struct Camera {
    enum class Projection { Perspective, Orthographic };
    Projection projection = Projection::Perspective;
    glm::vec3 position{0.0f};                ///< used by Perspective
    glm::vec3 forward{0.0f, 0.0f, -1.0f};    ///< unit, the way the camera looks; used by Orthographic
};

/// The view direction d in the reference joint's frame (SPEC A.3): from the reference
/// joint towards the camera, d = normalize(R_ref^T (camera_position - p_ref)), or
/// d = -R_ref^T camera_forward for an orthographic camera. A perspective camera sitting
/// on the reference joint (closer than 1e-6 m) has no direction from it; the
/// orthographic formula is used there so that d is always a unit vector.
[[nodiscard]] KODAWARI_API glm::vec3 view_direction(const Camera& camera, glm::vec3 reference_position,
                                                    glm::quat reference_rotation);

/// The weights w_0 .. w_m (SPEC A.3, exactly the seed's algorithm): s_k = (d_k . d + 1)/2,
/// w_k = s_k^p_k, S = sum w_k; if S >= 1 all w_k /= S and S = 1; w_0 = 1 - S.
/// Returns m + 1 weights, w_0 (the base shape's) first; they sum to 1 and lie in [0, 1].
/// Asserts every influence > 0.
[[nodiscard]] KODAWARI_API std::vector<float> view_weights(glm::vec3 d, std::span<const ViewExample> examples);

}  // namespace kodawari::rods
