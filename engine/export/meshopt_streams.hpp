#pragma once
// `--compact --meshopt` (docs/compact.md): compacted animation keys quantized per channel
// and written with meshoptimizer's attribute codec as EXT_meshopt_compression (the spec:
// KhronosGroup/glTF, extensions/2.0/Vendor/EXT_meshopt_compression/README.md, cited below
// as "the spec").
//
// Per channel (choose_rotation(), choose_vector()): every bit count the bound leaves room
// for is tried, the channel reduced (key_reduction.hpp) with the values a reader decodes in
// the loop, so the quantization counts in the bound; and of the reduced keys and all of
// them, at each bit count, the one the codec makes smallest is kept. Rotations go through
// the QUATERNION filter (spec Appendix B, filter 2: the three smallest components in K
// bits, 4 <= K <= 16, decoded to normalized shorts), translations and scales through the
// EXPONENTIAL filter (filter 3: a shared exponent and a K-bit mantissa per vector, decoded
// to floats, which glTF 2.0 §3.11 requires of them), key times unfiltered (floats, exact).
//
// The streams (MeshoptStreams): key times (stride 4), vectors (stride 12) and rotations
// (stride 8) each fill chunks of at most kChunkBytes decoded bytes; a chunk is one buffer
// view, encoded whole when it is full (mode ATTRIBUTES, the spec's Appendix A, bitstream
// version 0: what meshoptimizer 0.18 writes and every decoder reads) and appended to the
// compacted tail. Memory: one open chunk per stream. A channel's place is a location:
// its chunk (the buffer view, counted from the first) and its byte offset there.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "export/gltf_common.hpp"
#include "export/gltf_json_stream.hpp"
#include "export/key_reduction.hpp"

namespace kodawari::gltf {

/// What a decoder other than meshoptimizer's own may add to a rotation's error: the spec
/// (Appendix B) lets a filter's output be one unit off (1/32767) in each component, which
/// turns a unit quaternion by at most asin(2 / 32767) and the rotation by twice that,
/// 1.22e-4 rad. Rotation channels are reduced against the bound less this.
[[nodiscard]] KODAWARI_INTERNAL double meshopt_decoder_latitude();

/// The three streams, by what the spec allows each filter (a stride multiple of 4, at most
/// 256; the QUATERNION filter's 8).
enum class MeshoptStream : std::uint8_t { Times, Vectors, Rotations };
[[nodiscard]] constexpr std::size_t stride_of(MeshoptStream s) {
    return s == MeshoptStream::Times ? 4 : s == MeshoptStream::Vectors ? 12 : 8;
}

/// One channel as chosen: the frames kept, the largest error over every frame (as a reader
/// decodes and interpolates it), the filter's bits and the filter's input for the kept
/// keys (stride_of() bytes a key), ready for the stream.
struct MeshoptChannel {
    Reduction reduction;
    int bits = 0;
    std::vector<unsigned char> encoded;
};

/// A rotation channel (unit quaternions xyzw per frame, consecutive ones in one
/// hemisphere) within `bound` radians, the decoder latitude included.
[[nodiscard]] KODAWARI_INTERNAL MeshoptChannel choose_rotation(std::span<const float> times, std::span<const float> xyzw,
                                                               double bound);
/// A translation (Distance, metres) or scale (Relative) channel within `bound`.
[[nodiscard]] KODAWARI_INTERNAL MeshoptChannel choose_vector(std::span<const float> times, std::span<const float> xyz,
                                                             double bound, VectorMetric metric);

/// The QUATERNION filter's input for unit quaternions `xyzw` at `bits` (4 per key) and,
/// in `decoded`, what meshoptimizer's decoder gives back for it.
KODAWARI_INTERNAL void quaternion_filter(std::span<const float> xyzw, int bits, std::span<std::int16_t> encoded,
                                         std::span<std::int16_t> decoded);
/// The EXPONENTIAL filter's input for vec3s `xyz` with a `bits` mantissa (1 to 24) and an
/// exponent shared by each vector's components and, in `decoded`, the floats it decodes to.
KODAWARI_INTERNAL void exponential_filter(std::span<const float> xyz, int bits, std::span<std::uint32_t> encoded,
                                          std::span<float> decoded);

/// The key streams of one file.
class MeshoptStreams {
public:
    /// A chunk's decoded bytes at most (the memory of one open chunk, one buffer view).
    static constexpr std::size_t kChunkBytes = std::size_t{16} << 20;
    static constexpr int kChunkShift = 40;
    [[nodiscard]] static std::uint64_t chunk_of(std::uint64_t location) { return location >> kChunkShift; }
    [[nodiscard]] static std::uint64_t offset_of(std::uint64_t location) {
        return location & ((std::uint64_t{1} << kChunkShift) - 1);
    }

    /// Appends `count` elements of `stream` (stride_of() bytes each) and returns their
    /// location. A full chunk is encoded and appended to `tail`, `tail_bytes` counting.
    [[nodiscard]] Result<std::uint64_t> append(MeshoptStream stream, const void* data, std::size_t count, SpillFile& tail,
                                               std::uint64_t& tail_bytes);
    /// Encodes the chunks still open.
    [[nodiscard]] Result<void> finish(SpillFile& tail, std::uint64_t& tail_bytes);

    /// The decoded bytes of every chunk: the fallback buffer's byteLength.
    [[nodiscard]] std::uint64_t fallback_bytes() const;
    /// Adds the fallback buffer (index 1: the spec's "Fallback buffers", without a uri),
    /// a buffer view per chunk with its EXT_meshopt_compression object (its compressed
    /// bytes in buffer 0 from `head`, where the tail starts), and the extension to
    /// extensionsUsed and extensionsRequired (required: the fallback buffer holds nothing).
    /// Returns the first view's index. tinygltf 2.7 writes neither buffer nor buffer view
    /// extensions, nor a buffer's length without its data: `json` gets them, for
    /// write_streamed_glb().
    [[nodiscard]] int add_views(tinygltf::Model& model, std::uint64_t head, MeshoptJson& json) const;

private:
    struct Chunk {
        MeshoptStream stream = MeshoptStream::Times;
        std::uint64_t count = 0;
        std::uint64_t compressed_at = 0;
        std::uint64_t compressed_bytes = 0;
    };
    [[nodiscard]] Result<void> close(MeshoptStream stream, SpillFile& tail, std::uint64_t& tail_bytes);
    std::vector<Chunk> chunks_;
    std::array<int, 3> open_{-1, -1, -1};
    std::array<std::vector<unsigned char>, 3> raw_;
};

}  // namespace kodawari::gltf
