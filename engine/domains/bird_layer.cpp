// The bird domain's render layer (kodawari/domains/bird_draw.hpp, shaders/birds.vert):
// the part meshes of each wing type instanced per bird from BirdPoseGpu poses, the vulkan
// bird backend's own pose ring when it shares the renderer's device (nothing read back)
// or the same layout uploaded.
#include "kodawari/domains/bird_draw.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <kodawari/shared/bird_draw.h>

#include "birds/bird_meshes.hpp"
#include "gpu/compute_vulkan.hpp"
#include "kodawari/backends/device_data.hpp"
#include "render/layer.hpp"

namespace kodawari {

namespace {

using render::bytes_of;
using render::float_bits;

/// The birds of a BirdWorld.
class BirdLayer final : public render::Layer {
public:
    [[nodiscard]] static Result<BirdLayer> create(const render::LayerTarget& target);

    /// The birds of `world` (null: none): the part meshes of its wing types and the
    /// order of its birds by wing type are uploaded.
    [[nodiscard]] Result<void> set_world(gpu::VulkanContext& ctx, const birds::BirdWorld* world, float min_wingspan_px);
    /// The last simulated frame's poses where the vulkan backend keeps them, on `ctx`;
    /// an error for any other backend.
    [[nodiscard]] Result<void> from_backend(gpu::VulkanContext& ctx, const BirdBackend& backend);
    /// One pose per bird uploaded.
    [[nodiscard]] Result<void> from_poses(gpu::VulkanContext& ctx, std::span<const gpu::BirdPose> poses);

