// The cpu pose backend: engine/simd/poses_simd.cpp's kernel on every core. Instances are
// grouped by clip into batches of 16 (simd/poses_simd.hpp); per evaluation each thread
// takes a contiguous range of batches, samples their channels lane by lane with the
// reference's animation::sample (and clip_time), then composes their matrices in vectors,
// writing each instance's own rows of the output.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <hwy/aligned_allocator.h>

#include "backends/pose_backends.hpp"
#include "core/parallel.hpp"
#include "simd/poses_simd.hpp"

namespace kodawari {
namespace {

using simd::kBatchLanes;

std::array<float, 16> columns(const glm::mat4& m) {
    std::array<float, 16> out{};
    for (int col = 0; col < 4; ++col) {
        for (int row = 0; row < 4; ++row) out[static_cast<std::size_t>(col * 4 + row)] = m[col][row];
    }
    return out;
}

// The plan of clip `clip` (-1: the rest pose) of `character` (poses_simd.hpp).
simd::PoseClipPlan make_plan(const animation::Character& character, const animation::Pose& rest, int clip) {
    simd::PoseClipPlan plan;
    const std::size_t n = character.nodes.size();
    plan.order = character.order;
    plan.t_channel.assign(n, -1);
    plan.r_channel.assign(n, -1);
    plan.s_channel.assign(n, -1);
    if (clip >= 0) {
        const animation::Animation& animation = character.animations[static_cast<std::size_t>(clip)];
        plan.channels = static_cast<std::uint32_t>(animation.channels.size());
        for (std::size_t c = 0; c < animation.channels.size(); ++c) {
            const animation::Channel& channel = animation.channels[c];
            const auto node = static_cast<std::size_t>(channel.node);
            auto& slot = channel.path == animation::Path::Translation ? plan.t_channel
                         : channel.path == animation::Path::Rotation  ? plan.r_channel
                                                                 : plan.s_channel;
            slot[node] = static_cast<std::int32_t>(c);  // animation::evaluate applies the channels in order
        }
    }
    plan.uniform_world.assign(n, 1);
    for (const int index : character.order) {
        const auto i = static_cast<std::size_t>(index);
        const animation::Node& node = character.nodes[i];
        plan.parent.resize(n);
        plan.parent[i] = node.parent;
        const bool animated = plan.t_channel[i] >= 0 || plan.r_channel[i] >= 0 || plan.s_channel[i] >= 0;
        const bool under_animated = node.parent >= 0 && plan.uniform_world[static_cast<std::size_t>(node.parent)] == 0;
        plan.uniform_world[i] = animated || under_animated ? 0 : 1;
    }
    for (std::size_t i = 0; i < n; ++i) {
        const animation::Node& node = character.nodes[i];
        plan.world.push_back(columns(rest.world[i]));
        // compute_world's local matrix of the rest TRS.
        const glm::mat4 local = node.matrix ? *node.matrix
                                            : glm::translate(glm::mat4(1.0f), node.translation) * glm::mat4_cast(node.rotation) *
                                                  glm::scale(glm::mat4(1.0f), node.scale);
        plan.local.push_back(columns(local));
        plan.rest_t.push_back({node.translation.x, node.translation.y, node.translation.z, 0.0f});
        plan.rest_r.push_back({node.rotation.x, node.rotation.y, node.rotation.z, node.rotation.w});
        plan.rest_s.push_back({node.scale.x, node.scale.y, node.scale.z, 0.0f});
    }
    return plan;
}

// A vector's cost on each width, relative to a lane of the scalar target: one chibi's
// clips (50 nodes; its channels sampled for the lanes of a vector, then the kernel) took
// 5.6 us a frame on avx512, 3.7 on avx2, 3.1 on sse4 and 2.2 on scalar, one thread of the
// project's 2-core Xeon (bench crowd --count 1 --threads 1 --isa X, its clip_ms). A batch
// runs on the width that costs least for its instances in use (one, scalar; 2-4, sse4;
// 5-8, avx2; more, avx512); every width gives the same bits (poses_simd.hpp).
constexpr simd::VectorCosts kPoseVectorCosts{5.6 / 2.2, 3.7 / 2.2, 3.1 / 2.2, 1.0};

class SimdPoseBackend final : public PoseBackend {
public:
    SimdPoseBackend(simd::Isa isa, unsigned threads) : isa_(std::move(isa)), threads_(threads), widths_(simd::isas_up_to(isa_)) {
        for (const simd::Isa& w : widths_) kernels_.push_back(simd::pose_kernels(w.target));
    }

