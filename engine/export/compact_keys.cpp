// Compact animation keys for the streamed .glb writers: see compact_keys.hpp.
#include "export/compact_keys.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <cassert>
#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <unistd.h>

#include "core/parallel.hpp"
#include "export/key_reduction.hpp"

namespace kodawari {

std::string glb_stem(const std::string& path) {
    const bool glb = path.size() >= 4 && std::equal(path.end() - 4, path.end(), ".glb", [](char a, char b) {
        return std::tolower(static_cast<unsigned char>(a)) == b;
    });
    return path.substr(0, path.size() - (glb ? 4 : 0));
}

std::vector<std::string> glb_bake_paths(const std::string& out, bool has_birds, bool has_chains) {
    std::vector<std::string> paths;
    if (has_birds) paths.push_back(out);
    if (has_chains) paths.push_back(has_birds ? glb_stem(out) + "-characters.glb" : out);
    return paths;
}

std::string glb_name_problem(const std::string& out) {
    std::error_code ec;
    const auto status = std::filesystem::status(out, ec);
    if (!ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) return {};
    if (glb_stem(out).size() < out.size()) return {};
    return "the bake is a binary glTF file: name it .glb (a .gltf is read as JSON glTF)";
}

Result<void> check_compaction(const std::string& path, const GlbCompaction& compaction) {
    if (compaction.meshopt && !compaction.enabled) {
        return make_error(Error::Kind::InvalidInput, path + ": meshopt compression is for compacted keys only (enable compaction)");
    }
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

// A channel that keeps most of its keys is smaller keeping all of them: its values
// without key times of its own (they share every frame's). Exact then, but for the
// rotations' rounding (`rounding()`).
template <class Rounding>
void keep_all_if_smaller(Reduction& r, std::size_t value_bytes, std::uint32_t frames, const Rounding& rounding) {
    if (r.kept.size() < frames && r.kept.size() > 2 && r.kept.size() * (value_bytes + sizeof(float)) >= std::size_t{frames} * value_bytes) {
        r.kept.resize(frames);
        for (std::uint32_t f = 0; f < frames; ++f) r.kept[f] = f;
        r.max_error = rounding();
    }
}

// A channel's bytes in the tail: its values, and its key times unless shared (every
// frame's, or the ends'); sharing with another channel of its item is not counted.
std::uint64_t cost(const Reduction& r, std::size_t value_bytes, std::uint32_t frames) {
    const std::uint64_t kept = r.kept.size();
    return kept * value_bytes + (kept == frames || kept == 2 ? 0 : kept * sizeof(float));
}

// One channel of a group after the first pass: whether it is written, its reduction,
// and its kept keys' bytes as the tail holds them (without meshopt: floats, shorts or
// bytes; with it, the quantizing filter's output).
struct Prepared {
    bool kept = false;
    Reduction r;
    bool bytes = false;  // a rotation in normalized bytes
    std::vector<unsigned char> values;
};

// A thread's buffers for prepare_channel(): `channel` holds the channel's keys, frame
// after frame (3 or 4 floats each).
struct PrepareScratch {
    std::vector<float> channel;
    std::vector<std::int16_t> shorts;
    std::vector<std::int16_t> narrow;  // the rotations rounded to bytes (held in shorts)
};

// Reduces scratch.channel within `bounds` (key_reduction.hpp) into `p`.
void prepare_channel(ChannelKind kind, std::span<const float> times, const GlbCompaction& bounds, PrepareScratch& scratch,
                     Prepared& p) {
    const std::vector<float>& channel = scratch.channel;
    const auto frames = static_cast<std::uint32_t>(times.size());
    const std::size_t value_bytes = kind == ChannelKind::Rotation ? 4 * sizeof(std::int16_t) : 3 * sizeof(float);
    p.bytes = false;
    p.values.clear();
    if (bounds.meshopt) {
        MeshoptChannel quantized =
            kind == ChannelKind::Rotation
                ? choose_rotation(times, channel, bounds.rotation_rad)
                : choose_vector(times, channel, kind == ChannelKind::Translation ? bounds.position_m : bounds.scale_rel,
                                kind == ChannelKind::Translation ? VectorMetric::Distance : VectorMetric::Relative);
        p.r = std::move(quantized.reduction);
        p.values = std::move(quantized.encoded);
        return;
    }
    if (kind != ChannelKind::Rotation) {
        p.r = reduce_vec3(times, channel, kind == ChannelKind::Translation ? bounds.position_m : bounds.scale_rel,
                          kind == ChannelKind::Translation ? VectorMetric::Distance : VectorMetric::Relative);
        keep_all_if_smaller(p.r, value_bytes, frames, [] { return 0.0; });
        for (const std::uint32_t f : p.r.kept) append_bytes(p.values, &channel[f * 3], 3);
        return;
    }
    std::vector<std::int16_t>& shorts = scratch.shorts;
    std::vector<std::int16_t>& narrow = scratch.narrow;
    shorts.resize(channel.size());
    quantize_rotations(channel, shorts);
    p.r = reduce_rotations(times, channel, shorts, bounds.rotation_rad);
    keep_all_if_smaller(p.r, value_bytes, frames, [&] { return rounding_error(channel, shorts); });
    // Bytes where the bound absorbs their rounding at every key (then every kept key is
    // within it and reduce_rotations keeps the spans within it) and they come out
    // smaller: half the bytes per key, but more keys.
    narrow.resize(channel.size());
    quantize_rotations(channel, narrow, RotationBits::Byte);
    if (rounding_error(channel, narrow, RotationBits::Byte) <= static_cast<double>(bounds.rotation_rad)) {
        Reduction r8 = reduce_rotations(times, channel, narrow, bounds.rotation_rad, RotationBits::Byte);
        keep_all_if_smaller(r8, value_bytes / 2, frames, [&] { return rounding_error(channel, narrow, RotationBits::Byte); });
        if (r8.max_error <= static_cast<double>(bounds.rotation_rad) &&
            cost(r8, value_bytes / 2, frames) < cost(p.r, value_bytes, frames)) {
            p.r = std::move(r8);
            p.bytes = true;
        }
    }
    if (p.bytes) {
        for (const std::uint32_t f : p.r.kept) {
            std::int8_t key[4];
            for (std::size_t k = 0; k < 4; ++k) key[k] = static_cast<std::int8_t>(narrow[f * 4 + k]);
            append_bytes(p.values, key, 4);
        }
    } else {
        for (const std::uint32_t f : p.r.kept) append_bytes(p.values, &shorts[f * 4], 4);
    }
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
    out.frames_ = frames;
    out.first_time_ = frames > 0 ? static_cast<double>(times.front()) : 0.0;
    out.last_time_ = frames > 0 ? static_cast<double>(times.back()) : 0.0;

    // The shared key times: every frame's, then the first and the last (with meshopt, the
    // first elements of the times' first chunk, chunk 0: the same offsets).
    std::vector<unsigned char> block;
    const std::uint64_t all_frames = 0;
    std::uint64_t ends = std::uint64_t{frames} * sizeof(float);
    const float pair[2] = {frames > 0 ? times.front() : 0.0f, frames > 0 ? times.back() : 0.0f};
    out.meshopt_ = bounds.meshopt;
    if (out.meshopt_) {
        if (frames > 0) KW_TRY(out.streams_.append(MeshoptStream::Times, times.data(), frames, out.data_, out.bytes_));
        if (frames > 1) {
            auto at = out.streams_.append(MeshoptStream::Times, pair, 2, out.data_, out.bytes_);
            if (!at) return at.error();
            ends = at.value();
        }
    } else {
        append_bytes(block, times.data(), times.size());
        if (frames > 1) append_bytes(block, pair, 2);
        KW_TRY(out.data_.append(block.data(), block.size()));
        out.bytes_ = block.size();
        out.shared_bytes_ = out.bytes_;
    }
    out.ends_ = frames > 1 ? ends : 0;
    out.stats_.bytes_before = std::uint64_t{frames} * sizeof(float);

    std::size_t record_floats = 0;
    for (const ChannelKind kind : fields) record_floats += width(kind);
    const std::size_t record_bytes = record_floats * sizeof(float);
    const std::size_t group =
        std::max<std::size_t>(1, group_bytes / std::max<std::size_t>(1, std::size_t{frames} * record_bytes));
    std::vector<float> in(std::min(group, count) * std::size_t{frames} * record_floats);
    std::vector<float> kept_times;
    std::uint64_t accessors = 0;  // streamed: accessors of the items so far
    out.item_channels_.reserve(count + 1);
    out.item_accessors_.reserve(count + 1);
    // The kept frames of the current item's channels and where their times went, to
    // share them between its channels.
    std::vector<std::pair<std::vector<std::uint32_t>, std::uint64_t>> item_times;
    std::vector<Prepared> prepared(std::min(group, count) * fields.size());
    const unsigned threads = resolve_threads(bounds.threads);
    for (std::size_t begin = 0; begin < count; begin += group) {
        const std::size_t n = std::min(group, count - begin);
        KW_TRY(read_item_group(keys, count, frames, record_floats, begin, n, in.data()));
        // First pass, on every core: each channel of the group reduced and its kept keys
        // encoded (the channels are independent; the reductions are the cost).
        parallel_for(n, threads, [&](std::size_t first, std::size_t last) {
            PrepareScratch scratch;
            for (std::size_t item = first; item < last; ++item) {
                std::size_t offset = 0;
                for (std::size_t field = 0; field < fields.size(); ++field) {
                    const ChannelKind kind = fields[field];
                    const std::size_t w = width(kind);
                    Prepared& p = prepared[item * fields.size() + field];
                    p.kept = !keep || keep(begin + item, field);
                    if (p.kept) {
                        scratch.channel.resize(std::size_t{frames} * w);
                        for (std::uint32_t f = 0; f < frames; ++f) {
                            std::memcpy(scratch.channel.data() + std::size_t{f} * w,
                                        in.data() + (std::size_t{f} * n + item) * record_floats + offset, w * sizeof(float));
                        }
                        prepare_channel(kind, times, bounds, scratch, p);
                    }
                    offset += w;
                }
            }
        });
        // Second pass, in item order, alone: the channels appended to the tail, so that
        // the bytes are the same whatever the threads.
        block.clear();
        for (std::size_t item = 0; item < n; ++item) {
            out.item_channels_.push_back(out.channels_.size());
            out.item_accessors_.push_back(accessors);
            item_times.clear();
            for (std::size_t field = 0; field < fields.size(); ++field) {
                const ChannelKind kind = fields[field];
                const std::size_t w = width(kind);
                Prepared& p = prepared[item * fields.size() + field];
                if (!p.kept) continue;
                const Reduction& r = p.r;
                double& worst = kind == ChannelKind::Rotation      ? out.stats_.rotation_rad
                                : kind == ChannelKind::Translation ? out.stats_.position_m
                                                                   : out.stats_.scale_rel;
                worst = std::max(worst, r.max_error);
                Channel c;
                c.kind = kind;
                c.keys = static_cast<std::uint32_t>(r.kept.size());
                c.bytes = p.bytes;
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
                        kept_times.clear();
                        for (const std::uint32_t f : r.kept) kept_times.push_back(times[f]);
                        if (out.meshopt_) {
                            auto at = out.streams_.append(MeshoptStream::Times, kept_times.data(), kept_times.size(), out.data_,
                                                          out.bytes_);
                            if (!at) return at.error();
                            c.times = at.value();
                        } else {
                            c.times = out.bytes_ + block.size();
                            append_bytes(block, kept_times.data(), kept_times.size());
                        }
                        item_times.emplace_back(r.kept, c.times);
                        ++accessors;
                    }
                }
                c.values = out.bytes_ + block.size();
                if (out.meshopt_) {
                    auto at = out.streams_.append(kind == ChannelKind::Rotation ? MeshoptStream::Rotations : MeshoptStream::Vectors,
                                                  p.values.data(), r.kept.size(), out.data_, out.bytes_);
                    if (!at) return at.error();
                    c.values = at.value();
                } else {
                    append_bytes(block, p.values.data(), p.values.size());
                    if (kind == ChannelKind::Rotation && p.bytes) ++out.stats_.byte_rotations;
                }
                if (kind == ChannelKind::Rotation) ++out.stats_.rotations;
                out.channels_.push_back(c);
                ++accessors;
                out.stats_.keys += frames;
                out.stats_.kept += c.keys;
                out.stats_.bytes_before += std::uint64_t{frames} * w * sizeof(float);
            }
        }
        KW_TRY(out.data_.append(block.data(), block.size()));
        out.bytes_ += block.size();
    }
    if (out.meshopt_) KW_TRY(out.streams_.finish(out.data_, out.bytes_));
    out.item_channels_.push_back(out.channels_.size());
    out.item_accessors_.push_back(accessors);
    out.stats_.bytes_after = out.bytes_;
    out.local_bytes_ = out.bytes_;
    return out;
}

