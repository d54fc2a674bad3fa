#pragma once
/// @file
/// Animated PNG output (APNG: PNG with the acTL, fcTL and fdAT chunks), for previews that
/// play in browsers and show their first frame in any other PNG viewer. Frames are
/// streamed into the file as they are rendered, so memory does not grow with their count.

#include <cstdint>
#include <memory>
#include <string>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari::render {

struct Image;

/// How long each frame shows: numerator / denominator seconds (APNG's delay_num and
/// delay_den, both 16-bit; the denominator is never 0).
struct FrameDelay {
    std::uint16_t numerator = 1;
    std::uint16_t denominator = 60;
};

/// `step` / `fps` seconds as the closest fraction whose terms fit in 16 bits: exact for
/// a whole-number `fps` up to 65535 and `step` up to 65535 (e.g. step 4 at 60 fps: 1/15),
/// clamped to 65535 s. `fps` > 0.
[[nodiscard]] KODAWARI_API FrameDelay frame_delay(std::uint32_t step, double fps);

/// The shape of an animation, fixed before its first frame (APNG's acTL chunk, which
/// comes first, holds the frame count).
struct ApngSettings {
    std::uint32_t width = 0;        ///< every frame's width in pixels, >= 1
    std::uint32_t height = 0;       ///< every frame's height in pixels, >= 1
    std::uint32_t frame_count = 0;  ///< exactly how many frames add_frame() will get, >= 1
    FrameDelay delay;               ///< the same for every frame
    std::uint32_t plays = 0;        ///< times to play it; 0: loop forever
};

/// An APNG being written (8-bit RGBA, full frames, each replacing the last), through an
/// AtomicFile: nothing is at `path` until commit() succeeds, and a writer destroyed before
/// it leaves nothing.
class KODAWARI_API ApngWriter {
public:
    /// Starts the file. Errors name `path`: settings out of range, a file that cannot be
    /// created.
    [[nodiscard]] static Result<ApngWriter> open(const std::string& path, const ApngSettings& settings);

    ApngWriter(ApngWriter&& other) noexcept;
    ApngWriter& operator=(ApngWriter&& other) noexcept;
    ApngWriter(const ApngWriter&) = delete;
    ApngWriter& operator=(const ApngWriter&) = delete;
    ~ApngWriter();

    /// Compresses and writes the next frame. An image of another size than the settings',
    /// or one frame more than their count, is an error naming the file.
    [[nodiscard]] Result<void> add_frame(const Image& image);

    /// Ends the file and renames it into place; an error when fewer frames came than the
    /// settings promised, or when a write failed.
    [[nodiscard]] Result<void> commit();

    [[nodiscard]] const std::string& path() const;

private:
    struct State;
    explicit ApngWriter(std::unique_ptr<State> state);
    std::unique_ptr<State> state_;
};

}  // namespace kodawari::render
