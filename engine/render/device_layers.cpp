#include "render/device_layers.hpp"

#include <algorithm>
#include <cmath>
#include <bit>
#include <cassert>
#include <cstring>

#include <glm/gtc/packing.hpp>

#include "birds/bird_meshes.hpp"
#include "compute/compute.hpp"
#include "kodawari/render/scene_draw.hpp"

namespace kodawari::render {

namespace {

template <typename T>
std::span<const std::byte> bytes_of(const std::vector<T>& v) {
    return std::as_bytes(std::span<const T>(v));
}

std::uint32_t bits(float value) { return std::bit_cast<std::uint32_t>(value); }

}  // namespace

Result<void> store(gpu::VulkanContext& ctx, std::optional<compute::Buffer>& slot, std::span<const std::byte> bytes) {
    auto buffer = storage_with(ctx, bytes);
    if (!buffer) return buffer.error();
    slot.emplace(std::move(buffer).value());
    return {};
}

Result<compute::Buffer> storage_with(gpu::VulkanContext& ctx, std::span<const std::byte> bytes) {
    auto buffer = compute::Buffer::create(ctx, std::max<std::uint64_t>(bytes.size(), 16), compute::Usage::Storage);
    if (!buffer) return buffer.error();
    KW_TRY(compute::upload(ctx, buffer.value(), bytes));
    return buffer;
}

// ---------------------------------------------------------------------------------------
// Chains

Result<gpu::GraphicsPipeline> layer_pipeline(const gpu::VulkanContext& ctx, vk::RenderPass pass, std::string_view vertex,
                                             std::string_view fragment, std::uint32_t vertex_stride, std::uint32_t attributes,
                                             std::uint32_t storage_buffers, vk::SampleCountFlagBits samples, vk::PrimitiveTopology topology) {
    return gpu::GraphicsPipeline::create(ctx, pass, vertex, fragment, vertex_stride, attributes, sizeof(gpu::RenderPush),
                                         {.topology = topology, .depth = true, .samples = samples, .storage_buffers = storage_buffers});
}

namespace {

// A created pipeline and a descriptor set of it, into `pipeline` and `set`.
Result<void> with_set(const gpu::VulkanContext& ctx, Result<gpu::GraphicsPipeline> created, std::optional<gpu::GraphicsPipeline>& pipeline,
                      std::optional<gpu::BufferSet>& set) {
    if (!created) return created.error();
    pipeline.emplace(std::move(created).value());
    auto made = gpu::BufferSet::create(ctx, *pipeline);
    if (!made) return made.error();
    set.emplace(std::move(made).value());
    return {};
}

}  // namespace

Result<ChainLayer> ChainLayer::create(const gpu::VulkanContext& ctx, vk::RenderPass pass, vk::SampleCountFlagBits samples) {
    ChainLayer layer;
    KW_TRY(with_set(ctx, layer_pipeline(ctx, pass, "chains.vert", "lit.frag", 0, 0, KW_CHAINS_BINDING_COUNT, samples), layer.pipeline_,
                    layer.set_));
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
        const Rgba8 rgba = style.colors[c % style.colors.size()];
        const std::uint32_t color = glm::packUnorm4x8(glm::vec4(rgba.r, rgba.g, rgba.b, rgba.a) / 255.0f);
        const rods::ChainInstance& chain = world->chains[c];
        const rods::Chain& shape = world->templ(chain).chain;
        info.push_back({{chain.joint_begin, shape.joint_count, color, 0u}, {shape.thickness, 0.0f, 0.0f, 0.0f}});
        std::fill_n(joint_chain.begin() + chain.joint_begin, shape.joint_count, c);
    }
    KW_TRY(store(ctx, info_, bytes_of(info)));
    return store(ctx, joint_chain_, bytes_of(joint_chain));
}

Result<void> ChainLayer::from_backend(gpu::VulkanContext& ctx, RodBackend& backend) {
    assert(world_ != nullptr && "set_world() first");
    const DeviceData* state = backend.device_data();
    if (state == nullptr || &state->context() != &ctx) {
        KW_TRY(backend.read(scratch_));
        return from_snapshot(ctx, scratch_);
    }
    const gpu::BufferRange ranges[KW_CHAINS_BINDING_COUNT] = {{info_->handle()},
                                                              {joint_chain_->handle()},
                                                              {state->buffer(DeviceBuffer::RodChainStates).buffer->handle()},
                                                              {state->buffer(DeviceBuffer::RodMotion).buffer->handle()}};
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
        KW_TRY(store(ctx, host_states_, bytes_of(zero)));
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
            {info_->handle()}, {joint_chain_->handle()}, {host_states_->handle()}, {host_motion_->handle()}};
        set_->bind(ctx, ranges);
    }
    bound_ = true;
    on_device_ = false;
    return {};
}