tinygltf::Accessor CompactKeys::time_accessor(int view, const Channel& c) const {
    // Key times are float seconds with min and max, as §3.11 requires of sampler inputs;
    // every channel keeps the first and the last frame.
    tinygltf::Accessor accessor;
    accessor.bufferView = view + static_cast<int>(MeshoptStreams::chunk_of(c.times));
    accessor.byteOffset = MeshoptStreams::offset_of(c.times);
    accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    accessor.count = c.keys;
    accessor.type = TINYGLTF_TYPE_SCALAR;
    accessor.minValues = {first_time_};
    accessor.maxValues = {last_time_};
    return accessor;
}

tinygltf::Accessor CompactKeys::value_accessor(int view, const Channel& c) {
    tinygltf::Accessor accessor;
    accessor.bufferView = view + static_cast<int>(MeshoptStreams::chunk_of(c.values));
    accessor.byteOffset = MeshoptStreams::offset_of(c.values);
    accessor.count = c.keys;
    if (c.kind == ChannelKind::Rotation) {
        accessor.componentType = c.bytes ? TINYGLTF_COMPONENT_TYPE_BYTE : TINYGLTF_COMPONENT_TYPE_SHORT;
        accessor.normalized = true;
        accessor.type = TINYGLTF_TYPE_VEC4;
    } else {
        accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        accessor.type = TINYGLTF_TYPE_VEC3;
    }
    return accessor;
}

