// The renderer: one render pass into an RGBA8 colour + depth target (multisampled and
// resolved into the single-sample colour image at the end of the pass); three pipelines of
// the draw list's shaders (background without depth, lines, triangles), then the layers
// domains draw from their device buffers (layer.hpp), in their order; the image copied to
// a host-visible buffer after the pass, or blitted into a swapchain image
// (renderer_present.cpp).

#include "kodawari/render/renderer.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <optional>

#include <glm/gtc/matrix_transform.hpp>

#include "gpu/compute_vulkan.hpp"
#include "gpu/graphics.hpp"
#include "render/layer.hpp"
#include "render/draw_recorder.hpp"
#include "render/renderer_impl.hpp"

namespace kodawari::render {

namespace {

constexpr glm::vec3 kBackgroundTop{0.60f, 0.70f, 0.84f};
constexpr glm::vec3 kBackgroundBottom{0.82f, 0.83f, 0.80f};
// Lambert from above and in front-left, so that a bird's back and its wings' upper sides
// read lighter than their undersides.
const glm::vec3 kLight = glm::normalize(glm::vec3(-0.35f, 1.0f, 0.45f));

gpu::vec4 v4(const glm::vec3& v, float w) { return {v.x, v.y, v.z, w}; }

}  // namespace

CameraBasis camera_basis(const CameraView& camera) {
    glm::vec3 forward = camera.target - camera.position;
    const float length = glm::length(forward);
    forward = length > 0.0f ? forward / length : glm::vec3(0.0f, 0.0f, -1.0f);
    // Looking (almost) straight up or down, +Y cannot give "right": take +Z instead.
    const glm::vec3 world_up = std::abs(forward.y) > 0.999f ? glm::vec3(0.0f, 0.0f, 1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
    const glm::vec3 right = glm::normalize(glm::cross(forward, world_up));
    return {right, glm::cross(right, forward), forward};
}

glm::mat4 view_projection(const CameraView& camera, float aspect) {
    const CameraBasis basis = camera_basis(camera);
    const glm::mat4 view = glm::lookAtRH(camera.position, camera.position + basis.forward, basis.up);
    const float half_h = 0.5f * camera.ortho_height, half_w = half_h * aspect;
    glm::mat4 projection = camera.orthographic
                               ? glm::orthoRH_ZO(-half_w, half_w, -half_h, half_h, camera.near, camera.far)
                               : glm::perspectiveRH_ZO(glm::radians(camera.fov_deg), aspect, camera.near, camera.far);
    projection[1][1] = -projection[1][1];  // Vulkan's clip space has y down
    return projection * view;
}

glm::vec3 background_color(float v) { return glm::mix(kBackgroundTop, kBackgroundBottom, std::clamp(v, 0.0f, 1.0f)); }

Rgba8 Image::at(std::uint32_t x, std::uint32_t y) const {
    assert(x < width && y < height);
    const std::uint8_t* p = rgba.data() + (std::size_t{y} * width + x) * 4;
    return {p[0], p[1], p[2], p[3]};
}

// ---------------------------------------------------------------------------------------
// Renderer

Renderer::Renderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Renderer::~Renderer() {
    // A present may still wait on a frame's semaphore: the queue must be idle before the
    // window's objects go (the context waits too, but it is destroyed after them).
    if (impl_ && impl_->window) {
        // A failure here (device lost) means nothing is in flight any more, and a
        // destructor has no one to report it to: the Error is dropped on purpose.
        (void)gpu::guard("Vulkan queue idle", [&]() -> Result<void> {
            impl_->ctx->queue().waitIdle();
            return {};
        });
    }
}
std::uint32_t Renderer::width() const { return impl_->width; }
std::uint32_t Renderer::height() const { return impl_->height; }
std::string Renderer::device() const { return impl_->ctx->info().name; }
std::uint32_t Renderer::validation_messages() const { return impl_->ctx->validation_messages(); }
std::shared_ptr<compute::Device> Renderer::device_context() const { return impl_->ctx; }
std::uint64_t Renderer::read_back_bytes() const { return impl_->ctx->read_back_bytes(); }

void Renderer::lines(std::span<const glm::vec3> pairs, Rgba8 color) { impl_->draws.lines(pairs, color); }
void Renderer::tubes(std::span<const glm::vec3> points, std::span<const Polyline> polylines, float min_px) {
    impl_->draws.tubes(points, polylines, min_px);
}
void Renderer::capsules(std::span<const Capsule> capsules, Rgba8 color) { impl_->draws.capsules(capsules, color); }
void Renderer::discs(std::span<const glm::vec3> centers, float radius, Rgba8 color, float min_px) {
    impl_->draws.discs(centers, radius, color, min_px);
}
void Renderer::meshes(const MeshView& mesh, std::span<const glm::mat4> transforms, Rgba8 color) {
    impl_->draws.meshes(mesh, transforms, color);
}
void Renderer::clear_draws() { impl_->draws.clear(); }

Result<void> Renderer::clear_layers() {
    for (Impl::NamedLayer& named : impl_->layers) KW_TRY(named.layer->clear(*impl_->ctx));
    return {};
}

// The friend of Renderer that render/layer.hpp's functions reach its layers through.
struct LayerAccess {
    static Renderer::Impl& of(Renderer& renderer) { return *renderer.impl_; }
    static const Renderer::Impl& of(const Renderer& renderer) { return *renderer.impl_; }
};

Result<Layer*> layer(Renderer& renderer, std::string_view name, int order, const LayerFactory& make) {
    auto& r = LayerAccess::of(renderer);
    for (const auto& named : r.layers) {
        if (named.name == name) return named.layer.get();
    }
    auto made = make(LayerTarget{*r.ctx, *r.pass, r.samples});
    if (!made) return made.error();
    const auto at = std::find_if(r.layers.begin(), r.layers.end(),
                                 [&](const auto& n) { return n.order > order || (n.order == order && n.name > name); });
    return r.layers.insert(at, {order, std::string(name), std::move(made).value()})->layer.get();
}

const Layer* find_layer(const Renderer& renderer, std::string_view name) {
    for (const auto& named : LayerAccess::of(renderer).layers) {
        if (named.name == name) return named.layer.get();
    }
    return nullptr;
}

gpu::VulkanContext& layer_context(Renderer& renderer) { return *LayerAccess::of(renderer).ctx; }

namespace {

constexpr vk::Format kColorFormat = vk::Format::eR8G8B8A8Unorm;

// Anti-aliasing: 4 samples per pixel, or the most the device has for colour and depth
// together if fewer. Fixed sample positions (the standard ones): the same input gives the
// same bits on one device.
vk::SampleCountFlagBits sample_count(const vk::raii::PhysicalDevice& physical) {
    const vk::PhysicalDeviceLimits limits = physical.getProperties().limits;
    const vk::SampleCountFlags both = limits.framebufferColorSampleCounts & limits.framebufferDepthSampleCounts;
    for (const auto s : {vk::SampleCountFlagBits::e4, vk::SampleCountFlagBits::e2}) {
        if (both & s) return s;
    }
    return vk::SampleCountFlagBits::e1;
}

// The first depth format the device can render to (every device has one of these).
std::optional<vk::Format> depth_format(const vk::raii::PhysicalDevice& physical) {
    for (const vk::Format f : {vk::Format::eD32Sfloat, vk::Format::eX8D24UnormPack32, vk::Format::eD16Unorm}) {
        if (physical.getFormatProperties(f).optimalTilingFeatures & vk::FormatFeatureFlagBits::eDepthStencilAttachment) return f;
    }
    return std::nullopt;
}

}  // namespace

Result<std::unique_ptr<Renderer>> Renderer::create(const RendererOptions& options) {
    if (options.width < 1 || options.width > 8192 || options.height < 1 || options.height > 8192) {
        return make_error(Error::Kind::InvalidInput, "image size " + std::to_string(options.width) + "x" +
                                                         std::to_string(options.height) + " is outside 1x1 .. 8192x8192");
    }
    auto impl = std::make_unique<Impl>();
    auto ctx = gpu::VulkanContext::create({.device = options.device,
                                           .validation = options.validation,
                                           .force_staging = options.force_staging,
                                           .graphics = true,
                                           .instance_extensions = options.instance_extensions,
                                           .create_surface = options.create_surface});
    if (!ctx) return ctx.error();
    impl->ctx = std::move(ctx).value();
    impl->width = options.width;
    impl->height = options.height;
    impl->joints = options.joints;
    const gpu::VulkanContext& c = *impl->ctx;
    const auto depth = depth_format(c.physical_device());
    if (!depth) return make_error(Error::Kind::Unsupported, c.info().name + " has no depth format to render to");

    auto color_image = gpu::GpuImage::create(c, options.width, options.height, kColorFormat,
                                             vk::ImageUsageFlagBits::eColorAttachment | vk::ImageUsageFlagBits::eTransferSrc,
                                             vk::ImageAspectFlagBits::eColor);
    if (!color_image) return color_image.error();
    impl->color.emplace(std::move(color_image).value());
    impl->samples = sample_count(c.physical_device());
    const bool msaa = impl->samples != vk::SampleCountFlagBits::e1;
    if (msaa) {
        auto drawn = gpu::GpuImage::create(c, options.width, options.height, kColorFormat, vk::ImageUsageFlagBits::eColorAttachment,
                                           vk::ImageAspectFlagBits::eColor, impl->samples);
        if (!drawn) return drawn.error();
        impl->msaa_color.emplace(std::move(drawn).value());
    }
    auto depth_image = gpu::GpuImage::create(c, options.width, options.height, *depth,
                                             vk::ImageUsageFlagBits::eDepthStencilAttachment, vk::ImageAspectFlagBits::eDepth,
                                             impl->samples);
    if (!depth_image) return depth_image.error();
    impl->depth.emplace(std::move(depth_image).value());

    KW_TRY(gpu::guard("Vulkan render pass", [&]() -> Result<void> {
        // Multisampled: attachment 0 is drawn (its samples not kept) and resolved into
        // attachment 2, the image read back.
        const vk::AttachmentDescription attachments[] = {
            {.format = kColorFormat,
             .samples = impl->samples,
             .loadOp = vk::AttachmentLoadOp::eClear,
             .storeOp = msaa ? vk::AttachmentStoreOp::eDontCare : vk::AttachmentStoreOp::eStore,
             .stencilLoadOp = vk::AttachmentLoadOp::eDontCare,
             .stencilStoreOp = vk::AttachmentStoreOp::eDontCare,
             .initialLayout = vk::ImageLayout::eUndefined,
             .finalLayout = msaa ? vk::ImageLayout::eColorAttachmentOptimal : vk::ImageLayout::eTransferSrcOptimal},
            {.format = *depth,
             .samples = impl->samples,
             .loadOp = vk::AttachmentLoadOp::eClear,
             .storeOp = vk::AttachmentStoreOp::eDontCare,
             .stencilLoadOp = vk::AttachmentLoadOp::eDontCare,
             .stencilStoreOp = vk::AttachmentStoreOp::eDontCare,
             .initialLayout = vk::ImageLayout::eUndefined,
             .finalLayout = vk::ImageLayout::eDepthStencilAttachmentOptimal},
            {.format = kColorFormat,
             .samples = vk::SampleCountFlagBits::e1,
             .loadOp = vk::AttachmentLoadOp::eDontCare,
             .storeOp = vk::AttachmentStoreOp::eStore,
             .stencilLoadOp = vk::AttachmentLoadOp::eDontCare,
             .stencilStoreOp = vk::AttachmentStoreOp::eDontCare,
             .initialLayout = vk::ImageLayout::eUndefined,
             .finalLayout = vk::ImageLayout::eTransferSrcOptimal},
        };
        const vk::AttachmentReference color_ref{.attachment = 0, .layout = vk::ImageLayout::eColorAttachmentOptimal};
        const vk::AttachmentReference depth_ref{.attachment = 1, .layout = vk::ImageLayout::eDepthStencilAttachmentOptimal};
        const vk::AttachmentReference resolve_ref{.attachment = 2, .layout = vk::ImageLayout::eColorAttachmentOptimal};
        const vk::SubpassDescription subpass{.pipelineBindPoint = vk::PipelineBindPoint::eGraphics,
                                             .colorAttachmentCount = 1,
                                             .pColorAttachments = &color_ref,
                                             .pResolveAttachments = msaa ? &resolve_ref : nullptr,
                                             .pDepthStencilAttachment = &depth_ref};
        using Stage = vk::PipelineStageFlagBits;
        using Access = vk::AccessFlagBits;
        const vk::SubpassDependency dependencies[] = {
            // The previous frame's copy read the colour image, and its drawing and depth
            // test wrote the (multisampled) colour and depth images, before this frame
            // clears them.
            {.srcSubpass = VK_SUBPASS_EXTERNAL,
             .dstSubpass = 0,
             .srcStageMask = Stage::eTransfer | Stage::eColorAttachmentOutput | Stage::eLateFragmentTests,
             .dstStageMask = Stage::eColorAttachmentOutput | Stage::eEarlyFragmentTests | Stage::eLateFragmentTests,
             .srcAccessMask = Access::eColorAttachmentWrite | Access::eDepthStencilAttachmentWrite,
             .dstAccessMask = Access::eColorAttachmentWrite | Access::eDepthStencilAttachmentRead |
                              Access::eDepthStencilAttachmentWrite},
            // The copy after the pass reads what the pass drew.
            {.srcSubpass = 0,
             .dstSubpass = VK_SUBPASS_EXTERNAL,
             .srcStageMask = Stage::eColorAttachmentOutput,
             .dstStageMask = Stage::eTransfer,
             .srcAccessMask = Access::eColorAttachmentWrite,
             .dstAccessMask = Access::eTransferRead},
        };
        impl->pass = c.device().createRenderPass({.attachmentCount = msaa ? 3u : 2u,
                                                  .pAttachments = attachments,
                                                  .subpassCount = 1,
                                                  .pSubpasses = &subpass,
                                                  .dependencyCount = 2,
                                                  .pDependencies = dependencies});
        const vk::ImageView views[] = {msaa ? impl->msaa_color->view() : impl->color->view(), impl->depth->view(),
                                       impl->color->view()};
        impl->framebuffer = c.device().createFramebuffer({.renderPass = *impl->pass,
                                                          .attachmentCount = msaa ? 3u : 2u,
                                                          .pAttachments = views,
                                                          .width = options.width,
                                                          .height = options.height,
                                                          .layers = 1});
        return {};
    }));

    const auto pipeline = [&](vk::PrimitiveTopology topology, bool depth_test) {
        return gpu::GraphicsPipeline::create(c, *impl->pass, "render.vert", "render.frag", sizeof(gpu::RenderVertex), 3,
                                             sizeof(gpu::RenderPush), {.topology = topology, .depth = depth_test, .samples = impl->samples});
    };
    // Each created piece into its slot, or the first error.
    const auto keep = [](auto& slot, auto created) -> Result<void> {
        if (!created) return created.error();
        slot.emplace(std::move(created).value());
        return {};
    };
    KW_TRY(keep(impl->background, pipeline(vk::PrimitiveTopology::eTriangleList, false)));
    KW_TRY(keep(impl->lines, pipeline(vk::PrimitiveTopology::eLineList, true)));
    KW_TRY(keep(impl->triangles, pipeline(vk::PrimitiveTopology::eTriangleList, true)));
    KW_TRY(keep(impl->shadows, gpu::GraphicsPipeline::create(c, *impl->pass, "render.vert", "shadow.frag", sizeof(gpu::RenderVertex), 3,
                                                             sizeof(gpu::RenderPush),
                                                             {.depth = true, .samples = impl->samples, .blend = true})));

    auto readback = compute::Buffer::create(c, vk::DeviceSize{options.width} * options.height * 4, compute::Usage::Readback);
    if (!readback) return readback.error();
    impl->readback.emplace(std::move(readback).value());
    return std::unique_ptr<Renderer>(new Renderer(std::move(impl)));
}

namespace {
constexpr std::size_t kBackgroundVertices = 6;
}  // namespace

Result<void> Renderer::Impl::upload(const DrawList& list) {
    gpu::VulkanContext& c = *ctx;
    // The background: two clip-space triangles, top colour at y = -1 (Vulkan: top).
    const glm::vec3 top = background_color(0.0f), bottom = background_color(1.0f);
    const auto corner = [](float x, float y, const glm::vec3& col) {
        return gpu::RenderVertex{{x, y, 0.0f, 1.0f}, {col.x, col.y, col.z, 0.0f}, {0.0f, 0.0f, 0.0f, KW_RENDER_CLIP}};
    };
    const gpu::RenderVertex quad[kBackgroundVertices] = {corner(-1, -1, top),  corner(1, -1, top),  corner(1, 1, bottom),
                                                         corner(-1, -1, top),  corner(1, 1, bottom), corner(-1, 1, bottom)};
    const std::size_t count = kBackgroundVertices + list.lines().size() + list.triangles().size() + list.shadows().size();
    const vk::DeviceSize bytes = count * sizeof(gpu::RenderVertex);
    // The previous submission has finished (every submission is waited for), so the
    // buffer can be replaced.
    if (!vertices || vertices->size() < bytes) {
        auto grown = compute::Buffer::create(c, std::max<vk::DeviceSize>(bytes, vertices ? 2 * vertices->size() : 0),
                                            compute::Usage::Vertex);
        if (!grown) return grown.error();
        vertices.reset();
        vertices.emplace(std::move(grown).value());
    }
    std::byte* out = vertices->mapped();
    assert(out != nullptr);
    std::memcpy(out, quad, sizeof(quad));
    out += sizeof(quad);
    // memcpy from an empty span's null data() is undefined even for 0 bytes.
    if (!list.lines().empty()) std::memcpy(out, list.lines().data(), list.lines().size_bytes());
    out += list.lines().size_bytes();
    if (!list.triangles().empty()) std::memcpy(out, list.triangles().data(), list.triangles().size_bytes());
    out += list.triangles().size_bytes();
    if (!list.shadows().empty()) std::memcpy(out, list.shadows().data(), list.shadows().size_bytes());
    return {};
}

// The render pass; the colour image ends in TransferSrcOptimal.
void Renderer::Impl::record_pass(const vk::raii::CommandBuffer& cmd, const DrawList& list) const {
    gpu::RenderPush push{};
    const CameraView& camera = list.camera();
    const glm::mat4 vp = view_projection(camera, static_cast<float>(width) / static_cast<float>(height));
    for (int i = 0; i < 4; ++i) push.view_proj[i] = {vp[i].x, vp[i].y, vp[i].z, vp[i].w};
    push.light = {kLight.x, kLight.y, kLight.z, kAmbientLight};
    const CameraBasis basis = camera_basis(camera);
    push.eye = v4(camera.position, camera.near);
    push.forward = v4(basis.forward, list.pixel_per_depth());
    push.draw.w = camera.orthographic ? KW_RENDER_ORTHOGRAPHIC : KW_RENDER_PERSPECTIVE;
    using Stage = vk::PipelineStageFlagBits;
    using Access = vk::AccessFlagBits;
    // What layers compute on the device for their draws (before the barrier below, which
    // makes it visible to the vertex shaders).
    for (const NamedLayer& named : layers) named.layer->record_compute(cmd);
    // The layers' vertex shaders read what kernels, copies and the host wrote before
    // (the simulation's state on a shared device, uploads).
    const vk::MemoryBarrier layer_inputs{.srcAccessMask = Access::eShaderWrite | Access::eTransferWrite | Access::eHostWrite,
                                         .dstAccessMask = Access::eShaderRead | Access::eVertexAttributeRead};
    cmd.pipelineBarrier(Stage::eComputeShader | Stage::eTransfer | Stage::eHost, Stage::eVertexShader | Stage::eVertexInput, {},
                        layer_inputs, {}, {});
    const vk::ClearValue clears[] = {
        vk::ClearValue{.color = vk::ClearColorValue{.float32 = std::array<float, 4>{0.0f, 0.0f, 0.0f, 1.0f}}},
        vk::ClearValue{.depthStencil = vk::ClearDepthStencilValue{.depth = 1.0f, .stencil = 0}}};
    cmd.beginRenderPass({.renderPass = *pass,
                         .framebuffer = *framebuffer,
                         .renderArea = {{0, 0}, {width, height}},
                         .clearValueCount = 2,
                         .pClearValues = clears},
                        vk::SubpassContents::eInline);
    cmd.setViewport(0, vk::Viewport{0.0f, 0.0f, static_cast<float>(width), static_cast<float>(height), 0.0f, 1.0f});
    cmd.setScissor(0, vk::Rect2D{{0, 0}, {width, height}});
    cmd.bindVertexBuffers(0, gpu::vk_buffer(*vertices), vk::DeviceSize{0});
    const auto draw = [&](const gpu::GraphicsPipeline& pipeline, std::size_t first, std::size_t n) {
        if (n == 0) return;
        cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, pipeline.handle());
        cmd.pushConstants<gpu::RenderPush>(pipeline.layout(), vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment,
                                           0, push);
        cmd.draw(static_cast<std::uint32_t>(n), 1, static_cast<std::uint32_t>(first), 0);
    };
    draw(*background, 0, kBackgroundVertices);
    draw(*lines, kBackgroundVertices, list.lines().size());
    draw(*triangles, kBackgroundVertices + list.lines().size(), list.triangles().size());
    // The minimum sizes are for 720 rows; smaller images get thinner strands.
    const LayerFrame frame{push, std::clamp(static_cast<float>(height) / 720.0f, 0.5f, 2.0f), joints};
    for (const NamedLayer& named : layers) named.layer->record(cmd, frame);
    // Translucent, after everything opaque: what stands on the shadow hides it.
    cmd.bindVertexBuffers(0, gpu::vk_buffer(*vertices), vk::DeviceSize{0});
    draw(*shadows, kBackgroundVertices + list.lines().size() + list.triangles().size(), list.shadows().size());
    cmd.endRenderPass();
    // The next frame's kernels and uploads overwrite what the vertex shaders read.
    cmd.pipelineBarrier(Stage::eVertexShader, Stage::eComputeShader | Stage::eTransfer, {}, {}, {}, {});
}

Result<Image> Renderer::render(const DrawList& list) {
    assert(list.width() == impl_->width && list.height() == impl_->height && "the draw list is for another size");
    Impl& r = *impl_;
    gpu::VulkanContext& c = *r.ctx;
    std::optional<DrawList> merged;
    const DrawList& frame = r.with_draws(list, merged);
    KW_TRY(r.upload(frame));
    KW_TRY(c.submit([&](const vk::raii::CommandBuffer& cmd) {
        // The previous frame's copy into the readback buffer (its fence waited for)
        // before this frame's copy overwrites it.
        const vk::MemoryBarrier readback_reuse{.srcAccessMask = vk::AccessFlagBits::eTransferWrite,
                                               .dstAccessMask = vk::AccessFlagBits::eTransferWrite};
        cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eTransfer, {}, readback_reuse, {}, {});
        r.record_pass(cmd, frame);
        cmd.copyImageToBuffer(r.color->handle(), vk::ImageLayout::eTransferSrcOptimal, gpu::vk_buffer(*r.readback),
                              vk::BufferImageCopy{.bufferOffset = 0,
                                                  .imageSubresource = {.aspectMask = vk::ImageAspectFlagBits::eColor, .layerCount = 1},
                                                  .imageExtent = {r.width, r.height, 1}});
        const vk::MemoryBarrier to_host{.srcAccessMask = vk::AccessFlagBits::eTransferWrite, .dstAccessMask = vk::AccessFlagBits::eHostRead};
        cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {}, to_host, {}, {});
    }));
    KW_TRY(r.readback->invalidate(c));
    Image image;
    image.width = r.width;
    image.height = r.height;
    image.rgba.resize(std::size_t{r.width} * r.height * 4);
    std::memcpy(image.rgba.data(), r.readback->mapped(), image.rgba.size());
    return image;
}

Result<void> Renderer::draw(const DrawList& list) {
    assert(list.width() == impl_->width && list.height() == impl_->height && "the draw list is for another size");
    Impl& r = *impl_;
    std::optional<DrawList> merged;
    const DrawList& frame = r.with_draws(list, merged);
    KW_TRY(r.upload(frame));
    return r.ctx->submit([&](const vk::raii::CommandBuffer& cmd) { r.record_pass(cmd, frame); });
}

}  // namespace kodawari::render
