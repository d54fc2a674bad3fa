// Part payloads (frame_payload.hpp): the order of the arrays is the order of the channels.
#include "simulation/frame_payload.hpp"

#include <cassert>
#include <cstring>
#include <string>

namespace kodawari::detail {

namespace {

std::size_t frame_bytes(const ChannelInfo& c) { return static_cast<std::size_t>(c.elements) * c.element_bytes; }

}  // namespace

std::size_t PayloadLayout::bytes(std::uint32_t frames) const {
    std::size_t per_frame = 0;
    for (const ChannelInfo& c : channels) per_frame += frame_bytes(c);
    return per_frame * frames;
}

PayloadLayout payload_layout(std::span<const Domain* const> domains, const BakeNeeds& needs) {
    PayloadLayout layout;
    for (const std::string& name : needs.channels) {
        for (const Domain* domain : domains) {
            for (const ChannelInfo& info : domain->channels()) {
                if (info.name == name) layout.channels.push_back(info);
            }
        }
    }
    return layout;
}

void encode_frames(const BakeFrames& frames, const PayloadLayout& layout, std::vector<std::byte>& out) {
    out.clear();
    for (const ChannelInfo& c : layout.channels) {
        const std::span<const std::byte> bytes = frames.channel(c.name);
        assert(bytes.size() == frames.count * frame_bytes(c));
        out.insert(out.end(), bytes.begin(), bytes.end());
    }
    assert(out.size() == layout.bytes(frames.count));
}

FrameAssembler::FrameAssembler(std::vector<PayloadLayout> parts) : parts_(std::move(parts)) {
    assert(!parts_.empty());
    whole_.resize(parts_.front().channels.size());
}

Result<BakeFrames> FrameAssembler::assemble(std::uint32_t first, std::uint32_t count,
                                            std::span<const std::span<const std::byte>> payloads,
                                            std::span<const std::string> part_names) {
    assert(payloads.size() == parts_.size() && part_names.size() == parts_.size());
    const std::size_t channels = whole_.size();
    std::vector<std::size_t> whole_frame(channels, 0);  // bytes of one whole frame, per channel
    for (std::size_t p = 0; p < parts_.size(); ++p) {
        const std::size_t expected = parts_[p].bytes(count);
        if (payloads[p].size() != expected) {
            return make_error(Error::Kind::InvalidInput, part_names[p] + ": frames " + std::to_string(first) + ".." +
                                                             std::to_string(first + count - 1) + " hold " +
                                                             std::to_string(payloads[p].size()) + " bytes, expected " +
                                                             std::to_string(expected));
        }
        assert(parts_[p].channels.size() == channels);
        for (std::size_t c = 0; c < channels; ++c) whole_frame[c] += frame_bytes(parts_[p].channels[c]);
    }
    for (std::size_t c = 0; c < channels; ++c) whole_[c].resize(whole_frame[c] * count);
    // Parts hold consecutive instances: in every channel, a part's elements of frame f
    // follow the previous part's in the whole frame f.
    std::vector<std::size_t> part_at(channels, 0);  // where the part's elements go in a whole frame
    for (std::size_t p = 0; p < parts_.size(); ++p) {
        std::size_t at = 0;  // in the part's payload
        for (std::size_t c = 0; c < channels; ++c) {
            const std::size_t size = frame_bytes(parts_[p].channels[c]);
            for (std::uint32_t f = 0; f < count; ++f) {
                if (size != 0) std::memcpy(whole_[c].data() + f * whole_frame[c] + part_at[c], payloads[p].data() + at, size);
                at += size;
            }
            part_at[c] += size;
        }
    }
    BakeFrames out{first, count, {}};
    for (std::size_t c = 0; c < channels; ++c) out.channels.push_back({parts_.front().channels[c].name, whole_[c]});
    return out;
}

}  // namespace kodawari::detail
