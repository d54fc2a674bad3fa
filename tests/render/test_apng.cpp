// The APNG writer (kodawari/render/apng.hpp) and `kodawari render --animation`, checked
// with a decoder written here from the PNG and APNG specifications: every chunk's CRC, the
// sequence numbers shared by fcTL and fdAT, the frame count and loop count of acTL, each
// frame's delay, and its pixels inflated with zlib and unfiltered, compared with the
// frames themselves (and with the PNG files the same render wrote, decoded by stb_image).

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <stb/stb_image.h>

#include "kodawari/render/apng.hpp"
#include "kodawari/render/renderer.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

namespace kodawari {
namespace {

using render::Image;
using testing_support::TempDir;

struct DecodedFrame {
    std::uint16_t delay_num = 0, delay_den = 0;
    std::vector<std::uint8_t> rgba;
};

struct DecodedApng {
    std::uint32_t width = 0, height = 0, num_frames = 0, num_plays = 0;
    std::vector<DecodedFrame> frames;
    std::size_t data_chunks = 0;         // IDAT and fdAT: more than frames when a frame is split
    std::array<int, 5> filter_rows{};    // rows per PNG filter type, to see that each is exercised
    std::string error;                   // the first thing wrong; "" when the file is valid
};

std::uint32_t be32(const std::uint8_t* p) {
    return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}
std::uint16_t be16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }

// PNG's reconstruction of filtered scanlines (specification section 9), RGBA8.
bool unfilter(const std::vector<std::uint8_t>& raw, std::uint32_t width, std::uint32_t height, DecodedApng& out,
              std::vector<std::uint8_t>& rgba) {
    const std::size_t stride = std::size_t{width} * 4;
    if (raw.size() != (stride + 1) * height) return false;
    rgba.assign(stride * height, 0);
    for (std::uint32_t y = 0; y < height; ++y) {
        const std::uint8_t type = raw[y * (stride + 1)];
        if (type > 4) return false;
        ++out.filter_rows[type];
        const std::uint8_t* in = &raw[y * (stride + 1) + 1];
        std::uint8_t* row = &rgba[y * stride];
        const std::uint8_t* up = y > 0 ? row - stride : nullptr;
        for (std::size_t i = 0; i < stride; ++i) {
            const int a = i >= 4 ? row[i - 4] : 0, b = up ? up[i] : 0, c = (up && i >= 4) ? up[i - 4] : 0;
            int pred = 0;
            if (type == 1) pred = a;
            if (type == 2) pred = b;
            if (type == 3) pred = (a + b) >> 1;
            if (type == 4) {
                const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
                pred = (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
            }
            row[i] = static_cast<std::uint8_t>(in[i] + pred);
        }
    }
    return true;
}

bool inflate_all(const std::vector<std::uint8_t>& in, std::vector<std::uint8_t>& out) {
    z_stream z{};
    if (inflateInit(&z) != Z_OK) return false;
    z.next_in = const_cast<Bytef*>(in.data());
    z.avail_in = static_cast<uInt>(in.size());
    std::vector<std::uint8_t> buffer(1 << 16);
    int status = Z_OK;
    while (status == Z_OK) {
        z.next_out = buffer.data();
        z.avail_out = static_cast<uInt>(buffer.size());
        status = inflate(&z, Z_NO_FLUSH);
        out.insert(out.end(), buffer.data(), buffer.data() + (buffer.size() - z.avail_out));
    }
    inflateEnd(&z);
    return status == Z_STREAM_END && z.avail_in == 0;
}

DecodedApng decode_apng(const std::string& bytes) {
    DecodedApng d;
    const auto* p = reinterpret_cast<const std::uint8_t*>(bytes.data());
    const auto fail = [&](const std::string& why) {
        d.error = why;
        return d;
    };
    static const std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (bytes.size() < 8 || std::memcmp(p, kSignature, 8) != 0) return fail("no PNG signature");
    std::size_t at = 8;
    std::uint32_t next_sequence = 0;
    bool seen_actl = false, seen_iend = false, frame_open = false;
    std::vector<std::uint8_t> compressed;
    const auto finish_frame = [&]() -> bool {
        if (!frame_open) return true;
        frame_open = false;
        std::vector<std::uint8_t> raw;
        if (!inflate_all(compressed, raw)) return false;
        compressed.clear();
        return unfilter(raw, d.width, d.height, d, d.frames.back().rgba);
    };
    for (int index = 0; at < bytes.size(); ++index) {
        if (seen_iend) return fail("bytes after IEND");
        if (bytes.size() - at < 12) return fail("a truncated chunk");
        const std::uint32_t length = be32(p + at);
        if (bytes.size() - at - 12 < length) return fail("a chunk longer than the file");
        const std::string type(bytes.data() + at + 4, 4);
        const std::uint8_t* data = p + at + 8;
        const uLong crc = crc32(crc32(0L, Z_NULL, 0), p + at + 4, length + 4);
        if (crc != be32(data + length)) return fail(type + " chunk " + std::to_string(index) + ": bad CRC");
        at += 12 + length;
        if (index == 0 && type != "IHDR") return fail("IHDR is not first");
        if (type == "IHDR") {
            if (length != 13) return fail("IHDR length");
            d.width = be32(data);
            d.height = be32(data + 4);
            if (data[8] != 8 || data[9] != 6 || data[10] != 0 || data[11] != 0 || data[12] != 0) return fail("not 8-bit RGBA");
        } else if (type == "acTL") {
            if (length != 8 || !d.frames.empty()) return fail("acTL misplaced");
            seen_actl = true;
            d.num_frames = be32(data);
            d.num_plays = be32(data + 4);
        } else if (type == "fcTL") {
            if (!seen_actl || length != 26) return fail("fcTL before acTL or of the wrong length");
            if (be32(data) != next_sequence++) return fail("fcTL sequence number " + std::to_string(be32(data)));
            if (!finish_frame()) return fail("frame " + std::to_string(d.frames.size() - 1) + ": bad pixel data");
            if (be32(data + 4) != d.width || be32(data + 8) != d.height || be32(data + 12) != 0 || be32(data + 16) != 0) {
                return fail("a frame that is not the whole image");
            }
            if (data[24] != 0 || data[25] != 0) return fail("dispose_op or blend_op not 0");
            DecodedFrame frame;
            frame.delay_num = be16(data + 20);
            frame.delay_den = be16(data + 22);
            d.frames.push_back(std::move(frame));
            frame_open = true;
        } else if (type == "IDAT") {
            if (d.frames.size() != 1) return fail("IDAT is not frame 0 (no fcTL before it, or after fdAT)");
            compressed.insert(compressed.end(), data, data + length);
            ++d.data_chunks;
        } else if (type == "fdAT") {
            if (d.frames.size() < 2 || length < 4) return fail("fdAT before a second fcTL");
            if (be32(data) != next_sequence++) return fail("fdAT sequence number " + std::to_string(be32(data)));
            compressed.insert(compressed.end(), data + 4, data + length);
            ++d.data_chunks;
        } else if (type == "IEND") {
            seen_iend = true;
            if (!finish_frame()) return fail("last frame: bad pixel data");
        } else {
            return fail("unexpected chunk " + type);
        }
    }
    if (!seen_iend) return fail("no IEND");
    if (d.frames.size() != d.num_frames) return fail("acTL says " + std::to_string(d.num_frames) + " frames, the file has " +
                                                     std::to_string(d.frames.size()));
    return d;
}

// Frames that differ from each other everywhere and whose rows suit different filters.
Image synthetic_frame(std::uint32_t width, std::uint32_t height, std::uint32_t k) {
    Image image;
    image.width = width;
    image.height = height;
    image.rgba.resize(std::size_t{width} * height * 4);
    std::mt19937 noise(1234 + k);
    for (std::uint32_t y = 0; y < height; ++y) {
        for (std::uint32_t x = 0; x < width; ++x) {
            std::uint8_t* px = &image.rgba[(std::size_t{y} * width + x) * 4];
            const std::uint32_t band = (y / 5 + k) % 4;
            px[0] = static_cast<std::uint8_t>(band == 0 ? x * 3 + k : band == 1 ? y * 7 : band == 2 ? (x + y) * 5 : noise());
            px[1] = static_cast<std::uint8_t>(band == 3 ? noise() : 40 * k + x);
            px[2] = static_cast<std::uint8_t>((x * y + k) & 0xff);
            px[3] = static_cast<std::uint8_t>(k % 2 == 0 ? 255 : 128 + y);
        }
    }
    return image;
}

std::string write_frames(const TempDir& dir, const std::string& name, const std::vector<Image>& frames, render::FrameDelay delay) {
    const std::string path = dir.file(name);
    auto writer = render::ApngWriter::open(path, {frames[0].width, frames[0].height, static_cast<std::uint32_t>(frames.size()), delay, 0});
    EXPECT_TRUE(writer.ok()) << writer.error().message;
    for (const Image& frame : frames) {
        auto added = writer.value().add_frame(frame);
        EXPECT_TRUE(added.ok()) << added.error().message;
    }
    auto committed = writer.value().commit();
    EXPECT_TRUE(committed.ok()) << committed.error().message;
    return testing_support::file_bytes(path);
}

// The number of the first frame whose pixels are not `frames`'s, or -1.
int first_mismatch(const DecodedApng& d, const std::vector<Image>& frames) {
    for (std::size_t k = 0; k < frames.size(); ++k) {
        if (k >= d.frames.size() || d.frames[k].rgba != frames[k].rgba) return static_cast<int>(k);
    }
    return -1;
}

TEST(Apng, FramesComeBackExactlyWithTheirDelayAndLoop) {
    TempDir dir;
    std::vector<Image> frames;
    for (std::uint32_t k = 0; k < 7; ++k) frames.push_back(synthetic_frame(37, 23, k));  // 7: not a power of two
    const std::string bytes = write_frames(dir, "small.png", frames, {1, 15});
    const DecodedApng d = decode_apng(bytes);
    ASSERT_EQ(d.error, "");
    EXPECT_EQ(d.width, 37u);
    EXPECT_EQ(d.height, 23u);
    EXPECT_EQ(d.num_frames, 7u);
    EXPECT_EQ(d.num_plays, 0u);  // forever
    ASSERT_EQ(d.frames.size(), 7u);
    for (const DecodedFrame& f : d.frames) {
        EXPECT_EQ(f.delay_num, 1);
        EXPECT_EQ(f.delay_den, 15);
    }
    EXPECT_EQ(first_mismatch(d, frames), -1);
    std::printf("[ apng ] rows per filter type none/sub/up/average/paeth: %d %d %d %d %d\n", d.filter_rows[0], d.filter_rows[1],
                d.filter_rows[2], d.filter_rows[3], d.filter_rows[4]);
    for (int type = 1; type < 5; ++type) EXPECT_GT(d.filter_rows[type], 0) << "filter type " << type << " never chosen";
    // stb_image, which knows no APNG, reads the file as a still: frame 0.
    int w = 0, h = 0, n = 0;
    stbi_uc* still = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()), static_cast<int>(bytes.size()), &w,
                                           &h, &n, 4);
    ASSERT_NE(still, nullptr);
    EXPECT_TRUE(w == 37 && h == 23 && std::memcmp(still, frames[0].rgba.data(), frames[0].rgba.size()) == 0);
    stbi_image_free(still);
    // Same frames, same bytes.
    EXPECT_EQ(write_frames(dir, "again.png", frames, {1, 15}), bytes);
}

