// The bake's sinks (kodawari/bake.hpp): the glTF writers and the trace, fed frame by frame.
#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "kodawari/bake.hpp"
#include "kodawari/export.hpp"

namespace kodawari {

namespace {

// Streams: memory stays BirdGlbWriter's, whatever the frames.
class BirdsGlbSink final : public BakeSink {
public:
    BirdsGlbSink(std::string path, const GlbCompaction& compaction) : path_(std::move(path)), compaction_(compaction) {}

    BakeNeeds needs() const override { return {.bird_poses = true}; }

    // The built-in wing types' birds at `path`; each user's model's birds in its own
    // glTF beside it, `<path without .glb>-<model>.glb`, or at `path` itself when the
    // scene's birds are all of one model (docs/bird-models.md).
    Result<void> begin(const BakeWorld& world) override {
        if (world.birds->birds.empty()) return {};
        const auto& params = world.birds->birds;
        const bool built_in = std::any_of(params.begin(), params.end(),
                                          [](const gpu::BirdParams& p) { return p.ids.y < birds::kWingTypeCount; });
        if (built_in || world.birds->models.empty()) {
            auto writer = BirdGlbWriter::create(path_, *world.birds, world.frames, compaction_);
            if (!writer) return writer.error();
            writer_.emplace(std::move(writer).value());
        }
        const std::string stem = path_.substr(0, path_.size() - (path_.ends_with(".glb") ? 4 : 0));
        const bool alone = !built_in && world.birds->models.size() == 1;
        for (std::size_t k = 0; k < world.birds->models.size(); ++k) {
            const std::string path = alone ? path_ : stem + "-" + world.birds->models[k]->name + ".glb";
            auto model = BirdModelExport::create(*world.birds, k, path, compaction_);
            if (!model) return model.error();
            models_.push_back(std::move(model).value());
        }
        return {};
    }

    Result<void> consume(const BakeFrames& frames) override {
        if (writer_) KW_TRY(writer_->add_frames(frames.bird_poses));
        for (BirdModelExport& model : models_) KW_TRY(model.add_frames(frames.bird_poses));
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

private:
    std::string path_;
    GlbCompaction compaction_;
    std::optional<BirdGlbWriter> writer_;
    std::vector<BirdModelExport> models_;
};

class ChainsGlbSink final : public BakeSink {
public:
    ChainsGlbSink(std::string path, const GlbCompaction& compaction) : path_(std::move(path)), compaction_(compaction) {}

    BakeNeeds needs() const override { return {.chains = true}; }

    Result<void> begin(const BakeWorld& world) override {
        scene_ = world.rods;
        frames_ = world.frames;
        if (scene_ == nullptr) return {};
        const RodScene& rods = *scene_;
        // Rigged characters go back into their own glTF, one file per character template
        // (the path itself when it is the only character); procedural characters (and
        // then the rigged ones too, as bones) into ChainsGlbWriter's file.
        const bool any_procedural =
            std::any_of(rods.characters.begin(), rods.characters.end(), [](const CharacterKinematics& k) { return !k.rig; });
        const std::string stem = path_.substr(0, path_.size() - (path_.ends_with(".glb") ? 4 : 0));
        for (std::uint32_t k = 0; k < rods.characters.size(); ++k) {
            if (!rods.characters[k].rig) continue;
            std::string path = !any_procedural && rods.characters.size() == 1 ? path_ : stem + "-" + rods.characters[k].name + ".glb";
            auto e = RiggedCrowdExport::create(rods, k, path, compaction_);
            if (!e) return e.error();
            if (e.value().instances().empty()) continue;
            rigged_.push_back(std::move(e).value());
            rigged_paths_.push_back(std::move(path));
        }
        if (any_procedural) {
            auto writer = ChainsGlbWriter::create(path_, rods, frames_, compaction_);
            if (!writer) return writer.error();
            procedural_.emplace(std::move(writer).value());
        }
        return {};
    }

