#pragma once
// What the files of the Vulkan rod backend share (not public): vulkan_rods.cpp (a frame
// recorded and stepped, the state read back) and vulkan_rods_load.cpp (a world loaded
// into device buffers, and the kernels specialized to it): the backend's class and the
// conversions of rods values to the kernel's layout (shaders/shared/rods.h).

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <kodawari/shared/rod_keys.h>
#include <kodawari/shared/rods.h>

#include "backends/backends.hpp"
#include "vulkan_backends/device_backends.hpp"

namespace kodawari::vulkan_rods_detail {

using compute::Buffer;

inline gpu::vec4 to_gpu(glm::vec3 v, float w = 0.0f) { return {v.x, v.y, v.z, w}; }
inline gpu::vec4 to_gpu(glm::quat q) { return {q.x, q.y, q.z, q.w}; }
// The KW_RODS_FEATURE_* a collider kind needs (0: outside colliders are always compiled in).
inline std::uint32_t feature_of(rods::ColliderKind kind) {
    switch (kind) {
        case rods::ColliderKind::Inside: return KW_RODS_FEATURE_INSIDE;
        case rods::ColliderKind::Plane: return KW_RODS_FEATURE_PLANE;
        case rods::ColliderKind::Outside: break;
    }
    return 0u;
}
inline gpu::RodTransformGpu to_gpu(const rods::Transform& t) { return {to_gpu(t.position), to_gpu(t.rotation)}; }

template <typename T>
std::span<const std::byte> bytes_of(const std::vector<T>& v) {
    return std::as_bytes(std::span<const T>(v));
}

// A wind field as the kernel takes it (shared/rods.h), with rods::air_velocity's own
// reciprocals, so both sides scale the noise by the same bits.
inline gpu::RodWindGpu to_gpu(const rods::WindField& w) {
    return {to_gpu(w.velocity, w.gust), {1.0f / w.gust_period, 1.0f / w.gust_size, 0.0f, 0.0f}, {w.seed, 0u, 0u, 0u}};
}

class VulkanRodBackend final : public RodBackend, public DeviceRodBackend, public DeviceData {
public:
    VulkanRodBackend(std::shared_ptr<compute::Device> ctx, std::uint32_t workgroup, RodKernel kernel)
        : ctx_(std::move(ctx)), workgroup_(workgroup), kernel_kind_(kernel), joint_lanes_(kernel == RodKernel::PerJoint) {}

    using Variant = std::array<std::uint32_t, KW_RODS_SPEC_COUNT>;

    // The kernel of a variant, built on first use (vulkan_rods_load.cpp).
    Result<const compute::Kernel*> pipeline(const Variant& spec);

    std::string_view name() const override { return "vulkan"; }
    std::string device() const override { return ctx_->info().name; }
    double last_gpu_ms() const override { return gpu_ms_; }
    std::uint32_t validation_messages() const override { return ctx_->validation_messages(); }
    const DeviceData* device_data() const override { return world_ != nullptr ? this : nullptr; }
    const compute::Device& context() const override { return *ctx_; }
    DeviceSpan buffer(std::string_view name) const override;
    void set_input_writer(std::shared_ptr<const RodInputWriter> writer) override { input_writer_ = std::move(writer); }
    const rods::RodWorld* world() const override { return world_; }
    compute::Device& compute_device() const override { return *ctx_; }

    Result<void> load(const rods::RodWorld& world, const rods::RodFrame& initial) override;  // vulkan_rods_load.cpp
    Result<void> step(const rods::RodFrame& frame) override;
    Result<void> record_step(compute::Recording& recording, const rods::RodFrame& frame) override;
    Result<void> record_external(compute::Recording& borrowed, const rods::RodFrame& frame) override;
    Result<void> read(ChainSnapshot& out) override;
    Result<void> read_states(std::vector<rods::ChainState>& out) override;

private:
    // Chains a workgroup steps: one per invocation, or one per `lanes_` invocations.
    std::uint32_t chains_per_group() const { return joint_lanes_ ? workgroup_ / lanes_ : workgroup_; }

    // vulkan_rods_load.cpp
    Result<std::uint32_t> kernel_variant_for(const rods::RodWorld& world) const;
    Result<void> select_kernels();

    // vulkan_rods.cpp
    Result<void> record(compute::Recording& recording, const rods::RodFrame& frame, bool timed);

