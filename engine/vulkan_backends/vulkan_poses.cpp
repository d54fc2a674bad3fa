// The Vulkan pose backend: one dispatch of shaders/pose_eval.comp per evaluate() poses
// every instance (see shaders/shared/poses.h for the layout and why). The character and
// the instances are flattened and uploaded once by load(); evaluate() pushes only the
// scene time, and the world matrices stay on the device until read() fetches them.
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstring>
#include <optional>

#include <glm/gtc/matrix_transform.hpp>

#include <kodawari/shared/poses.h>

#include "vulkan_backends/device_backends.hpp"
#include "backends/pose_backends.hpp"

namespace kodawari {
namespace {

using compute::Buffer;

gpu::vec4 to_gpu(glm::vec3 v) { return {v.x, v.y, v.z, 0.0f}; }
gpu::vec4 to_gpu(glm::vec4 v) { return {v.x, v.y, v.z, v.w}; }
gpu::vec4 to_gpu(glm::quat q) { return {q.x, q.y, q.z, q.w}; }

template <typename T>
std::span<const std::byte> bytes_of(const std::vector<T>& v) {
    return std::as_bytes(std::span<const T>(v));
}

std::uint32_t path_of(animation::Path path) {
    switch (path) {
        case animation::Path::Translation: return KW_POSES_PATH_TRANSLATION;
        case animation::Path::Rotation: return KW_POSES_PATH_ROTATION;
        case animation::Path::Scale: return KW_POSES_PATH_SCALE;
    }
    return KW_POSES_PATH_TRANSLATION;
}

std::uint32_t interpolation_of(animation::Interpolation interpolation) {
    switch (interpolation) {
        case animation::Interpolation::Linear: return KW_POSES_INTERP_LINEAR;
        case animation::Interpolation::Step: return KW_POSES_INTERP_STEP;
        case animation::Interpolation::CubicSpline: return KW_POSES_INTERP_CUBICSPLINE;
    }
    return KW_POSES_INTERP_LINEAR;
}

// The character as the kernel reads it (shared/poses.h).
struct FlatCharacter {
    std::vector<gpu::PoseNodeGpu> nodes;
    std::vector<gpu::PoseAnchorGpu> anchors;
    std::vector<gpu::PoseClipGpu> clips;
    std::vector<gpu::PoseChannelGpu> channels;
    std::vector<float> times;
    std::vector<gpu::vec4> values;
    bool affine = true;  // every relative and link has the bottom row (0, 0, 0, 1)
};

void set_columns(gpu::vec4 (&out)[4], const glm::mat4& m) {
    for (int c = 0; c < 4; ++c) out[c] = to_gpu(m[c]);
}

// The kernel's first guess of a key index: keys per second over the sampler's span, as
// float bits (PoseChannelGpu::keys.z); only a guess, so its rounding does not matter.
std::uint32_t per_second(const animation::Sampler& sampler) {
    const std::size_t n = sampler.times.size();
    const float span = n >= 2 ? sampler.times.back() - sampler.times.front() : 0.0f;
    const float rate = span > 0.0f ? static_cast<float>(n - 1) / span : 0.0f;
    std::uint32_t bits = 0;
    std::memcpy(&bits, &rate, sizeof bits);
    return bits;
}

bool bottom_row_is_0001(const glm::mat4& m) { return m[0][3] == 0.0f && m[1][3] == 0.0f && m[2][3] == 0.0f && m[3][3] == 1.0f; }

FlatCharacter flatten(const animation::Character& character) {
    FlatCharacter flat;
    const std::size_t n = character.nodes.size();
    assert(character.order.size() == n && "Character::order lists every node");
    // The anchors: every node that some clip animates. A node with a matrix keeps it
    // whatever its channels say (compute_world; the importer rejects such channels,
    // §3.5.3, a Character built in code may still have them), so it is no anchor and its
    // channels are dropped below.
    std::vector<bool> animated(n, false);
    for (const animation::Animation& clip : character.animations) {
        for (const animation::Channel& channel : clip.channels) {
            const auto i = static_cast<std::size_t>(channel.node);
            animated[i] = !character.nodes[i].matrix;
        }
    }
    // Parents first: each node's slot (its anchor's) and its rest transform relative to
    // that anchor, multiplied in compute_world's order below the anchor, so that a node
    // with no animated ancestor gets compute_world's rest world matrix bit for bit.
    std::vector<std::uint32_t> slot(n, 0u);
    std::vector<glm::mat4> relative(n, glm::mat4(1.0f));
    std::vector<std::uint32_t> anchor_of_slot;  // node index of anchor slot - 1
    std::vector<bool> walked(n, false);
    for (const int index : character.order) {
        const auto i = static_cast<std::size_t>(index);
        const animation::Node& node = character.nodes[i];
        const bool has_parent = node.parent >= 0;
        const auto parent = static_cast<std::size_t>(has_parent ? node.parent : 0);
        assert((!has_parent || walked[parent]) && "parents first");
        walked[i] = true;
        if (animated[i]) {
            gpu::PoseAnchorGpu a{};
            a.ids = {has_parent ? slot[parent] : 0u, 0u, 0u, 0u};
            a.rest[0] = to_gpu(node.translation);
            a.rest[1] = to_gpu(node.rotation);
            a.rest[2] = to_gpu(node.scale);
            set_columns(a.link, has_parent ? relative[parent] : glm::mat4(1.0f));
            flat.affine = flat.affine && (!has_parent || bottom_row_is_0001(relative[parent]));
            flat.anchors.push_back(a);
            anchor_of_slot.push_back(static_cast<std::uint32_t>(i));
            slot[i] = static_cast<std::uint32_t>(flat.anchors.size());
            relative[i] = glm::mat4(1.0f);
            continue;
        }
        // compute_world's local matrix of the rest TRS.
        const glm::mat4 local = node.matrix ? *node.matrix
                                            : glm::translate(glm::mat4(1.0f), node.translation) * glm::mat4_cast(node.rotation) *
                                                  glm::scale(glm::mat4(1.0f), node.scale);
        slot[i] = has_parent ? slot[parent] : 0u;
        relative[i] = has_parent ? relative[parent] * local : local;
    }
    flat.nodes.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        flat.nodes[i].ids = {slot[i], 0u, 0u, 0u};
        flat.affine = flat.affine && bottom_row_is_0001(relative[i]);
        set_columns(flat.nodes[i].relative, relative[i]);
    }
    for (const animation::Animation& clip : character.animations) {
        // Each sampler's keys once, however many channels use it.
        std::vector<std::array<std::uint32_t, 2>> keys(clip.samplers.size());
        for (std::size_t s = 0; s < clip.samplers.size(); ++s) {
            const animation::Sampler& sampler = clip.samplers[s];
            keys[s] = {static_cast<std::uint32_t>(flat.times.size()), static_cast<std::uint32_t>(flat.values.size())};
            flat.times.insert(flat.times.end(), sampler.times.begin(), sampler.times.end());
            for (const glm::vec4& v : sampler.values) flat.values.push_back(to_gpu(v));
        }
        // Channels in the kernel's walk order of the anchors; stable, so that of two
        // channels of one property the file's later one is applied last and wins, as in
        // animation::evaluate.
        const auto anchor = [&](const animation::Channel& channel) { return slot[static_cast<std::size_t>(channel.node)] - 1u; };
        std::vector<std::size_t> sorted;
        for (std::size_t c = 0; c < clip.channels.size(); ++c) {
            if (animated[static_cast<std::size_t>(clip.channels[c].node)]) sorted.push_back(c);
        }
        std::stable_sort(sorted.begin(), sorted.end(),
                         [&](std::size_t a, std::size_t b) { return anchor(clip.channels[a]) < anchor(clip.channels[b]); });
        gpu::PoseClipGpu g{};
        g.channels = {static_cast<std::uint32_t>(flat.channels.size()), static_cast<std::uint32_t>(sorted.size()), 0u, 0u};
        g.range = {clip.start, clip.end, 0.0f, 0.0f};
        flat.clips.push_back(g);
        for (const std::size_t c : sorted) {
            const animation::Channel& channel = clip.channels[c];
            const animation::Sampler& sampler = clip.samplers[channel.sampler];
            flat.channels.push_back({{anchor(channel), path_of(channel.path), interpolation_of(sampler.interpolation),
                                      static_cast<std::uint32_t>(sampler.times.size())},
                                     {keys[channel.sampler][0], keys[channel.sampler][1], per_second(sampler), 0u}});
        }
    }
    return flat;
}

class VulkanPoseBackend final : public PoseBackend, public DevicePoseBackend, public DeviceData {
public:
    VulkanPoseBackend(std::shared_ptr<compute::Device> ctx, std::uint32_t workgroup) : ctx_(std::move(ctx)), workgroup_(workgroup) {}