    Result<void> consume(const BakeFrames& frames) override {
        if (scene_ == nullptr) return {};
        const ChainSnapshot& snapshot = *frames.chains;
        for (RiggedCrowdExport& e : rigged_) KW_TRY(e.add_frame(frames.first, snapshot));
        if (procedural_) KW_TRY(procedural_->add_frame(snapshot.positions, snapshot.orientations));
        return {};
    }

    Result<std::vector<BakeOutput>> finish() override {
        std::vector<BakeOutput> written;
        for (std::size_t i = 0; i < rigged_.size(); ++i) {
            KW_TRY(rigged_[i].finish(rigged_paths_[i]));
            written.push_back({rigged_paths_[i], BakeOutput::Format::Glb, "the character's own skeleton and meshes",
                               stats(rigged_[i].writer().compaction_stats())});
        }
        if (procedural_) {
            KW_TRY(procedural_->finish());
            written.push_back({path_, BakeOutput::Format::Glb, "", stats(procedural_->compaction_stats())});
        }
        return written;
    }

private:
    [[nodiscard]] std::optional<GlbCompactionStats> stats(const GlbCompactionStats& s) const {
        if (!compaction_.enabled) return std::nullopt;
        return s;
    }

    std::string path_;
    GlbCompaction compaction_;
    const RodScene* scene_ = nullptr;
    std::uint32_t frames_ = 0;
    std::vector<RiggedCrowdExport> rigged_;
    std::vector<std::string> rigged_paths_;
    std::optional<ChainsGlbWriter> procedural_;  // streams: memory does not grow with the frames
};

class TraceSink final : public BakeSink {
public:
    explicit TraceSink(std::string path) : path_(std::move(path)) {}

    BakeNeeds needs() const override { return {.bird_poses = true, .bird_diag = true, .chains = true, .chain_shapes = true}; }

    Result<void> begin(const BakeWorld& world) override {
        world_ = world;
        auto t = TraceWriter::open(path_, {world.scene->name, world.birds->fps, world.frames, world.backend});
        if (!t) return t.error();
        trace_.emplace(std::move(t).value());
        if (world.rods != nullptr) {
            // Per chain: its character instance and its index there (the trace's records).
            const RodScene& rods = *world.rods;
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
        const std::size_t count = world_.birds->birds.size();
        if (count > 0) {
            for (std::uint32_t k = 0; k < frames.count; ++k) {
                trace_->write_frame(frames.first + k, *world_.birds, frames.bird_poses.subspan(std::size_t{k} * count, count),
                                    frames.bird_diag.subspan(std::size_t{k} * count, count));
            }
        }
        if (frames.chains != nullptr) {
            const RodScene& rods = *world_.rods;
            trace_->write_chains(frames.first, rods.time(frames.first), rods.world, characters_, within_, rods.chain_names,
                                 *frames.chains);
        }
        return {};
    }

    Result<std::vector<BakeOutput>> finish() override {
        KW_TRY(trace_->finish());
        return std::vector<BakeOutput>{{path_, BakeOutput::Format::Trace, "", {}}};
    }

private:
    std::string path_;
    BakeWorld world_;
    std::optional<TraceWriter> trace_;
    std::vector<std::uint32_t> characters_, within_;
};

}  // namespace

std::unique_ptr<BakeSink> make_birds_glb_sink(std::string path, const GlbCompaction& compaction) {
    return std::make_unique<BirdsGlbSink>(std::move(path), compaction);
}
std::unique_ptr<BakeSink> make_chains_glb_sink(std::string path, const GlbCompaction& compaction) {
    return std::make_unique<ChainsGlbSink>(std::move(path), compaction);
}
std::unique_ptr<BakeSink> make_trace_sink(std::string path) { return std::make_unique<TraceSink>(std::move(path)); }

}  // namespace kodawari
