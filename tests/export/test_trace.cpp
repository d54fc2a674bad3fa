// The JSON Lines trace (docs/trace-format.md): round trip, and no file left behind by an
// unfinished or failed writer.

#include <gtest/gtest.h>

#include "export_support.hpp"

namespace kodawari {
namespace {

using namespace export_test;

std::vector<gpu::BirdDiag> make_diag(std::size_t count, std::uint32_t frame) {
    std::vector<gpu::BirdDiag> diag(count);
    for (std::size_t b = 0; b < count; ++b) {
        const float k = static_cast<float>(b) + 0.5f * static_cast<float>(frame);
        diag[b].velocity = {k, 2.0f, 3.0f, 0.25f};
        diag[b].acceleration = {0.5f, -0.5f, 0.125f, static_cast<float>(b % 3)};
        diag[b].angles = {0.1f, 0.2f, 0.3f, 0.4f};
        diag[b].attitude = {1.0f, -0.25f, 0.75f, 1.5f + k};
        diag[b].flight = {0.5f, 0.125f, 0.375f, 2.0f + k};
    }
    return diag;
}

std::vector<nlohmann::json> read_lines(const std::string& path) {
    std::vector<nlohmann::json> lines;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        // Every line on its own must be a complete JSON document.
        lines.push_back(nlohmann::json::parse(line));
    }
    return lines;
}

std::array<float, 3> as_vec3(const nlohmann::json& value) {
    EXPECT_TRUE(value.is_array());
    EXPECT_EQ(value.size(), 3u);
    return {value.at(0).get<float>(), value.at(1).get<float>(), value.at(2).get<float>()};
}

TEST(Trace, RoundTrip) {
    TempDir dir;
    const auto world = make_world();
    constexpr std::uint32_t kTraceFrames = 2;
    const auto poses = make_poses(world, kTraceFrames);
    const std::string path = dir.file("trace.jsonl");

    auto writer = TraceWriter::open(path, TraceHeader{"two \"frames\"\n", kFps, kTraceFrames, "cpu-reference"});
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    for (std::uint32_t f = 0; f < kTraceFrames; ++f) {
        const auto diag = make_diag(kBirds, f);
        writer.value().write_frame(f, world, std::span(poses).subspan(f * kBirds, kBirds), diag);
    }
    const auto finished = writer.value().finish();
    ASSERT_TRUE(finished.ok()) << finished.error().message;
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"trace.jsonl"});

    const auto lines = read_lines(path);
    ASSERT_EQ(lines.size(), 1 + kTraceFrames * kBirds);
    const auto& header = lines[0];
    EXPECT_EQ(header.at("kind"), "header");
    EXPECT_EQ(header.at("scene"), "two \"frames\"\n");
    EXPECT_EQ(header.at("fps").get<double>(), 24.0);
    EXPECT_EQ(header.at("frames"), kTraceFrames);
    EXPECT_EQ(header.at("backend"), "cpu-reference");

    // Records are frame-major, birds in index order.
    for (std::size_t i = 1; i < lines.size(); ++i) {
        EXPECT_EQ(lines[i].at("kind"), "bird");
        EXPECT_EQ(lines[i].at("frame"), (i - 1) / kBirds);
        EXPECT_EQ(lines[i].at("id"), (i - 1) % kBirds);
    }

    // Bird 31 (a gull: 31 % kWingTypeCount = 1; mode 31 % 3 = 1: ascend) in frame 1. A new
    // wing type changes which bird is a gull: the assert says so rather than a wrong name.
    constexpr std::size_t kBird = 31;
    static_assert(kBird % birds::kWingTypeCount == static_cast<std::size_t>(birds::WingType::Gull));
    const auto& record = lines[1 + kBirds + kBird];
    const std::set<std::string> expected_keys = {"kind",     "frame",    "time",         "id",  "wing_type",
                                                 "mode",     "phase",    "blend",        "position", "velocity",
                                                 "acceleration", "yaw",  "pitch",        "bank", "angles",
                                                 "parts", "speed_fraction", "extra_pitch", "tail_spread", "glided"};
    std::set<std::string> keys;
    for (const auto& item : record.items()) keys.insert(item.key());
    EXPECT_EQ(keys, expected_keys);

    const gpu::BirdPose& pose = poses[kBirds + kBird];
    const gpu::BirdDiag diag = make_diag(kBirds, 1)[kBird];
    EXPECT_EQ(record.at("frame"), 1);
    EXPECT_DOUBLE_EQ(record.at("time").get<double>(), 1.0 / 24.0);
    EXPECT_EQ(record.at("wing_type"), "gull");
    EXPECT_EQ(record.at("mode"), "ascend");
    EXPECT_EQ(record.at("phase").get<float>(), diag.attitude.w);
    EXPECT_EQ(record.at("blend").get<float>(), 0.25f);
    EXPECT_EQ(as_vec3(record.at("position")), (std::array<float, 3>{pose.position.x, pose.position.y, pose.position.z}));
    EXPECT_EQ(as_vec3(record.at("velocity")), (std::array<float, 3>{diag.velocity.x, 2.0f, 3.0f}));
    EXPECT_EQ(as_vec3(record.at("acceleration")), (std::array<float, 3>{0.5f, -0.5f, 0.125f}));
    EXPECT_EQ(record.at("yaw").get<float>(), 1.0f);
    EXPECT_EQ(record.at("pitch").get<float>(), -0.25f);
    EXPECT_EQ(record.at("bank").get<float>(), 0.75f);
    EXPECT_EQ(record.at("speed_fraction").get<float>(), 0.5f);
    EXPECT_EQ(record.at("extra_pitch").get<float>(), 0.125f);
    EXPECT_EQ(record.at("tail_spread").get<float>(), 0.375f);
    EXPECT_EQ(record.at("glided").get<float>(), diag.flight.w);
    const auto& angles = record.at("angles");
    EXPECT_EQ(angles.size(), 4u);
    EXPECT_EQ(angles.at("arm1_pitch").get<float>(), 0.1f);
    EXPECT_EQ(angles.at("arm2_pitch").get<float>(), 0.2f);
    EXPECT_EQ(angles.at("arm1_heading").get<float>(), 0.3f);
    EXPECT_EQ(angles.at("arm2_heading").get<float>(), 0.4f);

    const auto& parts = record.at("parts");
    ASSERT_EQ(parts.size(), birds::kPartCount);
    const auto offsets = birds::part_offsets(birds::WingType::Gull);
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        const std::string name(birds::kPartNames[part]);
        ASSERT_TRUE(parts.contains(name)) << name;
        const auto& entry = parts.at(name);
        const auto t = as_vec3(entry.at("t"));
        if (part == KW_PART_BODY) {
            EXPECT_EQ(t, (std::array<float, 3>{pose.position.x, pose.position.y, pose.position.z}));
        } else {
            EXPECT_EQ(t, offsets[part]) << name;
        }
        const auto& r = entry.at("r");
        ASSERT_EQ(r.size(), 4u);
        const gpu::vec4& q = pose.rotation[part];
        // Shortest round-trip formatting: the floats come back bit for bit.
        EXPECT_EQ(r.at(0).get<float>(), q.x) << name;
        EXPECT_EQ(r.at(1).get<float>(), q.y) << name;
        EXPECT_EQ(r.at(2).get<float>(), q.z) << name;
        EXPECT_EQ(r.at(3).get<float>(), q.w) << name;
    }
}

TEST(Trace, UnfinishedWriterLeavesNoFile) {
    TempDir dir;
    const auto world = make_world();
    const auto poses = make_poses(world, 1);
    const auto diag = make_diag(kBirds, 0);
    const std::string path = dir.file("trace.jsonl");
    {
        auto writer = TraceWriter::open(path, TraceHeader{"abandoned", kFps, 1, "cpu"});
        ASSERT_TRUE(writer.ok()) << writer.error().message;
        writer.value().write_frame(0, world, poses, diag);
        // Meanwhile the file has no name (O_TMPFILE), or a temporary one where the file
        // system cannot: either way none of it may stay.
    }
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(dir.entries().empty());
}

TEST(Trace, MissingDirectoryIsAnError) {
    TempDir dir;
    const std::string path = dir.file("no-such-dir/trace.jsonl");
    const auto writer = TraceWriter::open(path, TraceHeader{"s", kFps, 1, "cpu"});
    ASSERT_FALSE(writer.ok());
    EXPECT_EQ(writer.error().kind, Error::Kind::Io);
    EXPECT_NE(writer.error().message.find(path), std::string::npos) << writer.error().message;
}

}  // namespace
}  // namespace kodawari
