// Compact animation keys for the streamed .glb writers: see compact_keys.hpp.
#include "export/compact_keys.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "export/key_reduction.hpp"

namespace kodawari {

Result<void> check_compaction(const std::string& path, const GlbCompaction& compaction) {
    if (!compaction.enabled) return {};
    const auto bad = [](float v) { return !std::isfinite(v) || v < 0.0f; };
    if (bad(compaction.position_m) || bad(compaction.rotation_rad) || bad(compaction.scale_rel)) {
        return make_error(Error::Kind::InvalidInput,
                          path + ": compaction bounds must be finite and >= 0, got " + std::to_string(compaction.position_m) +
                              " m, " + std::to_string(compaction.rotation_rad) + " rad, " +
                              std::to_string(compaction.scale_rel) + " (relative scale)");
    }
    return {};
}

namespace gltf {
namespace {

std::size_t width(ChannelKind kind) { return kind == ChannelKind::Rotation ? 4 : 3; }

template <class T>
void append_bytes(std::vector<unsigned char>& out, const T* data, std::size_t count) {
    const std::size_t at = out.size();
    out.resize(at + count * sizeof(T));
    std::memcpy(out.data() + at, data, count * sizeof(T));
}

}  // namespace

Result<CompactKeys> CompactKeys::build(SpillFile& keys, const std::string& beside, std::size_t count,
                                       std::span<const ChannelKind> fields, std::span<const float> times,
                                       const GlbCompaction& bounds, std::size_t group_bytes,
                                       const std::function<bool(std::size_t item, std::size_t field)>& keep) {
    CompactKeys out;
    auto spill = SpillFile::open(beside);
    if (!spill) return spill.error();
    out.data_ = std::move(spill).value();
    const auto frames = static_cast<std::uint32_t>(times.size());
    out.first_time_ = frames > 0 ? static_cast<double>(times.front()) : 0.0;
    out.last_time_ = frames > 0 ? static_cast<double>(times.back()) : 0.0;

    // The shared key times: every frame's, then the first and the last.
    std::vector<unsigned char> block;
    append_bytes(block, times.data(), times.size());
    const std::uint64_t all_frames = 0;
    const std::uint64_t ends = block.size();
    if (frames > 1) {
        const float pair[2] = {times.front(), times.back()};
        append_bytes(block, pair, 2);
    }
    KW_TRY(out.data_.append(block.data(), block.size()));
    out.bytes_ = block.size();
    out.stats_.bytes_before = std::uint64_t{frames} * sizeof(float);

    std::size_t record_floats = 0;
    for (const ChannelKind kind : fields) record_floats += width(kind);
    const std::size_t record_bytes = record_floats * sizeof(float);
    const std::size_t group =
        std::max<std::size_t>(1, group_bytes / std::max<std::size_t>(1, std::size_t{frames} * record_bytes));
    std::vector<float> in(std::min(group, count) * std::size_t{frames} * record_floats);
    std::vector<float> channel;
    std::vector<std::int16_t> shorts;
    std::vector<float> kept_times;
    std::vector<float> kept_floats;
    std::vector<std::int16_t> kept_shorts;
    // The kept frames of the current item's channels and where their times went, to
    // share them between its channels.
    std::vector<std::pair<std::vector<std::uint32_t>, std::uint64_t>> item_times;
    for (std::size_t begin = 0; begin < count; begin += group) {
        const std::size_t n = std::min(group, count - begin);
        KW_TRY(read_item_group(keys, count, frames, record_floats, begin, n, in.data()));
        block.clear();
        for (std::size_t item = 0; item < n; ++item) {
            item_times.clear();
            std::size_t offset = 0;
            for (std::size_t field = 0; field < fields.size(); ++field) {
                const ChannelKind kind = fields[field];
                const std::size_t w = width(kind);
                if (keep && !keep(begin + item, field)) {
                    offset += w;
                    continue;
                }
                channel.resize(std::size_t{frames} * w);
                for (std::uint32_t f = 0; f < frames; ++f) {
                    std::memcpy(channel.data() + std::size_t{f} * w,
                                in.data() + (std::size_t{f} * n + item) * record_floats + offset, w * sizeof(float));
                }
                offset += w;
                Reduction r;
                if (kind == ChannelKind::Rotation) {
                    shorts.resize(channel.size());
                    quantize_rotations(channel, shorts);
                    r = reduce_rotations(times, channel, shorts, bounds.rotation_rad);
                } else {
                    r = reduce_vec3(times, channel, kind == ChannelKind::Translation ? bounds.position_m : bounds.scale_rel,
                                    kind == ChannelKind::Translation ? VectorMetric::Distance : VectorMetric::Relative);
                }
                // A channel that keeps most of its keys is smaller keeping all of them: its
                // values without key times of its own (they share every frame's). Exact
                // then, but for the rotations' rounding.
                const std::size_t value_bytes = kind == ChannelKind::Rotation ? 4 * sizeof(std::int16_t) : 3 * sizeof(float);
                if (r.kept.size() < frames && r.kept.size() > 2 &&
                    r.kept.size() * (value_bytes + sizeof(float)) >= std::size_t{frames} * value_bytes) {
                    r.kept.resize(frames);
                    for (std::uint32_t f = 0; f < frames; ++f) r.kept[f] = f;
                    r.max_error = kind == ChannelKind::Rotation ? rounding_error(channel, shorts) : 0.0;
                }
                double& worst = kind == ChannelKind::Rotation      ? out.stats_.rotation_rad
                                : kind == ChannelKind::Translation ? out.stats_.position_m
                                                                   : out.stats_.scale_rel;
                worst = std::max(worst, r.max_error);
                Channel c;
                c.kind = kind;
                c.keys = static_cast<std::uint32_t>(r.kept.size());
                if (r.kept.size() == frames) {
                    c.times = all_frames;
                } else if (r.kept.size() == 2) {
                    c.times = ends;  // first and last, always kept
                } else {
                    const auto same = std::find_if(item_times.begin(), item_times.end(),
                                                   [&](const auto& entry) { return entry.first == r.kept; });
                    if (same != item_times.end()) {
                        c.times = same->second;
                    } else {
                        c.times = out.bytes_ + block.size();
                        kept_times.clear();
                        for (const std::uint32_t f : r.kept) kept_times.push_back(times[f]);
                        append_bytes(block, kept_times.data(), kept_times.size());
                        item_times.emplace_back(r.kept, c.times);
                    }
                }
                c.values = out.bytes_ + block.size();
                if (kind == ChannelKind::Rotation) {
                    kept_shorts.clear();
                    for (const std::uint32_t f : r.kept) kept_shorts.insert(kept_shorts.end(), &shorts[f * 4], &shorts[f * 4] + 4);
                    append_bytes(block, kept_shorts.data(), kept_shorts.size());
                } else {
                    kept_floats.clear();
                    for (const std::uint32_t f : r.kept) kept_floats.insert(kept_floats.end(), &channel[f * 3], &channel[f * 3] + 3);
                    append_bytes(block, kept_floats.data(), kept_floats.size());
                }
                out.channels_.push_back(c);
                out.stats_.keys += frames;
                out.stats_.kept += c.keys;
                out.stats_.bytes_before += std::uint64_t{frames} * w * sizeof(float);
            }
        }
        KW_TRY(out.data_.append(block.data(), block.size()));
        out.bytes_ += block.size();
    }
    out.stats_.bytes_after = out.bytes_;
    return out;
}

std::pair<int, int> CompactKeys::add_next_channel(tinygltf::Model& model, int view) {
    const Channel& c = channels_.at(next_++);
    int input = -1;
    if (const auto it = time_accessors_.find(c.times); it != time_accessors_.end()) {
        input = it->second;
    } else {
        // Key times are float seconds with min and max, as §3.11 requires of sampler inputs.
        input = add_accessor(model, view, c.times, TINYGLTF_COMPONENT_TYPE_FLOAT, c.keys, TINYGLTF_TYPE_SCALAR);
        model.accessors[static_cast<std::size_t>(input)].minValues = {first_time_};
        model.accessors[static_cast<std::size_t>(input)].maxValues = {last_time_};
        time_accessors_.emplace(c.times, input);
    }
    int output = -1;
    if (c.kind == ChannelKind::Rotation) {
        output = add_accessor(model, view, c.values, TINYGLTF_COMPONENT_TYPE_SHORT, c.keys, TINYGLTF_TYPE_VEC4);
        model.accessors[static_cast<std::size_t>(output)].normalized = true;
    } else {
        output = add_accessor(model, view, c.values, TINYGLTF_COMPONENT_TYPE_FLOAT, c.keys, TINYGLTF_TYPE_VEC3);
    }
    return {input, output};
}

Result<void> CompactKeys::write(AtomicFile& file) {
    constexpr std::size_t kChunk = std::size_t{8} << 20;
    std::vector<unsigned char> buffer(static_cast<std::size_t>(std::min<std::uint64_t>(kChunk, bytes_)));
    for (std::uint64_t at = 0; at < bytes_; at += buffer.size()) {
        const auto size = static_cast<std::size_t>(std::min<std::uint64_t>(buffer.size(), bytes_ - at));
        KW_TRY(data_.read(at, buffer.data(), size));
        file.write(buffer.data(), size);
    }
    return {};
}

}  // namespace gltf
}  // namespace kodawari