int CompactKeys::add_views(tinygltf::Model& model, std::uint64_t head, MeshoptJson& json) const {
    if (!meshopt_) return add_buffer_view(model, head, bytes_, 0);
    return streams_.add_views(model, head, json);
}

std::pair<int, int> CompactKeys::add_next_channel(tinygltf::Model& model, int view) {
    const Channel& c = channels_.at(next_++);
    int input = -1;
    if (const auto it = time_accessors_.find(c.times); it != time_accessors_.end()) {
        input = it->second;
    } else {
        model.accessors.push_back(time_accessor(view, c));
        input = static_cast<int>(model.accessors.size() - 1);
        time_accessors_.emplace(c.times, input);
    }
    model.accessors.push_back(value_accessor(view, c));
    return {input, static_cast<int>(model.accessors.size() - 1)};
}

void CompactKeys::add_shared_times(tinygltf::Model& model, int view) {
    // Only those some channel uses: an accessor nothing refers to is an unused object to
    // glTF-Validator.
    for (const Channel& c : channels_) {
        int& shared = c.times == 0 ? all_frames_accessor_ : ends_accessor_;
        if (!shared_times(c) || shared >= 0) continue;
        model.accessors.push_back(time_accessor(view, c));
        shared = static_cast<int>(model.accessors.size() - 1);
        if (all_frames_accessor_ >= 0 && (ends_ == 0 || ends_accessor_ >= 0)) break;
    }
}

