#pragma once
/// @file
/// Draw lists of a scene's content for the renderer (renderer.hpp): the scene camera,
/// a ground grid, characters (skeleton bones, colliders, chains with joint dots) and
/// birds (their seven part meshes, flat shaded). Shared by `kodawari render` and `kodawari
/// view`.

#include <cstdint>
#include <span>

#include "kodawari/birds/world.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/rod_backend.hpp"
#include "kodawari/rod_scene.hpp"
#include "kodawari/scene.hpp"

namespace kodawari::render {

/// Chains and their joint dots: one exact, unlit colour (tests look for it).
inline constexpr Rgba8 kChainColor{235, 95, 20};
inline constexpr Rgba8 kBoneColor{50, 60, 80};
inline constexpr Rgba8 kColliderColor{110, 120, 140};
inline constexpr Rgba8 kGridColor{150, 156, 168};
/// At 720 rows (scaled by rows / 720 within [0.5, 2]), a chain is drawn at least this
/// many pixels wide and its joint dots at least this radius, so that a strand a few
/// millimetres thick reads in a preview. A chain too short on screen for its dots to
/// stay apart gets none.
inline constexpr float kChainMinPixels = 4.0f;
inline constexpr float kJointDotMinPixels = 3.0f;
/// Birds smaller than this wingspan in pixels are drawn scaled up to it, so that a far
/// flock stays visible (a preview aid: the birds' positions are exact, their size not).
inline constexpr float kBirdMinPixels = 6.0f;

/// The scene camera at `frame` (time = frame / fps) as scene.camera.motion gives it, the
/// same pose RodScene::camera_pose gives characters. Near and far planes follow the
/// distance to the target: near = 1% of it (within [0.01, 1] m), far = 1000 x near.
[[nodiscard]] CameraView scene_camera(const Scene& scene, std::uint32_t frame);

/// A square grid on the ground (y = 0) covering the points' horizontal extent plus a
/// margin, with about 10 to 25 lines each way (spacing 1, 2 or 5 x 10^k m).
void add_ground_grid(DrawList& list, std::span<const glm::vec3> points);

/// Every character instance of `scene` at `frame`: skeleton bones from
/// RodScene::joint_poses, colliders of `kinematic` (that frame's input; may be null)
/// as circles, and every chain of `snapshot` (the backend's state at that frame) as a
/// thick line with a dot at each joint, in kChainColor.
void add_characters(DrawList& list, const RodScene& scene, std::uint32_t frame, const ChainSnapshot& snapshot,
                    const rods::RodFrame* kinematic);

/// Every bird of `world` posed by `poses` (one frame, one pose per bird): the part
/// meshes of the glTF export, lit, in the wing type's colour.
void add_birds(DrawList& list, const birds::BirdWorld& world, std::span<const gpu::BirdPose> poses);

/// Where the content is, for add_ground_grid: character instances' placements and
/// chain joints, bird positions.
[[nodiscard]] std::vector<glm::vec3> content_points(const RodScene* scene, const ChainSnapshot* snapshot,
                                                    std::span<const gpu::BirdPose> poses);

}  // namespace kodawari::render