TEST(Apng, LargeFramesSplitIntoSeveralChunksInSequence) {
    TempDir dir;
    std::vector<Image> frames;
    for (std::uint32_t k = 0; k < 3; ++k) frames.push_back(synthetic_frame(301, 211, k));  // noise: > 64 KiB deflated
    const DecodedApng d = decode_apng(write_frames(dir, "large.png", frames, {7, 60}));
    ASSERT_EQ(d.error, "");
    EXPECT_GT(d.data_chunks, frames.size());
    EXPECT_EQ(first_mismatch(d, frames), -1);
    EXPECT_EQ(d.frames[2].delay_num, 7);
    EXPECT_EQ(d.frames[2].delay_den, 60);
}

// The decoder and the comparison catch what they are there to catch.
TEST(Apng, TheChecksFailOnBrokenFiles) {
    TempDir dir;
    std::vector<Image> frames;
    for (std::uint32_t k = 0; k < 5; ++k) frames.push_back(synthetic_frame(29, 17, k));
    const std::string good = write_frames(dir, "good.png", frames, {1, 30});
    ASSERT_EQ(decode_apng(good).error, "");

    // Two frames swapped once: a valid file, but frame 1 is not frame 1.
    std::vector<Image> swapped = frames;
    std::swap(swapped[1], swapped[2]);
    const DecodedApng d = decode_apng(write_frames(dir, "swapped.png", swapped, {1, 30}));
    ASSERT_EQ(d.error, "");
    EXPECT_EQ(first_mismatch(d, frames), 1);

    // One byte of the last chunk's data changed: its CRC no longer matches.
    std::string corrupt = good;
    corrupt[corrupt.size() - 12 - 10] ^= 0x01;  // inside the last fdAT (IEND is the last 12 bytes)
    EXPECT_NE(decode_apng(corrupt).error.find("bad CRC"), std::string::npos) << decode_apng(corrupt).error;

    // A sequence number skipped (the second fcTL's, at 8 + 25 IHDR + 20 acTL + 38 fcTL + the
    // IDAT), with its CRC made right so that only the number is wrong.
    std::string skipped = good;
    const std::size_t idat = 8 + 25 + 20 + 38;
    const std::size_t fctl1 = idat + 12 + be32(reinterpret_cast<const std::uint8_t*>(skipped.data()) + idat);
    ASSERT_EQ(skipped.substr(fctl1 + 4, 4), "fcTL");
    skipped[fctl1 + 8 + 3] = 5;
    const uLong crc = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(skipped.data()) + fctl1 + 4, 30);
    for (int i = 0; i < 4; ++i) skipped[fctl1 + 34 + i] = static_cast<char>((crc >> (24 - 8 * i)) & 0xff);
    EXPECT_NE(decode_apng(skipped).error.find("sequence number 5"), std::string::npos) << decode_apng(skipped).error;

    // A frame count that promises more frames than there are.
    std::string more = good;
    more[8 + 25 + 8 + 3] = 6;
    const uLong actl_crc = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(more.data()) + 8 + 25 + 4, 12);
    for (int i = 0; i < 4; ++i) more[8 + 25 + 16 + i] = static_cast<char>((actl_crc >> (24 - 8 * i)) & 0xff);
    EXPECT_NE(decode_apng(more).error.find("acTL says 6"), std::string::npos) << decode_apng(more).error;
}

