// A distributed bake (kodawari/simulation/distributed.hpp) in one process: the ranks are threads
// that speak through ThreadRanks, a Communicator of their own, so the protocol runs
// under the sanitizers (the MPI runs of tests/scaleout_test.sh cannot check leaks). The
// compacted birds' .glb, whose work every rank shares (each compacts its own birds'
// channels and writes them into rank 0's file), is the single process's file byte for
// byte on any number of ranks, more ranks than birds included; a shared sink that fails
// on one rank stops every rank with its message and leaves no file.
#include <gtest/gtest.h>

#include <barrier>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "kodawari/simulation/bake.hpp"
#include "kodawari/simulation/distributed.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

std::string scene_path(const char* name) { return std::string(KODAWARI_SOURCE_DIR) + "/scenes/" + name; }

// What the threads of one job share: a barrier and a slot per rank.
struct ThreadJob {
    explicit ThreadJob(int ranks) : size(ranks), sync(ranks), slots(static_cast<std::size_t>(ranks)), errors(slots.size()) {}
    int size;
    std::barrier<> sync;
    std::vector<std::vector<std::byte>> slots;
    std::vector<std::optional<Error>> errors;
    std::vector<std::byte> broadcast;
};

// Every call is collective, as MPI's are: each rank puts its part in its slot, all wait,
// each reads what it needs, all wait again before a slot is reused.
class ThreadRanks final : public Communicator {
public:
    ThreadRanks(ThreadJob& job, int rank) : job_(job), rank_(rank) {}
    int rank() const override { return rank_; }
    int size() const override { return job_.size; }
    int local_rank() const override { return rank_; }

    Result<void> agree(const Result<void>& mine) override {
        job_.errors[static_cast<std::size_t>(rank_)] = mine ? std::nullopt : std::optional<Error>(mine.error());
        job_.sync.arrive_and_wait();
        Result<void> out;
        for (int r = 0; r < job_.size; ++r) {
            if (const auto& e = job_.errors[static_cast<std::size_t>(r)]) {
                out = make_error(e->kind, (job_.size > 1 ? "rank " + std::to_string(r) + ": " : std::string()) + e->message);
                break;
            }
        }
        job_.sync.arrive_and_wait();
        return out;
    }

    void gather(std::span<const std::byte> mine, std::vector<std::byte>& all, std::vector<std::size_t>& sizes) override {
        job_.slots[static_cast<std::size_t>(rank_)].assign(mine.begin(), mine.end());
        job_.sync.arrive_and_wait();
        if (rank_ == 0) {
            all.clear();
            sizes.clear();
            for (const auto& slot : job_.slots) {
                all.insert(all.end(), slot.begin(), slot.end());
                sizes.push_back(slot.size());
            }
        }
        job_.sync.arrive_and_wait();
    }

    void broadcast(std::vector<std::byte>& data) override {
        if (rank_ == 0) job_.broadcast = data;
        job_.sync.arrive_and_wait();
        if (rank_ != 0) data = job_.broadcast;
        job_.sync.arrive_and_wait();
    }

private:
    ThreadJob& job_;
    int rank_;
};

// bake_distributed() on `ranks` threads; every rank's result.
std::vector<Result<std::vector<BakeOutput>>> bake_on_threads(int ranks, const char* scene, const DistributedBakeOptions& options) {
    ThreadJob job(ranks);
    std::vector<std::optional<Result<std::vector<BakeOutput>>>> results(static_cast<std::size_t>(ranks));
    std::vector<std::thread> threads;
    for (int r = 0; r < ranks; ++r) {
        threads.emplace_back([&, r] {
            ThreadRanks comm(job, r);
            results[static_cast<std::size_t>(r)].emplace(bake_distributed(comm, scene_path(scene), options));
        });
    }
    for (std::thread& t : threads) t.join();
    std::vector<Result<std::vector<BakeOutput>>> out;
    for (auto& result : results) out.push_back(std::move(*result));
    return out;
}

constexpr GlbCompaction kCompact{.enabled = true, .threads = 1};

DistributedBakeOptions birds_glb(const std::string& path, std::uint32_t frames, const GlbCompaction& compaction) {
    DistributedBakeOptions options;
    options.simulation.backend = BackendKind::Cpu;
    options.simulation.options.threads = 1;
    options.simulation.frames = frames;
    options.make_sinks = [path, compaction](const BakeWorld&) {
        std::vector<std::unique_ptr<BakeSink>> sinks;
        sinks.push_back(make_birds_glb_sink(path, compaction));
        return sinks;
    };
    return options;
}

