#pragma once
/// @file
/// Sketching a chain's shape from a view (SPEC A.6): the artist draws one stroke over the
/// current view and the chain takes that shape as a new view example for the current view
/// direction. Everything here is a pure function of its input (no scene, no window), so
/// the editor, `kodawari sketch` and the tests share it.
///
/// Pixel coordinates: the origin is the top-left corner of the image, x to the right,
/// y down, in pixels; (W, H) is the bottom-right corner, so the centre of the image is
/// (W/2, H/2) and the centre of the top-left pixel is (0.5, 0.5). Coordinates are real
/// numbers (a stroke from a tablet has sub-pixel positions).

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/kinematics.hpp"
#include "kodawari/rods/shape.hpp"
#include "kodawari/rods/solver.hpp"
#include "kodawari/rods/view.hpp"

namespace kodawari::rods {

/// A camera that makes pictures: look-at view and a perspective or orthographic projection
/// onto a W x H image. Its up vector is world +Y (the renderer's convention), except when
/// the camera looks straight up or down, where world -Z is used (the picture's up is then
/// the scene's back).
/// The farthest a stroke point may lie from the image's origin, pixels, in x and in y: far
/// past any image (8192 px at most), near enough that its ray's meeting with the sketch
/// plane stays finite (a stroke at 7e160 px made the joints infinite; found by fuzzing).
inline constexpr double kMaxStrokePixels = 1e6;

struct KODAWARI_API ImageCamera {
    Camera::Projection projection = Camera::Projection::Perspective;
    glm::vec3 position{0.0f, 0.0f, 1.0f};  ///< eye, world
    glm::vec3 target{0.0f};                ///< point looked at; must differ from position
    float fov_deg = 50.0f;                 ///< vertical field of view, in (0, 180)
    /// Orthographic only: the height of the view in metres. 0 = the height of the
    /// perspective frustum at the target (2 |target - position| tan(fov/2)), so switching
    /// the projection keeps the target's framing.
    float ortho_height = 0.0f;
    std::uint32_t width = 1280;   ///< pixels, > 0
    std::uint32_t height = 720;   ///< pixels, > 0

    /// The camera at `pose` (as RodScene::camera_pose gives it) with `fov_deg` and an image size.
    [[nodiscard]] static ImageCamera from_pose(const CameraPose& pose, float fov_deg, std::uint32_t width,
                                               std::uint32_t height);
    /// The camera as the view weights (SPEC A.3) need it.
    [[nodiscard]] Camera view_camera() const;
};

/// `world` projected to pixels (origin top-left, y down), and its depth along the camera's
/// forward axis (m; > 0 in front of a perspective camera). Asserts a valid camera.
[[nodiscard]] KODAWARI_API glm::dvec3 project_to_pixels(const ImageCamera& camera, glm::dvec3 world);

/// The distance in pixels from `point` to the polyline `stroke` (>= 1 point).
[[nodiscard]] KODAWARI_API double distance_to_polyline(glm::dvec2 point, std::span<const glm::dvec2> stroke);

/// What the sketch needs (SPEC A.6).
struct SketchInput {
    ImageCamera camera;
    /// The chain root's frame in the world (RodFrame::roots[chain]): joint 0 stays there,
    /// and the result is expressed in it.
    Transform root;
    /// The base shape's segment lengths l_0 .. l_{n-2} (ShapeBasis::lengths), m, > 0.
    /// Blending keeps them (SPEC A.2), so the sketch keeps them too.
    std::vector<float> lengths;
    /// The reference joint's world pose (RodFrame::reference[character]): the view
    /// direction is measured in its frame (SPEC A.3).
    Transform reference;
    /// The stroke in pixels (see the file comment), >= 2 points, finite.
    std::vector<glm::dvec2> stroke;
    /// p_k of the new example (> 0): large keeps the sketched shape to views near this one.
    float influence = 4.0f;
};

/// The new view example and how well it fits the stroke.
struct SketchResult {
    /// The shape in the chain root's frame: joint 0 at the origin, orientations by the
    /// scene format's default rule (each joint's +Y along its segment, the last joint
    /// along the last segment).
    ChainShape shape;
    ViewExample view;  ///< d (SPEC A.3, the reference joint's frame) and the influence
    std::vector<glm::dvec3> world_positions;  ///< the joints in the world
    std::vector<glm::dvec2> pixels;           ///< the joints projected to the image
    /// The stroke as used: translated so that it starts at the root's projection.
    std::vector<glm::dvec2> stroke;
    glm::dvec2 stroke_offset{0.0};  ///< the translation applied to the stroke, pixels
    /// The largest distance from a projected joint placed on the stroke to the stroke,
    /// pixels (0 up to rounding: those joints are on it by construction).
    double max_error_px = 0.0;
    /// The largest distance from a projected joint past the stroke's end to the stroke
    /// itself (not its extension): how far the continuation left the drawn line; 0 when
    /// every joint is on the stroke.
    double max_overrun_px = 0.0;
    /// Joints placed on the stroke, joint 0 included; the others continue past its end.
    std::uint32_t joints_on_stroke = 1;
    /// How much of the stroke's length (pixels) the chain used, [0, 1]: up to its tip, or
    /// 1 when the chain ran past the stroke's end.
    double stroke_used = 0.0;
};

/// SPEC A.6: places the joints so that their projections lie on the stroke and the segment
/// lengths are kept, and returns them as a view example for the current view direction.
///
/// - The stroke is first translated so that its first point is the projection of joint 0
///   (the root stays where it is; the artist need not hit it exactly, and the drawn shape
///   is kept rather than bent towards the root).
/// - The joints lie on the plane through joint 0 parallel to the image plane (SPEC: "the
///   plane through j_0 facing the camera"; parallel to the image, every pixel's ray meets
///   it in front of the camera, so every stroke point has a place on it).
/// - Each next joint is the first point along the stroke, after the previous joint, at
///   distance l_i from it (SPEC A.6), measured in the plane in metres; a joint therefore
///   projects exactly onto the stroke.
/// - Past the stroke's end the stroke continues along its last segment's direction
///   (SPEC A.6), so every joint is found: a stroke shorter than the chain lays the
///   remaining joints on a straight line in the plane, reported by joints_on_stroke and
///   max_overrun_px.
/// - Stroke points closer than 1e-3 px to the previous one are dropped (a resting pen).
///
/// Fails (InvalidInput) on fewer than 2 or non-finite stroke points, a stroke of zero
/// length, no segment lengths or more than kMaxChainJoints joints, a non-positive or
/// non-finite length or influence, an invalid camera (size 0, fov outside (0, 180),
/// position = target), or a root behind (or on) a perspective camera's image plane.
[[nodiscard]] KODAWARI_API Result<SketchResult> sketch_view_example(const SketchInput& input);

}  // namespace kodawari::rods
