// Animated PNG writer (the APNG 1.0 extension of PNG): signature, IHDR, acTL, then per
// frame an fcTL and its pixels (the first frame in IDAT, so that a viewer without APNG
// shows it, the others in fdAT), IEND. Pixels are filtered here and deflated with zlib.

#include "kodawari/render/apng.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <utility>
#include <vector>

#include <zlib.h>

#include "kodawari/core/atomic_file.hpp"
#include "kodawari/render/renderer.hpp"

namespace kodawari::render {

FrameDelay frame_delay(std::uint32_t step, double fps) {
    assert(fps > 0.0 && step > 0);
    constexpr std::uint64_t kMax = 65535;
    const double seconds = static_cast<double>(step) / fps;
    if (seconds >= static_cast<double>(kMax)) return {static_cast<std::uint16_t>(kMax), 1};
    // A whole-number rate (the usual 24, 30, 60) gives the exact fraction step/fps in
    // lowest terms; any other rate the best continued-fraction convergent that fits.
    if (fps == std::floor(fps)) {
        std::uint64_t num = step, den = static_cast<std::uint64_t>(fps);
        std::uint64_t a = num, b = den;
        while (b != 0) a = std::exchange(b, a % b);
        num /= a;
        den /= a;
        if (num <= kMax && den <= kMax) return {static_cast<std::uint16_t>(num), static_cast<std::uint16_t>(den)};
    }
    std::uint64_t h0 = 0, h1 = 1, k0 = 1, k1 = 0;  // convergents h/k, previous and current
    double x = seconds;
    std::uint64_t best_h = static_cast<std::uint64_t>(std::llround(seconds * kMax)), best_k = kMax;
    for (int i = 0; i < 64; ++i) {
        const double a = std::floor(x);
        const auto ai = static_cast<std::uint64_t>(a);
        const std::uint64_t h2 = ai * h1 + h0, k2 = ai * k1 + k0;
        if (h2 > kMax || k2 > kMax) break;
        best_h = h2;
        best_k = k2;
        h0 = std::exchange(h1, h2);
        k0 = std::exchange(k1, k2);
        const double frac = x - a;
        if (frac < 1e-12) break;
        x = 1.0 / frac;
    }
    // Shorter than 1/65535 s: the shortest delay there is rather than none (0 means "as
    // fast as possible" to some players and 1/10 s to others).
    if (best_h == 0) best_h = 1;
    return {static_cast<std::uint16_t>(best_h), static_cast<std::uint16_t>(best_k)};
}

namespace {

constexpr std::array<unsigned char, 8> kSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
// The most deflated bytes held before they go out as a chunk: memory stays at this plus
// a few rows whatever the frame's size.
constexpr std::size_t kChunkBytes = std::size_t{1} << 16;

void put_u32(std::vector<unsigned char>& out, std::uint32_t v) {
    out.push_back(static_cast<unsigned char>(v >> 24));
    out.push_back(static_cast<unsigned char>(v >> 16));
    out.push_back(static_cast<unsigned char>(v >> 8));
    out.push_back(static_cast<unsigned char>(v));
}
void put_u16(std::vector<unsigned char>& out, std::uint16_t v) {
    out.push_back(static_cast<unsigned char>(v >> 8));
    out.push_back(static_cast<unsigned char>(v));
}

unsigned char paeth(int a, int b, int c) {
    const int p = a + b - c;
    const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
    if (pa <= pb && pa <= pc) return static_cast<unsigned char>(a);
    return static_cast<unsigned char>(pb <= pc ? b : c);
}

// `row` filtered with PNG filter `type` (0 none, 1 sub, 2 up, 3 average, 4 Paeth) against
// the row above, `prior` (zeros for the first), into out[1..], out[0] = type.
void filter_row(int type, const unsigned char* row, const unsigned char* prior, std::size_t bytes, unsigned char* out) {
    constexpr std::size_t kPixel = 4;
    out[0] = static_cast<unsigned char>(type);
    for (std::size_t i = 0; i < bytes; ++i) {
        const int left = i >= kPixel ? row[i - kPixel] : 0;
        const int up = prior[i];
        const int up_left = i >= kPixel ? prior[i - kPixel] : 0;
        int predicted = 0;
        switch (type) {
            case 1: predicted = left; break;
            case 2: predicted = up; break;
            case 3: predicted = (left + up) / 2; break;
            case 4: predicted = paeth(left, up, up_left); break;
            default: break;
        }
        out[1 + i] = static_cast<unsigned char>(row[i] - predicted);
    }
}

}  // namespace

struct ApngWriter::State {
    AtomicFile file;
    ApngSettings settings;
    std::uint32_t frames_written = 0;
    std::uint32_t sequence = 0;  // fcTL and fdAT share one count
    std::vector<unsigned char> chunk;
    std::optional<std::string> failure;  // a zlib error: commit() reports it