std::string single_process_file(const char* scene, std::uint32_t frames, const GlbCompaction& compaction,
                                      const std::string& path) {
    auto sim = Simulation::open(scene_path(scene), {.backend = BackendKind::Cpu, .frames = frames});
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    if (!sim) return {};
    auto sink = make_birds_glb_sink(path, compaction);
    BakeSink* sinks[] = {sink.get()};
    auto written = bake(*sim.value(), sinks);
    EXPECT_TRUE(written.ok()) << written.error().message;
    return testing_support::file_bytes(path);
}

// A sink every rank shares that fails on one rank, at one of three points.
class FailingSharedSink final : public BakeSink {
public:
    enum class When { Consume, Finish };
    FailingSharedSink(int failing_rank, When when, std::string path) : failing_(failing_rank), when_(when), path_(std::move(path)) {}
    BakeNeeds needs() const override { return {{std::string(kBirdPosesChannel)}}; }
    Result<void> begin(const BakeWorld&) override { return {}; }
    bool can_share() const override { return true; }
    std::string share_probe() const override { return path_; }
    Result<void> share(const ShardInfo& mine) override {
        rank_ = static_cast<int>(mine.shard.index);
        return {};
    }
    Result<void> consume(const BakeFrames& frames) override {
        if (when_ == When::Consume && rank_ == failing_ && frames.first > 0) return make_error(Error::Kind::Io, "consume failed here");
        return {};
    }
    Result<std::vector<BakeOutput>> finish() override { return make_error(Error::Kind::Internal, "finish() of a shared sink"); }
    Result<std::vector<BakeOutput>> finish_shared(Communicator& ranks) override {
        // A file only rank 0 would keep: left behind unless every rank agrees.
        const Result<void> mine = when_ == When::Finish && ranks.rank() == failing_
                                      ? Result<void>{make_error(Error::Kind::Io, "finish failed here")}
                                      : Result<void>{};
        KW_TRY(ranks.agree(mine));
        if (ranks.rank() == 0) std::ofstream(path_) << "written";
        return std::vector<BakeOutput>{};
    }

private:
    int failing_;
    When when_;
    std::string path_;
    int rank_ = -1;
};

}  // namespace

TEST(DistributedBake, CompactedBirdsAreTheSingleProcessBytesOnAnyNumberOfRanks) {
    testing_support::TempDir dir;
    constexpr std::uint32_t kFrames = 130;  // more than one chunk of steps
    const std::string expected = single_process_file("flock.json", kFrames, kCompact, dir.file("one.glb"));
    ASSERT_FALSE(expected.empty());
    for (const int ranks : {1, 2, 3}) {
        SCOPED_TRACE(std::to_string(ranks) + " ranks");
        const std::string path = dir.file("ranks-" + std::to_string(ranks) + ".glb");
        const auto results = bake_on_threads(ranks, "flock.json", birds_glb(path, kFrames, kCompact));
        for (int r = 0; r < ranks; ++r) {
            ASSERT_TRUE(results[static_cast<std::size_t>(r)].ok()) << results[static_cast<std::size_t>(r)].error().message;
            EXPECT_EQ(results[static_cast<std::size_t>(r)].value().size(), r == 0 ? 1u : 0u) << "only rank 0 names the file";
        }
        const BakeOutput& file = results[0].value()[0];
        EXPECT_EQ(file.description, "its birds' keys compacted on " + std::to_string(ranks) + " ranks");
        const std::string got = testing_support::file_bytes(path);
        EXPECT_TRUE(got == expected) << "the file differs from the single process's (" << got.size() << " and "
                                     << expected.size() << " bytes)";
    }
    // Three birds on five ranks: rank 0 and rank 2 have none of their own (shard_range).
    const std::string closeup = single_process_file("birds-closeup.json", 30, kCompact, dir.file("closeup.glb"));
    const auto results = bake_on_threads(5, "birds-closeup.json", birds_glb(dir.file("closeup-5.glb"), 30, kCompact));
    ASSERT_TRUE(results[0].ok()) << results[0].error().message;
    EXPECT_TRUE(testing_support::file_bytes(dir.file("closeup-5.glb")) == closeup) << "5 ranks, 3 birds: not the same bytes";
}

// The characters' files: every rank poses and compacts its own instances, rigged
// (RiggedGlbWriter, crowd-gltf.json) or procedural (ChainsGlbWriter, bunny.json).
class DistributedCharacters : public testing::TestWithParam<const char*> {};

