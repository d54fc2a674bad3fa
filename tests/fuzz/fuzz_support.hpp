// What the fuzz targets share: a reader that turns the fuzzer's bytes into bounded
// values, a private scratch folder for targets that must hand a loader a real file,
// and the check that every number a successful load hands on is finite.
//
// Each target (fuzz_*.cpp) defines LLVMFuzzerTestOneInput only. It is linked twice:
// with libFuzzer (-fsanitize=fuzzer) in the `asan` preset, where `make fuzz` runs it,
// and with replay_main.cpp in every build, where ctest feeds it the kept corpus and the
// regressions (tests/fuzz/README.md).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <unistd.h>

namespace kodawari::fuzz {

/// Reads values off the front of the input; past its end every read gives 0, so any
/// input decodes (the same idea as LLVM's FuzzedDataProvider, which gcc's replay build
/// cannot include).
class ByteReader {
public:
    ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

    std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
    std::uint32_t u32() {
        std::uint32_t v = 0;
        for (int k = 0; k < 4; ++k) v = (v << 8) | byte();
        return v;
    }
    /// In [0, n] (n small).
    std::uint32_t upto(std::uint32_t n) { return n == 0 ? 0 : u32() % (n + 1); }
    bool flag() { return (byte() & 1) != 0; }
    /// Any float bit pattern one time in four (NaN, infinities, denormals), else a value
    /// in [-range, range]: loaders must reject the first kind and accept or reject the
    /// second with a message, never crash.
    float number(float range) {
        const std::uint8_t kind = byte();
        if ((kind & 3) == 0) {
            const std::uint32_t bits = u32();
            float f;
            std::memcpy(&f, &bits, sizeof f);
            return f;
        }
        return (static_cast<float>(u32()) / 4294967295.0f * 2.0f - 1.0f) * range;
    }
    /// The rest of the input.
    std::string_view rest() {
        const std::string_view r(reinterpret_cast<const char*>(data_ + pos_), size_ - pos_);
        pos_ = size_;
        return r;
    }

private:
    const std::uint8_t* data_;
    std::size_t size_;
    std::size_t pos_ = 0;
};

/// A folder of this process's own (libFuzzer's -jobs run several processes at once),
/// removed at exit.
inline const std::filesystem::path& scratch_dir() {
    static const std::filesystem::path dir = [] {
        // KODAWARI_FUZZ_SCRATCH: a fixed folder for scripts/fuzz --runs, whose runs must
        // repeat exactly (the path reaches messages and so comparisons libFuzzer learns
        // from); otherwise one per process, as fork mode runs several at once.
        const char* fixed = std::getenv("KODAWARI_FUZZ_SCRATCH");
        std::filesystem::path base = fixed != nullptr && *fixed != '\0'
                                         ? std::filesystem::path(fixed)
                                         : std::filesystem::temp_directory_path() /
                                               ("kodawari-fuzz-" + std::to_string(::getpid()));
        std::filesystem::create_directories(base);
        std::atexit([] {
            std::error_code ec;
            std::filesystem::remove_all(scratch_dir(), ec);
        });
        return base;
    }();
    return dir;
}

/// Writes `bytes` to `path` (whole, replacing what was there).
inline void write_file(const std::filesystem::path& path, const std::uint8_t* bytes, std::size_t size) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(size));
    if (!out) {
        std::fprintf(stderr, "fuzz: cannot write %s\n", path.string().c_str());
        std::abort();
    }
}

/// A finding of the harness itself: what was wrong, then abort() so that libFuzzer keeps
/// the input (and the replay test fails).
[[noreturn]] inline void finding(const std::string& what) {
    std::fprintf(stderr, "fuzz finding: %s\n", what.c_str());
    std::abort();
}

inline void require_finite(float v, const char* what) {
    if (!std::isfinite(v)) finding(std::string(what) + " is not finite after a successful load");
}

}  // namespace kodawari::fuzz
