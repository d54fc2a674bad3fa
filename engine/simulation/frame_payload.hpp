#pragma once
// The frames of one part of a scene (a shard, an MPI rank) as bytes, and the whole
// scene's frames put back together from the parts in order: what part files hold
// (shards.cpp) and what ranks send to the writing rank (distributed_bake.cpp).
// Channel after channel (kodawari/simulation/domain.hpp), each frames x the part's elements in the
// domain's own layout, so that the whole is the single process's frames bit for bit. It
// names no domain: a part's instances are consecutive in every channel.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "kodawari/simulation/bake.hpp"

namespace kodawari::detail {

/// What a part's payload holds per frame: channels in order, with the part's elements.
struct PayloadLayout {
    std::vector<ChannelInfo> channels;

    /// Bytes of `frames` frames.
    [[nodiscard]] std::size_t bytes(std::uint32_t frames) const;
};

/// The channels of `domains` that `needs` names, in the order `needs` names them, with
/// those domains' element counts (a part's domains: its part).
[[nodiscard]] PayloadLayout payload_layout(std::span<const Domain* const> domains, const BakeNeeds& needs);

/// Appends `frames`' channels under `layout` to `out` (cleared first). The frames must
/// hold what the layout says (asserted: a source hands them so).
void encode_frames(const BakeFrames& frames, const PayloadLayout& layout, std::vector<std::byte>& out);

/// Puts the parts' payloads of one chunk back into the whole scene's frames.
class FrameAssembler {
public:
    /// `parts`: each part's layout (the same channels in the same order), in instance
    /// order (shard or rank order).
    explicit FrameAssembler(std::vector<PayloadLayout> parts);
    /// The whole frames [first, first + count) from one payload per part. A payload of the
    /// wrong size is an InvalidInput error naming the part (`part_names[i]`). The frames'
    /// spans stay valid until the next call.
    [[nodiscard]] Result<BakeFrames> assemble(std::uint32_t first, std::uint32_t count,
                                              std::span<const std::span<const std::byte>> payloads,
                                              std::span<const std::string> part_names);

private:
    std::vector<PayloadLayout> parts_;
    std::vector<std::vector<std::byte>> whole_;  // per channel
};

}  // namespace kodawari::detail
