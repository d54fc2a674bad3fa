#pragma once
/// @file
/// The renderer (issue 5): Vulkan draws into a WxH RGBA8 + depth target (4x multisampled
/// where the device can, resolved: anti-aliased edges), read back as an
/// image (render(); PNG output and contact sheets) or blitted into a window's swapchain
/// (present(), the viewer). A frame is a draw list built on the CPU (ground grid,
/// skeletons, colliders, overlays) plus the chains, birds and rigged characters' skinned
/// meshes, which are drawn from buffers on the device: the vulkan backends' own when they
/// share the renderer's device (BackendOptions::context = device_context(); nothing read
/// back), else uploaded.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <vulkan/vulkan_core.h>

#include <kodawari/shared/render.h>

#include "kodawari/api.hpp"
#include "draw.hpp"
#include "kodawari/backend.hpp"
#include "kodawari/result.hpp"
#include "kodawari/rod_backend.hpp"

namespace kodawari {
class CrowdAnimator;
struct RodScene;
}  // namespace kodawari

namespace kodawari::render {


/// The first chain's colour (chain 0 of every world: the one tests look for). Chains are
/// lit (ChainStyle), so a pixel of a chain is this colour scaled by a light factor in
/// [kAmbientLight, 1]; joint dots are unlit, exactly this colour.
inline constexpr Rgba8 kChainColor{235, 95, 20};
/// The colours chains cycle through (chain c: kChainPalette[c % size]): distinct hues, so
/// that neighbouring strands read apart, the same for the same world every time.
inline constexpr std::array<Rgba8, 6> kChainPalette{
    kChainColor, Rgba8{40, 150, 160}, Rgba8{150, 85, 205}, Rgba8{225, 180, 40}, Rgba8{205, 45, 80}, Rgba8{60, 115, 215}};
/// The renderer's light: the fraction of a lit colour that faces turned away from the
/// light keep (the rest is Lambert from one directional light).
inline constexpr float kAmbientLight = 0.45f;
/// Colliders: the procedural characters' bodies, solid capsules and spheres lit as the
/// chains are (f x this, f in [kAmbientLight, 1]). A muted clay.
inline constexpr Rgba8 kColliderColor{196, 172, 150};
/// At 720 rows (scaled by rows / 720 within [0.5, 2]), a chain is drawn at least this
/// many pixels wide and its joint dots at least this radius, so that a strand a few
/// millimetres thick reads in a preview. A chain too short on screen for its dots to
/// stay apart (its length under 3 dot radii per joint) gets none.
inline constexpr float kChainMinPixels = 4.0f;
inline constexpr float kJointDotMinPixels = 3.0f;
/// Birds smaller than this wingspan in pixels are drawn scaled up to it, so that a far
/// flock stays visible (a preview aid: the birds' positions are exact, their size not).
inline constexpr float kBirdMinPixels = 8.0f;

/// How chains are drawn: lit tubes (camera-facing ribbons shaded as cylinders) 2 x
/// thickness wide at the root, tapering to 40% of that at the tip, with minimum widths in
/// pixels; chain c in colors[c % colors.size()]. With RendererOptions::joints, a dot of
/// radius 1.5 x thickness at each joint, unlit in the chain's exact colour.
struct ChainStyle {
    std::vector<Rgba8> colors{kChainPalette.begin(), kChainPalette.end()};  ///< not empty
    float min_width_px = kChainMinPixels;  ///< at 720 rows
    float min_dot_px = kJointDotMinPixels; ///< at 720 rows
};

/// A look-at camera, perspective or orthographic. Up is world +Y (+Z when looking
/// straight up or down).
struct CameraView {
    glm::vec3 position{0.0f, 1.5f, 3.0f};
    glm::vec3 target{0.0f, 1.5f, 0.0f};
    float fov_deg = 50.0f;  ///< vertical field of view (perspective)
    float near = 0.05f;     ///< m, > 0
    float far = 1000.0f;    ///< m, > near
    bool orthographic = false;
    float ortho_height = 1.0f;  ///< m, > 0: the height of the view (orthographic)
};

/// The camera's orthonormal basis: right, up, forward (towards the target).
struct CameraBasis {
    glm::vec3 right, up, forward;
};
[[nodiscard]] KODAWARI_API CameraBasis camera_basis(const CameraView& camera);

/// projection * view in Vulkan's clip space (x right, y down, depth 0 at near .. 1 at
/// far) for an image of aspect width / height; orthographic: ortho_height tall, centred
/// on the line of sight.
[[nodiscard]] KODAWARI_API glm::mat4 view_projection(const CameraView& camera, float aspect);

/// The background gradient at `v` (0 = top row, 1 = bottom row), rgb in [0, 1].
[[nodiscard]] KODAWARI_API glm::vec3 background_color(float v);

/// An RGBA8 image, rows top to bottom.
struct KODAWARI_API Image {
    std::uint32_t width = 0, height = 0;
    std::vector<std::uint8_t> rgba;  ///< width x height x 4 bytes
    [[nodiscard]] Rgba8 at(std::uint32_t x, std::uint32_t y) const;
};

/// What one frame draws besides the chains, birds and skinned meshes, in world space:
/// built on the CPU and uploaded every frame.
class KODAWARI_API DrawList {
public:
    /// `width` x `height` is the image the list is for: segments and dots have minimum
    /// sizes in pixels.
    DrawList(const CameraView& camera, std::uint32_t width, std::uint32_t height);

