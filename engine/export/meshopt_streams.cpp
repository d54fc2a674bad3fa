// `--compact --meshopt`: see meshopt_streams.hpp.
#include "export/meshopt_streams.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <meshoptimizer.h>

#include "export/gltf_json_stream.hpp"

namespace kodawari::gltf {
namespace {

// The codec's size for `count` elements of `stride` bytes, less what a stream pays once
// (its header byte and its 32-byte tail: spec Appendix A), since a channel's keys go into
// a stream that others share: the channels' choices compare what each adds.
std::size_t codec_bytes(const void* data, std::size_t count, std::size_t stride, std::vector<unsigned char>& scratch) {
    if (count == 0) return 0;
    scratch.resize(meshopt_encodeVertexBufferBound(count, stride));
    const std::size_t size = meshopt_encodeVertexBuffer(scratch.data(), scratch.size(), data, count, stride);
    const std::size_t once = 1 + std::max<std::size_t>(stride, 32);
    return size > once ? size - once : 0;
}

// The candidates of one channel, the smallest kept: `frames` keys at most, `stride` bytes
// a key in `encoded` (every frame's filter input), key times of its own unless it keeps
// every frame or only the ends (then shared).
class Chooser {
public:
    Chooser(std::span<const float> times, std::size_t stride) : times_(times), stride_(stride) {}