TEST(Apng, WriterRefusesMistakesAndLeavesNothing) {
    TempDir dir;
    const Image frame = synthetic_frame(8, 6, 0);
    const std::string path = dir.file("anim.png");
    {
        auto writer = render::ApngWriter::open(path, {8, 6, 3, {1, 60}, 0});
        ASSERT_TRUE(writer.ok()) << writer.error().message;
        auto wrong = writer.value().add_frame(synthetic_frame(9, 6, 1));
        ASSERT_FALSE(wrong.ok());
        EXPECT_NE(wrong.error().message.find(path), std::string::npos) << wrong.error().message;
        EXPECT_NE(wrong.error().message.find("9x6"), std::string::npos) << wrong.error().message;
        ASSERT_TRUE(writer.value().add_frame(frame).ok());
        auto early = writer.value().commit();
        ASSERT_FALSE(early.ok());
        EXPECT_NE(early.error().message.find("1 of its 3 frames"), std::string::npos) << early.error().message;
    }
    EXPECT_TRUE(dir.entries().empty()) << "left " << dir.entries().front();
    {
        auto writer = render::ApngWriter::open(path, {8, 6, 1, {1, 60}, 0});
        ASSERT_TRUE(writer.ok());
        ASSERT_TRUE(writer.value().add_frame(frame).ok());
        EXPECT_FALSE(writer.value().add_frame(frame).ok());
        ASSERT_TRUE(writer.value().commit().ok());  // a 1-frame animation is a valid file
        const DecodedApng d = decode_apng(testing_support::file_bytes(path));
        EXPECT_EQ(d.error, "");
        EXPECT_EQ(d.num_frames, 1u);
    }
    const std::string nowhere = dir.file("missing/anim.png");
    auto bad = render::ApngWriter::open(nowhere, {8, 6, 2, {1, 60}, 0});
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find(nowhere), std::string::npos) << bad.error().message;
    EXPECT_FALSE(render::ApngWriter::open(path, {8, 6, 0, {1, 60}, 0}).ok());
    EXPECT_FALSE(render::ApngWriter::open(path, {0, 6, 2, {1, 60}, 0}).ok());
}

