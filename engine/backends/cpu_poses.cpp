// The cpu-reference pose backend: instance after instance on one thread with
// animation::evaluate (engine/animation/character.cpp), the validation oracle. (The cpu backend is
// simd_poses.cpp.)
#include <cassert>
#include <cmath>
#include <string>
#include <vector>

#include "backends/pose_backends.hpp"

namespace kodawari {
namespace {

class CpuPoseBackend final : public PoseBackend {
public:
    std::string_view name() const override { return "cpu-reference"; }
    std::string device() const override { return "1 thread"; }

    Result<void> load(const animation::Character& character, std::span<const PoseInstance> instances) override {
        KW_TRY(check_instances(character, instances));
        character_ = &character;
        instances_.assign(instances.begin(), instances.end());
        placements_.resize(instances.size());
        for (std::size_t i = 0; i < instances.size(); ++i) placements_[i] = placement_matrix(instances[i].placement);
        // Every rest-pose instance shares one evaluation of the rest pose.
        rest_ = animation::rest_pose(character);
        world_.assign(instances.size() * character.nodes.size(), glm::mat4(0.0f));
        evaluated_ = false;
        return {};
    }

    Result<void> evaluate(float time) override {
        assert(character_ != nullptr && "load() first");
        if (!std::isfinite(time)) return make_error(Error::Kind::InvalidInput, "the scene time is not finite");
        evaluate_range(0, instances_.size(), time, scratch_);
        evaluated_ = true;
        return {};
    }

    Result<void> read(std::vector<glm::mat4>& world) override {
        assert(character_ != nullptr && evaluated_ && "evaluate() first");
        world = world_;
        return {};
    }

    std::span<const glm::mat4> host_world() const override {
        assert(character_ != nullptr && evaluated_ && "evaluate() first");
        return world_;
    }

private:
    // Instances [begin, end): the clip at the instance's clip time (or the rest pose),
    // then the placement.
    void evaluate_range(std::size_t begin, std::size_t end, float time, animation::Pose& scratch) {
        const animation::Character& character = *character_;
        const std::size_t nodes = character.nodes.size();
        for (std::size_t i = begin; i < end; ++i) {
            const PoseInstance& instance = instances_[i];
            const animation::Pose* pose = &rest_;
            if (instance.clip >= 0) {
                const auto clip = static_cast<std::size_t>(instance.clip);
                animation::evaluate(character, clip, clip_time(character.animations[clip], instance, time), scratch);
                pose = &scratch;
            }
            glm::mat4* out = world_.data() + i * nodes;
            for (std::size_t n = 0; n < nodes; ++n) out[n] = placements_[i] * pose->world[n];
        }
    }

    const animation::Character* character_ = nullptr;
    std::vector<PoseInstance> instances_;
    std::vector<glm::mat4> placements_;
    animation::Pose rest_;
    animation::Pose scratch_;  // reused from evaluation to evaluation
    std::vector<glm::mat4> world_;
    bool evaluated_ = false;
};

}  // namespace

std::unique_ptr<PoseBackend> new_reference_pose_backend() { return std::make_unique<CpuPoseBackend>(); }

}  // namespace kodawari
