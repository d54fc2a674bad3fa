// The chain domain's render layers (kodawari/domains/chain_draw.hpp): the chains
// (shaders/chains.vert) from rod state and the colliders (shaders/colliders.vert) from the
// rod input, each binding the vulkan rod backend's own buffers when it shares the
// renderer's device (nothing read back) or buffers of the same layout filled from host
// data; the skinned meshes' layer is domains/skinned_layer.hpp.
#include "kodawari/domains/chain_draw.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/gtc/packing.hpp>

#include <kodawari/shared/chain_draw.h>
#include <kodawari/shared/rods.h>

#include "gpu/compute_vulkan.hpp"
#include "domains/skinned_layer.hpp"
#include "kodawari/domains/scene_draw.hpp"
#include "kodawari/scene/scene.hpp"
#include "render/layer.hpp"

namespace kodawari {

namespace {

using render::bytes_of;
using render::float_bits;

/// The chains of a RodWorld.
class ChainLayer final : public render::Layer {
public:
    /// The pipeline for the renderer's pass (shared by every world drawn).
    [[nodiscard]] static Result<ChainLayer> create(const render::LayerTarget& target);

    /// The chains of `world` (null: none) in `style`; static per-chain data is uploaded.
    [[nodiscard]] Result<void> set_world(gpu::VulkanContext& ctx, const rods::RodWorld* world, const ChainStyle& style);
    /// The state to draw: the vulkan backend's buffers when on `ctx`, else read and uploaded.
    [[nodiscard]] Result<void> from_backend(gpu::VulkanContext& ctx, RodBackend& backend);
    /// Joint positions (world) uploaded.
    [[nodiscard]] Result<void> from_snapshot(gpu::VulkanContext& ctx, const ChainSnapshot& snapshot);
    /// Whether the last from_*() bound the backend's own buffers.
    [[nodiscard]] bool on_device() const { return on_device_; }

    [[nodiscard]] Result<void> clear(gpu::VulkanContext& ctx) override { return set_world(ctx, nullptr, style_); }
    /// The tubes, and with LayerFrame::joints the joint dots.
    void record(const vk::raii::CommandBuffer& cmd, const render::LayerFrame& frame) const override;

private:
    ChainLayer() = default;
    std::optional<gpu::GraphicsPipeline> pipeline_;
    std::optional<gpu::BufferSet> set_;
    const rods::RodWorld* world_ = nullptr;
    ChainStyle style_;
    std::optional<compute::Buffer> info_, joint_chain_, host_states_, host_motion_;
    ChainSnapshot scratch_;
    std::vector<gpu::RodJointMotionGpu> motion_;
    bool bound_ = false, on_device_ = false;
};


/// The colliders of a RodWorld's input, as lit capsules: the procedural characters'
/// bodies. Those of characters drawn as skinned meshes are left out (the mesh is their
/// body; solid capsules would poke through it).
class ColliderLayer final : public render::Layer {
public:
    [[nodiscard]] static Result<ColliderLayer> create(const render::LayerTarget& target);

    /// The colliders of `world` (null: none).
    void set_world(const rods::RodWorld* world);
    /// The scene whose characters with meshes (draws_skinned) are drawn by the skinned
    /// layer (null: none): their colliders are not drawn.
    void set_skinned(const RodScene* scene);
    /// This frame's colliders: the vulkan rod backend's input buffer when on `ctx` (rigged
    /// characters' colliders are written there on the device), else `input`'s uploaded.
    [[nodiscard]] Result<void> from(gpu::VulkanContext& ctx, const RodBackend& backend, const rods::RodFrame& input);