TEST(Apng, FrameDelayIsStepOverFps) {
    const auto is = [](render::FrameDelay d, int num, int den) { return d.numerator == num && d.denominator == den; };
    EXPECT_TRUE(is(render::frame_delay(4, 60.0), 1, 15));
    EXPECT_TRUE(is(render::frame_delay(1, 60.0), 1, 60));
    EXPECT_TRUE(is(render::frame_delay(7, 60.0), 7, 60));
    EXPECT_TRUE(is(render::frame_delay(3, 24.0), 1, 8));
    EXPECT_TRUE(is(render::frame_delay(90, 30.0), 3, 1));
    EXPECT_TRUE(is(render::frame_delay(100000, 0.01), 65535, 1));  // clamped to the longest APNG delay
    // A rate that is no whole number (the loader's float): the nearest fraction that fits.
    const render::FrameDelay ntsc = render::frame_delay(2, static_cast<double>(29.97f));
    EXPECT_NEAR(static_cast<double>(ntsc.numerator) / ntsc.denominator, 2.0 / static_cast<double>(29.97f), 1e-8);
    EXPECT_TRUE(is(ntsc, 200, 2997)) << ntsc.numerator << "/" << ntsc.denominator;
}

std::vector<std::uint8_t> load_png_rgba(const std::string& path, int& w, int& h) {
    int n = 0;
    stbi_uc* data = stbi_load(path.c_str(), &w, &h, &n, 4);
    if (data == nullptr) return {};
    std::vector<std::uint8_t> rgba(data, data + std::size_t(w) * h * 4);
    stbi_image_free(data);
    return rgba;
}

