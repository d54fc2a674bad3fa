#pragma once
// The scene builders' random numbers (flock_builder.cpp, character_builder.cpp). The
// output must be the same bits on every platform, so they come from std::mt19937_64 (its
// sequence is fixed by the standard) and are mapped to [0, 1) here rather than by
// std::uniform_*_distribution, whose algorithm each standard library chooses. Each
// purpose (a "stream") has its own generator, so that adding one kind of jitter does not
// move every other draw.

#include <cstdint>
#include <random>
#include <type_traits>

namespace kodawari::scene_detail {

inline std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

class SeededRandom {
public:
    /// The generator of `stream` (an enum of the caller's purposes) under `seed`.
    template <typename Stream>
        requires std::is_enum_v<Stream>
    SeededRandom(std::uint64_t seed, Stream stream)
        : engine_(splitmix64(splitmix64(seed) ^ static_cast<std::uint64_t>(stream))) {}

    /// Uniform in [0, 1): the top 53 bits of one 64-bit draw.
    double unit() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
    /// Uniform in [-1, 1). 2u is exact, so no rounding step can differ between compilers.
    double symmetric() { return 2.0 * unit() - 1.0; }

private:
    std::mt19937_64 engine_;
};

}  // namespace kodawari::scene_detail