    [[nodiscard]] const CameraView& camera() const { return camera_; }
    [[nodiscard]] std::uint32_t width() const { return width_; }
    [[nodiscard]] std::uint32_t height() const { return height_; }
    /// The world size of one pixel at the depth of `p` (0 behind the near plane);
    /// orthographic: the same everywhere.
    [[nodiscard]] float pixel_size_at(const glm::vec3& p) const;
    /// The world size of one pixel at depth 1 m (perspective), or everywhere (orthographic).
    [[nodiscard]] float pixel_per_depth() const { return pixel_per_depth_; }
    /// The direction from `p` towards the viewer: towards the eye, or against the line of
    /// sight (orthographic).
    [[nodiscard]] glm::vec3 towards_viewer(const glm::vec3& p) const;

    /// A 1-pixel line.
    void add_line(const glm::vec3& a, const glm::vec3& b, Rgba8 color);
    /// A flat-shaded triangle lit by the light; `normal` need not be unit.
    void add_lit_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& normal, glm::vec3 color);
    /// An unlit triangle in exactly `color` (depth tested like the rest).
    void add_unlit_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, Rgba8 color);
    /// A thick segment: a quad facing the camera, `width` m wide but at least `min_px`
    /// pixels, in exactly `color` (unlit).
    void add_segment(const glm::vec3& a, const glm::vec3& b, float width, float min_px, Rgba8 color);
    /// A dot facing the camera (an octagon), `radius` m but at least `min_px` pixels.
    void add_dot(const glm::vec3& p, float radius, float min_px, Rgba8 color);
    /// Overlays (the viewer's stroke and status line): in pixels of the image (origin
    /// top-left, y down), unlit, drawn over everything (depth 0, the near plane).
    void add_screen_line(glm::vec2 a, glm::vec2 b, Rgba8 color);
    void add_screen_triangle(glm::vec2 a, glm::vec2 b, glm::vec2 c, Rgba8 color);
    /// A soft contact shadow on the ground (y = 0): a dark disc of `radius` m round
    /// `center`'s foot, `opacity` (in [0, 1]) at the middle fading to none at the rim,
    /// blended over what is drawn (after the opaque geometry; depth tested, not written).
    void add_ground_shadow(const glm::vec3& center, float radius, float opacity);

    [[nodiscard]] std::span<const gpu::RenderVertex> triangles() const { return triangles_; }
    [[nodiscard]] std::span<const gpu::RenderVertex> lines() const { return lines_; }
    /// Ground shadows: triangles whose colour's r is the opacity, a the way in from the rim (shadow.frag).
    [[nodiscard]] std::span<const gpu::RenderVertex> shadows() const { return shadows_; }

private:
    CameraView camera_;
    CameraBasis basis_;
    std::uint32_t width_, height_;
    float pixel_per_depth_;  // world size of a pixel at depth 1
    std::vector<gpu::RenderVertex> triangles_, lines_, shadows_;
};

