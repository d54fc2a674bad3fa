// Part payloads (frame_payload.hpp): the order of the arrays is the order of the fields.
#include "simulation/frame_payload.hpp"

#include <cassert>
#include <cstring>
#include <string>

#include "kodawari/rods/world.hpp"

namespace kodawari::detail {

namespace {

constexpr std::size_t kWeights = rods::kMaxViewExamples + 1;  // per chain, ChainSnapshot::weights

template <class T>
void append(std::vector<std::byte>& out, std::span<const T> values) {
    const std::size_t at = out.size();
    out.resize(at + values.size_bytes());
    if (!values.empty()) std::memcpy(out.data() + at, values.data(), values.size_bytes());
}

// Reads `count` T from `in` at `at` into `out` at `to`.
template <class T>
void take(std::span<const std::byte> in, std::size_t& at, T* out, std::size_t count) {
    const std::size_t size = count * sizeof(T);
    if (size != 0) std::memcpy(out, in.data() + at, size);
    at += size;
}

}  // namespace

std::size_t PayloadLayout::bytes(std::uint32_t frames) const {
    std::size_t per_frame = 0;
    if (poses) per_frame += std::size_t{birds} * sizeof(gpu::BirdPose);
    if (diag) per_frame += std::size_t{birds} * sizeof(gpu::BirdDiag);
    if (chain_pose) per_frame += std::size_t{joints} * (sizeof(glm::vec3) + sizeof(glm::quat));
    if (chain_extra) per_frame += std::size_t{joints} * sizeof(glm::vec3) + std::size_t{chains} * (sizeof(glm::vec3) + kWeights * sizeof(float));
    return per_frame * frames;
}

PayloadLayout payload_content(const BakeNeeds& needs) {
    PayloadLayout layout;
    layout.poses = needs.bird_poses || needs.bird_diag;  // diagnostics come with their poses
    layout.diag = needs.bird_diag;
    layout.chain_pose = needs.chains;
    layout.chain_extra = needs.chains && needs.chain_shapes;
    return layout;
}

void encode_frames(const BakeFrames& frames, const PayloadLayout& layout, std::vector<std::byte>& out) {
    out.clear();
    [[maybe_unused]] const std::size_t entries = std::size_t{frames.count} * layout.birds;
    if (layout.poses && layout.birds > 0) {
        assert(frames.bird_poses.size() == entries);
        append(out, frames.bird_poses);
    }
    if (layout.diag && layout.birds > 0) {
        assert(frames.bird_diag.size() == entries);
        append(out, frames.bird_diag);
    }
    if ((layout.chain_pose || layout.chain_extra) && layout.chains > 0) {
        assert(frames.chains != nullptr && frames.count == 1);
        const ChainSnapshot& s = *frames.chains;
        if (layout.chain_pose) {
            assert(s.positions.size() == layout.joints && s.orientations.size() == layout.joints);
            append(out, std::span<const glm::vec3>(s.positions));
            append(out, std::span<const glm::quat>(s.orientations));
        }
        if (layout.chain_extra) {
            assert(s.rest.size() == layout.joints && s.view_directions.size() == layout.chains &&
                   s.weights.size() == std::size_t{layout.chains} * kWeights);
            append(out, std::span<const glm::vec3>(s.rest));
            append(out, std::span<const glm::vec3>(s.view_directions));
            append(out, std::span<const float>(s.weights));
        }
    }
    assert(out.size() == layout.bytes(frames.count));
}

FrameAssembler::FrameAssembler(std::vector<PayloadLayout> parts) : parts_(std::move(parts)) {}

Result<BakeFrames> FrameAssembler::assemble(std::uint32_t first, std::uint32_t count,
                                            std::span<const std::span<const std::byte>> payloads,
                                            std::span<const std::string> part_names) {
    assert(payloads.size() == parts_.size() && part_names.size() == parts_.size());
    std::size_t birds = 0, joints = 0, chains = 0;
    for (std::size_t p = 0; p < parts_.size(); ++p) {
        const std::size_t expected = parts_[p].bytes(count);
        if (payloads[p].size() != expected) {
            return make_error(Error::Kind::InvalidInput, part_names[p] + ": frames " + std::to_string(first) + ".." +
                                                             std::to_string(first + count - 1) + " hold " +
                                                             std::to_string(payloads[p].size()) + " bytes, expected " +
                                                             std::to_string(expected));
        }
        birds += parts_[p].birds;
        joints += parts_[p].joints;
        chains += parts_[p].chains;
    }
    const PayloadLayout& content = parts_.front();
    BakeFrames out{first, count, {}, {}, nullptr};
    if (content.poses && birds > 0) poses_.resize(std::size_t{count} * birds);
    if (content.diag && birds > 0) diag_.resize(std::size_t{count} * birds);
    const bool chain_data = (content.chain_pose || content.chain_extra) && chains > 0;
    if (chain_data) {
        if (content.chain_pose) {
            snapshot_.positions.resize(joints);
            snapshot_.orientations.resize(joints);
        }
        if (content.chain_extra) {
            snapshot_.rest.resize(joints);
            snapshot_.view_directions.resize(chains);
            snapshot_.weights.resize(chains * kWeights);
        }
    }
    // Parts hold consecutive instances: a part's birds of frame f follow the previous
    // part's in the whole frame f; its joints and chains follow the previous part's.
    std::size_t bird_at = 0, joint_at = 0, chain_at = 0;
    for (std::size_t p = 0; p < parts_.size(); ++p) {
        const PayloadLayout& part = parts_[p];
        const std::span<const std::byte> in = payloads[p];
        std::size_t at = 0;
        if (content.poses && part.birds > 0) {
            for (std::uint32_t f = 0; f < count; ++f) take(in, at, poses_.data() + f * birds + bird_at, part.birds);
        }
        if (content.diag && part.birds > 0) {
            for (std::uint32_t f = 0; f < count; ++f) take(in, at, diag_.data() + f * birds + bird_at, part.birds);
        }
        if (chain_data && part.chains > 0) {
            if (content.chain_pose) {
                take(in, at, snapshot_.positions.data() + joint_at, part.joints);
                take(in, at, snapshot_.orientations.data() + joint_at, part.joints);
            }
            if (content.chain_extra) {
                take(in, at, snapshot_.rest.data() + joint_at, part.joints);
                take(in, at, snapshot_.view_directions.data() + chain_at, part.chains);
                take(in, at, snapshot_.weights.data() + chain_at * kWeights, std::size_t{part.chains} * kWeights);
            }
        }
        bird_at += part.birds;
        joint_at += part.joints;
        chain_at += part.chains;
    }
    if (content.poses && birds > 0) out.bird_poses = poses_;
    if (content.diag && birds > 0) out.bird_diag = diag_;
    if (content.chain_pose || content.chain_extra) out.chains = &snapshot_;
    return out;
}

}  // namespace kodawari::detail
