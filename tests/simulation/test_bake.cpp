// The bake pipeline (kodawari/simulation/bake.hpp): its files are those of the writers fed by hand,
// a failure anywhere leaves no file (not even a temporary one), and it needs a fresh
// simulation. CPU backends: the loop is the same for every kind.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "kodawari/simulation/bake.hpp"
#include "kodawari/export/export.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/domains/trace.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_support.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

std::string scene_path(const char* name) { return std::string(KODAWARI_SOURCE_DIR) + "/scenes/" + name; }

std::unique_ptr<Simulation> open(const char* scene, std::uint32_t frames) {
    auto made = Simulation::open(scene_path(scene), {.backend = BackendKind::Cpu, .frames = frames});
    EXPECT_TRUE(made.ok()) << made.error().message;
    return made.ok() ? std::move(made).value() : nullptr;
}

// Fails on the frame it is told, after the other sinks have seen the frames before.
class FailingSink final : public BakeSink {
public:
    explicit FailingSink(std::uint32_t frame) : frame_(frame) {}
    BakeNeeds needs() const override { return {}; }
    Result<void> begin(const BakeWorld&) override { return {}; }
    Result<void> consume(const BakeFrames& frames) override {
        if (frames.first + frames.count > frame_) return make_error(Error::Kind::InvalidInput, "failing sink");
        return {};
    }
    Result<std::vector<BakeOutput>> finish() override { return std::vector<BakeOutput>{}; }

private:
    std::uint32_t frame_;
};

}  // namespace

TEST(Bake, BirdsGlbIsTheWritersFileOfTheSteppedPoses) {
    constexpr std::uint32_t kFrames = 150;  // more than one chunk of steps
    testing_support::TempDir dir;
    auto baked = open("flock.json", kFrames);
    ASSERT_NE(baked, nullptr);
    auto sink = make_birds_glb_sink(dir.file("baked.glb"));
    BakeSink* sinks[] = {sink.get()};
    auto written = bake(*baked, sinks);
    ASSERT_TRUE(written.ok()) << written.error().message;
    ASSERT_EQ(written.value().size(), 1u);
    EXPECT_EQ(written.value()[0].path, dir.file("baked.glb"));

    auto stepped = open("flock.json", kFrames);
    ASSERT_NE(stepped, nullptr);
    std::vector<gpu::BirdPose> poses(std::size_t{kFrames} * bird_world(*stepped).birds.size());
    ASSERT_TRUE(step_birds(*stepped, kFrames, poses).ok());
    ASSERT_TRUE(write_birds_glb(dir.file("stepped.glb"), bird_world(*stepped), poses, kFrames).ok());
    EXPECT_EQ(testing_support::file_bytes(dir.file("baked.glb")), testing_support::file_bytes(dir.file("stepped.glb")));
}

// The procedural characters' sink streams its keys: its file is write_chains_glb's of
// the snapshots a simulation gives frame by frame.
TEST(Bake, ChainsGlbIsTheWritersFileOfTheSnapshots) {
    constexpr std::uint32_t kFrames = 12;
    testing_support::TempDir dir;
    auto baked = open("bunny.json", kFrames);
    ASSERT_NE(baked, nullptr);
    auto sink = make_chains_glb_sink(dir.file("baked.glb"));
    BakeSink* sinks[] = {sink.get()};
    auto written = bake(*baked, sinks);
    ASSERT_TRUE(written.ok()) << written.error().message;

    auto stepped = open("bunny.json", kFrames);
    ASSERT_NE(stepped, nullptr);
    std::vector<glm::vec3> positions;
    std::vector<glm::quat> orientations;
    ChainSnapshot snapshot;
    for (std::uint32_t f = 0; f < kFrames; ++f) {
        ASSERT_TRUE(stepped->step().ok());
        ASSERT_TRUE(read_chains(*stepped, snapshot).ok());
        positions.insert(positions.end(), snapshot.positions.begin(), snapshot.positions.end());
        orientations.insert(orientations.end(), snapshot.orientations.begin(), snapshot.orientations.end());
    }
    ASSERT_TRUE(write_chains_glb(dir.file("stepped.glb"), *rod_scene(*stepped), kFrames, positions, orientations).ok());
    EXPECT_EQ(testing_support::file_bytes(dir.file("baked.glb")), testing_support::file_bytes(dir.file("stepped.glb")));
}

TEST(Bake, AFailureLeavesNoFile) {
    testing_support::TempDir dir;
    auto sim = open("crowd-gltf.json", 12);
    ASSERT_NE(sim, nullptr);
    auto chains = make_chains_glb_sink(dir.file("crowd.glb"));
    auto trace = make_trace_sink(dir.file("crowd.jsonl"));
    FailingSink failing(5);
    BakeSink* sinks[] = {chains.get(), trace.get(), &failing};
    auto written = bake(*sim, sinks);
    ASSERT_FALSE(written.ok());
    EXPECT_EQ(written.error().message, "failing sink");
    chains.reset();
    trace.reset();
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Bake, AFailureAfterTheLastFrameLeavesNoFile) {
    testing_support::TempDir dir;
    auto sim = open("flock.json", 10);
    ASSERT_NE(sim, nullptr);
    auto birds = make_birds_glb_sink(dir.file("flock.glb"));
    BakeSink* sinks[] = {birds.get()};
    BakeOptions options;
    options.simulated = [] { return Result<void>(make_error(Error::Kind::Vulkan, "validation")); };
    EXPECT_FALSE(bake(*sim, sinks, options).ok());
    birds.reset();
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Bake, NeedsASimulationThatHasNotStepped) {
    auto sim = open("flock.json", 10);
    ASSERT_NE(sim, nullptr);
    ASSERT_TRUE(sim->step().ok());
    const auto baked = bake(*sim, {});
    ASSERT_FALSE(baked.ok());
    EXPECT_EQ(baked.error().kind, Error::Kind::InvalidInput);
    EXPECT_NE(baked.error().message.find("flock.json"), std::string::npos) << baked.error().message;
}