void CompactKeys::item_accessors(std::size_t item, int view, std::vector<tinygltf::Accessor>& out) const {
    // The same walk as item_channels(): a channel's own times come before its values,
    // once per item (channels of one item with the same kept frames share them).
    const std::uint64_t end = item_channels_.at(item + 1);
    for (std::uint64_t k = item_channels_.at(item); k < end; ++k) {
        const Channel& c = channels_[k];
        if (!shared_times(c)) {
            bool seen = false;
            for (std::uint64_t j = item_channels_[item]; j < k && !seen; ++j) seen = channels_[j].times == c.times;
            if (!seen) out.push_back(time_accessor(view, c));
        }
        out.push_back(value_accessor(view, c));
    }
}

void CompactKeys::item_channels(std::size_t item, int first, std::vector<std::pair<int, int>>& out) const {
    const std::uint64_t begin = item_channels_.at(item);
    const std::uint64_t end = item_channels_.at(item + 1);
    const std::size_t at = out.size();
    int next = first;
    for (std::uint64_t k = begin; k < end; ++k) {
        const Channel& c = channels_[k];
        int input = c.times == 0 ? all_frames_accessor_ : ends_accessor_;
        if (!shared_times(c)) {
            input = -1;
            for (std::uint64_t j = begin; j < k && input < 0; ++j) {
                if (channels_[j].times == c.times) input = out[at + (j - begin)].first;
            }
            if (input < 0) input = next++;
        }
        out.emplace_back(input, next++);
    }
}