void ChainLayer::record(const vk::raii::CommandBuffer& cmd, gpu::RenderPush push, float rows_scale, bool joints) const {
    if (!bound_ || world_ == nullptr || world_->joint_count == 0) return;
    cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, pipeline_->handle());
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, pipeline_->layout(), 0, set_->handle(), {});
    const auto stages = vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment;
    push.draw = {KW_CHAINS_DRAW_SEGMENTS, bits(rows_scale * style_.min_width_px), bits(rows_scale * style_.min_dot_px), push.draw.w};
    cmd.pushConstants<gpu::RenderPush>(pipeline_->layout(), stages, 0, push);
    cmd.draw(KW_CHAIN_SEGMENT_VERTICES, world_->joint_count, 0, 0);
    if (!joints) return;
    push.draw.x = KW_CHAINS_DRAW_DOTS;
    cmd.pushConstants<gpu::RenderPush>(pipeline_->layout(), stages, 0, push);
    cmd.draw(KW_CHAIN_DOT_VERTICES, world_->joint_count, 0, 0);
}

// ---------------------------------------------------------------------------------------
// Colliders

Result<ColliderLayer> ColliderLayer::create(const gpu::VulkanContext& ctx, vk::RenderPass pass, vk::SampleCountFlagBits samples) {
    ColliderLayer layer;
    KW_TRY(with_set(ctx,
                    layer_pipeline(ctx, pass, "colliders.vert", "lit.frag", 0, 0, KW_COLLIDERS_BINDING_COUNT, samples),
                    layer.pipeline_, layer.set_));
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
        const gpu::BufferRange ranges[KW_COLLIDERS_BINDING_COUNT] = {{state->buffer(DeviceBuffer::RodColliders).buffer->handle()}};
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
    const gpu::BufferRange ranges[KW_COLLIDERS_BINDING_COUNT] = {{host_->handle()}};
    set_->bind(ctx, ranges);
    bound_ = true;
    return {};
}

void ColliderLayer::record(const vk::raii::CommandBuffer& cmd, gpu::RenderPush push, Rgba8 color) const {
    if (!bound_ || count_ == 0) return;
    cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, pipeline_->handle());
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, pipeline_->layout(), 0, set_->handle(), {});
    push.draw = {glm::packUnorm4x8(glm::vec4(color.r, color.g, color.b, color.a) / 255.0f), 0u, 0u, push.draw.w};
    cmd.pushConstants<gpu::RenderPush>(pipeline_->layout(), vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment, 0,
                                       push);
    for (const auto& [first, n] : ranges_) cmd.draw(KW_COLLIDER_VERTICES, n, 0, first);
}

// ---------------------------------------------------------------------------------------
// Birds

Result<BirdLayer> BirdLayer::create(const gpu::VulkanContext& ctx, vk::RenderPass pass, vk::SampleCountFlagBits samples) {
    BirdLayer layer;
    KW_TRY(with_set(ctx, layer_pipeline(ctx, pass, "birds.vert", "render.frag", sizeof(gpu::BirdDrawVertex), 2, KW_BIRDS_DRAW_BINDING_COUNT, samples),
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
    KW_TRY(store(ctx, types_, bytes_of(types)));
    return store(ctx, order_, bytes_of(order));
}

Result<void> BirdLayer::from_backend(gpu::VulkanContext& ctx, const BirdBackend& backend) {
    if (count_ == 0) return {};
    const DeviceData* data = backend.device_data();
    const DeviceSpan poses = data != nullptr ? data->buffer(DeviceBuffer::BirdPoses) : DeviceSpan{};
    if (data == nullptr || &data->context() != &ctx || poses.buffer == nullptr) {
        return make_error(Error::Kind::InvalidInput, "the " + std::string(backend.name()) +
                                                         " bird backend has no poses on the renderer's device: pass its poses");
    }
    const gpu::BufferRange ranges[KW_BIRDS_DRAW_BINDING_COUNT] = {{types_->handle()}, {order_->handle()}, {poses.buffer->handle()}};
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
    const gpu::BufferRange ranges[KW_BIRDS_DRAW_BINDING_COUNT] = {{types_->handle()}, {order_->handle()}, {host_poses_->handle()}};
    set_->bind(ctx, ranges);
    first_pose_ = 0;
    bound_ = true;
    return {};
}

void BirdLayer::record(const vk::raii::CommandBuffer& cmd, gpu::RenderPush push) const {
    if (!bound_ || count_ == 0) return;
    cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, pipeline_->handle());
    cmd.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, pipeline_->layout(), 0, set_->handle(), {});
    cmd.bindVertexBuffers(0, vertices_->handle(), vk::DeviceSize{0});
    for (std::uint32_t t = 0; t < birds::kWingTypeCount; ++t) {
        const TypeRange& r = ranges_[t];
        if (r.birds == 0 || r.vertices == 0) continue;
        push.draw = {t, first_pose_, bits(min_wingspan_px_), push.draw.w};
        cmd.pushConstants<gpu::RenderPush>(pipeline_->layout(), vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment,
                                           0, push);
        cmd.draw(r.vertices, r.birds, r.first_vertex, r.first_bird);
    }
}

}  // namespace kodawari::render
