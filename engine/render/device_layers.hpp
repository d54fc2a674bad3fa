#pragma once
// What the renderer draws from device buffers rather than from a DrawList (issue 5: the
// viewer draws the simulation where it was computed): the chains (shaders/chains.vert)
// from rod state and the birds (shaders/birds.vert) from their poses. Each layer binds
// either the vulkan backend's own buffers (same device: nothing is read back) or buffers
// of the same layout it fills from host data (the CPU backends, other devices).

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>
#include <string_view>

#include <kodawari/shared/birds.h>
#include <kodawari/shared/render.h>
#include <kodawari/shared/rods.h>

#include "compute/buffer.hpp"
#include "gpu/graphics.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/rod_backend.hpp"
#include "kodawari/scene.hpp"

namespace kodawari::render {

/// A storage buffer of at least 16 bytes (an empty world still binds one) filled with `bytes`.
[[nodiscard]] Result<compute::Buffer> storage_with(gpu::VulkanContext& ctx, std::span<const std::byte> bytes);
/// `slot` becomes a storage buffer holding `bytes` (storage_with).
[[nodiscard]] Result<void> store(gpu::VulkanContext& ctx, std::optional<compute::Buffer>& slot, std::span<const std::byte> bytes);

/// A layer's pipeline: triangle lists, depth tested, the renderer's push constants, and
/// `storage_buffers` read by the vertex shader.
[[nodiscard]] Result<gpu::GraphicsPipeline> layer_pipeline(const gpu::VulkanContext& ctx, vk::RenderPass pass,
                                                           std::string_view vertex, std::string_view fragment,
                                                           std::uint32_t vertex_stride, std::uint32_t attributes,
                                                           std::uint32_t storage_buffers, vk::SampleCountFlagBits samples,
                                                           vk::PrimitiveTopology topology = vk::PrimitiveTopology::eTriangleList);

/// The chains of a RodWorld.
class ChainLayer {
public:
    /// The pipeline for `pass` with `samples` per pixel (shared by every world drawn).
    [[nodiscard]] static Result<ChainLayer> create(const gpu::VulkanContext& ctx, vk::RenderPass pass, vk::SampleCountFlagBits samples);

    /// The chains of `world` (null: none) in `style`; static per-chain data is uploaded.
    [[nodiscard]] Result<void> set_world(gpu::VulkanContext& ctx, const rods::RodWorld* world, const ChainStyle& style);
    /// The state to draw: the vulkan backend's buffers when on `ctx`, else read and uploaded.
    [[nodiscard]] Result<void> from_backend(gpu::VulkanContext& ctx, RodBackend& backend);
    /// Joint positions (world) uploaded.
    [[nodiscard]] Result<void> from_snapshot(gpu::VulkanContext& ctx, const ChainSnapshot& snapshot);
    /// Whether the last from_*() bound the backend's own buffers.
    [[nodiscard]] bool on_device() const { return on_device_; }

    /// Records the draws (inside the render pass; `push` has the camera): the tubes, and
    /// with `joints` the joint dots.
    void record(const vk::raii::CommandBuffer& cmd, gpu::RenderPush push, float rows_scale, bool joints) const;

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
class ColliderLayer {
public:
    [[nodiscard]] static Result<ColliderLayer> create(const gpu::VulkanContext& ctx, vk::RenderPass pass, vk::SampleCountFlagBits samples);

    /// The colliders of `world` (null: none).
    void set_world(const rods::RodWorld* world);
    /// The scene whose characters with meshes (draws_skinned) are drawn by the skinned
    /// layer (null: none): their colliders are not drawn.
    void set_skinned(const RodScene* scene);
    /// This frame's colliders: the vulkan rod backend's input buffer when on `ctx` (rigged
    /// characters' colliders are written there on the device), else `input`'s uploaded.
    [[nodiscard]] Result<void> from(gpu::VulkanContext& ctx, const RodBackend& backend, const rods::RodFrame& input);

    void record(const vk::raii::CommandBuffer& cmd, gpu::RenderPush push, Rgba8 color) const;

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

/// The birds of a BirdWorld.
class BirdLayer {
public:
    [[nodiscard]] static Result<BirdLayer> create(const gpu::VulkanContext& ctx, vk::RenderPass pass, vk::SampleCountFlagBits samples);

    /// The birds of `world` (null: none): the part meshes of its wing types and the
    /// order of its birds by wing type are uploaded.
    [[nodiscard]] Result<void> set_world(gpu::VulkanContext& ctx, const birds::BirdWorld* world, float min_wingspan_px);
    /// The last simulated frame's poses where the vulkan backend keeps them, on `ctx`;
    /// an error for any other backend.
    [[nodiscard]] Result<void> from_backend(gpu::VulkanContext& ctx, const BirdBackend& backend);
    /// One pose per bird uploaded.
    [[nodiscard]] Result<void> from_poses(gpu::VulkanContext& ctx, std::span<const gpu::BirdPose> poses);

    void record(const vk::raii::CommandBuffer& cmd, gpu::RenderPush push) const;

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

}  // namespace kodawari::render