    std::string_view name() const override { return "cpu"; }
    std::string device() const override {
        return std::to_string(threads_) + (threads_ == 1 ? " thread, " : " threads, ") + isa_.name;
    }

    Result<void> load(const animation::Character& character, std::span<const PoseInstance> instances) override {
        KW_TRY(check_instances(character, instances));
        character_ = &character;
        instances_.assign(instances.begin(), instances.end());
        const animation::Pose rest = animation::rest_pose(character);
        plans_.clear();
        for (int clip = -1; clip < static_cast<int>(character.animations.size()); ++clip) {
            plans_.push_back(make_plan(character, rest, clip));
        }
        // Batches: each clip's instances (plan clip + 1) in instance order, 16 at a time.
        batches_.clear();
        batch_width_.clear();
        std::vector<std::vector<std::uint32_t>> by_plan(plans_.size());
        for (std::uint32_t i = 0; i < instances_.size(); ++i) by_plan[static_cast<std::size_t>(instances_[i].clip + 1)].push_back(i);
        value_offset_.clear();
        std::size_t values = 0;
        for (std::uint32_t p = 0; p < by_plan.size(); ++p) {
            for (std::size_t first = 0; first < by_plan[p].size(); first += kBatchLanes) {
                simd::PoseBatch b;
                b.plan = p;
                b.count = static_cast<std::uint32_t>(std::min(kBatchLanes, by_plan[p].size() - first));
                for (std::size_t l = 0; l < kBatchLanes; ++l) b.instance[l] = by_plan[p][first + (l < b.count ? l : 0)];
                batches_.push_back(b);
                batch_width_.push_back(static_cast<std::uint8_t>(simd::cheapest_width(widths_, b.count, kPoseVectorCosts)));
                value_offset_.push_back(values);
                values += std::size_t{plans_[p].channels} * 4 * kBatchLanes;
            }
        }
        values_ = hwy::AllocateAligned<float>(std::max<std::size_t>(values, 1));
        placements_ = hwy::AllocateAligned<float>(std::max<std::size_t>(batches_.size() * 16 * kBatchLanes, 1));
        for (std::size_t b = 0; b < batches_.size(); ++b) {
            for (std::size_t l = 0; l < kBatchLanes; ++l) {
                const std::array<float, 16> m = columns(placement_matrix(instances_[batches_[b].instance[l]].placement));
                for (std::size_t r = 0; r < 16; ++r) placements_[(b * 16 + r) * kBatchLanes + l] = m[r];
            }
        }
        // 64-byte aligned: an instance's matrices are whole cache lines (64 bytes each), so
        // threads writing neighbouring instances never share a line.
        matrices_ = instances.size() * character.nodes.size();
        world_ = hwy::AllocateAligned<float>(std::max<std::size_t>(matrices_, 1) * 16);
        evaluated_ = false;
        return {};
    }

    Result<void> evaluate(float time) override { return evaluate_some(time, {}); }