    std::string_view name() const override { return "vulkan"; }
    std::string device() const override { return ctx_->info().name; }
    double last_gpu_ms() const override { return gpu_ms_; }
    std::uint32_t validation_messages() const override { return ctx_->validation_messages(); }

    Result<void> load(const animation::Character& character, std::span<const PoseInstance> instances) override {
        KW_TRY(check_instances(character, instances));
        const std::uint64_t count = instances.size();
        if (compute::groups_for(count, workgroup_) > ctx_->info().max_workgroup_count[0]) {
            return make_error(Error::Kind::Unsupported, std::to_string(count) + " instances exceed what one dispatch on " +
                                                            ctx_->info().name + " can cover");
        }
        character_ = nullptr;
        evaluated_ = false;
        const FlatCharacter flat = flatten(character);
        std::vector<gpu::PoseInstanceGpu> per_instance(instances.size());
        for (std::size_t i = 0; i < instances.size(); ++i) {
            const PoseInstance& instance = instances[i];
            const glm::mat4 placement = placement_matrix(instance.placement);
            gpu::PoseInstanceGpu& g = per_instance[i];
            for (int c = 0; c < 4; ++c) g.placement[c] = to_gpu(placement[c]);
            g.timing = {instance.time_offset, 0.0f, 0.0f, 0.0f};
            g.clip = {instance.clip >= 0 ? static_cast<std::uint32_t>(instance.clip) : KW_POSES_NONE, instance.loop ? 1u : 0u,
                      0u, 0u};
        }

        buffers_.clear();
        const std::size_t first_nodes = std::min<std::size_t>(flat.nodes.size(), KW_POSES_UNIFORM_NODES);
        const std::uint64_t sizes[KW_POSES_BINDING_COUNT] = {
            KW_POSES_UNIFORM_NODES * sizeof(gpu::PoseNodeGpu),
            flat.clips.size() * sizeof(gpu::PoseClipGpu),
            flat.channels.size() * sizeof(gpu::PoseChannelGpu),
            flat.times.size() * sizeof(float),
            flat.values.size() * sizeof(gpu::vec4),
            per_instance.size() * sizeof(gpu::PoseInstanceGpu),
            count * character.nodes.size() * sizeof(gpu::PoseMatrixGpu),
            flat.anchors.size() * sizeof(gpu::PoseAnchorGpu),
            (flat.nodes.size() - first_nodes) * sizeof(gpu::PoseNodeGpu)};
        auto storage = compute::create_storage_buffers(*ctx_, sizes, "the crowd");
        if (!storage) return storage.error();
        buffers_ = std::move(storage).value();
        // The uniform block is KW_POSES_UNIFORM_NODES records whatever the character.
        std::vector<gpu::PoseNodeGpu> uniform_nodes(KW_POSES_UNIFORM_NODES);
        std::copy_n(flat.nodes.begin(), first_nodes, uniform_nodes.begin());
        const std::vector<gpu::PoseNodeGpu> more_nodes(flat.nodes.begin() + static_cast<std::ptrdiff_t>(first_nodes), flat.nodes.end());
        KW_TRY(compute::upload(*ctx_, buffers_[KW_POSES_BINDING_NODES], bytes_of(uniform_nodes)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_POSES_BINDING_MORE_NODES], bytes_of(more_nodes)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_POSES_BINDING_CLIPS], bytes_of(flat.clips)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_POSES_BINDING_CHANNELS], bytes_of(flat.channels)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_POSES_BINDING_TIMES], bytes_of(flat.times)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_POSES_BINDING_VALUES], bytes_of(flat.values)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_POSES_BINDING_INSTANCES], bytes_of(per_instance)));
        KW_TRY(compute::upload(*ctx_, buffers_[KW_POSES_BINDING_ANCHORS], bytes_of(flat.anchors)));

        // The bottom row of every output matrix, written once (KW_POSES_SPEC_AFFINE).
        const bool affine = flat.affine;
        if (affine) {
            gpu::PoseMatrixGpu m{};
            m.columns[3].w = 1.0f;
            const std::vector<gpu::PoseMatrixGpu> rows(count * character.nodes.size(), m);
            KW_TRY(compute::upload(*ctx_, buffers_[KW_POSES_BINDING_WORLD], bytes_of(rows)));
        }
        // The specialization constants: a new pipeline (compiled at its first dispatch)
        // only for a character with another number of anchors or bottom row.
        const std::uint32_t slots = static_cast<std::uint32_t>(flat.anchors.size()) + 1u;
        if (!kernel_ || slots != slots_ || affine != affine_) {
            kernel_.reset();
            std::vector<compute::Binding> types(KW_POSES_BINDING_COUNT, compute::Binding::Storage);
            types[KW_POSES_BINDING_NODES] = compute::Binding::Uniform;
            const std::uint32_t specialization[KW_POSES_SPEC_COUNT] = {slots, affine ? 1u : 0u, workgroup_};
            auto created = compute::Kernel::create(*ctx_, "pose_eval", types, sizeof(gpu::PosePush), specialization);
            if (!created) return created.error();
            kernel_.emplace(std::move(created).value());
            slots_ = slots;
            affine_ = affine;
        }
        std::vector<const Buffer*> bound;
        for (const auto& b : buffers_) bound.push_back(&b);
        kernel_->bind(bound);
        character_ = &character;
        count_ = static_cast<std::uint32_t>(count);
        return {};
    }

    Result<void> record_external(compute::Recording& recording, float time) override {
        if (character_ == nullptr) return make_error(Error::Kind::InvalidInput, "record_evaluate: the backend has no character; load() one first");
        if (!std::isfinite(time)) return make_error(Error::Kind::InvalidInput, "record_evaluate: time is not finite");
        evaluated_ = true;
        if (count_ == 0) return {};
        compute::barrier(recording, embedding_consumers(*ctx_), compute::Stage::Compute);
        kernel_->dispatch(recording, push_bytes(time), groups());
        compute::barrier(recording, compute::Stage::Compute, embedding_consumers(*ctx_));
        return {};
    }

    Result<void> evaluate(float time) override {
        assert(character_ != nullptr && "load() first");
        if (!std::isfinite(time)) return make_error(Error::Kind::InvalidInput, "the scene time is not finite");
        evaluated_ = true;
        if (count_ == 0) return {};
        const compute::Queue queue(*ctx_);
        auto recording = queue.begin();
        if (!recording) return recording.error();
        compute::Recording& rec = recording.value();
        // The previous evaluate's matrices were read (by a copy or kernels of earlier
        // submissions) before this dispatch overwrites them.
        compute::barrier(rec, compute::Stage::Compute | compute::Stage::Transfer, compute::Stage::Compute);
        rec.timestamp(compute::Timestamp::Begin);
        kernel_->dispatch(rec, push_bytes(time), groups());
        rec.timestamp(compute::Timestamp::End);
        compute::barrier(rec, compute::Stage::Compute, compute::Stage::Host | compute::Stage::Transfer);
        auto submission = queue.submit(std::move(recording).value());
        if (!submission) return submission.error();
        double ms = -1.0;
        KW_TRY(submission.value().wait(&ms));
        gpu_ms_ = ms;
        return {};
    }

    const DeviceData* device_data() const override { return evaluated_ ? this : nullptr; }
    const compute::Device& context() const override { return *ctx_; }
    compute::Device& compute_device() const override { return *ctx_; }
    DeviceSpan buffer(std::string_view name) const override {
        if (name != pose_buffers::world || !evaluated_) return {};
        return {.buffer = &buffers_[KW_POSES_BINDING_WORLD],
                .first = 0,
                .items = count_,
                .per_item = static_cast<std::uint32_t>(character_->nodes.size()),
                .element_bytes = sizeof(gpu::PoseMatrixGpu)};
    }

    Result<void> read(std::vector<glm::mat4>& world) override {
        assert(character_ != nullptr && evaluated_ && "evaluate() first");
        static_assert(sizeof(glm::mat4) == sizeof(gpu::PoseMatrixGpu), "four column vec4s on both sides");
        world.resize(std::size_t{count_} * character_->nodes.size());
        return compute::download(*ctx_, buffers_[KW_POSES_BINDING_WORLD], std::as_writable_bytes(std::span(world)));
    }

