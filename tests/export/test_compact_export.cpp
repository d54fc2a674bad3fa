// Compact .glb files (GlbCompaction, docs/compact.md), checked by re-importing: the
// uncompacted and the compacted file of the same simulation are loaded with tinygltf, and
// every channel of the compacted one, interpolated here (lerp; glm's slerp in double on
// the rotations decoded as max(c / 32767, -1) or, bytes, max(c / 127, -1)), is evaluated
// at every frame time of the uncompacted one and compared with its key: within the bound
// (+1e-6 for float rounding). Also: the file's accessors (shorts or bytes, shared key
// times), glTF-Validator, and fewer keys and bytes.

#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "export_support.hpp"

namespace kodawari {
namespace {

using namespace export_test;

// One sampler of a re-imported file: key times and values, decoded.
struct Track {
    std::vector<float> times;
    std::vector<double> values;  // width per key
    std::size_t width = 0;
};

Track read_track(const tinygltf::Model& model, const tinygltf::AnimationSampler& sampler) {
    Track track;
    track.times = read_floats(model, sampler.input);
    const tinygltf::Accessor& out = model.accessors.at(static_cast<std::size_t>(sampler.output));
    track.width = static_cast<std::size_t>(tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(out.type)));
    EXPECT_EQ(out.count, track.times.size());
    if (out.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT) {
        for (const float v : read_floats(model, sampler.output)) track.values.push_back(v);
        return track;
    }
    // Normalized shorts or bytes (glTF 2.0 §3.11: rotation outputs only).
    EXPECT_TRUE(out.componentType == TINYGLTF_COMPONENT_TYPE_SHORT || out.componentType == TINYGLTF_COMPONENT_TYPE_BYTE);
    EXPECT_TRUE(out.normalized);
    EXPECT_EQ(track.width, 4u);
    const tinygltf::BufferView& view = model.bufferViews.at(static_cast<std::size_t>(out.bufferView));
    const std::size_t offset = view.byteOffset + out.byteOffset;
    const unsigned char* data = model.buffers[0].data.data() + offset;
    if (out.componentType == TINYGLTF_COMPONENT_TYPE_BYTE) {
        std::vector<std::int8_t> bytes(out.count * 4);
        std::memcpy(bytes.data(), data, bytes.size());
        for (const std::int8_t c : bytes) track.values.push_back(std::max(static_cast<double>(c) / 127.0, -1.0));
        return track;
    }
    EXPECT_EQ(offset % 2, 0u);
    std::vector<std::int16_t> shorts(out.count * 4);
    std::memcpy(shorts.data(), data, shorts.size() * sizeof(std::int16_t));
    for (const std::int16_t c : shorts) track.values.push_back(std::max(static_cast<double>(c) / 32767.0, -1.0));
    return track;
}

// The tracks of the file's one animation by (node, path).
std::map<std::pair<int, std::string>, Track> read_tracks(const tinygltf::Model& model) {
    std::map<std::pair<int, std::string>, Track> tracks;
    EXPECT_EQ(model.animations.size(), 1u);
    const tinygltf::Animation& animation = model.animations.at(0);
    for (const tinygltf::AnimationChannel& channel : animation.channels) {
        const tinygltf::AnimationSampler& sampler = animation.samplers.at(static_cast<std::size_t>(channel.sampler));
        EXPECT_EQ(sampler.interpolation, "LINEAR");
        tracks[{channel.target_node, channel.target_path}] = read_track(model, sampler);
    }
    return tracks;
}

glm::dquat quat_at(const Track& t, std::size_t k) {
    const double* v = &t.values[k * 4];
    return glm::normalize(glm::dquat(v[3], v[0], v[1], v[2]));
}

glm::dvec3 vec_at(const Track& t, std::size_t k) {
    const double* v = &t.values[k * 3];
    return {v[0], v[1], v[2]};
}

// The track at time `time`, as a player evaluates LINEAR samplers (Appendix C).
std::pair<std::size_t, double> locate(const Track& t, float time) {
    const auto it = std::upper_bound(t.times.begin(), t.times.end(), time);
    if (it == t.times.begin()) return {0, 0.0};
    if (it == t.times.end()) return {t.times.size() - 1, 0.0};
    const auto b = static_cast<std::size_t>(it - t.times.begin());
    const double ta = t.times[b - 1];
    return {b - 1, (static_cast<double>(time) - ta) / (static_cast<double>(t.times[b]) - ta)};
}

glm::dvec3 vec_value(const Track& t, float time) {
    const auto [a, s] = locate(t, time);
    if (s == 0.0) return vec_at(t, a);
    return glm::mix(vec_at(t, a), vec_at(t, a + 1), s);
}

glm::dquat quat_value(const Track& t, float time) {
    const auto [a, s] = locate(t, time);
    if (s == 0.0) return quat_at(t, a);
    return glm::slerp(quat_at(t, a), quat_at(t, a + 1), s);
}

struct Measured {
    double position_m = 0.0, rotation_rad = 0.0, scale_rel = 0.0;
    std::size_t keys = 0, kept = 0;
};

// Every track of `full` against the compacted file's at every key time of `full`.
Measured compare(const std::string& full_path, const std::string& compact_path) {
    tinygltf::Model full;
    tinygltf::Model compact;
    EXPECT_TRUE(load_glb(full_path, full));
    EXPECT_TRUE(load_glb(compact_path, compact));
    EXPECT_EQ(full.nodes.size(), compact.nodes.size());
    const auto full_tracks = read_tracks(full);
    const auto compact_tracks = read_tracks(compact);
    EXPECT_EQ(full_tracks.size(), compact_tracks.size());
    Measured m;
    for (const auto& [key, f] : full_tracks) {
        const auto it = compact_tracks.find(key);
        if (it == compact_tracks.end()) {
            ADD_FAILURE() << "node " << key.first << " " << key.second << ": no compacted channel";
            continue;
        }
        const Track& c = it->second;
        EXPECT_EQ(c.times.front(), f.times.front());
        EXPECT_EQ(c.times.back(), f.times.back());
        m.keys += f.times.size();
        m.kept += c.times.size();
        for (std::size_t k = 0; k < f.times.size(); ++k) {
            if (key.second == "rotation") {
                const double dot = std::min(1.0, std::abs(glm::dot(quat_value(c, f.times[k]), quat_at(f, k))));
                m.rotation_rad = std::max(m.rotation_rad, 2.0 * std::acos(dot));
            } else {
                const glm::dvec3 d = glm::abs(vec_value(c, f.times[k]) - vec_at(f, k));
                if (key.second == "translation") {
                    m.position_m = std::max(m.position_m, glm::length(d));
                } else {
                    const glm::dvec3 o = vec_at(f, k);
                    for (int i = 0; i < 3; ++i) {
                        if (d[i] > 0.0) m.scale_rel = std::max(m.scale_rel, d[i] / std::abs(o[i]));
                    }
                }
            }
        }
    }
    return m;
}

// The rotation outputs are normalized shorts or bytes, the others floats, and every
// key-time accessor has min and max. Returns how many rotation outputs are bytes.
std::size_t expect_compact_accessors(const std::string& path) {
    tinygltf::Model model;
    EXPECT_TRUE(load_glb(path, model));
    if (model.animations.empty()) return 0;
    std::size_t bytes = 0;
    for (const auto& sampler : model.animations.at(0).samplers) {
        const auto& input = model.accessors.at(static_cast<std::size_t>(sampler.input));
        EXPECT_EQ(input.minValues.size(), 1u);
        EXPECT_EQ(input.maxValues.size(), 1u);
    }
    for (const auto& channel : model.animations[0].channels) {
        const auto& out = model.accessors.at(static_cast<std::size_t>(model.animations[0].samplers.at(static_cast<std::size_t>(channel.sampler)).output));
        if (channel.target_path != "rotation") {
            EXPECT_EQ(out.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
            continue;
        }
        EXPECT_TRUE(out.normalized);
        if (out.componentType == TINYGLTF_COMPONENT_TYPE_BYTE) {
            ++bytes;
        } else {
            EXPECT_EQ(out.componentType, TINYGLTF_COMPONENT_TYPE_SHORT);
        }
    }
    return bytes;
}

void expect_valid(const std::string& path) {
    std::string output;
    EXPECT_EQ(run_command(gltf_validator_command(path), output), 0) << output;
    EXPECT_NE(output.find("glTF-Validator: 0 errors, 0 warnings"), std::string::npos) << output;
}

constexpr double kFloat = 1e-6;  // float rounding of the re-importer's own arithmetic

// What re-importing measures lies within the bounds, and is what the writer says it
// introduced (its stats).
void expect_within_bounds_as_reported(const Measured& m, const GlbCompactionStats& stats, const GlbCompaction& bounds) {
    EXPECT_LE(m.position_m, static_cast<double>(bounds.position_m) + kFloat);
    EXPECT_LE(m.rotation_rad, static_cast<double>(bounds.rotation_rad) + kFloat);
    EXPECT_LE(m.scale_rel, static_cast<double>(bounds.scale_rel) + kFloat);
    EXPECT_NEAR(stats.position_m, m.position_m, kFloat);
    EXPECT_NEAR(stats.rotation_rad, m.rotation_rad, kFloat);
    EXPECT_EQ(stats.keys, m.keys);
    EXPECT_EQ(stats.kept, m.kept);
}

// Five procedural characters of crowd.json (ears, tails, arms), 90 frames: the chains'
// writer at the default bounds and at loose ones.
TEST(CompactExport, ChainsWithinBoundsWhenReimported) {
    TempDir dir;
    const RodRun run = run_rod_scene(scene_with_count(dir, "crowd", 5), 90);
    const std::string full = dir.file("full.glb");
    ASSERT_TRUE(write_chains_glb(full, run.scene, run.frames, run.positions, run.orientations).ok());
    for (const GlbCompaction bounds : {GlbCompaction{true, 0.001f, 0.001f, 0.001f}, GlbCompaction{true, 0.01f, 0.02f, 0.02f}}) {
        SCOPED_TRACE(std::to_string(bounds.position_m) + " m, " + std::to_string(bounds.rotation_rad) + " rad");
        const std::string path = dir.file("compact.glb");
        auto writer = ChainsGlbWriter::create(path, run.scene, run.frames, bounds);
        ASSERT_TRUE(writer.ok()) << writer.error().message;
        const std::size_t joints = run.scene.world.joint_count;
        for (std::uint32_t f = 0; f < run.frames; ++f) {
            ASSERT_TRUE(writer.value()
                            .add_frame(std::span(run.positions).subspan(f * joints, joints),
                                       std::span(run.orientations).subspan(f * joints, joints))
                            .ok());
        }
        ASSERT_TRUE(writer.value().finish().ok());
        const GlbCompactionStats& stats = writer.value().compaction_stats();
        const Measured m = compare(full, path);
        expect_within_bounds_as_reported(m, stats, bounds);
        EXPECT_LT(m.kept, m.keys / 2);
        // 90 frames: the JSON (the nodes' names, a time accessor per reduced channel) is
        // a large part of these small files, so the keys' bytes are what is compared.
        EXPECT_LT(stats.bytes_after * 2, stats.bytes_before);
        EXPECT_LT(fs::file_size(path), fs::file_size(full));
        const std::size_t bytes = expect_compact_accessors(path);
        EXPECT_EQ(bytes, stats.byte_rotations);
        // 20 mrad absorbs 8-bit rounding (at most 15.7 mrad): most rotations take bytes.
        if (bounds.rotation_rad >= 0.02f) {
            EXPECT_GT(bytes * 2, stats.rotations);
        }
        expect_valid(path);
        EXPECT_EQ(dir.entries().size(), 3u);  // crowd.json, full.glb, compact.glb: no spill file left
    }
}

// Seven chibis of crowd-gltf.json (their own skeleton and meshes; clip-animated bones and
// simulated hair), 60 frames: the rigged writer.
TEST(CompactExport, RiggedWithinBoundsWhenReimported) {
    TempDir dir;
    const RodRun run = run_rod_scene(scene_with_count(dir, "crowd-gltf", 7), 60);
    ASSERT_EQ(run.scene.characters.size(), 1u);
    const std::size_t joints = run.scene.world.joint_count;
    ChainSnapshot snapshot;
    const auto bake = [&](const std::string& path, const GlbCompaction& compaction) {
        auto e = RiggedCrowdExport::create(run.scene, 0, path, compaction);
        EXPECT_TRUE(e.ok()) << e.error().message;
        for (std::uint32_t f = 0; f < run.frames; ++f) {
            snapshot.positions.assign(run.positions.begin() + f * joints, run.positions.begin() + (f + 1) * joints);
            snapshot.orientations.assign(run.orientations.begin() + f * joints, run.orientations.begin() + (f + 1) * joints);
            EXPECT_TRUE(e.value().add_frame(f, snapshot).ok());
        }
        EXPECT_TRUE(e.value().finish(path).ok());
        return e.value().writer().compaction_stats();
    };
    const std::string full = dir.file("full.glb");
    const std::string path = dir.file("compact.glb");
    bake(full, {});
    const GlbCompaction bounds{true, 0.001f, 0.001f, 0.001f};
    const GlbCompactionStats stats = bake(path, bounds);
    const Measured m = compare(full, path);
    expect_within_bounds_as_reported(m, stats, bounds);
    EXPECT_LT(m.kept, m.keys / 2);
    EXPECT_LT(stats.bytes_after * 3, stats.bytes_before);
    EXPECT_EQ(expect_compact_accessors(path), stats.byte_rotations);
    expect_valid(path);
}

// 67 birds (four wing types; bird 4's tail flips hemisphere every other frame in the
// input), 90 frames: the birds' writer, without and with the Tail's scale channels (bird
// 5 spreads its tail from frame 30 on, so every bird gets one).
TEST(CompactExport, BirdsWithinBoundsWhenReimported) {
    const birds::BirdWorld world = make_world();
    const std::uint32_t frames = 90;
    for (const bool spread : {false, true}) {
        SCOPED_TRACE(spread ? "tail spread" : "no tail spread");
        std::vector<gpu::BirdPose> poses = make_poses(world, frames);
        if (spread) {
            for (std::uint32_t f = 30; f < frames; ++f) poses[f * kBirds + 5].position.w = 0.01f * static_cast<float>(f - 30);
        }
        TempDir dir;
        const std::string full = dir.file("full.glb");
        const std::string path = dir.file("compact.glb");
        ASSERT_TRUE(write_birds_glb(full, world, poses, frames).ok());
        for (const GlbCompaction bounds : {GlbCompaction{true, 0.001f, 0.001f, 0.001f}, GlbCompaction{true, 0.005f, 0.02f, 0.02f}}) {
            SCOPED_TRACE(std::to_string(bounds.position_m) + " m, " + std::to_string(bounds.rotation_rad) + " rad");
            auto writer = BirdGlbWriter::create(path, world, frames, bounds);
            ASSERT_TRUE(writer.ok()) << writer.error().message;
            ASSERT_TRUE(writer.value().add_frames(poses).ok());
            ASSERT_TRUE(writer.value().finish().ok());
            const GlbCompactionStats& stats = writer.value().compaction_stats();
            const Measured m = compare(full, path);
            expect_within_bounds_as_reported(m, stats, bounds);
            EXPECT_EQ(m.keys, std::size_t{kBirds} * (spread ? 9 : 8) * frames);
            EXPECT_LT(m.kept, m.keys / 4);
            EXPECT_LT(fs::file_size(path) * 2, fs::file_size(full));
            const std::size_t bytes = expect_compact_accessors(path);
            EXPECT_EQ(bytes, stats.byte_rotations);
            EXPECT_EQ(stats.rotations, std::size_t{kBirds} * 7);
            if (bounds.rotation_rad >= 0.02f) {
                EXPECT_GT(bytes * 2, stats.rotations);
                EXPECT_GT(m.rotation_rad, 1e-3);  // the bound is used, not only the 16-bit floor
            }
            expect_valid(path);
            EXPECT_EQ(dir.entries().size(), 2u);
        }
    }
}

// The channels are reduced and encoded on several threads (GlbCompaction::threads), then
// appended in bird order: the file's bytes are the same on 1, 2, 3 and 7 threads (7: more
// threads than a range of birds needs, ranges of 9 or 10 birds), plain and meshopt.
TEST(CompactExport, TheBytesAreTheSameOnAnyNumberOfThreads) {
    const birds::BirdWorld world = make_world();
    const std::uint32_t frames = 90;
    const std::vector<gpu::BirdPose> poses = make_poses(world, frames);
    TempDir dir;
    for (const bool meshopt : {false, true}) {
        SCOPED_TRACE(meshopt ? "meshopt" : "plain");
        std::string first;
        for (const unsigned threads : {1u, 2u, 3u, 7u}) {
            SCOPED_TRACE(std::to_string(threads) + " threads");
            const std::string path = dir.file("compact-" + std::to_string(threads) + ".glb");
            auto writer = BirdGlbWriter::create(path, world, frames, GlbCompaction{true, 0.001f, 0.001f, 0.001f, meshopt, threads});
            ASSERT_TRUE(writer.ok()) << writer.error().message;
            ASSERT_TRUE(writer.value().add_frames(poses).ok());
            ASSERT_TRUE(writer.value().finish().ok());
            const std::string bytes = testing_support::file_bytes(path);
            EXPECT_GT(bytes.size(), 1000u);
            if (first.empty()) first = bytes;
            EXPECT_TRUE(bytes == first) << "the file differs from the one written on 1 thread";
        }
    }
}

// The 4 GiB limit of a .glb: uncompacted, keys past it are refused before the simulation
// runs; compacted, their size is known only once reduced, so create() takes them (and
// finish() refuses a BIN chunk past 4 GiB before writing any JSON).
TEST(CompactExport, TheLimitIsTheCompactedSize) {
    const birds::BirdWorld world = make_world();
    // 124 bytes per bird and frame uncompacted (without the Tail's scale, written only
    // when a tail spreads): just past 4e9 bytes.
    const auto frames = static_cast<std::uint32_t>(4.0e9 / (124.0 * kBirds)) + 1;
    TempDir dir;
    const auto refused = BirdGlbWriter::create(dir.file("full.glb"), world, frames);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("4 GiB"), std::string::npos) << refused.error().message;
    EXPECT_TRUE(BirdGlbWriter::create(dir.file("compact.glb"), world, frames, GlbCompaction{true, 0.001f, 0.001f, 0.001f}).ok());
    // One frame fewer: the keys alone fit, but every bird's armature, skin and animation
    // JSON (about 3 kB a bird whatever the frames) takes the file past the limit, which
    // the writer used to find only after the simulation had run. A million birds over 10
    // frames: 1.24 GB of keys and some 3 GB of the birds' own part.
    const auto keys_fit = BirdGlbWriter::create(dir.file("birds.glb"), world, frames - 1);
    ASSERT_FALSE(keys_fit.ok());
    EXPECT_NE(keys_fit.error().message.find(" birds exceed the 4 GiB limit of a .glb (about "), std::string::npos)
        << keys_fit.error().message;
    // Well within it: taken.
    EXPECT_TRUE(BirdGlbWriter::create(dir.file("small.glb"), world, frames / 2).ok());
}

// Compaction off is the uncompacted writer, byte for byte (export_identity pins those
// bytes for the shipped scenes); bad bounds are refused, naming the file.
TEST(CompactExport, OffIsTheUncompactedFileAndBadBoundsAreRefused) {
    const RodRun run = run_bunny(6);
    TempDir dir;
    ASSERT_TRUE(write_chains_glb(dir.file("a.glb"), run.scene, run.frames, run.positions, run.orientations).ok());
    GlbCompaction off{false, -1.0f, 0.0f, 0.0f};  // bounds are not looked at when off
    ASSERT_TRUE(write_chains_glb(dir.file("b.glb"), run.scene, run.frames, run.positions, run.orientations, off).ok());
    std::ifstream a(dir.file("a.glb"), std::ios::binary);
    std::ifstream b(dir.file("b.glb"), std::ios::binary);
    EXPECT_TRUE(std::equal(std::istreambuf_iterator<char>(a), {}, std::istreambuf_iterator<char>(b), {}));
    for (const float bad : {-0.001f, std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()}) {
        const auto refused = ChainsGlbWriter::create(dir.file("c.glb"), run.scene, run.frames, {true, 0.001f, bad, 0.001f});
        ASSERT_FALSE(refused.ok());
        EXPECT_EQ(refused.error().kind, Error::Kind::InvalidInput);
        EXPECT_NE(refused.error().message.find("c.glb"), std::string::npos) << refused.error().message;
    }
}

}  // namespace
}  // namespace kodawari