    [[nodiscard]] Result<void> clear(gpu::VulkanContext& ctx) override { return set_world(ctx, nullptr, min_wingspan_px_); }
    void record(const vk::raii::CommandBuffer& cmd, const render::LayerFrame& frame) const override;

private:
    BirdLayer() = default;
    struct TypeRange {
        std::uint32_t first_vertex = 0, vertices = 0, first_bird = 0, birds = 0;
    };
    std::optional<gpu::GraphicsPipeline> pipeline_;
    std::optional<gpu::BufferSet> set_;
    std::size_t count_ = 0;
    float min_wingspan_px_ = 0.0f;
    std::array<TypeRange, birds::kWingTypeCount> ranges_{};
    std::optional<compute::Buffer> vertices_, types_, order_, host_poses_;
    std::vector<gpu::BirdPoseGpu> packed_;
    std::uint32_t first_pose_ = 0;
    bool bound_ = false;
};

constexpr std::string_view kBirdsLayer = "birds";
constexpr int kBirdsOrder = 2;  // after the chains' layers, before the skinned meshes

Result<BirdLayer> BirdLayer::create(const render::LayerTarget& target) {
    BirdLayer layer;
    KW_TRY(render::layer_pipeline_with_set(target, "birds.vert", "render.frag", sizeof(gpu::BirdDrawVertex), 2, KW_BIRDS_DRAW_BINDING_COUNT,
                                           layer.pipeline_, layer.set_));
    return layer;
}

Result<void> BirdLayer::set_world(gpu::VulkanContext& ctx, const birds::BirdWorld* world, float min_wingspan_px) {
    count_ = 0;
    bound_ = false;
    ranges_ = {};
    min_wingspan_px_ = min_wingspan_px;
    vertices_.reset();
    types_.reset();
    order_.reset();
    host_poses_.reset();
    if (world == nullptr || world->birds.empty()) return {};
    count_ = world->birds.size();

    // The birds grouped by wing type (one instanced draw per type); unknown types are not
    // drawn. A user's model's birds (docs/bird-models.md) are drawn with the part meshes
    // of the built-in type whose wingspan is nearest the model's: the model's own mesh is
    // the export's, not the renderer's yet.
    const auto drawn_type = [&](std::uint32_t type) -> std::uint32_t {
        if (type < birds::kWingTypeCount || type >= birds::kWingTypeCount + world->models.size()) return type;
        const float span = world->models[type - birds::kWingTypeCount]->measure.wingspan;
        std::uint32_t best = 0;
        for (std::uint32_t t = 1; t < birds::kWingTypeCount; ++t) {
            const auto gap = [&](std::uint32_t k) {
                return std::abs(birds::wing_type_spec(static_cast<birds::WingType>(k)).wingspan - span);
            };
            if (gap(t) < gap(best)) best = t;
        }
        return best;
    };
    std::vector<std::uint32_t> order;
    std::vector<gpu::BirdDrawVertex> vertices;
    std::vector<gpu::BirdDrawType> types(birds::kWingTypeCount);
    for (std::uint32_t t = 0; t < birds::kWingTypeCount; ++t) {
        TypeRange& range = ranges_[t];
        range.first_bird = static_cast<std::uint32_t>(order.size());
        for (std::uint32_t b = 0; b < world->birds.size(); ++b) {
            if (drawn_type(world->birds[b].ids.y) == t) order.push_back(b);
        }
        range.birds = static_cast<std::uint32_t>(order.size()) - range.first_bird;
        if (range.birds == 0) continue;
        const auto wing = static_cast<birds::WingType>(t);
        const auto meshes = bird_part_meshes(wing);
        const auto offsets = birds::part_offsets(wing);
        const auto color = bird_base_color(wing);
        gpu::BirdDrawType& type = types[t];
        for (std::size_t k = 0; k < birds::kPartCount; ++k) {
            type.parts[k] = {offsets[k][0], offsets[k][1], offsets[k][2], static_cast<float>(birds::kPartParents[k])};
        }
        type.color = {color[0], color[1], color[2], birds::wing_type_spec(wing).wingspan};
        range.first_vertex = static_cast<std::uint32_t>(vertices.size());
        for (std::size_t k = 0; k < birds::kPartCount; ++k) {
            const core::MeshData& mesh = meshes[k];
            const auto at = [&](std::uint16_t i) {
                const auto& v = mesh.positions[i];
                return glm::vec3(v[0], v[1], v[2]);
            };
            for (std::size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
                const glm::vec3 a = at(mesh.indices[i]), b = at(mesh.indices[i + 1]), c = at(mesh.indices[i + 2]);
                const glm::vec3 n = glm::cross(b - a, c - a);
                for (const glm::vec3& p : {a, b, c}) {
                    vertices.push_back({{p.x, p.y, p.z, static_cast<float>(k)}, {n.x, n.y, n.z, 0.0f}});
                }
            }
        }
        range.vertices = static_cast<std::uint32_t>(vertices.size()) - range.first_vertex;
    }
    auto vertex_buffer = compute::Buffer::create(ctx, std::max<std::uint64_t>(vertices.size() * sizeof(gpu::BirdDrawVertex), 16),
                                                compute::Usage::Vertex);
    if (!vertex_buffer) return vertex_buffer.error();
    vertices_.emplace(std::move(vertex_buffer).value());
    if (!vertices.empty()) std::memcpy(vertices_->mapped(), vertices.data(), vertices.size() * sizeof(gpu::BirdDrawVertex));
    KW_TRY(render::store(ctx, types_, bytes_of(types)));
    return render::store(ctx, order_, bytes_of(order));
}

Result<void> BirdLayer::from_backend(gpu::VulkanContext& ctx, const BirdBackend& backend) {
    if (count_ == 0) return {};
    const DeviceData* data = backend.device_data();
    const DeviceSpan poses = data != nullptr ? data->buffer(bird_buffers::poses) : DeviceSpan{};
    if (data == nullptr || &data->context() != &ctx || poses.buffer == nullptr) {
        return make_error(Error::Kind::InvalidInput, "the " + std::string(backend.name()) +
                                                         " bird backend has no poses on the renderer's device: pass its poses");
    }
    const gpu::BufferRange ranges[KW_BIRDS_DRAW_BINDING_COUNT] = {{gpu::vk_buffer(*types_)}, {gpu::vk_buffer(*order_)}, {gpu::vk_buffer(*poses.buffer)}};
    set_->bind(ctx, ranges);
    first_pose_ = static_cast<std::uint32_t>(poses.first);
    bound_ = true;
    return {};
}

Result<void> BirdLayer::from_poses(gpu::VulkanContext& ctx, std::span<const gpu::BirdPose> poses) {
    if (count_ == 0) return {};
    if (poses.size() != count_) {
        return make_error(Error::Kind::InvalidInput,
                          std::to_string(poses.size()) + " bird poses for " + std::to_string(count_) + " birds");
    }
    // The kernel's layout (shared/birds.h, BirdPoseGpu): the shader mirrors the left wing,
    // as every backend poses it.
    packed_.resize(count_);
    for (std::size_t b = 0; b < count_; ++b) {
        const gpu::BirdPose& p = poses[b];
        packed_[b] = {p.position,          p.rotation[KW_PART_BODY],      p.rotation[KW_PART_HEAD],
                      p.rotation[KW_PART_TAIL], p.rotation[KW_PART_LEFT_ARM1], p.rotation[KW_PART_LEFT_ARM2]};
    }
    if (!host_poses_) {
        auto buffer = compute::Buffer::create(ctx, count_ * sizeof(gpu::BirdPoseGpu), compute::Usage::Storage);
        if (!buffer) return buffer.error();
        host_poses_.emplace(std::move(buffer).value());
        bound_ = false;
    }
    KW_TRY(compute::upload(ctx, *host_poses_, bytes_of(packed_)));
    const gpu::BufferRange ranges[KW_BIRDS_DRAW_BINDING_COUNT] = {{gpu::vk_buffer(*types_)}, {gpu::vk_buffer(*order_)}, {gpu::vk_buffer(*host_poses_)}};
    set_->bind(ctx, ranges);
    first_pose_ = 0;
    bound_ = true;
    return {};
}

void BirdLayer::record(const vk::raii::CommandBuffer& cmd, const render::LayerFrame& frame) const {
    if (!bound_ || count_ == 0) return;
    gpu::RenderPush push = frame.push;
    cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, pipeline_->handle());
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, pipeline_->layout(), 0, set_->handle(), {});
    cmd.bindVertexBuffers(0, gpu::vk_buffer(*vertices_), vk::DeviceSize{0});
    for (std::uint32_t t = 0; t < birds::kWingTypeCount; ++t) {
        const TypeRange& r = ranges_[t];
        if (r.birds == 0 || r.vertices == 0) continue;
        push.draw = {t, first_pose_, float_bits(min_wingspan_px_), push.draw.w};
        cmd.pushConstants<gpu::RenderPush>(pipeline_->layout(), vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment,
                                           0, push);
        cmd.draw(r.vertices, r.birds, r.first_vertex, r.first_bird);
    }
}

}  // namespace

Result<void> show_birds(render::Renderer& renderer, const birds::BirdWorld* world) {
    auto layer = render::layer_of<BirdLayer>(renderer, kBirdsLayer, kBirdsOrder);
    if (!layer) return layer.error();
    return layer.value()->set_world(render::layer_context(renderer), world, kBirdMinPixels);
}

Result<void> draw_birds(render::Renderer& renderer, const BirdBackend& backend) {
    auto layer = render::layer_of<BirdLayer>(renderer, kBirdsLayer, kBirdsOrder);
    if (!layer) return layer.error();
    return layer.value()->from_backend(render::layer_context(renderer), backend);
}

Result<void> draw_birds(render::Renderer& renderer, std::span<const gpu::BirdPose> poses) {
    auto layer = render::layer_of<BirdLayer>(renderer, kBirdsLayer, kBirdsOrder);
    if (!layer) return layer.error();
    return layer.value()->from_poses(render::layer_context(renderer), poses);
}

}  // namespace kodawari