Result<void> CompactKeys::write(AtomicFile& file) {
    written_at_ = file.position();
    constexpr std::size_t kChunk = std::size_t{8} << 20;
    std::vector<unsigned char> buffer(static_cast<std::size_t>(std::min<std::uint64_t>(kChunk, local_bytes_)));
    for (std::uint64_t at = 0; at < local_bytes_; at += buffer.size()) {
        const auto size = static_cast<std::size_t>(std::min<std::uint64_t>(buffer.size(), local_bytes_ - at));
        KW_TRY(data_.read(at, buffer.data(), size));
        file.write(buffer.data(), size);
    }
    file.skip(bytes_ - local_bytes_);
    return {};
}

namespace {

// describe()'s bytes: fixed-size fields in the host's order (every rank runs the same
// build of the engine on the same kind of machine).
class Described {
public:
    explicit Described(std::vector<std::byte>& out) : out_(&out) {}
    explicit Described(std::span<const std::byte> in) : in_(in) {}
    template <class T>
    void put(const T& value) {
        const auto* bytes = reinterpret_cast<const std::byte*>(&value);
        out_->insert(out_->end(), bytes, bytes + sizeof(T));
    }
    template <class T>
    [[nodiscard]] bool get(T& value) {
        if (in_.size() - at_ < sizeof(T)) return false;
        std::memcpy(&value, in_.data() + at_, sizeof(T));
        at_ += sizeof(T);
        return true;
    }
    [[nodiscard]] bool done() const { return at_ == in_.size(); }

private:
    std::vector<std::byte>* out_ = nullptr;
    std::span<const std::byte> in_;
    std::size_t at_ = 0;
};

}  // namespace

std::vector<std::byte> CompactKeys::describe() const {
    assert(!meshopt_ && next_ == 0 && local_bytes_ == bytes_ && "describe() a part as build() made it");
    std::vector<std::byte> out;
    Described d(out);
    d.put(bytes_);
    d.put(shared_bytes_);
    d.put(ends_);
    d.put(frames_);
    d.put(static_cast<std::uint64_t>(item_channels_.size()));
    d.put(static_cast<std::uint64_t>(channels_.size()));
    d.put(stats_);
    for (std::size_t i = 0; i < item_channels_.size(); ++i) {
        d.put(item_channels_[i]);
        d.put(item_accessors_[i]);
    }
    for (const Channel& c : channels_) {
        d.put(c.times);
        d.put(c.values);
        d.put(c.keys);
        d.put(static_cast<std::uint8_t>(c.kind));
        d.put(static_cast<std::uint8_t>(c.bytes));
    }
    return out;
}