/// Where the renderer runs.
struct RendererOptions {
    std::uint32_t width = 1280, height = 720;  ///< in [1, 8192]
    std::string device;       ///< Vulkan device name substring or index ("" = best)
    bool validation = false;  ///< Khronos validation + synchronization validation
    bool force_staging = false;  ///< staging copies even on shared memory (BackendOptions::force_staging)
    /// Dots at the chains' joints (ChainStyle; a debugging aid: where the simulation's
    /// joints are). Off: the strands alone.
    bool joints = false;
    /// A window to present to (the viewer): the instance extensions its surface needs and
    /// a function that creates the surface on the renderer's instance. Empty = offscreen
    /// only. The renderer owns the surface and, from the first present(), a swapchain.
    std::vector<std::string> instance_extensions{};
    std::function<Result<VkSurfaceKHR>(VkInstance)> create_surface{};
};

/// Draws draw lists offscreen on a Vulkan device with a graphics queue; what domains draw
/// through render::Draw (kodawari/render/draw.hpp) joins every frame's list until
/// clear_draws().
class KODAWARI_API Renderer final : public Draw {
public:
    /// Creates the device, the targets and the pipelines. Fails with a readable reason
    /// when there is no Vulkan device or it cannot draw.
    [[nodiscard]] static Result<std::unique_ptr<Renderer>> create(const RendererOptions& options);
    ~Renderer() override;
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Draws the background, then `list`'s lines and triangles and the chain, bird and
    /// skinned-mesh layers (depth tested), waits and reads the image back. `list` must be
    /// for this renderer's size. Deterministic: the same list and layer state give the
    /// same bytes.
    [[nodiscard]] Result<Image> render(const DrawList& list);

    /// Draws as render() does and waits, without reading the image back (benchmarks:
    /// what a window's frame costs without the blit).
    [[nodiscard]] Result<void> draw(const DrawList& list);

    /// Draws `list` as render() does into the offscreen image, then blits it (scaled,
    /// linear filter) into the window's next swapchain image and presents it; no read
    /// back. `window_width` x `window_height` is the window's framebuffer size in pixels:
    /// the swapchain is (re)made when it changes or the surface reports it out of date.
    /// Returns false when nothing was presented (a minimized window, a swapchain just
    /// remade). Waits for the frame to finish. Needs RendererOptions::create_surface.
    [[nodiscard]] Result<bool> present(const DrawList& list, std::uint32_t window_width, std::uint32_t window_height);

    [[nodiscard]] std::uint32_t width() const;
    [[nodiscard]] std::uint32_t height() const;
    /// The device it draws on ("llvmpipe (LLVM 15.0.6, 256 bits)").
    [[nodiscard]] std::string device() const;
    /// The renderer's Vulkan device, to run the simulation on (BackendOptions::context):
    /// the vulkan backends then keep their state where the layers draw it.
    [[nodiscard]] std::shared_ptr<gpu::VulkanContext> device_context() const;
    /// Bytes of kernel output read back to the host on this device so far (the
    /// simulation's, when it shares the device): the viewer's per-frame figure.
    [[nodiscard]] std::uint64_t read_back_bytes() const;

    /// render::Draw: primitives that join every frame's draw list until clear_draws(),
    /// sized for its camera at render time.
    void lines(std::span<const glm::vec3> pairs, Rgba8 color) override;
    void tubes(std::span<const glm::vec3> points, std::span<const Polyline> polylines, float min_px = 2.0f) override;
    void capsules(std::span<const Capsule> capsules, Rgba8 color) override;
    void discs(std::span<const glm::vec3> centers, float radius, Rgba8 color, float min_px = 2.0f) override;
    void meshes(const MeshView& mesh, std::span<const glm::mat4> transforms, Rgba8 color) override;
    /// Forgets what was drawn through render::Draw (Simulation::draw_on() starts with it).
    void clear_draws();

    /// Draws no layer from now on (a simulation's show_on() starts with it, so that what
    /// another simulation showed goes).
    [[nodiscard]] Result<void> clear_layers();

