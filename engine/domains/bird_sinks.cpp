// The birds' glTF sink of the bake (kodawari/domains/birds.hpp): BirdGlbWriter fed with
// the "birds.poses" channel frame by frame.
#include <algorithm>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "kodawari/simulation/bake.hpp"
#include "kodawari/core/communicator.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari {

namespace {

// Streams: memory stays BirdGlbWriter's, whatever the frames.
class BirdsGlbSink final : public BakeSink {
public:
    BirdsGlbSink(std::string path, const GlbCompaction& compaction) : path_(std::move(path)), compaction_(compaction) {}

    BakeNeeds needs() const override { return {{std::string(kBirdPosesChannel)}}; }

    // The built-in wing types' birds at `path`; each user's model's birds in its own
    // glTF beside it, `<path without .glb>-<model>.glb`, or at `path` itself when the
    // scene's birds are all of one model (docs/bird-models.md).
    Result<void> begin(const BakeWorld& world) override {
        if (const Domain* domain = world.domain(kBirdDomain)) noun_ = domain->instance_noun();
        const birds::BirdWorld& birds = bird_world_of(world);
        if (birds.birds.empty()) return {};
        const auto& params = birds.birds;
        const bool built_in = std::any_of(params.begin(), params.end(),
                                          [](const gpu::BirdParams& p) { return p.ids.y < birds::kWingTypeCount; });
        if (built_in || birds.models.empty()) {
            auto writer = BirdGlbWriter::create(path_, birds, world.frames, compaction_);
            if (!writer) return writer.error();
            writer_.emplace(std::move(writer).value());
        }
        const std::string stem = glb_stem(path_);
        const bool alone = !built_in && birds.models.size() == 1;
        // Each flock loads its model, so two flocks of one file (or two files of one
        // stem) are two models of one name: the later ones get "-2", "-3", ..., or the
        // last file written would replace the others.
        std::set<std::string> used;
        for (std::size_t k = 0; k < birds.models.size(); ++k) {
            std::string name = birds.models[k]->name;
            for (int n = 2; !used.insert(name).second; ++n) name = birds.models[k]->name + "-" + std::to_string(n);
            const std::string path = alone ? path_ : stem + "-" + name + ".glb";
            auto model = BirdModelExport::create(birds, k, path, compaction_);
            if (!model) return model.error();
            models_.push_back(std::move(model).value());
        }
        return {};
    }

    Result<void> consume(const BakeFrames& frames) override {
        const auto poses = frames.channel_as<gpu::BirdPose>(kBirdPosesChannel);
        if (writer_) KW_TRY(writer_->add_frames(poses));
        for (BirdModelExport& model : models_) KW_TRY(model.add_frames(poses));
        return {};
    }

    Result<std::vector<BakeOutput>> finish() override {
        std::vector<BakeOutput> out;
        if (writer_) {
            KW_TRY(writer_->finish());
            std::optional<GlbCompactionStats> stats;
            if (compaction_.enabled) stats = writer_->compaction_stats();
            out.push_back({path_, BakeOutput::Format::Glb, "", stats});
        }
        for (BirdModelExport& model : models_) {
            KW_TRY(model.finish());
            std::optional<GlbCompactionStats> model_stats;
            if (compaction_.enabled) model_stats = model.compaction_stats();
            out.push_back({model.path(), BakeOutput::Format::Glb, "user's bird model", model_stats});
        }
        return out;
    }

    // A distributed bake's ranks each compact their own birds' channels (BirdGlbWriter's
    // share()); a user's model's birds go to files of their own, which rank 0 writes.
    bool can_share() const override { return writer_ && models_.empty() && writer_->can_share(); }
    std::string share_probe() const override { return path_; }

    Result<void> share(const ShardInfo& mine) override {
        if (!writer_) return BakeSink::share(mine);
        const ShardPart part = mine.part(noun_);
        return writer_->share(part.range.begin, part.range.end);
    }

    Result<std::vector<BakeOutput>> finish_shared(Communicator& ranks) override {
        if (!writer_) return BakeSink::finish_shared(ranks);
        KW_TRY(writer_->finish(ranks));
        if (ranks.rank() != 0) return std::vector<BakeOutput>{};
        return std::vector<BakeOutput>{{path_, BakeOutput::Format::Glb,
                                         "its birds' keys compacted on " + std::to_string(ranks.size()) + " ranks",
                                         writer_->compaction_stats()}};
    }

private:
    std::string noun_;  // what the bird domain calls its instances (ShardInfo's parts)
    std::string path_;
    GlbCompaction compaction_;
    std::optional<BirdGlbWriter> writer_;
    std::vector<BirdModelExport> models_;
};

}  // namespace

std::unique_ptr<BakeSink> make_birds_glb_sink(std::string path, const GlbCompaction& compaction) {
    return std::make_unique<BirdsGlbSink>(std::move(path), compaction);
}

const birds::BirdWorld& bird_world_of(const BakeWorld& world) {
    static const birds::BirdWorld none;
    const Domain* domain = world.domain(kBirdDomain);
    const birds::BirdWorld* birds = domain ? bird_world_of(*domain) : nullptr;
    return birds ? *birds : none;
}

}  // namespace kodawari
