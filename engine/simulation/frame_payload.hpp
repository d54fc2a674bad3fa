#pragma once
// The frames of one part of a scene (a shard, an MPI rank) as bytes, and the whole
// scene's frames put back together from the parts in order: what part files hold
// (shards.cpp) and what ranks send to the writing rank (distributed_bake.cpp).
// Raw little-endian arrays in the engine's own layouts (gpu::BirdPose, glm vectors), so
// that the whole is the single process's frames bit for bit.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "kodawari/bake.hpp"

namespace kodawari::detail {

/// What a part's payload holds per frame, and its sizes.
struct PayloadLayout {
    std::uint32_t birds = 0;   ///< the part's birds
    std::uint32_t joints = 0;  ///< the part's chain joints
    std::uint32_t chains = 0;  ///< the part's chains
    bool poses = false;        ///< bird poses
    bool diag = false;         ///< bird diagnostics
    bool chain_pose = false;   ///< chain joint positions and orientations
    bool chain_extra = false;  ///< blended rest shapes, view directions and weights (traces)

    /// Bytes of `frames` frames (chains are handed over one frame at a time).
    [[nodiscard]] std::size_t bytes(std::uint32_t frames) const;
};

/// The content a set of sinks needs from every part.
[[nodiscard]] PayloadLayout payload_content(const BakeNeeds& needs);

/// Appends `frames`' content under `layout` to `out` (cleared first). The spans must hold
/// what the layout says (asserted: a bake hands them so).
void encode_frames(const BakeFrames& frames, const PayloadLayout& layout, std::vector<std::byte>& out);

/// Puts the parts' payloads of one chunk back into the whole scene's frames.
class FrameAssembler {
public:
    /// `parts`: each part's layout, in instance order (shard or rank order).
    explicit FrameAssembler(std::vector<PayloadLayout> parts);
    /// The whole frames [first, first + count) from one payload per part. A payload of the
    /// wrong size is an InvalidInput error naming the part (`part_names[i]`).
    [[nodiscard]] Result<BakeFrames> assemble(std::uint32_t first, std::uint32_t count,
                                              std::span<const std::span<const std::byte>> payloads,
                                              std::span<const std::string> part_names);

private:
    std::vector<PayloadLayout> parts_;
    std::vector<gpu::BirdPose> poses_;
    std::vector<gpu::BirdDiag> diag_;
    ChainSnapshot snapshot_;
};

}  // namespace kodawari::detail