    [[nodiscard]] Result<void> clear(gpu::VulkanContext&) override {
        set_world(nullptr);
        set_skinned(nullptr);
        return {};
    }
    /// Lit capsules in kColliderColor.
    void record(const vk::raii::CommandBuffer& cmd, const render::LayerFrame& frame) const override;

private:
    ColliderLayer() = default;
    // The runs of colliders drawn, [first, first + count), from world_ and skinned_.
    void update_ranges();
    std::optional<gpu::GraphicsPipeline> pipeline_;
    std::optional<gpu::BufferSet> set_;
    const rods::RodWorld* world_ = nullptr;
    const RodScene* skinned_ = nullptr;
    std::uint32_t count_ = 0;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> ranges_;
    std::optional<compute::Buffer> host_;
    std::vector<gpu::RodColliderGpu> packed_;
    bool bound_ = false;
};

// The layers' names and drawing order in a renderer.
constexpr std::string_view kChainsLayer = "chains", kCollidersLayer = "chains.colliders", kSkinnedLayer = "chains.skinned";
constexpr int kChainsOrder = 0, kCollidersOrder = 1, kSkinnedOrder = 3;  // the birds' is 2

Result<ChainLayer> ChainLayer::create(const render::LayerTarget& target) {
    ChainLayer layer;
    KW_TRY(render::layer_pipeline_with_set(target, "chains.vert", "lit.frag", 0, 0, KW_CHAINS_BINDING_COUNT, layer.pipeline_, layer.set_));
    return layer;
}

Result<void> ChainLayer::set_world(gpu::VulkanContext& ctx, const rods::RodWorld* world, const ChainStyle& style) {
    world_ = world;
    style_ = style;
    bound_ = on_device_ = false;
    info_.reset();
    joint_chain_.reset();
    host_states_.reset();
    host_motion_.reset();
    if (world == nullptr || world->joint_count == 0) return {};
    std::vector<gpu::ChainDrawInfo> info;
    std::vector<std::uint32_t> joint_chain(world->joint_count, 0u);
    assert(!style.colors.empty());
    for (std::uint32_t c = 0; c < world->chains.size(); ++c) {
        const render::Rgba8 rgba = style.colors[c % style.colors.size()];
        const std::uint32_t color = glm::packUnorm4x8(glm::vec4(rgba.r, rgba.g, rgba.b, rgba.a) / 255.0f);
        const rods::ChainInstance& chain = world->chains[c];
        const rods::Chain& shape = world->templ(chain).chain;
        info.push_back({{chain.joint_begin, shape.joint_count, color, 0u}, {shape.thickness, 0.0f, 0.0f, 0.0f}});
        std::fill_n(joint_chain.begin() + chain.joint_begin, shape.joint_count, c);
    }
    KW_TRY(render::store(ctx, info_, bytes_of(info)));
    return render::store(ctx, joint_chain_, bytes_of(joint_chain));
}

Result<void> ChainLayer::from_backend(gpu::VulkanContext& ctx, RodBackend& backend) {
    assert(world_ != nullptr && "set_world() first");
    const DeviceData* state = backend.device_data();
    if (state == nullptr || &state->context() != &ctx) {
        KW_TRY(backend.read(scratch_));
        return from_snapshot(ctx, scratch_);
    }
    const gpu::BufferRange ranges[KW_CHAINS_BINDING_COUNT] = {{gpu::vk_buffer(*info_)},
                                                              {gpu::vk_buffer(*joint_chain_)},
                                                              {gpu::vk_buffer(*state->buffer(rod_buffers::chain_states).buffer)},
                                                              {gpu::vk_buffer(*state->buffer(rod_buffers::motion).buffer)}};
    set_->bind(ctx, ranges);
    bound_ = on_device_ = true;
    return {};
}

Result<void> ChainLayer::from_snapshot(gpu::VulkanContext& ctx, const ChainSnapshot& snapshot) {
    assert(world_ != nullptr && "set_world() first");
    if (snapshot.positions.size() != world_->joint_count) {
        return make_error(Error::Kind::InvalidInput, "the snapshot has " + std::to_string(snapshot.positions.size()) +
                                                         " joints; the world has " + std::to_string(world_->joint_count));
    }
    // The backend's layout with every root at the origin: x is then the world position.
    if (!host_states_) {
        const std::vector<gpu::RodChainStateGpu> zero(world_->chains.size(), gpu::RodChainStateGpu{});
        KW_TRY(render::store(ctx, host_states_, bytes_of(zero)));
        auto motion = compute::Buffer::create(ctx, std::max<std::uint64_t>(world_->joint_count * sizeof(gpu::RodJointMotionGpu), 16),
                                             compute::Usage::Storage);
        if (!motion) return motion.error();
        host_motion_.emplace(std::move(motion).value());
    }
    motion_.resize(world_->joint_count);
    for (std::size_t j = 0; j < motion_.size(); ++j) {
        const glm::vec3& p = snapshot.positions[j];
        motion_[j] = {{p.x, p.y, p.z, 0.0f}, {0.0f, 0.0f, 0.0f, 0.0f}};
    }
    KW_TRY(compute::upload(ctx, *host_motion_, bytes_of(motion_)));
    if (on_device_ || !bound_) {
        const gpu::BufferRange ranges[KW_CHAINS_BINDING_COUNT] = {
            {gpu::vk_buffer(*info_)}, {gpu::vk_buffer(*joint_chain_)}, {gpu::vk_buffer(*host_states_)}, {gpu::vk_buffer(*host_motion_)}};
        set_->bind(ctx, ranges);
    }
    bound_ = true;
    on_device_ = false;
    return {};
}

void ChainLayer::record(const vk::raii::CommandBuffer& cmd, const render::LayerFrame& frame) const {
    if (!bound_ || world_ == nullptr || world_->joint_count == 0) return;
    gpu::RenderPush push = frame.push;
    const float rows_scale = frame.rows_scale;
    cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, pipeline_->handle());
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, pipeline_->layout(), 0, set_->handle(), {});
    const auto stages = vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment;
    push.draw = {KW_CHAINS_DRAW_SEGMENTS, float_bits(rows_scale * style_.min_width_px), float_bits(rows_scale * style_.min_dot_px), push.draw.w};
    cmd.pushConstants<gpu::RenderPush>(pipeline_->layout(), stages, 0, push);
    cmd.draw(KW_CHAIN_SEGMENT_VERTICES, world_->joint_count, 0, 0);
    if (!frame.joints) return;
    push.draw.x = KW_CHAINS_DRAW_DOTS;
    cmd.pushConstants<gpu::RenderPush>(pipeline_->layout(), stages, 0, push);
    cmd.draw(KW_CHAIN_DOT_VERTICES, world_->joint_count, 0, 0);
}