    /// Draws the chains of `world` in every following frame (null: none), their state
    /// set per frame by chains_from(). `world` must outlive its use here.
    [[nodiscard]] Result<void> set_chains(const rods::RodWorld* world, const ChainStyle& style = {});
    /// This frame's chain state: a backend whose state lives on this renderer's device
    /// (the vulkan one made with device_context()) is drawn from its own buffers, nothing
    /// read back; any other is read (RodBackend::read) and uploaded.
    [[nodiscard]] Result<void> chains_from(RodBackend& backend);
    /// This frame's chain state from a snapshot (joint positions, uploaded).
    [[nodiscard]] Result<void> chains_from(const ChainSnapshot& snapshot);
    /// Whether the last chains_from() drew the backend's own buffers.
    [[nodiscard]] bool chains_on_device() const;
    /// This frame's colliders of the world given to set_chains() (drawn as lit capsules in
    /// kColliderColor; not those of characters set_skinned() draws as meshes): the vulkan rod backend's input buffer when it lives on this
    /// renderer's device (rigged characters' colliders are written there on the device),
    /// otherwise those of `input` (the frame given to the backend's step), uploaded.
    [[nodiscard]] Result<void> colliders_from(const RodBackend& backend, const rods::RodFrame& input);

    /// Draws the birds of `world` (their part meshes, lit, in the wing type's colour) in
    /// every following frame (null: none), their poses set per frame by birds_from().
    [[nodiscard]] Result<void> set_birds(const birds::BirdWorld* world);
    /// This frame's bird poses where a vulkan bird backend made with device_context()
    /// keeps them (BirdBackend::device_poses(): simulate() need not read them back). An
    /// error for a backend on another device or on the CPU: pass its poses instead.
    [[nodiscard]] Result<void> birds_from(const BirdBackend& backend);
    /// This frame's bird poses, one per bird, uploaded.
    [[nodiscard]] Result<void> birds_from(std::span<const gpu::BirdPose> poses);

    /// Draws the rigged characters of `scene` that have meshes as their skinned meshes
    /// (glTF §3.7.3; flat shaded, lit) in every following frame (null: none), posed per
    /// frame by skinned_from(). `scene` must outlive its use here.
    [[nodiscard]] Result<void> set_skinned(const RodScene* scene);
    /// Frame `frame`'s poses: the clip's with the hair bones where `rods` simulated them
    /// (RodScene::rigged_world). When the animator's pose backends and `rods` keep their
    /// buffers on this renderer's device (the vulkan ones made with device_context()), a
    /// kernel composes the node matrices there, nothing read back; the animator's last
    /// frame() and `rods`' state must then be frame `frame`'s. Otherwise `rods` is read
    /// and the matrices are composed on the CPU and uploaded. `animator` must be made from
    /// the scene given to set_skinned().
    [[nodiscard]] Result<void> skinned_from(const CrowdAnimator& animator, RodBackend& rods, std::uint32_t frame);
    /// Frame `frame`'s poses from a snapshot of the chains at that frame, composed on the
    /// CPU (RodScene::rigged_world) and uploaded.
    [[nodiscard]] Result<void> skinned_from(const ChainSnapshot& snapshot, std::uint32_t frame);
    /// Whether the last skinned_from() composed the poses on the device.
    [[nodiscard]] bool skinned_on_device() const;

    /// Validation messages seen so far (with validation on).
    [[nodiscard]] std::uint32_t validation_messages() const;

private:
    struct Impl;
    explicit Renderer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

/// Writes `image` as a PNG, atomically (a temporary file renamed into place).
[[nodiscard]] KODAWARI_API Result<void> write_png(const std::string& path, const Image& image);

/// `image` scaled to `width` x `height` by averaging the source pixels under each
/// target pixel (a box filter; for shrinking).
[[nodiscard]] KODAWARI_API Image downscale(const Image& image, std::uint32_t width, std::uint32_t height);

/// A grid of `images` (all the same size), `columns` per row, each shrunk to
/// `cell_width` x `cell_height`, in order left to right, top to bottom, separated by
/// 2-pixel white gutters.
[[nodiscard]] KODAWARI_API Image contact_sheet(std::span<const Image> images, std::uint32_t columns,
                                               std::uint32_t cell_width,
                                               std::uint32_t cell_height);

}  // namespace kodawari::render
