#include "domains/skinned_layer.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cstring>
#include <string>

#include <kodawari/shared/skin.h>

#include "gpu/compute_vulkan.hpp"
#include "kodawari/domains/scene_draw.hpp"

namespace kodawari {

namespace {

using render::bytes_of;

gpu::vec4 v4(const glm::vec4& v) { return {v.x, v.y, v.z, v.w}; }

gpu::PoseMatrixGpu packed(const glm::mat4& m) { return {{v4(m[0]), v4(m[1]), v4(m[2]), v4(m[3])}}; }

}  // namespace

Result<SkinnedLayer> SkinnedLayer::create(const render::LayerTarget& target) {
    SkinnedLayer layer;
    auto pipeline = render::layer_pipeline(target, "skinned.vert", "skinned.frag", sizeof(gpu::SkinnedVertexGpu), 4, KW_SKINNED_BINDING_COUNT);
    if (!pipeline) return pipeline.error();
    layer.pipeline_.emplace(std::move(pipeline).value());
    return layer;
}

Result<void> SkinnedLayer::set_scene(gpu::VulkanContext& ctx, const RodScene* scene) {
    scene_ = scene;
    characters_.clear();
    on_device_ = false;
    if (scene == nullptr) return {};
    for (std::uint32_t k = 0; k < scene->characters.size(); ++k) {
        const CharacterKinematics& kin = scene->characters[k];
        if (!kin.rig || !draws_skinned(*kin.rig)) continue;
        Character ch;
        ch.character = k;
        for (std::uint32_t c = 0; c < scene->instances.size(); ++c) {
            if (scene->instances[c].character == k) ch.instances.push_back(c);
        }
        if (ch.instances.empty()) continue;
        const animation::Character& rig = *kin.rig;
        ch.nodes = static_cast<std::uint32_t>(rig.nodes.size());
        ch.chains = static_cast<std::uint32_t>(kin.chains.size());

        // The node walk: rigged_world's, parents first, each node told how it is composed.
        std::vector<gpu::SkinNodeGpu> walk;
        std::vector<std::uint32_t> kind(rig.nodes.size(), KW_SKIN_NODE_CLIP);
        const CharacterInstance& first = scene->instances[ch.instances[0]];
        for (const int n : rig.order) {
            const auto node = static_cast<std::size_t>(n);
            const int parent = rig.nodes[node].parent;
            const auto [chain, joint] = kin.simulated_joint[node];
            gpu::SkinNodeGpu entry{};
            entry.ids = {static_cast<std::uint32_t>(n), parent >= 0 ? static_cast<std::uint32_t>(parent) : KW_SKIN_NONE, 0u, 0u};
            if (chain >= 0) {
                // Every instance of the template has the same chain templates.
                const rods::ChainInstance& ci = scene->world.chains[first.chain_begin + static_cast<std::size_t>(chain)];
                const rods::Chain& rod = scene->world.templ(ci).chain;
                const glm::vec3 axis = rod.bone_axis[static_cast<std::size_t>(joint)];
                kind[node] = KW_SKIN_NODE_SIMULATED;
                entry.ids.w = static_cast<std::uint32_t>(chain);
                entry.joint = {static_cast<std::uint32_t>(joint), rod.joint_count, 0u, 0u};
                entry.axis = {axis.x, axis.y, axis.z, 0.0f};
            } else if (parent >= 0 && kind[static_cast<std::size_t>(parent)] != KW_SKIN_NODE_CLIP) {
                kind[node] = KW_SKIN_NODE_BELOW;
            }
            entry.ids.z = kind[node];
            walk.push_back(entry);
        }
        // Where each instance's chains are in the rod backend's buffers.
        std::vector<gpu::SkinChainGpu> chains;
        for (const std::uint32_t c : ch.instances) {
            for (std::uint32_t i = 0; i < ch.chains; ++i) {
                const std::uint32_t chain = scene->instances[c].chain_begin + i;
                chains.push_back({{chain, scene->world.chains[chain].joint_begin, 0u, 0u}});
            }
        }
        // Every skin's joints in one table (JOINTS_0 entry j of skin s is entry first[s] + j).
        std::vector<gpu::SkinJointGpu> joints;
        std::vector<std::uint32_t> skin_first;
        for (const animation::Skin& skin : rig.skins) {
            skin_first.push_back(static_cast<std::uint32_t>(joints.size()));
            for (std::size_t j = 0; j < skin.joints.size(); ++j) {
                const glm::mat4& m = skin.inverse_bind_matrices[j];
                joints.push_back({{static_cast<std::uint32_t>(skin.joints[j]), 0u, 0u, 0u}, {v4(m[0]), v4(m[1]), v4(m[2]), v4(m[3])}});
            }
        }
        // The triangles of every mesh node in one indexed list (a vertex is skinned once
        // however many faces share it: the fragment shader finds each face's normal
        // itself). Weights the CPU path would skip (not positive, or a joint the skin
        // does not have) are 0, so the shader skips them too.
        std::vector<gpu::SkinnedVertexGpu> vertices;
        std::vector<std::uint32_t> indices;
        for (std::size_t n = 0; n < rig.nodes.size(); ++n) {
            const animation::Node& node = rig.nodes[n];
            if (node.mesh < 0) continue;
            const animation::Skin* skin = node.skin >= 0 ? &rig.skins[static_cast<std::size_t>(node.skin)] : nullptr;
            for (const animation::Mesh::Triangles& t : rig.meshes[static_cast<std::size_t>(node.mesh)].triangles) {
                const auto base = static_cast<std::uint32_t>(vertices.size());
                for (std::size_t v = 0; v < t.positions.size(); ++v) {
                    const glm::vec3& p = t.positions[v];
                    gpu::SkinnedVertexGpu out{{p.x, p.y, p.z, static_cast<float>(n)}, {}, {}, {t.color.r, t.color.g, t.color.b, 1.0f}};
                    if (skin != nullptr && !t.joints.empty()) {
                        std::array<float, 4> joint_out{}, weight_out{};
                        for (int k2 = 0; k2 < 4; ++k2) {
                            const std::uint32_t j = t.joints[v][k2];
                            const float w = t.weights[v][k2];
                            if (!(w > 0.0f) || j >= skin->joints.size()) continue;
                            joint_out[static_cast<std::size_t>(k2)] = static_cast<float>(skin_first[static_cast<std::size_t>(node.skin)] + j);
                            weight_out[static_cast<std::size_t>(k2)] = w;
                        }
                        out.joints = {joint_out[0], joint_out[1], joint_out[2], joint_out[3]};
                        out.weights = {weight_out[0], weight_out[1], weight_out[2], weight_out[3]};
                    }
                    vertices.push_back(out);
                }
                for (std::size_t i = 0; i + 2 < t.indices.size(); i += 3) {
                    for (std::size_t corner = 0; corner < 3; ++corner) indices.push_back(base + t.indices[i + corner]);
                }
            }
        }
        ch.indices = static_cast<std::uint32_t>(indices.size());

        KW_TRY(render::store(ctx, ch.walk, bytes_of(walk)));
        KW_TRY(render::store(ctx, ch.instance_chains, bytes_of(chains)));
        KW_TRY(render::store(ctx, ch.joints, bytes_of(joints)));
        // One storage buffer of every instance's node matrices (range-checked).
        const std::uint64_t world_bytes[] = {std::uint64_t{ch.nodes} * ch.instances.size() * sizeof(gpu::PoseMatrixGpu)};
        auto world = compute::create_storage_buffers(ctx, world_bytes, "the skinned meshes of " + rig.source);
        if (!world) return world.error();
        ch.world.emplace(std::move(world.value()[0]));
        auto vertex_buffer = compute::Buffer::create(
            ctx, std::max<std::uint64_t>(vertices.size() * sizeof(gpu::SkinnedVertexGpu), 16), compute::Usage::Vertex);
        if (!vertex_buffer) return vertex_buffer.error();
        ch.vertex_buffer.emplace(std::move(vertex_buffer).value());
        if (!vertices.empty()) std::memcpy(ch.vertex_buffer->mapped(), vertices.data(), vertices.size() * sizeof(gpu::SkinnedVertexGpu));
        auto index_buffer =
            compute::Buffer::create(ctx, std::max<std::uint64_t>(indices.size() * sizeof(std::uint32_t), 16), compute::Usage::Vertex);
        if (!index_buffer) return index_buffer.error();
        ch.index_buffer.emplace(std::move(index_buffer).value());
        if (!indices.empty()) std::memcpy(ch.index_buffer->mapped(), indices.data(), indices.size() * sizeof(std::uint32_t));
        auto set = gpu::BufferSet::create(ctx, *pipeline_);
        if (!set) return set.error();
        ch.set.emplace(std::move(set).value());
        const gpu::BufferRange ranges[KW_SKINNED_BINDING_COUNT] = {{gpu::vk_buffer(*ch.joints)}, {gpu::vk_buffer(*ch.world)}};
        ch.set->bind(ctx, ranges);
        characters_.push_back(std::move(ch));
    }
    return {};
}

Result<void> SkinnedLayer::from_backends(gpu::VulkanContext& ctx, const CrowdAnimator& animator, RodBackend& rods,
                                         std::uint32_t frame) {
    assert(scene_ != nullptr && "set_scene() first");
    if (characters_.empty()) return {};
    const DeviceData* state = rods.device_data();
    bool device = state != nullptr && &state->context() == &ctx;
    const std::vector<CrowdAnimator::PosedCharacter> posed = animator.posed_characters();
    std::vector<DeviceSpan> worlds;
    for (const Character& ch : characters_) {
        const auto it = std::find_if(posed.begin(), posed.end(), [&](const auto& p) { return p.character == ch.character; });
        if (it == posed.end() || !std::ranges::equal(it->instances, ch.instances)) {
            return make_error(Error::Kind::InvalidInput, "the crowd animator does not pose the instances of character template " +
                                                             scene_->characters[ch.character].name +
                                                             " the renderer draws: make it from the scene given to show_skinned()");
        }
        const DeviceData* poses = it->backend->device_data();
        const DeviceSpan world = poses != nullptr ? poses->buffer(pose_buffers::world) : DeviceSpan{};
        device = device && world.buffer != nullptr && &poses->context() == &ctx && world.items == ch.instances.size() &&
                 world.per_item == ch.nodes;
        worlds.push_back(world);
    }
    if (!device) {
        KW_TRY(rods.read(scratch_));
        return from_snapshot(ctx, scratch_, frame);
    }
    for (std::size_t k = 0; k < characters_.size(); ++k) {
        Character& ch = characters_[k];
        if (!ch.kernel) {
            const std::vector<compute::Binding> types(KW_SKIN_BINDING_COUNT, compute::Binding::Storage);
            auto kernel = compute::Kernel::create(ctx, "skin_nodes", types, sizeof(gpu::SkinPush));
            if (!kernel) return kernel.error();
            ch.kernel.emplace(std::move(kernel).value());
        }
        // Bound every frame: a backend may replace its buffers (load()).
        const compute::BufferView buffers[KW_SKIN_BINDING_COUNT] = {{&*ch.walk},
                                                                    {&*ch.instance_chains},
                                                                    {worlds[k].buffer},
                                                                    {state->buffer(rod_buffers::chain_states).buffer},
                                                                    {state->buffer(rod_buffers::motion).buffer},
                                                                    {state->buffer(rod_buffers::spin).buffer},
                                                                    {&*ch.world}};
        ch.kernel->bind(buffers);
        ch.filled = ch.dispatch = true;
    }
    on_device_ = true;
    return {};
}

Result<void> SkinnedLayer::from_snapshot(gpu::VulkanContext& ctx, const ChainSnapshot& snapshot, std::uint32_t frame) {
    assert(scene_ != nullptr && "set_scene() first");
    const std::size_t joints = scene_->world.joint_count;
    if (snapshot.positions.size() != joints || snapshot.orientations.size() != joints) {
        return make_error(Error::Kind::InvalidInput, "the snapshot has " + std::to_string(snapshot.positions.size()) + " positions and " +
                                                         std::to_string(snapshot.orientations.size()) + " orientations; the world has " +
                                                         std::to_string(joints) + " joints");
    }
    for (Character& ch : characters_) {
        packed_.resize(std::size_t{ch.nodes} * ch.instances.size());
        for (std::size_t i = 0; i < ch.instances.size(); ++i) {
            scene_->rigged_world(ch.instances[i], frame, snapshot.positions, snapshot.orientations, pose_, matrices_);
            for (std::size_t n = 0; n < ch.nodes; ++n) packed_[i * ch.nodes + n] = packed(matrices_[n]);
        }
        KW_TRY(compute::upload(ctx, *ch.world, bytes_of(packed_)));
        ch.filled = true;
        ch.dispatch = false;
    }
    on_device_ = false;
    return {};
}

void SkinnedLayer::record_compute(const vk::raii::CommandBuffer& cmd) const {
    const bool any = std::any_of(characters_.begin(), characters_.end(), [](const Character& ch) { return ch.dispatch; });
    if (!any) return;
    using Stage = vk::PipelineStageFlagBits;
    using Access = vk::AccessFlagBits;
    // The pose and rod kernels' state (earlier submissions) before this kernel reads it;
    // the last frame's vertex shader reads of the matrices before it overwrites them.
    const vk::MemoryBarrier inputs{.srcAccessMask = Access::eShaderWrite | Access::eTransferWrite | Access::eHostWrite,
                                   .dstAccessMask = Access::eShaderRead | Access::eShaderWrite};
    cmd.pipelineBarrier(Stage::eComputeShader | Stage::eTransfer | Stage::eHost | Stage::eVertexShader, Stage::eComputeShader, {},
                        inputs, {}, {});
    for (const Character& ch : characters_) {
        if (!ch.dispatch) continue;
        const auto instances = static_cast<std::uint32_t>(ch.instances.size());
        const gpu::SkinPush push{{instances, ch.nodes, ch.chains, 0u}};
        gpu::dispatch(*ch.kernel, cmd, std::as_bytes(std::span(&push, 1)), (instances + KW_SKIN_WORKGROUP_SIZE - 1) / KW_SKIN_WORKGROUP_SIZE);
    }
}

void SkinnedLayer::record(const vk::raii::CommandBuffer& cmd, const render::LayerFrame& frame) const {
    gpu::RenderPush push = frame.push;
    bool bound = false;
    for (const Character& ch : characters_) {
        if (!ch.filled || ch.indices == 0) continue;
        if (!bound) {
            cmd.bindPipeline(vk::PipelineBindPoint::eGraphics, pipeline_->handle());
            bound = true;
        }
        cmd.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, pipeline_->layout(), 0, ch.set->handle(), {});
        cmd.bindVertexBuffers(0, gpu::vk_buffer(*ch.vertex_buffer), vk::DeviceSize{0});
        cmd.bindIndexBuffer(gpu::vk_buffer(*ch.index_buffer), 0, vk::IndexType::eUint32);
        push.draw = {ch.nodes, 0u, 0u, push.draw.w};
        cmd.pushConstants<gpu::RenderPush>(pipeline_->layout(), vk::ShaderStageFlagBits::eVertex | vk::ShaderStageFlagBits::eFragment, 0,
                                           push);
        cmd.drawIndexed(ch.indices, static_cast<std::uint32_t>(ch.instances.size()), 0, 0, 0);
    }
}

}  // namespace kodawari