Result<ColliderLayer> ColliderLayer::create(const render::LayerTarget& target) {
    ColliderLayer layer;
    KW_TRY(render::layer_pipeline_with_set(target, "colliders.vert", "lit.frag", 0, 0, KW_COLLIDERS_BINDING_COUNT, layer.pipeline_,
                                           layer.set_));
    return layer;
}

void ColliderLayer::set_world(const rods::RodWorld* world) {
    world_ = world;
    count_ = world != nullptr ? world->collider_count : 0;
    host_.reset();
    bound_ = false;
    update_ranges();
}

void ColliderLayer::set_skinned(const RodScene* scene) {
    skinned_ = scene;
    update_ranges();
}

void ColliderLayer::update_ranges() {
    ranges_.clear();
    std::vector<bool> drawn(count_, true);
    if (world_ != nullptr && skinned_ != nullptr && &skinned_->world == world_) {
        // A skinned instance's whole collider range, which holds all its chains' runs.
        for (const CharacterInstance& inst : skinned_->instances) {
            const CharacterKinematics& k = skinned_->characters[inst.character];
            if (!k.rig || !draws_skinned(*k.rig)) continue;
            const auto end = static_cast<std::uint32_t>(std::min<std::size_t>(inst.collider_begin + k.colliders.size(), count_));
            for (std::uint32_t c = inst.collider_begin; c < end; ++c) drawn[c] = false;
        }
    }
    for (std::uint32_t k = 0; k < count_; ++k) {
        if (!drawn[k]) continue;
        if (!ranges_.empty() && ranges_.back().first + ranges_.back().second == k) {
            ++ranges_.back().second;
        } else {
            ranges_.emplace_back(k, 1u);
        }
    }
}

Result<void> ColliderLayer::from(gpu::VulkanContext& ctx, const RodBackend& backend, const rods::RodFrame& input) {
    if (count_ == 0) return {};
    const DeviceData* state = backend.device_data();
    if (state != nullptr && &state->context() == &ctx) {
        const gpu::BufferRange ranges[KW_COLLIDERS_BINDING_COUNT] = {{gpu::vk_buffer(*state->buffer(rod_buffers::colliders).buffer)}};
        set_->bind(ctx, ranges);
        bound_ = true;
        return {};
    }
    if (input.colliders.size() != count_) {
        return make_error(Error::Kind::InvalidInput, "the frame has " + std::to_string(input.colliders.size()) +
                                                         " colliders; the world has " + std::to_string(count_));
    }
    packed_.resize(count_);
    std::transform(input.colliders.begin(), input.colliders.end(), packed_.begin(), [](const rods::Collider& c) {
        return gpu::RodColliderGpu{{c.a.x, c.a.y, c.a.z, c.radius}, {c.b.x, c.b.y, c.b.z, static_cast<float>(c.kind)}};
    });
    if (!host_) {
        auto buffer = compute::Buffer::create(ctx, count_ * sizeof(gpu::RodColliderGpu), compute::Usage::Storage);
        if (!buffer) return buffer.error();
        host_.emplace(std::move(buffer).value());
    }
    KW_TRY(compute::upload(ctx, *host_, bytes_of(packed_)));
    const gpu::BufferRange ranges[KW_COLLIDERS_BINDING_COUNT] = {{gpu::vk_buffer(*host_)}};
    set_->bind(ctx, ranges);
    bound_ = true;
    return {};
}

