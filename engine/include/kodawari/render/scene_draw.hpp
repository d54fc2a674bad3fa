#pragma once
/// @file
/// Draw lists of a scene's content for the renderer (renderer.hpp): the scene camera,
/// a ground grid, characters (skeleton bones, colliders). The chains, birds and skinned
/// meshes are the renderer's layers (Renderer::set_chains, set_birds, set_skinned).
/// Shared by `kodawari render` and `kodawari view`.

#include <cstdint>
#include <span>

#include "kodawari/api.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/rod_backend.hpp"
#include "kodawari/rod_scene.hpp"
#include "kodawari/scene.hpp"

namespace kodawari::render {

inline constexpr Rgba8 kBoneColor{50, 60, 80};
inline constexpr Rgba8 kGridColor{150, 156, 168};
/// The scene camera at `frame` (time = frame / fps) as scene.camera.motion gives it, the
/// same pose RodScene::camera_pose gives characters, and its projection: an orthographic
/// camera is as tall as the perspective frustum at its target (rods::ImageCamera's
/// convention). Perspective near and far planes follow the distance to the target:
/// near = 1% of it (within [0.01, 1] m), far = 1000 x near; orthographic: 0.01 to 10 km.
[[nodiscard]] KODAWARI_API CameraView scene_camera(const Scene& scene, std::uint32_t frame);

/// A square grid on the ground (y = 0) covering the points' horizontal extent plus a
/// margin, with about 10 to 25 lines each way (spacing 1, 2 or 5 x 10^k m).
KODAWARI_API void add_ground_grid(DrawList& list, std::span<const glm::vec3> points);

/// Whether a rigged character is drawn as its skinned mesh (the renderer's skinned-mesh
/// layer, Renderer::set_skinned) rather than as bones: some node has a mesh with triangles.
[[nodiscard]] KODAWARI_API bool draws_skinned(const gltf::Character& character);

/// The darkest a contact shadow gets (a character whose lowest joint is on the ground).
inline constexpr float kShadowOpacity = 0.35f;

/// A soft contact shadow on the ground under a character posed as `joints` (root first):
/// a disc under the joints' centroid about as wide as the body (0.3 x the skeleton's height), fading
/// as the character rises off the ground (kShadowOpacity when it stands on it).
KODAWARI_API void add_contact_shadow(DrawList& list, std::span<const rods::Transform> joints);

/// Every character instance of `scene` at `frame`: its contact shadow (add_contact_shadow)
/// and, unless it is drawn as a skinned mesh (Renderer::set_skinned), its skeleton bones
/// from RodScene::joint_poses. The colliders are the renderer's (Renderer::colliders_from).
KODAWARI_API void add_characters(DrawList& list, const RodScene& scene, std::uint32_t frame);

/// Where the content is, for add_ground_grid, from the scene alone (no simulation state,
/// so that nothing needs reading back): character instances' placements, the chain roots
/// of `frame` (a RodScene frame's kinematic input; may be null), the control points of
/// the birds' routes.
[[nodiscard]] KODAWARI_API std::vector<glm::vec3> content_points(const RodScene* scene, const rods::RodFrame* frame,
                                                                 const birds::BirdWorld* birds);

}  // namespace kodawari::render
