// The characters' glTF sink of the bake (kodawari/domains/chains.hpp): ChainsGlbWriter and
// RiggedCrowdExport fed with the chains' channels frame by frame.
#include <algorithm>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "kodawari/simulation/bake.hpp"
#include "kodawari/core/communicator.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari {

namespace {

class ChainsGlbSink final : public BakeSink {
public:
    ChainsGlbSink(std::string path, const GlbCompaction& compaction) : path_(std::move(path)), compaction_(compaction) {}

    BakeNeeds needs() const override {
        return {{std::string(kChainPositionsChannel), std::string(kChainOrientationsChannel)}};
    }

    Result<void> begin(const BakeWorld& world) override {
        scene_ = rod_scene_of(world);
        if (const Domain* domain = world.domain(kChainDomain)) noun_ = domain->instance_noun();
        frames_ = world.frames;
        if (scene_ == nullptr) return {};
        const RodScene& rods = *scene_;
        // Rigged characters go back into their own glTF, one file per character template
        // (the path itself when it is the only character); procedural characters (and
        // then the rigged ones too, as bones) into ChainsGlbWriter's file.
        const bool any_procedural =
            std::any_of(rods.characters.begin(), rods.characters.end(), [](const CharacterKinematics& k) { return !k.rig; });
        const std::string stem = glb_stem(path_);
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
        snapshot_from(frames, snapshot_);
        if (shared_) {
            // This rank's chains, in the whole world's joint order where the exports read them.
            const std::size_t local = snapshot_.positions.size();
            if (joint_offset_ + local > whole_.positions.size() || snapshot_.orientations.size() != local) {
                return make_error(Error::Kind::Internal, path_ + ": this rank's " + std::to_string(local) +
                                                             " chain joints do not fit the world's from joint " +
                                                             std::to_string(joint_offset_));
            }
            std::copy(snapshot_.positions.begin(), snapshot_.positions.end(), whole_.positions.begin() + joint_offset_);
            std::copy(snapshot_.orientations.begin(), snapshot_.orientations.end(), whole_.orientations.begin() + joint_offset_);
        }
        const ChainSnapshot& snapshot = shared_ ? whole_ : snapshot_;
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

    // A distributed bake's ranks each pose and compact their own characters: their
    // instances of each rigged template (RiggedGlbWriter::share()) and, in the
    // procedural characters' file, their tracks (ChainsGlbWriter::share()).
    bool can_share() const override {
        return scene_ != nullptr && (procedural_ || !rigged_.empty()) && (!procedural_ || procedural_->can_share()) &&
               std::all_of(rigged_.begin(), rigged_.end(), [](const RiggedCrowdExport& e) { return e.can_share(); });
    }

    // The rigged characters' files are beside path_: one folder.
    std::string share_probe() const override { return path_; }

    Result<void> share(const ShardInfo& mine) override {
        if (!can_share()) return BakeSink::share(mine);
        const InstanceRange range = mine.part(noun_).range;
        for (RiggedCrowdExport& e : rigged_) {
            const auto& instances = e.instances();  // ascending scene indices
            const auto first = std::lower_bound(instances.begin(), instances.end(), range.begin);
            const auto end = std::lower_bound(instances.begin(), instances.end(), range.end);
            KW_TRY(e.share(static_cast<std::size_t>(first - instances.begin()), static_cast<std::size_t>(end - instances.begin())));
        }
        if (procedural_) KW_TRY(procedural_->share(range.begin, range.end));
        const rods::RodWorld& world = scene_->world;
        const std::uint32_t chain = range.begin < scene_->instances.size() ? scene_->instances[range.begin].chain_begin
                                                                           : static_cast<std::uint32_t>(world.chains.size());
        joint_offset_ = chain < world.chains.size() ? world.chains[chain].joint_begin : world.joint_count;
        whole_.positions.assign(world.joint_count, glm::vec3(0.0f));
        whole_.orientations.assign(world.joint_count, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
        shared_ = true;
        return {};
    }

    Result<std::vector<BakeOutput>> finish_shared(Communicator& ranks) override {
        if (!shared_) return BakeSink::finish_shared(ranks);
        std::vector<BakeOutput> written;
        for (std::size_t i = 0; i < rigged_.size(); ++i) {
            KW_TRY(rigged_[i].finish(ranks, rigged_paths_[i]));
            written.push_back({rigged_paths_[i], BakeOutput::Format::Glb,
                               "the character's own skeleton and meshes, its keys compacted on " +
                                   std::to_string(ranks.size()) + " ranks",
                               stats(rigged_[i].writer().compaction_stats())});
        }
        if (procedural_) {
            KW_TRY(procedural_->finish(ranks));
            written.push_back({path_, BakeOutput::Format::Glb, "its keys compacted on " + std::to_string(ranks.size()) + " ranks",
                               stats(procedural_->compaction_stats())});
        }
        if (ranks.rank() != 0) written.clear();
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
    ChainSnapshot snapshot_;
    std::string noun_;  // what the chain domain calls its instances (ShardInfo's parts)
    bool shared_ = false;
    std::size_t joint_offset_ = 0;  // this rank's first chain joint in the world (shared)
    ChainSnapshot whole_;           // the world's joints, this rank's filled in (shared)
};

}  // namespace

std::unique_ptr<BakeSink> make_chains_glb_sink(std::string path, const GlbCompaction& compaction) {
    return std::make_unique<ChainsGlbSink>(std::move(path), compaction);
}

const RodScene* rod_scene_of(const BakeWorld& world) {
    const Domain* domain = world.domain(kChainDomain);
    return domain ? rod_scene_of(*domain) : nullptr;
}

void snapshot_from(const BakeFrames& frames, ChainSnapshot& out) {
    const auto take = [&]<class T>(std::string_view name, std::vector<T>& into) {
        const auto values = frames.channel_as<T>(name);
        into.assign(values.begin(), values.end());
    };
    take(kChainPositionsChannel, out.positions);
    take(kChainOrientationsChannel, out.orientations);
    take(kChainRestChannel, out.rest);
    take(kChainViewDirectionsChannel, out.view_directions);
    take(kChainWeightsChannel, out.weights);
}

}  // namespace kodawari