    Result<void> evaluate_some(float time, std::span<const std::uint8_t> may_keep) override {
        assert(character_ != nullptr && "load() first");
        assert((may_keep.empty() || may_keep.size() == instances_.size()) && "one entry per instance");
        if (!std::isfinite(time)) return make_error(Error::Kind::InvalidInput, "the scene time is not finite");
        // A batch whose lanes all may keep their matrices is skipped (after a first
        // evaluation, so that every matrix has been written).
        auto keeps = [&](std::size_t b) {
            if (may_keep.empty() || !evaluated_) return false;
            const simd::PoseBatch& batch = batches_[b];
            for (std::uint32_t l = 0; l < batch.count; ++l) {
                if (may_keep[batch.instance[l]] == 0) return false;
            }
            return true;
        };
        const std::size_t nodes = character_->nodes.size();
        simd::PoseStepArgs args;
        args.plans = plans_.data();
        args.batches = batches_.data();
        args.placements = placements_.get();
        args.values = values_.get();
        args.value_offset = value_offset_.data();
        args.world = world_.get();
        args.nodes = nodes;
        parallel_for(batches_.size(), threads_, [&](std::size_t begin, std::size_t end) {
            auto scratch = hwy::AllocateAligned<float>(std::max<std::size_t>(nodes, 1) * 16 * kBatchLanes);
            simd::PoseStepArgs mine = args;
            mine.scratch = scratch.get();
            for (std::size_t b = begin; b < end; ++b) {
                if (keeps(b)) continue;
                sample(b, time);
                kernels_[batch_width_[b]].evaluate(mine, b, b + 1);
            }
        });
        evaluated_ = true;
        return {};
    }

    Result<void> read(std::vector<glm::mat4>& world) override {
        assert(character_ != nullptr && evaluated_ && "evaluate() first");
        world.resize(matrices_);
        std::memcpy(static_cast<void*>(world.data()), world_.get(), matrices_ * sizeof(glm::mat4));  // glm::mat4: 16 floats, column-major
        return {};
    }

    std::span<const glm::mat4> host_world() const override {
        assert(character_ != nullptr && evaluated_ && "evaluate() first");
        // glm::mat4 is 16 floats, column-major, as the kernel writes them (read() copies
        // the same bytes).
        static_assert(sizeof(glm::mat4) == 16 * sizeof(float) && alignof(glm::mat4) <= 64);
        return {reinterpret_cast<const glm::mat4*>(world_.get()), matrices_};
    }

private:
    // Batch b's channel values at scene time `time`, lane by lane with the reference's own
    // functions (clip_time, animation::sample), into its rows.
    void sample(std::size_t b, float time) {
        const simd::PoseBatch& batch = batches_[b];
        if (batch.plan == 0) return;  // the rest pose samples nothing
        const animation::Animation& clip = character_->animations[batch.plan - 1];
        float* rows = values_.get() + value_offset_[b];
        // The lanes its width's vectors read: its instances, and the padding up to a whole vector.
        const unsigned width = widths_[batch_width_[b]].lanes;
        const std::size_t lanes = std::min<std::size_t>(kBatchLanes, (batch.count + width - 1) / width * width);
        for (std::size_t l = 0; l < lanes; ++l) {
            const float t = clip_time(clip, instances_[batch.instance[l]], time);
            for (std::size_t c = 0; c < clip.channels.size(); ++c) {
                const animation::Channel& channel = clip.channels[c];
                const glm::vec4 v = animation::sample(clip.samplers[channel.sampler], channel.path, t);
                for (int k = 0; k < 4; ++k) rows[(c * 4 + static_cast<std::size_t>(k)) * kBatchLanes + l] = v[k];
            }
        }
    }

    simd::Isa isa_;
    unsigned threads_;
    std::vector<simd::Isa> widths_;          // isa_ and the narrower ones this machine runs (simd::isas_up_to)
    std::vector<simd::PoseKernels> kernels_;  // per width
    std::vector<std::uint8_t> batch_width_;   // per batch, its width (simd::cheapest_width of its instances)
    const animation::Character* character_ = nullptr;
    std::vector<PoseInstance> instances_;
    std::vector<simd::PoseClipPlan> plans_;  // plans_[clip + 1]
    std::vector<simd::PoseBatch> batches_;
    std::vector<std::size_t> value_offset_;
    hwy::AlignedFreeUniquePtr<float[]> values_, placements_;
    hwy::AlignedFreeUniquePtr<float[]> world_;  // instances x nodes matrices, instance-major
    std::size_t matrices_ = 0;
    bool evaluated_ = false;
};

}  // namespace

std::unique_ptr<PoseBackend> new_simd_pose_backend(simd::Isa isa, unsigned threads) {
    return std::make_unique<SimdPoseBackend>(std::move(isa), threads);
}

}  // namespace kodawari