void ColliderLayer::record(const vk::raii::CommandBuffer& cmd, const render::LayerFrame& frame) const {
    if (!bound_ || count_ == 0) return;
    gpu::RenderPush push = frame.push;
    const render::Rgba8 color = kColliderColor;
    cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, pipeline_->handle());
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, pipeline_->layout(), 0, set_->handle(), {});
    push.draw = {glm::packUnorm4x8(glm::vec4(color.r, color.g, color.b, color.a) / 255.0f), 0u, 0u, push.draw.w};
    cmd.pushConstants<gpu::RenderPush>(pipeline_->layout(), vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment, 0,
                                       push);
    for (const auto& [first, n] : ranges_) cmd.draw(KW_COLLIDER_VERTICES, n, 0, first);
}

}  // namespace

Result<void> show_chains(render::Renderer& renderer, const rods::RodWorld* world, const ChainStyle& style) {
    auto chains = render::layer_of<ChainLayer>(renderer, kChainsLayer, kChainsOrder);
    if (!chains) return chains.error();
    auto colliders = render::layer_of<ColliderLayer>(renderer, kCollidersLayer, kCollidersOrder);
    if (!colliders) return colliders.error();
    colliders.value()->set_world(world);
    return chains.value()->set_world(render::layer_context(renderer), world, style);
}

Result<void> draw_chains(render::Renderer& renderer, RodBackend& backend) {
    auto chains = render::layer_of<ChainLayer>(renderer, kChainsLayer, kChainsOrder);
    if (!chains) return chains.error();
    return chains.value()->from_backend(render::layer_context(renderer), backend);
}

Result<void> draw_chains(render::Renderer& renderer, const ChainSnapshot& snapshot) {
    auto chains = render::layer_of<ChainLayer>(renderer, kChainsLayer, kChainsOrder);
    if (!chains) return chains.error();
    return chains.value()->from_snapshot(render::layer_context(renderer), snapshot);
}

bool chains_drawn_on_device(const render::Renderer& renderer) {
    const auto* chains = static_cast<const ChainLayer*>(render::find_layer(renderer, kChainsLayer));
    return chains != nullptr && chains->on_device();
}

Result<void> draw_colliders(render::Renderer& renderer, const RodBackend& backend, const rods::RodFrame& input) {
    auto colliders = render::layer_of<ColliderLayer>(renderer, kCollidersLayer, kCollidersOrder);
    if (!colliders) return colliders.error();
    return colliders.value()->from(render::layer_context(renderer), backend, input);
}

Result<void> show_skinned(render::Renderer& renderer, const RodScene* scene) {
    auto colliders = render::layer_of<ColliderLayer>(renderer, kCollidersLayer, kCollidersOrder);
    if (!colliders) return colliders.error();
    auto skinned = render::layer_of<SkinnedLayer>(renderer, kSkinnedLayer, kSkinnedOrder);
    if (!skinned) return skinned.error();
    colliders.value()->set_skinned(scene);
    return skinned.value()->set_scene(render::layer_context(renderer), scene);
}

Result<void> draw_skinned(render::Renderer& renderer, const CrowdAnimator& animator, RodBackend& rods, std::uint32_t frame) {
    auto skinned = render::layer_of<SkinnedLayer>(renderer, kSkinnedLayer, kSkinnedOrder);
    if (!skinned) return skinned.error();
    return skinned.value()->from_backends(render::layer_context(renderer), animator, rods, frame);
}

Result<void> draw_skinned(render::Renderer& renderer, const ChainSnapshot& snapshot, std::uint32_t frame) {
    auto skinned = render::layer_of<SkinnedLayer>(renderer, kSkinnedLayer, kSkinnedOrder);
    if (!skinned) return skinned.error();
    return skinned.value()->from_snapshot(render::layer_context(renderer), snapshot, frame);
}

bool skinned_drawn_on_device(const render::Renderer& renderer) {
    const auto* skinned = static_cast<const SkinnedLayer*>(render::find_layer(renderer, kSkinnedLayer));
    return skinned != nullptr && skinned->on_device();
}

}  // namespace kodawari
