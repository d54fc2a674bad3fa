#pragma once
// Compact animation keys for the streamed .glb writers (GlbCompaction in export.hpp,
// docs/compact.md). The writers' keys wait frame-major in a SpillFile; a .glb wants each
// channel contiguous, and its JSON (every accessor's count) before its binary chunk. So
// the keys are compacted in a first pass, before the model is built: a group of items at
// a time is read back item-major (as copy_item_major does), each channel reduced
// (key_reduction.hpp) and its kept keys and key times appended to a second SpillFile,
// whose bytes become the .glb buffer's tail. In memory: the group buffers and, per
// channel, its key count and offsets (24 bytes), never frames x items.
//
// The tail's layout: the key times of every frame (shared by the channels that keep
// every frame), the first and the last time (shared by the channels that keep only
// those), then channel after channel its own key times (unless they equal those of an
// earlier channel of the same item, or one of the shared ones) and its values: floats
// for translations and scales, normalized shorts (componentType 5122) or bytes (5120)
// for rotations (glTF 2.0 §3.11, "Animations", allows both for rotation outputs). A
// rotation channel is stored in bytes when the bound absorbs their rounding (every key's
// within it; always so from worst_rounding(Byte), 0.0158 rad, up) and that is smaller
// than shorts: bytes halve the values but keep more keys. Every block is a multiple of
// 4 bytes, so every accessor is aligned to its component size (§3.6.2.4).
//
// With GlbCompaction::meshopt (meshopt_streams.hpp) each channel is also quantized, and
// its key times and values go to meshopt streams instead: the tail then holds the
// streams' compressed chunks, each a buffer view of its own (add_views()), and a
// channel's offsets are locations (a chunk, an offset in it; MeshoptStreams). Without it,
// the tail is one buffer view and the file is byte for byte what it was before meshopt.
//
// Two ways to get the accessors: add_next_channel() adds them to a tinygltf model
// (the chains' and the rigged writers); item_accessors() and item_channels() make an
// item's on demand (the birds' writer, whose JSON is streamed: gltf_json_stream.hpp), so
// that nothing per channel is held but its 24-byte record.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "export/gltf_common.hpp"
#include "export/meshopt_streams.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari::gltf {

/// What a record's field animates.
enum class ChannelKind : std::uint8_t { Translation, Rotation, Scale };

class CompactKeys {
public:
    /// Compacts `keys`: `frames` x `count` records, frame-major, each the fields of
    /// `fields` in order (3 floats for translations and scales, 4 for rotations, x y z w,
    /// consecutive frames in one hemisphere) at `times` (one per frame, increasing).
    /// `keep(item, field)` false leaves a field out (called from bounds.threads threads at
    /// once: it only reads). The compacted keys wait in a SpillFile beside `beside`.
    /// `group_bytes` bounds the transpose's buffers as copy_item_major's does; the
    /// channels of a group are reduced on bounds.threads threads, then appended in item
    /// order (the same bytes on any count). Errors: the spill files' (Io).
    [[nodiscard]] static Result<CompactKeys> build(SpillFile& keys, const std::string& beside, std::size_t count,
                                                   std::span<const ChannelKind> fields, std::span<const float> times,
                                                   const GlbCompaction& bounds, std::size_t group_bytes,
                                                   const std::function<bool(std::size_t item, std::size_t field)>& keep = {});

    /// The compacted data's size in bytes: the tail.
    [[nodiscard]] std::uint64_t bytes() const { return bytes_; }
    [[nodiscard]] const GlbCompactionStats& stats() const { return stats_; }

    /// Adds the buffer views that hold the tail, which starts at `head` in buffer 0, and
    /// returns the first one's index, the `view` of the calls below: one view of the whole
    /// tail; with meshopt, one per chunk, the fallback buffer and the extension, and
    /// `json` gets the JSON tinygltf does not write (pass it to write_streamed_glb()).
    [[nodiscard]] int add_views(tinygltf::Model& model, std::uint64_t head, MeshoptJson& json) const;
    /// The decoded size of the meshopt streams (0 without meshopt).
    [[nodiscard]] std::uint64_t fallback_bytes() const { return meshopt_ ? streams_.fallback_bytes() : 0; }

    /// Adds to `model` the key-time and value accessors of the next channel (in build
    /// order: item after item, its kept fields in order) within `view`, add_views()'s. Time accessors are shared where the
    /// times are (one per distinct offset). Returns {input, output}.
    [[nodiscard]] std::pair<int, int> add_next_channel(tinygltf::Model& model, int view);

