// The points sink of the bake (kodawari/simulation/bake.hpp's make_points_glb_sink): a positions
// channel of any domain, kept frame by frame and written by write_points_glb(). It names
// no domain.
#include <cstring>
#include <string>
#include <vector>

#include "kodawari/simulation/bake.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari {

namespace {

class PointsGlbSink final : public BakeSink {
public:
    PointsGlbSink(std::string path, std::string channel, std::string name, float fps)
        : path_(std::move(path)), channel_(std::move(channel)), name_(std::move(name)), fps_(fps) {}

    BakeNeeds needs() const override { return {{channel_}}; }

    Result<void> begin(const BakeWorld& world) override {
        const auto info = world.channel(channel_);
        if (!info) {
            return make_error(Error::Kind::InvalidInput,
                              path_ + ": make_points_glb_sink: no domain of the scene has a channel \"" + channel_ + "\"");
        }
        if (info->element_bytes < sizeof(glm::vec3) || info->element_bytes % sizeof(float) != 0) {
            return make_error(Error::Kind::InvalidInput, path_ + ": make_points_glb_sink: channel \"" + channel_ +
                                                             "\" holds elements of " + std::to_string(info->element_bytes) +
                                                             " bytes, expected 3 or more floats (x, y, z first)");
        }
        stride_ = info->element_bytes;
        points_ = info->elements;
        frames_ = world.frames;
        positions_.reserve(std::size_t{frames_} * points_);
        return {};
    }

    Result<void> consume(const BakeFrames& frames) override {
        const std::span<const std::byte> bytes = frames.channel(channel_);
        for (std::size_t i = 0; i < std::size_t{frames.count} * points_; ++i) {
            glm::vec3 p;
            std::memcpy(&p, bytes.data() + i * stride_, sizeof p);
            positions_.push_back(p);
        }
        return {};
    }

    Result<std::vector<BakeOutput>> finish() override {
        KW_TRY(write_points_glb(path_, name_, fps_, frames_, positions_));
        return std::vector<BakeOutput>{{path_, BakeOutput::Format::Glb, "the points of channel " + channel_, {}}};
    }

private:
    std::string path_, channel_, name_;
    float fps_;
    std::size_t stride_ = 0;
    std::uint64_t points_ = 0;
    std::uint32_t frames_ = 0;
    std::vector<glm::vec3> positions_;
};

}  // namespace

std::unique_ptr<BakeSink> make_points_glb_sink(std::string path, std::string channel, std::string name, float fps) {
    return std::make_unique<PointsGlbSink>(std::move(path), std::move(channel), std::move(name), fps);
}

}  // namespace kodawari