Result<std::vector<std::uint64_t>> CompactKeys::join(std::span<const std::vector<std::byte>> parts) {
    assert(!meshopt_ && next_ == 0 && "join() parts as build() made them");
    const auto bad = [](const std::string& why) {
        return make_error(Error::Kind::Internal, "joining the ranks' compacted keys: " + why);
    };
    const std::uint64_t times_bytes = std::uint64_t{frames_} * sizeof(float);  // build()'s first bytes_before
    std::vector<std::uint64_t> at;
    for (std::size_t p = 0; p < parts.size(); ++p) {
        Described d(parts[p]);
        std::uint64_t bytes = 0, shared = 0, ends = 0, items = 0, channels = 0;
        std::uint32_t frames = 0;
        GlbCompactionStats stats;
        if (!d.get(bytes) || !d.get(shared) || !d.get(ends) || !d.get(frames) || !d.get(items) || !d.get(channels) ||
            !d.get(stats)) {
            return bad("part " + std::to_string(p + 1) + " is cut short");
        }
        if (shared != shared_bytes_ || ends != ends_ || frames != frames_ || bytes < shared || items == 0) {
            return bad("part " + std::to_string(p + 1) + " has other shared key times");
        }
        // This part's bytes go after those so far; its offsets counted from its own tail's
        // start move by `shift` (it has the same shared key times, which it does not write).
        const std::uint64_t base = bytes_;
        at.push_back(base);
        const std::uint64_t first_channel = channels_.size();
        const std::uint64_t first_accessor = item_accessors_.back();
        item_channels_.pop_back();
        item_accessors_.pop_back();
        for (std::uint64_t i = 0; i < items; ++i) {
            std::uint64_t channel = 0, accessors = 0;
            if (!d.get(channel) || !d.get(accessors)) return bad("part " + std::to_string(p + 1) + " is cut short");
            item_channels_.push_back(first_channel + channel);
            item_accessors_.push_back(first_accessor + accessors);
        }
        for (std::uint64_t k = 0; k < channels; ++k) {
            Channel c;
            std::uint8_t kind = 0, narrow = 0;
            if (!d.get(c.times) || !d.get(c.values) || !d.get(c.keys) || !d.get(kind) || !d.get(narrow) ||
                kind > static_cast<std::uint8_t>(ChannelKind::Scale)) {
                return bad("part " + std::to_string(p + 1) + " is cut short");
            }
            c.kind = static_cast<ChannelKind>(kind);
            c.bytes = narrow != 0;
            if (!shared_times(c)) {
                if (c.times < shared) return bad("a channel's key times are inside the shared ones");
                c.times = c.times - shared + base;
            }
            if (c.values < shared) return bad("a channel's values are inside the shared key times");
            c.values = c.values - shared + base;
            channels_.push_back(c);
        }
        if (!d.done() || item_channels_.back() != channels_.size()) return bad("part " + std::to_string(p + 1) + " does not add up");
        bytes_ += bytes - shared;
        stats_.keys += stats.keys;
        stats_.kept += stats.kept;
        stats_.bytes_before += stats.bytes_before - times_bytes;  // its key times are counted once
        stats_.position_m = std::max(stats_.position_m, stats.position_m);
        stats_.rotation_rad = std::max(stats_.rotation_rad, stats.rotation_rad);
        stats_.scale_rel = std::max(stats_.scale_rel, stats.scale_rel);
        stats_.rotations += stats.rotations;
        stats_.byte_rotations += stats.byte_rotations;
    }
    stats_.bytes_after = bytes_;
    return at;
}

Result<void> CompactKeys::write_part(const std::string& path, std::uint64_t at) {
    const auto failed = [&](const char* what) {
        return make_error(Error::Kind::Io, path + ": cannot " + what + " this rank's compacted keys (" + std::strerror(errno) + ")");
    };
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) return failed("open the file for");
    constexpr std::size_t kChunk = std::size_t{8} << 20;
    std::vector<unsigned char> buffer(static_cast<std::size_t>(std::min<std::uint64_t>(kChunk, bytes_ - shared_bytes_)));
    Result<void> status;
    for (std::uint64_t done = 0; status && done < bytes_ - shared_bytes_;) {
        const auto size = static_cast<std::size_t>(std::min<std::uint64_t>(buffer.size(), bytes_ - shared_bytes_ - done));
        status = data_.read(shared_bytes_ + done, buffer.data(), size);
        for (std::size_t put = 0; status && put < size;) {
            const ssize_t n = ::pwrite(fd, buffer.data() + put, size - put, static_cast<off_t>(at + done + put));
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) status = failed("write");
            else put += static_cast<std::size_t>(n);
        }
        done += size;
    }
    if (status && ::fsync(fd) != 0) status = failed("sync");
    if (::close(fd) != 0 && status) status = failed("close");
    return status;
}

}  // namespace gltf
}  // namespace kodawari