TEST_P(DistributedCharacters, CompactedFileIsTheSingleProcessBytesOnAnyNumberOfRanks) {
    testing_support::TempDir dir;
    constexpr std::uint32_t kFrames = 8;
    const GlbCompaction compaction{.enabled = true, .position_m = 0.005f, .rotation_rad = 0.02f, .threads = 1};
    std::string expected;
    {
        auto sim = Simulation::open(scene_path(GetParam()), {.backend = BackendKind::Cpu, .frames = kFrames});
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        auto sink = make_chains_glb_sink(dir.file("one.glb"), compaction);
        BakeSink* sinks[] = {sink.get()};
        auto written = bake(*sim.value(), sinks);
        ASSERT_TRUE(written.ok()) << written.error().message;
        expected = testing_support::file_bytes(dir.file("one.glb"));
    }
    for (const int ranks : {2, 3}) {
        SCOPED_TRACE(std::to_string(ranks) + " ranks");
        const std::string path = dir.file("ranks-" + std::to_string(ranks) + ".glb");
        DistributedBakeOptions options = birds_glb(path, kFrames, compaction);
        options.make_sinks = [path, compaction](const BakeWorld&) {
            std::vector<std::unique_ptr<BakeSink>> sinks;
            sinks.push_back(make_chains_glb_sink(path, compaction));
            return sinks;
        };
        const auto results = bake_on_threads(ranks, GetParam(), options);
        ASSERT_TRUE(results[0].ok()) << results[0].error().message;
        ASSERT_EQ(results[0].value().size(), 1u);
        EXPECT_NE(results[0].value()[0].description.find("compacted on " + std::to_string(ranks) + " ranks"), std::string::npos);
        EXPECT_TRUE(testing_support::file_bytes(path) == expected) << "not the single process's bytes";
    }
}

INSTANTIATE_TEST_SUITE_P(Scenes, DistributedCharacters, testing::Values("crowd-gltf.json", "bunny.json"),
                         [](const testing::TestParamInfo<const char*>& scene) {
                             return std::string(scene.param) == "crowd-gltf.json" ? std::string("rigged") : std::string("procedural");
                         });

TEST(DistributedBake, MeshoptKeysAreCompactedOnRankZeroTheSameBytes) {
    testing_support::TempDir dir;
    const GlbCompaction meshopt{.enabled = true, .meshopt = true, .threads = 1};
    const std::string expected = single_process_file("flock.json", 40, meshopt, dir.file("one.glb"));
    const auto results = bake_on_threads(2, "flock.json", birds_glb(dir.file("two.glb"), 40, meshopt));
    ASSERT_TRUE(results[0].ok()) << results[0].error().message;
    EXPECT_EQ(results[0].value()[0].description, "") << "meshopt's chunks span birds: not shared";
    EXPECT_TRUE(testing_support::file_bytes(dir.file("two.glb")) == expected) << "meshopt on 2 ranks: not the same bytes";
}

TEST(DistributedBake, ASharedSinkFailingOnOneRankStopsEveryRankAndLeavesNoFile) {
    for (const auto when : {FailingSharedSink::When::Consume, FailingSharedSink::When::Finish}) {
        testing_support::TempDir dir;
        const std::string path = dir.file("never.txt");
        DistributedBakeOptions options = birds_glb(dir.file("birds.glb"), 130, kCompact);
        options.make_sinks = [path, when, &dir](const BakeWorld&) {
            std::vector<std::unique_ptr<BakeSink>> sinks;
            sinks.push_back(make_birds_glb_sink(dir.file("birds.glb"), kCompact));
            sinks.push_back(std::make_unique<FailingSharedSink>(1, when, path));
            return sinks;
        };
        const auto results = bake_on_threads(3, "flock.json", options);
        for (const auto& result : results) {
            ASSERT_FALSE(result.ok());
            EXPECT_EQ(result.error().message,
                      std::string("rank 1: ") + (when == FailingSharedSink::When::Consume ? "consume" : "finish") + " failed here");
        }
        EXPECT_FALSE(std::filesystem::exists(path));
        // The birds' file, finished before the failing sink, is written; a consume
        // failure stops the bake before any sink finishes.
        EXPECT_EQ(std::filesystem::exists(dir.file("birds.glb")), when == FailingSharedSink::When::Finish);
        EXPECT_EQ(dir.entries().size(), std::filesystem::exists(dir.file("birds.glb")) ? 1u : 0u)
            << "no temporary file is left";
    }
}
