#pragma once
/// @file
/// The renderer (issue 5): Vulkan draws into a WxH RGBA8 + depth target (4x multisampled
/// where the device can, resolved: anti-aliased edges), read back as an
/// image (render(); PNG output and contact sheets) or blitted into a window's swapchain
/// (present(), the viewer). A frame is a draw list built on the CPU (ground grid,
/// overlays), what domains draw through render::Draw, and the layers domains draw from
/// their buffers on the device (the vulkan backends' own when they share the renderer's
/// device: BackendOptions::context = device_context(), nothing read back). The renderer
/// names no domain (issue 31).

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

#include "kodawari/core/api.hpp"
#include "kodawari/render/draw.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::compute {
class Device;
}  // namespace kodawari::compute

namespace kodawari::render {

/// The renderer's light: the fraction of a lit colour that faces turned away from the
/// light keep (the rest is Lambert from one directional light).
inline constexpr float kAmbientLight = 0.45f;

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

/// What one frame draws besides what domains draw, in world space:
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

/// The ground grid's colour.
inline constexpr Rgba8 kGridColor{150, 156, 168};
/// A square grid on the ground (y = 0) covering the points' horizontal extent plus a
/// margin, with about 10 to 25 lines each way (spacing 1, 2 or 5 x 10^k m).
KODAWARI_API void add_ground_grid(DrawList& list, std::span<const glm::vec3> points);

/// Where the renderer runs.
struct RendererOptions {
    std::uint32_t width = 1280, height = 720;  ///< in [1, 8192]
    std::string device;       ///< Vulkan device name substring or index ("" = best)
    bool validation = false;  ///< Khronos validation + synchronization validation
    bool force_staging = false;  ///< staging copies even on shared memory (BackendOptions::force_staging)
    /// Dots at the joints of what layers draw as strands (a debugging aid: where the
    /// simulation's joints are). Off: the strands alone.
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

    /// Draws the background, then `list`'s lines and triangles, what was drawn through
    /// render::Draw and the layers (depth tested), waits and reads the image back. `list` must be
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
    [[nodiscard]] std::shared_ptr<compute::Device> device_context() const;
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

    /// Validation messages seen so far (with validation on).
    [[nodiscard]] std::uint32_t validation_messages() const;

private:
    struct Impl;
    friend struct LayerAccess;  // render/layer.hpp: the layers domains draw from device buffers
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
