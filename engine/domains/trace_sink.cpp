// The JSON Lines trace sink of the bake (kodawari/domains/trace.hpp): the birds' and the
// chains' channels, diagnostics included, frame by frame.
#include <optional>
#include <string>
#include <vector>

#include "kodawari/simulation/bake.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/domains/trace.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari {

namespace {

class TraceSink final : public BakeSink {
public:
    explicit TraceSink(std::string path) : path_(std::move(path)) {}

    BakeNeeds needs() const override {
        return {{std::string(kBirdPosesChannel), std::string(kBirdDiagChannel), std::string(kChainPositionsChannel),
                 std::string(kChainOrientationsChannel), std::string(kChainRestChannel),
                 std::string(kChainViewDirectionsChannel), std::string(kChainWeightsChannel)}};
    }

    Result<void> begin(const BakeWorld& world) override {
        birds_ = &bird_world_of(world);
        rods_ = rod_scene_of(world);
        auto t = TraceWriter::open(path_, {world.scene->name, birds_->fps, world.frames, world.backend});
        if (!t) return t.error();
        trace_.emplace(std::move(t).value());
        if (rods_ != nullptr) {
            // Per chain: its character instance and its index there (the trace's records).
            const RodScene& rods = *rods_;
            characters_.resize(rods.world.chains.size());
            within_.resize(rods.world.chains.size());
            for (std::uint32_t c = 0; c < rods.world.character_count; ++c) {
                for (std::uint32_t k = 0; k < rods.chain_count(c); ++k) {
                    characters_[rods.instances[c].chain_begin + k] = c;
                    within_[rods.instances[c].chain_begin + k] = k;
                }
            }
        }
        return {};
    }

    Result<void> consume(const BakeFrames& frames) override {
        const std::size_t count = birds_->birds.size();
        if (count > 0) {
            const auto poses = frames.channel_as<gpu::BirdPose>(kBirdPosesChannel);
            const auto diag = frames.channel_as<gpu::BirdDiag>(kBirdDiagChannel);
            for (std::uint32_t k = 0; k < frames.count; ++k) {
                trace_->write_frame(frames.first + k, *birds_, poses.subspan(std::size_t{k} * count, count),
                                    diag.subspan(std::size_t{k} * count, count));
            }
        }
        if (rods_ != nullptr) {
            const RodScene& rods = *rods_;
            snapshot_from(frames, snapshot_);
            trace_->write_chains(frames.first, rods.time(frames.first), rods.world, characters_, within_, rods.chain_names,
                                 snapshot_);
        }
        return {};
    }

    Result<std::vector<BakeOutput>> finish() override {
        KW_TRY(trace_->finish());
        return std::vector<BakeOutput>{{path_, BakeOutput::Format::Trace, "", {}}};
    }

private:
    std::string path_;
    const birds::BirdWorld* birds_ = nullptr;
    const RodScene* rods_ = nullptr;
    ChainSnapshot snapshot_;
    std::optional<TraceWriter> trace_;
    std::vector<std::uint32_t> characters_, within_;
};

}  // namespace

std::unique_ptr<BakeSink> make_trace_sink(std::string path) { return std::make_unique<TraceSink>(std::move(path)); }

}  // namespace kodawari