    /// Streamed use, instead of add_next_channel(). First: adds to `model` the shared
    /// key-time accessors (every frame's, the ends) that some channel uses, within `view`.
    void add_shared_times(tinygltf::Model& model, int view);
    /// How many accessors item_accessors() makes for the items before `item` (item =
    /// count: for all of them).
    [[nodiscard]] std::uint64_t accessors_before(std::size_t item) const { return item_accessors_.at(item); }
    /// Appends `item`'s accessors to `out`: per channel its own key times (where no
    /// earlier channel of the item or the shared ones have them) and its values.
    void item_accessors(std::size_t item, int view, std::vector<tinygltf::Accessor>& out) const;
    /// Appends {input, output} of each of `item`'s channels to `out`, its accessors
    /// numbered from `first`.
    void item_channels(std::size_t item, int first, std::vector<std::pair<int, int>>& out) const;

    /// Appends the tail to `file`. After join(): this part's bytes, then room for the
    /// other parts' (AtomicFile::skip()), which write_part() fills.
    [[nodiscard]] Result<void> write(AtomicFile& file);
    /// Where the last write() began in its file (AtomicFile::position()).
    [[nodiscard]] std::uint64_t written_at() const { return written_at_; }

    /// Distributed bakes (docs/scale-out.md): the items of one file compacted by several
    /// ranks, each its own contiguous run of them, with the same bounds and key times.
    /// What the first part needs of this one to join it: its records (channels, items),
    /// its stats and its size, not its keys. Without meshopt only (its chunks span items).
    [[nodiscard]] std::vector<std::byte> describe() const;
    /// Appends to this part (rank 0's) the parts `parts` describe (the other ranks',
    /// in item order): their channels and items follow this one's, as if one build() had
    /// made them all, and their bytes follow in the tail, each without the shared key
    /// times it starts with. Returns where each part's bytes go, counted from the tail's
    /// first byte. Errors: a description that is not one of a part compacted alike
    /// (Internal).
    [[nodiscard]] Result<std::vector<std::uint64_t>> join(std::span<const std::vector<std::byte>> parts);
    /// Writes this part's own bytes (its tail without the shared key times) into the file
    /// at `path` (another process's AtomicFile::share()) from byte `at` on, and syncs it.
    /// Errors: the file's, naming it (Io).
    [[nodiscard]] Result<void> write_part(const std::string& path, std::uint64_t at);

private:
    struct Channel {
        // Where its key times and values are: a byte offset in the tail's one view, or
        // with meshopt a MeshoptStreams location (chunk, offset).
        std::uint64_t times = 0;
        std::uint64_t values = 0;
        std::uint32_t keys = 0;
        ChannelKind kind = ChannelKind::Translation;
        bool bytes = false;  // a rotation in normalized bytes, not shorts
    };
    [[nodiscard]] tinygltf::Accessor time_accessor(int view, const Channel& c) const;
    [[nodiscard]] static tinygltf::Accessor value_accessor(int view, const Channel& c);
    [[nodiscard]] bool shared_times(const Channel& c) const { return c.times == 0 || (ends_ != 0 && c.times == ends_); }
    SpillFile data_;
    std::uint64_t bytes_ = 0;
    std::uint64_t local_bytes_ = 0;   // of bytes_, those in data_ (less after join())
    std::uint64_t shared_bytes_ = 0;  // the shared key times the tail starts with
    std::uint64_t written_at_ = 0;
    bool meshopt_ = false;
    MeshoptStreams streams_;
    std::vector<Channel> channels_;
    std::size_t next_ = 0;
    std::uint32_t frames_ = 0;
    double first_time_ = 0.0;
    double last_time_ = 0.0;
    std::uint64_t ends_ = 0;  // offset of the shared first and last times (0: none)
    std::unordered_map<std::uint64_t, int> time_accessors_;  // by offset
    // Per item (count + 1 entries): its first channel, and how many accessors the items
    // before it make (streamed use).
    std::vector<std::uint64_t> item_channels_;
    std::vector<std::uint64_t> item_accessors_;
    int all_frames_accessor_ = -1;
    int ends_accessor_ = -1;
    GlbCompactionStats stats_;
};

}  // namespace kodawari::gltf
