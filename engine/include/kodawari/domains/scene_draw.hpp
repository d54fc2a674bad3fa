#pragma once
/// @file
/// Draw lists of a scene's content besides what its domains simulate: the scene camera,
/// the characters (skeleton bones, faces, legs, contact shadows) and the birds' perches.
/// The chains, colliders, skinned meshes and birds are the domains' render layers
/// (kodawari/domains/chain_draw.hpp, bird_draw.hpp). Shared by `kodawari render` and
/// `kodawari view`.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/domains/chain_draw.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/scene/scene.hpp"

namespace kodawari {

inline constexpr render::Rgba8 kBoneColor{50, 60, 80};
/// The scene camera at `frame` (time = frame / fps) as scene.camera.motion gives it, the
/// same pose RodScene::camera_pose gives characters, and its projection: an orthographic
/// camera is as tall as the perspective frustum at its target (rods::ImageCamera's
/// convention). Perspective near and far planes follow the distance to the target:
/// near = 1% of it (within [0.01, 1] m), far = 1000 x near; orthographic: 0.01 to 10 km.
[[nodiscard]] KODAWARI_API render::CameraView scene_camera(const Scene& scene, std::uint32_t frame);

/// Whether a rigged character is drawn as its skinned mesh (the chain domain's skinned-mesh
/// layer, show_skinned()) rather than as bones: some node has a mesh with triangles.
[[nodiscard]] KODAWARI_API bool draws_skinned(const animation::Character& character);

/// The darkest a contact shadow gets (a character whose lowest joint is on the ground).
inline constexpr float kShadowOpacity = 0.35f;

/// A soft contact shadow on the ground under a character posed as `joints` (root first):
/// a disc under the joints' centroid about as wide as the body (0.3 x the skeleton's height), fading
/// as the character rises off the ground (kShadowOpacity when it stands on it).
KODAWARI_API void add_contact_shadow(render::DrawList& list, std::span<const rods::Transform> joints);

/// A character's head: the largest sphere collider on its reference joint (the joint the
/// view examples are measured from), posed. Its face looks along the joint's +Z (the
/// characters' forward, as walks and the view examples' "front" are).
struct Head {
    glm::vec3 centre{0.0f};
    glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  ///< the reference joint's
    float radius = 0.0f;
};

/// Character instance `c`'s head posed as `joints` (RodScene::joint_poses), or none when
/// its reference joint has no outside sphere collider.
[[nodiscard]] KODAWARI_API std::optional<Head> head_of(const RodScene& scene, std::uint32_t c,
                                                       std::span<const rods::Transform> joints);

/// The eyes: dark ovals on the head sphere, kEyeAzimuthDeg either side of the face and
/// kEyeElevationDeg above its middle (where the tests measure the bangs' clearance from
/// the eyes: tests/character_support.hpp), with a short mouth below.
inline constexpr float kEyeAzimuthDeg = 20.0f;
inline constexpr float kEyeElevationDeg = 5.0f;
inline constexpr render::Rgba8 kFaceColor{40, 32, 48};

/// The centres of the eyes on the head's surface: the character's left eye (+X of the
/// head frame) first.
[[nodiscard]] KODAWARI_API std::array<glm::vec3, 2> eye_centres(const Head& head);

/// The face of `head` (unlit, kFaceColor), 1% of the radius off the sphere: the renderer's
/// low-poly sphere lies inside the true one, so the face shows in front of it where the
/// face is turned to the camera and is hidden behind the head where it is turned away.
KODAWARI_API void add_face(render::DrawList& list, const Head& head);

/// Legs of a procedural character whose skeleton stops above the floor (the body, neck,
/// head characters: the body joint is the hips, 0.9 m up): two straight legs from the
/// lowest joint down to the floor the character stands on (its placement's height; the
/// ground, y = 0, in every shipped scene), each ending in a foot that points forward.
inline constexpr float kLegRadius = 0.05f;
inline constexpr float kHipHalfWidth = 0.075f;
inline constexpr float kFootLength = 0.14f;
struct Legs {
    std::array<glm::vec3, 2> hip{};   ///< the legs' tops (inside the body)
    std::array<glm::vec3, 2> foot{};  ///< on the floor, under the hips
    glm::vec3 forward{0.0f, 0.0f, 1.0f};  ///< the feet's direction (horizontal, unit)
};

/// Character instance `c`'s legs posed as `joints`, or none: a rigged character (its
/// model has legs), or a skeleton whose lowest joint is within 0.1 m of the floor.
[[nodiscard]] KODAWARI_API std::optional<Legs> legs_of(const RodScene& scene, std::uint32_t c,
                                                       std::span<const rods::Transform> joints);

/// The legs as lit tubes in kColliderColor (the body's colour).
KODAWARI_API void add_legs(render::DrawList& list, const Legs& legs);

/// Every character instance of `scene` at `frame`: its contact shadow (add_contact_shadow,
/// the feet included), and, unless it is drawn as a skinned mesh (show_skinned()),
/// its skeleton bones from RodScene::joint_poses, its face (add_face) and its legs
/// (add_legs). The colliders are the chain domain's layer (draw_colliders()).
KODAWARI_API void add_characters(render::DrawList& list, const RodScene& scene, std::uint32_t frame);

/// The perches of a scene's birds, which the scene gives only as routes: a roof under
/// the birds' bellies where a route takes off (its first point) or lands (its last),
/// and a flower bed on the ground under a route with hovering segments.
struct Roof {
    /// The ends of the ridge's middle line: the flat top the perched birds' bellies rest
    /// on (a bird's belly is kBellyDepth x its body length under its position).
    glm::vec3 a{0.0f}, b{0.0f};
    glm::vec3 across{0.0f, 0.0f, 1.0f};  ///< horizontal, unit: the route's heading there
    float cap = 0.0f;         ///< the flat top's half-width across the ridge
    float half_depth = 0.0f;  ///< the eaves' distance from the ridge's middle line
};
struct FlowerBed {
    glm::vec2 lo{0.0f}, hi{0.0f};  ///< x, z extent
    /// The soil's height: kFlowerGap under the lowest point the birds hover at, on a
    /// flat-roofed building when that is off the ground (a roof garden), else 0.
    float height = 0.0f;
};
/// How far under the hovering birds' lowest point the bed's soil is: the flowers stand
/// 0.35 to 0.5 m tall, so the birds hover about half a metre over the blossoms.
inline constexpr float kFlowerGap = 1.0f;
struct Perches {
    std::vector<Roof> roofs;
    std::vector<FlowerBed> beds;
};
/// The body mesh's lowest point under a bird's position, per metre of body length
/// (engine/birds/bird_meshes.cpp: the body's half height).
inline constexpr float kBellyDepth = 0.10f;
inline constexpr render::Rgba8 kRoofColor{168, 86, 62};
inline constexpr render::Rgba8 kWallColor{222, 212, 190};
inline constexpr render::Rgba8 kSoilColor{112, 82, 56};

/// Where the perches of `birds` are: per route that takes off or lands, one roof whose
/// ridge runs across the route's heading, under every bird of the route as it sits there
/// (the route's end point plus the bird's offset); per route with a hover segment, one
/// bed under its control points and its birds' offsets, with a 1 m margin, kFlowerGap
/// under the lowest of them.
[[nodiscard]] KODAWARI_API Perches perches_of(const birds::BirdWorld& birds);

/// The perches drawn: each roof a gable roof (flat top, slopes of 35 degrees) on a house
/// whose walls go down to the ground; each bed a patch of soil with flowers on it, on a
/// flat-roofed building as tall as the bed is high. `perches` is perches_of() of the
/// scene's birds, which does not change from frame to frame: a caller finds it once.
KODAWARI_API void add_perches(render::DrawList& list, const Perches& perches);

/// Where the content is, for render::add_ground_grid(), from the scene alone (no simulation state,
/// so that nothing needs reading back): character instances' placements, the chain roots
/// of `frame` (a RodScene frame's kinematic input; may be null), the control points of
/// the birds' routes.
[[nodiscard]] KODAWARI_API std::vector<glm::vec3> content_points(const RodScene* scene, const rods::RodFrame* frame,
                                                                 const birds::BirdWorld* birds);

}  // namespace kodawari
