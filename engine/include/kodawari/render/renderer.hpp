#pragma once
/// @file
/// The offscreen renderer (issue 5): draw lists built on the CPU (ground grid, skeletons,
/// chains, birds) drawn by Vulkan into a WxH RGBA8 + depth target and read back as an
/// image; PNG output and contact sheets. `kodawari render` uses it; `kodawari view`
/// draws the same draw lists and blits the image into a window's swapchain (present()).

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <vulkan/vulkan_core.h>

#include <shared/render.h>

#include "kodawari/result.hpp"

namespace kodawari::render {

/// An 8-bit colour (sRGB values, written to the image as they are).
struct Rgba8 {
    std::uint8_t r = 0, g = 0, b = 0, a = 255;
    friend bool operator==(const Rgba8&, const Rgba8&) = default;
};

/// A perspective look-at camera. Up is world +Y (+Z when looking straight up or down).
struct CameraView {
    glm::vec3 position{0.0f, 1.5f, 3.0f};
    glm::vec3 target{0.0f, 1.5f, 0.0f};
    float fov_deg = 50.0f;  ///< vertical field of view
    float near = 0.05f;     ///< m, > 0
    float far = 1000.0f;    ///< m, > near
};

/// The camera's orthonormal basis: right, up, forward (towards the target).
struct CameraBasis {
    glm::vec3 right, up, forward;
};
[[nodiscard]] CameraBasis camera_basis(const CameraView& camera);

/// projection * view in Vulkan's clip space (x right, y down, depth 0 at near .. 1 at
/// far) for an image of aspect width / height.
[[nodiscard]] glm::mat4 view_projection(const CameraView& camera, float aspect);

/// The background gradient at `v` (0 = top row, 1 = bottom row), rgb in [0, 1].
[[nodiscard]] glm::vec3 background_color(float v);

/// An RGBA8 image, rows top to bottom.
struct Image {
    std::uint32_t width = 0, height = 0;
    std::vector<std::uint8_t> rgba;  ///< width x height x 4 bytes
    [[nodiscard]] Rgba8 at(std::uint32_t x, std::uint32_t y) const;
};

/// What one frame draws, in world space: built on the CPU and uploaded every frame.
/// (Fine for previews and tests; the viewer uses them too for now, but wants GPU-resident
/// buffers that the backends write directly, without the CPU round trip: not done yet.)
class DrawList {
public:
    /// `width` x `height` is the image the list is for: segments and dots have minimum
    /// sizes in pixels.
    DrawList(const CameraView& camera, std::uint32_t width, std::uint32_t height);

    [[nodiscard]] const CameraView& camera() const { return camera_; }
    [[nodiscard]] std::uint32_t width() const { return width_; }
    [[nodiscard]] std::uint32_t height() const { return height_; }
    /// The world size of one pixel at the depth of `p` (0 behind the near plane).
    [[nodiscard]] float pixel_size_at(const glm::vec3& p) const;

    /// A 1-pixel line.
    void add_line(const glm::vec3& a, const glm::vec3& b, Rgba8 color);
    /// A flat-shaded triangle lit by the light; `normal` need not be unit.
    void add_lit_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& normal, glm::vec3 color);
    /// A thick segment: a quad facing the camera, `width` m wide but at least `min_px`
    /// pixels, in exactly `color` (unlit).
    void add_segment(const glm::vec3& a, const glm::vec3& b, float width, float min_px, Rgba8 color);
    /// A dot facing the camera (an octagon), `radius` m but at least `min_px` pixels.
    void add_dot(const glm::vec3& p, float radius, float min_px, Rgba8 color);
    /// A circle outline of 1-pixel lines facing the camera (colliders).
    void add_circle(const glm::vec3& center, float radius, Rgba8 color);
    /// Overlays (the viewer's stroke and status line): in pixels of the image (origin
    /// top-left, y down), unlit, drawn over everything (depth 0, the near plane).
    void add_screen_line(glm::vec2 a, glm::vec2 b, Rgba8 color);
    void add_screen_triangle(glm::vec2 a, glm::vec2 b, glm::vec2 c, Rgba8 color);

    [[nodiscard]] std::span<const gpu::RenderVertex> triangles() const { return triangles_; }
    [[nodiscard]] std::span<const gpu::RenderVertex> lines() const { return lines_; }

private:
    void add_unlit_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, Rgba8 color);

    CameraView camera_;
    CameraBasis basis_;
    std::uint32_t width_, height_;
    float pixel_per_depth_;  // world size of a pixel at depth 1
    std::vector<gpu::RenderVertex> triangles_, lines_;
};

/// Where the renderer runs.
struct RendererOptions {
    std::uint32_t width = 1280, height = 720;  ///< in [1, 8192]
    std::string device;       ///< Vulkan device name substring or index ("" = best; env KODAWARI_DEVICE)
    bool validation = false;  ///< Khronos validation + synchronization validation (also KODAWARI_VALIDATION=1)
    /// A window to present to (the viewer): the instance extensions its surface needs and
    /// a function that creates the surface on the renderer's instance. Empty = offscreen
    /// only. The renderer owns the surface and, from the first present(), a swapchain.
    std::vector<std::string> instance_extensions{};
    std::function<Result<VkSurfaceKHR>(VkInstance)> create_surface{};
};

/// Draws draw lists offscreen on a Vulkan device with a graphics queue.
class Renderer {
public:
    /// Creates the device, the targets and the pipelines. Fails with a readable reason
    /// when there is no Vulkan device or it cannot draw.
    [[nodiscard]] static Result<std::unique_ptr<Renderer>> create(const RendererOptions& options);
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Draws the background, then `list`'s lines and triangles (depth tested), waits and
    /// reads the image back. `list` must be for this renderer's size. Deterministic: the
    /// same list gives the same bytes.
    [[nodiscard]] Result<Image> render(const DrawList& list);

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
    /// Validation messages seen so far (with validation on).
    [[nodiscard]] std::uint32_t validation_messages() const;

private:
    struct Impl;
    explicit Renderer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

/// Writes `image` as a PNG, atomically (a temporary file renamed into place).
[[nodiscard]] Result<void> write_png(const std::string& path, const Image& image);

/// `image` scaled to `width` x `height` by averaging the source pixels under each
/// target pixel (a box filter; for shrinking).
[[nodiscard]] Image downscale(const Image& image, std::uint32_t width, std::uint32_t height);

/// A grid of `images` (all the same size), `columns` per row, each shrunk to
/// `cell_width` x `cell_height`, in order left to right, top to bottom, separated by
/// 2-pixel white gutters.
[[nodiscard]] Image contact_sheet(std::span<const Image> images, std::uint32_t columns, std::uint32_t cell_width,
                                  std::uint32_t cell_height);

}  // namespace kodawari::render