    // The frame's kinematic input into the input buffers.
    // `target`: the device (a submission of its own) or a recording (compute::upload).
    template <typename Target>
    Result<void> upload_input(Target& target, const rods::RodFrame& frame) {
        reference_.resize(frame.reference.size());
        std::transform(frame.reference.begin(), frame.reference.end(), reference_.begin(),
                       [](const rods::Transform& t) { return to_gpu(t); });
        roots_.resize(frame.roots.size());
        std::transform(frame.roots.begin(), frame.roots.end(), roots_.begin(), [](const rods::Transform& t) { return to_gpu(t); });
        colliders_.resize(frame.colliders.size());
        std::transform(frame.colliders.begin(), frame.colliders.end(), colliders_.begin(), [](const rods::Collider& c) {
            return gpu::RodColliderGpu{to_gpu(c.a, c.radius), to_gpu(c.b, static_cast<float>(c.kind))};  // KW_RODS_COLLIDER_* (shared_layout.cpp)
        });
        centers_.resize(frame.centers.size());
        std::transform(frame.centers.begin(), frame.centers.end(), centers_.begin(), [](const rods::Transform& t) { return to_gpu(t); });
        KW_TRY(compute::upload(target, buffers_[KW_RODS_BINDING_CENTERS], bytes_of(centers_)));
        KW_TRY(compute::upload(target, buffers_[KW_RODS_BINDING_REFERENCE], bytes_of(reference_)));
        KW_TRY(compute::upload(target, buffers_[KW_RODS_BINDING_ROOTS], bytes_of(roots_)));
        keys_.resize(frame.keys.size());
        std::transform(frame.keys.begin(), frame.keys.end(), keys_.begin(), [](const rods::Transform& t) { return to_gpu(t); });
        KW_TRY(compute::upload(target, key_buffers_[KW_ROD_KEYS_BINDING_KEYS], bytes_of(keys_)));
        winds_.resize(frame.winds.size());
        std::transform(frame.winds.begin(), frame.winds.end(), winds_.begin(), [](const rods::WindField& w) { return to_gpu(w); });
        KW_TRY(compute::upload(target, buffers_[KW_RODS_BINDING_WINDS], bytes_of(winds_)));
        return compute::upload(target, buffers_[KW_RODS_BINDING_COLLIDERS], bytes_of(colliders_));
    }

    rods::ChainShape rest_of(std::uint32_t c) const;
    Result<void> fetch();

    std::shared_ptr<compute::Device> ctx_;
    // A few variants at most (one per kind of world): a vector is the simplest map.
    // (A deque: kernel_ and the groups' kernels point into it.)
    std::deque<std::pair<Variant, compute::Kernel>> pipelines_;
    std::uint32_t workgroup_ = KW_RODS_WORKGROUP_SIZE;  // invocations per workgroup (KW_RODS_SPEC_WORKGROUP_SIZE)
    RodKernel kernel_kind_ = RodKernel::PerChain;  // BackendOptions::rod_kernel
    bool joint_lanes_ = false;  // RodKernel::PerJoint: rods_lanes.comp
    std::uint32_t lanes_ = 0;   // its invocations per chain (KW_RODS_SPEC_LANES) for the loaded world
    const compute::Kernel* kernel_ = nullptr;  // the one dispatch's when not grouped_
    const rods::RodWorld* world_ = nullptr;
    std::vector<Buffer> buffers_;
    std::shared_ptr<const RodInputWriter> input_writer_;
    std::optional<compute::StagingRing> ring_;  // record_external's input uploads
    std::vector<gpu::RodTemplateGpu> templates_;
    // Keyed examples (shared/rod_keys.h): per template its constants; the kernel and its
    // buffers (binding KW_ROD_KEYS_BINDING_WEIGHTS is buffers_[KW_RODS_BINDING_KEYED]).
    std::vector<gpu::RodKeyTemplateGpu> key_templates_;
    std::optional<compute::Kernel> key_kernel_;
    std::vector<Buffer> key_buffers_;
    std::uint32_t keyed_chains_ = 0;  // chains with keyed examples: rod_keys.comp's invocations
    // The runs of RodChainGpu that share a template, and whether each is a dispatch of its own.
    struct Group {
        std::uint32_t template_index, first, count;
        const compute::Kernel* kernel;  // its variant (grouped_)
    };
    std::vector<Group> groups_;
    bool grouped_ = false;
    std::uint32_t features_ = KW_RODS_FEATURE_ALL;  // KW_RODS_SPEC_FEATURES of the loaded world
    // What the world's kernels are specialized to besides features_ (select_kernels()).
    std::uint32_t suppression_ = KW_RODS_SUPPRESSION_PARTIAL, max_joints_ = 2, max_views_ = 0, max_keyed_ = 0;
    std::uint32_t max_colliders_ = 0;  // KW_RODS_SPEC_MAX_COLLIDERS: the most colliders of one chain
    float dt_ = -1.0f;
    bool started_ = false;  // whether a step has been recorded since load()
    double gpu_ms_ = -1.0;
    // Per-frame staging on the host, kept to avoid reallocating every frame.
    std::vector<gpu::RodTransformGpu> reference_, roots_, keys_, centers_;
    std::vector<gpu::RodColliderGpu> colliders_;
    std::vector<gpu::RodWindGpu> winds_;
    std::vector<gpu::RodJointMotionGpu> motion_;
    std::vector<gpu::RodJointSpinGpu> spin_;
    std::vector<gpu::RodChainStateGpu> chain_states_;
    std::vector<gpu::RodTransformGpu> center_states_;
};

}  // namespace kodawari::vulkan_rods_detail