private:
    std::span<const std::byte> push_bytes(float time) {
        push_ = {{time, 0.0f, 0.0f, 0.0f}, {count_, static_cast<std::uint32_t>(character_->nodes.size()), slots_ - 1u, 0u}};
        return std::as_bytes(std::span(&push_, 1));
    }
    std::uint32_t groups() const { return compute::groups_for(count_, workgroup_); }

    std::shared_ptr<compute::Device> ctx_;
    std::uint32_t workgroup_ = KW_POSES_WORKGROUP_SIZE;  // invocations per workgroup (KW_POSES_SPEC_WORKGROUP_SIZE)
    gpu::PosePush push_{};
    std::optional<compute::Kernel> kernel_;
    std::uint32_t slots_ = 0;  // the kernel's KW_POSES_SPEC_SLOTS
    bool affine_ = false;      // and KW_POSES_SPEC_AFFINE
    std::vector<Buffer> buffers_;
    const animation::Character* character_ = nullptr;
    std::uint32_t count_ = 0;
    bool evaluated_ = false;
    double gpu_ms_ = -1.0;
};

}  // namespace

Result<std::unique_ptr<PoseBackend>> make_vulkan_pose_backend(const BackendOptions& options) {
    auto ctx = backend_context(options);
    if (!ctx) return ctx.error();
    auto workgroup = compute::workgroup_size(*ctx.value(), options.workgroup_size, KW_POSES_WORKGROUP_SIZE);
    if (!workgroup) return workgroup.error();
    return std::unique_ptr<PoseBackend>(std::make_unique<VulkanPoseBackend>(std::move(ctx).value(), workgroup.value()));
}

}  // namespace kodawari
