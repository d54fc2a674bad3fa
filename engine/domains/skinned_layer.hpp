#pragma once
// The chain domain's skinned-mesh layer (a render::Layer, kodawari/domains/chain_draw.hpp): rigged characters drawn as their glTF meshes,
// skinned in a vertex shader (shaders/skinned.vert) with node world matrices that live in
// a buffer of the layer. Those are composed on the device by shaders/skin_nodes.comp from
// the pose and rod backends' buffers when both are on the renderer's device (nothing
// read back), or on the CPU by RodScene::rigged_world() from a snapshot and uploaded in
// the same layout; one vertex shader draws both.

#include <cstdint>
#include <optional>
#include <vector>

#include <kodawari/shared/poses.h>
#include <kodawari/shared/render.h>

#include "gpu/compute_vulkan.hpp"
#include "gpu/graphics.hpp"
#include "kodawari/vulkan/crowd_animator.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/scene/scene.hpp"
#include "render/layer.hpp"

namespace kodawari {

class SkinnedLayer final : public render::Layer {
public:
    [[nodiscard]] static Result<SkinnedLayer> create(const render::LayerTarget& target);

    /// The rigged characters of `scene` that have meshes (null: none): per character
    /// template its expanded triangles, skin joints, node walk and instances' chains are
    /// uploaded once.
    [[nodiscard]] Result<void> set_scene(gpu::VulkanContext& ctx, const RodScene* scene);
    /// Frame `frame`'s matrices: composed on the device when the animator's pose backends
    /// and `rods` keep their buffers on `ctx`, else from `rods`' snapshot on the CPU.
    [[nodiscard]] Result<void> from_backends(gpu::VulkanContext& ctx, const CrowdAnimator& animator, RodBackend& rods,
                                             std::uint32_t frame);
    /// Frame `frame`'s matrices by RodScene::rigged_world() from `snapshot`, uploaded.
    [[nodiscard]] Result<void> from_snapshot(gpu::VulkanContext& ctx, const ChainSnapshot& snapshot, std::uint32_t frame);
    /// Whether the last from_*() composed the matrices on the device.
    [[nodiscard]] bool on_device() const { return on_device_; }

    [[nodiscard]] Result<void> clear(gpu::VulkanContext& ctx) override { return set_scene(ctx, nullptr); }
    /// The kernels that compose the matrices (outside the render pass; the renderer's
    /// barrier to the vertex shaders follows).
    void record_compute(const vk::raii::CommandBuffer& cmd) const override;
    void record(const vk::raii::CommandBuffer& cmd, const render::LayerFrame& frame) const override;

private:
    SkinnedLayer() = default;
    // A rigged character template with a mesh and instances.
    struct Character {
        std::uint32_t character = 0;           // RodScene::characters index
        std::vector<std::uint32_t> instances;  // RodScene::instances indices, ascending (CrowdAnimator's order)
        std::uint32_t nodes = 0, chains = 0, indices = 0;
        std::optional<compute::Buffer> vertex_buffer, index_buffer, joints, walk, instance_chains, world;
        std::optional<gpu::BufferSet> set;
        std::optional<compute::Kernel> kernel;  // made on the first device frame
        bool filled = false;                         // world holds a frame's matrices
        bool dispatch = false;                       // the kernel composes them each frame drawn
    };
    std::optional<gpu::GraphicsPipeline> pipeline_;
    const RodScene* scene_ = nullptr;
    std::vector<Character> characters_;
    std::vector<gpu::PoseMatrixGpu> packed_;
    animation::Pose pose_;
    std::vector<glm::mat4> matrices_;
    ChainSnapshot scratch_;
    bool on_device_ = false;
};

}  // namespace kodawari