    void consider(Reduction&& r, int bits, const unsigned char* encoded) {
        const std::size_t frames = times_.size();
        keys_.resize(r.kept.size() * stride_);
        for (std::size_t k = 0; k < r.kept.size(); ++k) {
            std::memcpy(keys_.data() + k * stride_, encoded + std::size_t{r.kept[k]} * stride_, stride_);
        }
        std::size_t size = codec_bytes(keys_.data(), r.kept.size(), stride_, scratch_);
        if (r.kept.size() != frames && r.kept.size() != 2) {
            kept_times_.clear();
            for (const std::uint32_t f : r.kept) kept_times_.push_back(times_[f]);
            size += codec_bytes(kept_times_.data(), kept_times_.size(), sizeof(float), scratch_);
        }
        if (size < best_size_) {
            best_size_ = size;
            best_.reduction = std::move(r);
            best_.bits = bits;
            best_.encoded = keys_;
        }
    }
    [[nodiscard]] bool chosen() const { return best_size_ != std::numeric_limits<std::size_t>::max(); }
    [[nodiscard]] MeshoptChannel take() { return std::move(best_); }

private:
    std::span<const float> times_;
    std::size_t stride_;
    std::vector<unsigned char> keys_;
    std::vector<unsigned char> scratch_;
    std::vector<float> kept_times_;
    std::size_t best_size_ = std::numeric_limits<std::size_t>::max();
    MeshoptChannel best_;
};

Reduction every_frame(std::size_t frames, double error) {
    Reduction r;
    r.kept.resize(frames);
    for (std::size_t f = 0; f < frames; ++f) r.kept[f] = static_cast<std::uint32_t>(f);
    r.max_error = error;
    return r;
}

const char* filter_name(MeshoptStream s) {
    return s == MeshoptStream::Times ? "NONE" : s == MeshoptStream::Vectors ? "EXPONENTIAL" : "QUATERNION";
}

}  // namespace

double meshopt_decoder_latitude() { return 2.0 * std::asin(2.0 / 32767.0); }

void quaternion_filter(std::span<const float> xyzw, int bits, std::span<std::int16_t> encoded, std::span<std::int16_t> decoded) {
    const std::size_t count = xyzw.size() / 4;
    if (count == 0) return;
    meshopt_encodeFilterQuat(encoded.data(), count, 8, bits, xyzw.data());
    std::copy(encoded.begin(), encoded.end(), decoded.begin());
    meshopt_decodeFilterQuat(decoded.data(), count, 8);
}

void exponential_filter(std::span<const float> xyz, int bits, std::span<std::uint32_t> encoded, std::span<float> decoded) {
    const std::size_t count = xyz.size() / 3;
    if (count == 0) return;
    meshopt_encodeFilterExp(encoded.data(), count, 12, bits, xyz.data());
    std::memcpy(decoded.data(), encoded.data(), encoded.size_bytes());
    meshopt_decodeFilterExp(decoded.data(), count, 12);
}

MeshoptChannel choose_rotation(std::span<const float> times, std::span<const float> xyzw, double bound) {
    const std::size_t frames = times.size();
    const double budget = bound - meshopt_decoder_latitude();
    std::vector<std::int16_t> encoded(xyzw.size());
    std::vector<std::int16_t> decoded(xyzw.size());
    Chooser chooser(times, 8);
    // From 16 bits down, while the rounding alone leaves room: fewer bits make smaller
    // keys but leave less of the bound to interpolation, so more keys.
    for (int bits = 16; bits >= 4; --bits) {
        quaternion_filter(xyzw, bits, encoded, decoded);
        const double rounding = rounding_error(xyzw, decoded);
        if (!(rounding <= budget)) break;
        Reduction reduced = reduce_rotations(times, xyzw, decoded, budget, RotationBits::Short, true);
        const bool all = reduced.kept.size() == frames;
        chooser.consider(std::move(reduced), bits, reinterpret_cast<const unsigned char*>(encoded.data()));
        if (!all) chooser.consider(every_frame(frames, rounding), bits, reinterpret_cast<const unsigned char*>(encoded.data()));
    }
    if (chooser.chosen()) return chooser.take();
    // A bound below 16 bits' rounding and the decoders' latitude: every key, at 16 bits.
    quaternion_filter(xyzw, 16, encoded, decoded);
    chooser.consider(every_frame(frames, rounding_error(xyzw, decoded) + meshopt_decoder_latitude()), 16,
                     reinterpret_cast<const unsigned char*>(encoded.data()));
    return chooser.take();
}

MeshoptChannel choose_vector(std::span<const float> times, std::span<const float> xyz, double bound, VectorMetric metric) {
    const std::size_t frames = times.size();
    std::vector<std::uint32_t> encoded(xyz.size());
    std::vector<float> decoded(xyz.size());
    Chooser chooser(times, 12);
    const auto rounding_of = [&] {
        double worst = 0.0;
        for (std::size_t k = 0; k < xyz.size(); k += 3) {
            double distance = 0.0;
            double relative = 0.0;
            for (std::size_t c = 0; c < 3; ++c) {
                const double v = xyz[k + c];
                const double d = std::abs(static_cast<double>(decoded[k + c]) - v);
                distance += d * d;
                if (d > 0.0) relative = std::max(relative, v != 0.0 ? d / std::abs(v) : std::numeric_limits<double>::infinity());
            }
            worst = std::max(worst, metric == VectorMetric::Distance ? std::sqrt(distance) : relative);
        }
        return worst;
    };
    // 24 bits (a float's precision) down, as for rotations.
    for (int bits = 24; bits >= 1; --bits) {
        exponential_filter(xyz, bits, encoded, decoded);
        const double rounding = rounding_of();
        if (!(rounding <= bound)) break;
        Reduction reduced = reduce_vec3(times, xyz, decoded, bound, metric);
        const bool all = reduced.kept.size() == frames;
        chooser.consider(std::move(reduced), bits, reinterpret_cast<const unsigned char*>(encoded.data()));
        if (!all) chooser.consider(every_frame(frames, rounding), bits, reinterpret_cast<const unsigned char*>(encoded.data()));
    }
    if (chooser.chosen()) return chooser.take();
    // A bound below 24 bits' rounding (0 most often): every key, at 24 bits.
    exponential_filter(xyz, 24, encoded, decoded);
    chooser.consider(every_frame(frames, rounding_of()), 24, reinterpret_cast<const unsigned char*>(encoded.data()));
    return chooser.take();
}

Result<std::uint64_t> MeshoptStreams::append(MeshoptStream stream, const void* data, std::size_t count, SpillFile& tail,
                                             std::uint64_t& tail_bytes) {
    const auto s = static_cast<std::size_t>(stream);
    const std::size_t bytes = count * stride_of(stream);
    if (open_[s] >= 0 && !raw_[s].empty() && raw_[s].size() + bytes > kChunkBytes) KW_TRY(close(stream, tail, tail_bytes));
    if (open_[s] < 0) {
        open_[s] = static_cast<int>(chunks_.size());
        chunks_.push_back(Chunk{stream, 0, 0, 0});
        raw_[s].clear();
    }
    const std::uint64_t location = (static_cast<std::uint64_t>(open_[s]) << kChunkShift) | raw_[s].size();
    const auto* from = static_cast<const unsigned char*>(data);
    raw_[s].insert(raw_[s].end(), from, from + bytes);
    chunks_[static_cast<std::size_t>(open_[s])].count += count;
    return location;
}

Result<void> MeshoptStreams::close(MeshoptStream stream, SpillFile& tail, std::uint64_t& tail_bytes) {
    const auto s = static_cast<std::size_t>(stream);
    Chunk& chunk = chunks_.at(static_cast<std::size_t>(open_[s]));
    const std::size_t stride = stride_of(stream);
    std::vector<unsigned char> out(meshopt_encodeVertexBufferBound(chunk.count, stride));
    const std::size_t size = meshopt_encodeVertexBuffer(out.data(), out.size(), raw_[s].data(), chunk.count, stride);
    if (size == 0) return make_error(Error::Kind::Internal, "meshopt: the vertex codec refused a stream");
    // Each view's compressed bytes start on a 4-byte boundary, as buffer views' data do.
    out.resize((size + 3) / 4 * 4, 0);
    KW_TRY(tail.append(out.data(), out.size()));
    chunk.compressed_at = tail_bytes;
    chunk.compressed_bytes = size;
    tail_bytes += out.size();
    open_[s] = -1;
    raw_[s].clear();
    raw_[s].shrink_to_fit();
    return {};
}

Result<void> MeshoptStreams::finish(SpillFile& tail, std::uint64_t& tail_bytes) {
    // In chunk order, so the tail's order does not depend on which stream filled first.
    std::vector<MeshoptStream> open;
    for (std::size_t s = 0; s < open_.size(); ++s) {
        if (open_[s] >= 0) open.push_back(static_cast<MeshoptStream>(s));
    }
    std::sort(open.begin(), open.end(),
              [&](MeshoptStream a, MeshoptStream b) { return open_[static_cast<std::size_t>(a)] < open_[static_cast<std::size_t>(b)]; });
    for (const MeshoptStream s : open) KW_TRY(close(s, tail, tail_bytes));
    return {};
}

std::uint64_t MeshoptStreams::fallback_bytes() const {
    std::uint64_t total = 0;
    for (const Chunk& c : chunks_) total += c.count * stride_of(c.stream);
    return total;
}

int MeshoptStreams::add_views(tinygltf::Model& model, std::uint64_t head, MeshoptJson& json) const {
    model.buffers.emplace_back();  // the fallback buffer: its JSON from `json`
    json.fallback = static_cast<int>(model.buffers.size() - 1);
    json.fallback_bytes = fallback_bytes();
    json.first_view = static_cast<int>(model.bufferViews.size());
    json.views.clear();
    std::uint64_t at = 0;
    for (const Chunk& c : chunks_) {
        tinygltf::BufferView view;
        view.buffer = json.fallback;
        view.byteOffset = at;
        view.byteLength = c.count * stride_of(c.stream);
        at += view.byteLength;
        model.bufferViews.push_back(view);
        json.views.push_back(MeshoptJson::View{head + c.compressed_at, c.compressed_bytes,
                                               static_cast<std::uint32_t>(stride_of(c.stream)), c.count, filter_name(c.stream)});
    }
    for (auto* list : {&model.extensionsUsed, &model.extensionsRequired}) {
        if (std::find(list->begin(), list->end(), "EXT_meshopt_compression") == list->end()) {
            list->push_back("EXT_meshopt_compression");
        }
    }
    return json.first_view;
}

}  // namespace kodawari::gltf