// `kodawari render --animation`: frame k of the animation is the PNG frame k the same
// render wrote; --animation-size shrinks each as render::downscale does.
TEST(Apng, RenderCommandWritesTheFramesItDraws) {
    if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    TempDir dir;
    const std::string cli = testing_support::shell_quote(KODAWARI_CLI);
    const std::string scene = testing_support::shell_quote(std::string(KODAWARI_SOURCE_DIR) + "/scenes/ahoge.json");
    const std::string anim = dir.file("ahoge.png"), small = dir.file("small.png");
    std::string output;
    // Frames 3, 7, ..., 27: seven of them; the ahoge scene runs at 60 fps.
    ASSERT_EQ(testing_support::run_command(cli + " render " + scene + " --frames 3:30:4 --size 96x64 --backend cpu --out " +
                                               testing_support::shell_quote(dir.file("frames")) + " --animation " +
                                               testing_support::shell_quote(anim),
                                           output),
              0)
        << output;
    EXPECT_NE(output.find("wrote animation " + anim + " (7 frames, 96x64, 1/15 s each, looping)"), std::string::npos) << output;
    ASSERT_EQ(testing_support::run_command(cli + " render " + scene + " --frames 3:30:4 --size 96x64 --backend cpu --out " +
                                               testing_support::shell_quote(dir.file("frames2")) + " --animation " +
                                               testing_support::shell_quote(small) + " --animation-size 35x21",
                                           output),
              0)
        << output;
    const DecodedApng d = decode_apng(testing_support::file_bytes(anim));
    const DecodedApng s = decode_apng(testing_support::file_bytes(small));
    ASSERT_EQ(d.error, "");
    ASSERT_EQ(s.error, "");
    EXPECT_EQ(d.num_frames, 7u);
    EXPECT_EQ(d.num_plays, 0u);
    ASSERT_EQ(d.frames.size(), 7u);
    ASSERT_EQ(s.frames.size(), 7u);
    EXPECT_TRUE(d.width == 96 && d.height == 64 && s.width == 35 && s.height == 21);
    std::vector<Image> pngs;
    for (std::uint32_t k = 0; k < 7; ++k) {
        char name[32];
        std::snprintf(name, sizeof name, "frames/ahoge_%05u.png", 3 + 4 * k);
        Image png;
        int w = 0, h = 0;
        png.rgba = load_png_rgba(dir.file(name), w, h);
        ASSERT_FALSE(png.rgba.empty()) << name;
        png.width = static_cast<std::uint32_t>(w);
        png.height = static_cast<std::uint32_t>(h);
        EXPECT_EQ(d.frames[k].delay_num, 1);
        EXPECT_EQ(d.frames[k].delay_den, 15);
        EXPECT_TRUE(d.frames[k].rgba == png.rgba) << "animation frame " << k << " is not " << name;
        EXPECT_TRUE(s.frames[k].rgba == render::downscale(png, 35, 21).rgba) << "small animation frame " << k;
        pngs.push_back(std::move(png));
    }
    // The frames differ from one another, so an animation out of order would fail above.
    for (std::size_t k = 1; k < pngs.size(); ++k) EXPECT_NE(pngs[k].rgba, pngs[k - 1].rgba) << "frames " << k - 1 << " and " << k;
}

}  // namespace
}  // namespace kodawari