    State(AtomicFile f, const ApngSettings& s) : file(std::move(f)), settings(s) {}

    void write_chunk(const char* type, const std::vector<unsigned char>& data) {
        std::vector<unsigned char> head;
        put_u32(head, static_cast<std::uint32_t>(data.size()));
        head.insert(head.end(), type, type + 4);
        uLong crc = crc32(0L, Z_NULL, 0);
        crc = crc32(crc, reinterpret_cast<const Bytef*>(type), 4);
        // zlib's crc32 takes uInt lengths (a chunk here is at most kChunkBytes + 4) and
        // answers 0 for a null buffer, which an empty vector may have.
        if (!data.empty()) crc = crc32(crc, data.data(), static_cast<uInt>(data.size()));
        file.write(head.data(), head.size());
        file.write(data.data(), data.size());
        std::vector<unsigned char> tail;
        put_u32(tail, static_cast<std::uint32_t>(crc));
        file.write(tail.data(), tail.size());
    }

    // The deflated bytes so far as the frame's next data chunk: IDAT for the first frame,
    // fdAT (a sequence number, then the bytes) for the others.
    void flush_data(const unsigned char* data, std::size_t size) {
        if (size == 0) return;
        chunk.clear();
        if (frames_written > 0) put_u32(chunk, sequence++);
        chunk.insert(chunk.end(), data, data + size);
        write_chunk(frames_written == 0 ? "IDAT" : "fdAT", chunk);
    }
};

ApngWriter::ApngWriter(std::unique_ptr<State> state) : state_(std::move(state)) {}
ApngWriter::ApngWriter(ApngWriter&& other) noexcept = default;
ApngWriter& ApngWriter::operator=(ApngWriter&& other) noexcept = default;
ApngWriter::~ApngWriter() = default;

const std::string& ApngWriter::path() const { return state_->file.path(); }

Result<ApngWriter> ApngWriter::open(const std::string& path, const ApngSettings& settings) {
    // PNG sizes are 31-bit; the render sizes are far below, and the cap keeps a frame's
    // row arithmetic in range.
    constexpr std::uint32_t kMaxSide = 1u << 15;
    if (settings.width < 1 || settings.height < 1 || settings.width > kMaxSide || settings.height > kMaxSide) {
        return make_error(Error::Kind::InvalidInput, path + ": an animation's frames must be 1 to " +
                                                         std::to_string(kMaxSide) + " pixels on a side, not " +
                                                         std::to_string(settings.width) + "x" + std::to_string(settings.height));
    }
    if (settings.frame_count < 1) return make_error(Error::Kind::InvalidInput, path + ": an animation needs at least one frame");
    if (settings.delay.denominator == 0) {
        return make_error(Error::Kind::InvalidInput, path + ": the frame delay's denominator must not be 0");
    }
    auto file = AtomicFile::open(path);
    if (!file) return file.error();
    auto state = std::make_unique<State>(std::move(file).value(), settings);
    state->file.write(kSignature.data(), kSignature.size());
    std::vector<unsigned char> data;
    put_u32(data, settings.width);
    put_u32(data, settings.height);
    // 8 bits per sample, colour type 6 (RGBA), deflate, adaptive filtering, no interlace.
    data.insert(data.end(), {8, 6, 0, 0, 0});
    state->write_chunk("IHDR", data);
    data.clear();
    put_u32(data, settings.frame_count);
    put_u32(data, settings.plays);
    state->write_chunk("acTL", data);
    return ApngWriter(std::move(state));
}

Result<void> ApngWriter::add_frame(const Image& image) {
    State& s = *state_;
    const ApngSettings& set = s.settings;
    if (image.width != set.width || image.height != set.height) {
        return make_error(Error::Kind::InvalidInput, path() + ": frame " + std::to_string(s.frames_written) + " is " +
                                                         std::to_string(image.width) + "x" + std::to_string(image.height) +
                                                         ", the animation's frames are " + std::to_string(set.width) + "x" +
                                                         std::to_string(set.height));
    }
    if (s.frames_written == set.frame_count) {
        return make_error(Error::Kind::InvalidInput,
                          path() + ": the animation was opened for " + std::to_string(set.frame_count) + " frames, got one more");
    }
    if (s.failure) return make_error(Error::Kind::Internal, *s.failure);
    assert(image.rgba.size() == std::size_t{image.width} * image.height * 4);

    std::vector<unsigned char> control;
    put_u32(control, s.sequence++);
    put_u32(control, set.width);
    put_u32(control, set.height);
    put_u32(control, 0);  // x offset
    put_u32(control, 0);  // y offset
    put_u16(control, set.delay.numerator);
    put_u16(control, set.delay.denominator);
    // dispose_op NONE, blend_op SOURCE: each frame is whole and replaces the last, so
    // frame k on screen is exactly image k.
    control.push_back(0);
    control.push_back(0);
    s.write_chunk("fcTL", control);

    // Level 9 with zlib's defaults otherwise: the same zlib gives the same bytes.
    z_stream z{};
    if (deflateInit(&z, Z_BEST_COMPRESSION) != Z_OK) {
        s.failure = path() + ": zlib could not start compressing";
        return make_error(Error::Kind::Internal, *s.failure);
    }
    const std::size_t row_bytes = std::size_t{set.width} * 4;
    const std::vector<unsigned char> zeros(row_bytes, 0);
    // Each row takes the filter whose output has the smallest sum of magnitudes (as
    // signed bytes), libpng's heuristic: flat backgrounds and gradients deflate far better.
    std::array<std::vector<unsigned char>, 5> candidates;
    for (auto& c : candidates) c.resize(1 + row_bytes);
    std::vector<unsigned char> out(kChunkBytes);
    z.next_out = out.data();
    z.avail_out = static_cast<uInt>(out.size());
    int status = Z_OK;
    for (std::uint32_t y = 0; y < set.height && status == Z_OK; ++y) {
        const unsigned char* row = image.rgba.data() + y * row_bytes;
        const unsigned char* prior = y == 0 ? zeros.data() : row - row_bytes;
        std::size_t best = 0;
        std::uint64_t best_cost = UINT64_MAX;
        for (int type = 0; type < 5; ++type) {
            filter_row(type, row, prior, row_bytes, candidates[type].data());
            std::uint64_t cost = 0;
            for (std::size_t i = 1; i <= row_bytes; ++i) {
                cost += static_cast<std::uint64_t>(std::abs(static_cast<signed char>(candidates[type][i])));
            }
            if (cost < best_cost) {
                best_cost = cost;
                best = static_cast<std::size_t>(type);
            }
        }
        z.next_in = candidates[best].data();
        z.avail_in = static_cast<uInt>(candidates[best].size());
        const int flush = y + 1 == set.height ? Z_FINISH : Z_NO_FLUSH;
        for (;;) {
            status = deflate(&z, flush);
            if (status == Z_STREAM_ERROR) break;
            if (z.avail_out == 0) {
                s.flush_data(out.data(), out.size());
                z.next_out = out.data();
                z.avail_out = static_cast<uInt>(out.size());
                continue;
            }
            if (z.avail_in == 0 && (flush == Z_NO_FLUSH || status == Z_STREAM_END)) break;
        }
        if (status == Z_STREAM_END) break;
    }
    deflateEnd(&z);
    if (status != Z_STREAM_END) {
        s.failure = path() + ": zlib failed compressing frame " + std::to_string(s.frames_written);
        return make_error(Error::Kind::Internal, *s.failure);
    }
    s.flush_data(out.data(), out.size() - z.avail_out);
    ++s.frames_written;
    return {};
}

Result<void> ApngWriter::commit() {
    State& s = *state_;
    if (s.failure) return make_error(Error::Kind::Internal, *s.failure);
    if (s.frames_written != s.settings.frame_count) {
        return make_error(Error::Kind::Internal, path() + ": the animation got " + std::to_string(s.frames_written) + " of its " +
                                                     std::to_string(s.settings.frame_count) + " frames");
    }
    s.write_chunk("IEND", {});
    return s.file.commit();
}

}  // namespace kodawari::render
