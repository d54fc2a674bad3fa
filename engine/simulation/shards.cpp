// Part files of a sharded bake (kodawari/shards.hpp): the sink that writes a shard's
// frames, and the source that reads every shard back as the whole scene's frames.
#include "kodawari/shards.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string_view>

#include <nlohmann/json.hpp>

#include "kodawari/atomic_file.hpp"
#include "kodawari/version.hpp"
#include "simulation/frame_payload.hpp"
#include "simulation/scene_worlds.hpp"

namespace kodawari {

namespace {

constexpr std::string_view kMagic = "KODAWARI-PART 1\n";
constexpr std::string_view kEndMark = "KODAWARI-PART-END\n";
// A header line longer than this is not a part file's (the real ones hold ~400 bytes).
constexpr std::size_t kMaxHeaderBytes = 1 << 16;

Error bad(const std::string& text) { return Error{Error::Kind::InvalidInput, text}; }

// FNV-1a 64 of the scene file: merge checks that the scene the parts were baked from is
// the one it rebuilds the world from (a changed scene would give other instances).
Result<std::uint64_t> hash_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return make_error(Error::Kind::InvalidInput, path + ": cannot read the scene file");
    std::uint64_t hash = 0xcbf29ce484222325ull;
    char buffer[1 << 16];
    while (in) {
        in.read(buffer, sizeof buffer);
        for (std::streamsize i = 0; i < in.gcount(); ++i) {
            hash ^= static_cast<unsigned char>(buffer[i]);
            hash *= 0x100000001b3ull;
        }
    }
    return hash;
}

std::string hex(std::uint64_t value) {
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
    return text;
}

struct ChunkHead {
    std::uint32_t first = 0;
    std::uint32_t count = 0;
    std::uint64_t bytes = 0;
};

class PartSink final : public BakeSink {
public:
    PartSink(std::string path, const ShardInfo& shard) : path_(std::move(path)), shard_(shard) {}

    BakeNeeds needs() const override { return {.bird_poses = true, .chains = true}; }

    Result<void> begin(const BakeWorld& world) override {
        auto hash = hash_file(world.scene->path);
        if (!hash) return hash.error();
        layout_.birds = static_cast<std::uint32_t>(world.birds->birds.size());
        layout_.poses = true;
        if (world.rods != nullptr) {
            layout_.joints = world.rods->world.joint_count;
            layout_.chains = static_cast<std::uint32_t>(world.rods->world.chains.size());
            layout_.chain_pose = true;
        }
        std::error_code ec;
        const auto scene_path = std::filesystem::absolute(world.scene->path, ec);
        const nlohmann::json header = {
            {"kodawari", std::string(version())},
            {"scene", ec ? world.scene->path : scene_path.lexically_normal().string()},
            {"scene_fnv1a64", hex(hash.value())},
            {"frames", world.frames},
            {"shard", {shard_.shard.index, shard_.shard.count}},
            {"birds", range("birds")},
            {"characters", range("characters")},
            {"joints", layout_.joints},
            {"chains", layout_.chains},
            {"backend", world.backend},
        };
        auto file = AtomicFile::open(path_);
        if (!file) return file.error();
        file_.emplace(std::move(file).value());
        file_->write(std::string(kMagic));
        file_->write(header.dump() + "\n");
        return {};
    }

    Result<void> consume(const BakeFrames& frames) override {
        detail::encode_frames(frames, layout_, payload_);
        const ChunkHead head{frames.first, frames.count, payload_.size()};
        file_->write(&head.first, sizeof head.first);
        file_->write(&head.count, sizeof head.count);
        file_->write(&head.bytes, sizeof head.bytes);
        file_->write(payload_.data(), payload_.size());
        return {};
    }

    Result<std::vector<BakeOutput>> finish() override {
        file_->write(std::string(kEndMark));
        KW_TRY(file_->commit());
        return std::vector<BakeOutput>{{path_, BakeOutput::Format::Part,
                                        "shard " + std::to_string(shard_.shard.index) + " of " + std::to_string(shard_.shard.count),
                                        {}}};
    }

private:
    // [begin, end, scene count] of the instances called `instances`.
    nlohmann::json range(std::string_view instances) const {
        const ShardPart part = shard_.part(instances);
        return {part.range.begin, part.range.end, part.scene_count};
    }

    std::string path_;
    ShardInfo shard_;
    detail::PayloadLayout layout_;
    std::optional<AtomicFile> file_;
    std::vector<std::byte> payload_;
};

// One part file being read.
struct Part {
    std::string path;
    std::FILE* file = nullptr;
    nlohmann::json header;
    Shard shard;
    InstanceRange birds, characters;
    std::uint32_t scene_birds = 0, scene_characters = 0;
    detail::PayloadLayout layout;

    Part() = default;
    Part(Part&& other) noexcept { *this = std::move(other); }
    Part& operator=(Part&& other) noexcept {
        std::swap(path, other.path);
        std::swap(file, other.file);
        std::swap(header, other.header);
        shard = other.shard;
        birds = other.birds;
        characters = other.characters;
        scene_birds = other.scene_birds;
        scene_characters = other.scene_characters;
        layout = other.layout;
        return *this;
    }
    Part(const Part&) = delete;
    Part& operator=(const Part&) = delete;
    ~Part() {
        if (file != nullptr) std::fclose(file);
    }

    [[nodiscard]] Result<void> read(void* data, std::size_t size, const char* what) {
        if (size != 0 && std::fread(data, 1, size, file) != size) {
            return bad(path + ": ends inside " + std::string(what) + " (a truncated part file)");
        }
        return {};
    }
};

// Reads "[a, b, ...]" of `count` unsigned 32-bit numbers from header field `key`.
Result<std::vector<std::uint32_t>> numbers(const Part& part, const char* key, std::size_t count) {
    const auto it = part.header.find(key);
    const std::string expected = std::to_string(count) + " unsigned 32-bit integers";
    if (it == part.header.end()) return bad(part.path + ": header field \"" + key + "\" is missing (expected " + expected + ")");
    std::vector<std::uint32_t> out;
    const nlohmann::json& value = *it;
    const bool array = value.is_array();
    if ((array && value.size() != count) || (!array && count != 1)) {
        return bad(part.path + ": header field \"" + key + "\": expected " + expected + ", got " + value.dump());
    }
    for (const nlohmann::json& v : array ? value : nlohmann::json::array({value})) {
        if (!v.is_number_unsigned() || v.get<std::uint64_t>() > 0xffffffffull) {
            return bad(part.path + ": header field \"" + key + "\": expected " + expected + ", got " + value.dump());
        }
        out.push_back(v.get<std::uint32_t>());
    }
    return out;
}

Result<std::string> text(const Part& part, const char* key) {
    const auto it = part.header.find(key);
    if (it == part.header.end() || !it->is_string()) {
        return bad(part.path + ": header field \"" + key + "\" must be a string");
    }
    return it->get<std::string>();
}

Result<Part> open_part(const std::string& path) {
    Part part;
    part.path = path;
    part.file = std::fopen(path.c_str(), "rb");
    if (part.file == nullptr) return make_error(Error::Kind::InvalidInput, path + ": cannot open the part file: " + std::strerror(errno));
    std::string magic(kMagic.size(), '\0');
    if (std::fread(magic.data(), 1, magic.size(), part.file) != magic.size() || magic != kMagic) {
        return bad(path + ": not a kodawari part file (it does not start with \"KODAWARI-PART 1\"; `kodawari run --shard I/N` writes them)");
    }
    std::string line;
    for (int c; (c = std::fgetc(part.file)) != '\n';) {
        if (c == EOF || line.size() > kMaxHeaderBytes) return bad(path + ": the header line is cut short or too long");
        line.push_back(static_cast<char>(c));
    }
    part.header = nlohmann::json::parse(line, nullptr, false);
    if (part.header.is_discarded() || !part.header.is_object()) return bad(path + ": the header is not a JSON object");
    auto shard = numbers(part, "shard", 2);
    if (!shard) return shard.error();
    part.shard = {shard.value()[0], shard.value()[1]};
    if (part.shard.count == 0 || part.shard.index >= part.shard.count) {
        return bad(path + ": header field \"shard\": expected [index, count] with index < count, got " + part.header["shard"].dump());
    }
    auto birds = numbers(part, "birds", 3);
    if (!birds) return birds.error();
    auto characters = numbers(part, "characters", 3);
    if (!characters) return characters.error();
    part.scene_birds = birds.value()[2];
    part.scene_characters = characters.value()[2];
    part.birds = {birds.value()[0], birds.value()[1]};
    part.characters = {characters.value()[0], characters.value()[1]};
    // The ranges follow from the shard; a part that says otherwise was not written by
    // `run --shard` (or by another version of the formula).
    const InstanceRange b = shard_range(part.scene_birds, part.shard);
    const InstanceRange c = shard_range(part.scene_characters, part.shard);
    if (b.begin != part.birds.begin || b.end != part.birds.end || c.begin != part.characters.begin ||
        c.end != part.characters.end) {
        return bad(path + ": header fields \"birds\" and \"characters\" are not shard " + std::to_string(part.shard.index) +
                   " of " + std::to_string(part.shard.count) + "'s ranges");
    }
    auto joints = numbers(part, "joints", 1);
    if (!joints) return joints.error();
    auto chains = numbers(part, "chains", 1);
    if (!chains) return chains.error();
    KW_TRY(numbers(part, "frames", 1));
    KW_TRY(text(part, "scene"));
    KW_TRY(text(part, "scene_fnv1a64"));
    KW_TRY(text(part, "backend"));
    part.layout.birds = part.birds.size();
    part.layout.joints = joints.value()[0];
    part.layout.chains = chains.value()[0];
    part.layout.poses = true;
    part.layout.chain_pose = part.scene_characters > 0;
    return part;
}

class PartsSource final : public BakeSource {
public:
    PartsSource(std::vector<Part> parts, Scene scene, detail::SceneWorlds worlds, std::string backend)
        : parts_(std::move(parts)), scene_(std::move(scene)), worlds_(std::move(worlds)), backend_(std::move(backend)) {
        std::vector<detail::PayloadLayout> layouts;
        for (const Part& part : parts_) {
            layouts.push_back(part.layout);
            names_.push_back(part.path);
        }
        assembler_.emplace(std::move(layouts));
    }

    BakeWorld world() const override {
        return worlds_.bake_world(scene_, backend_);
    }

    std::uint32_t chunk_frames() const override {
        return bake_chunk_frames(worlds_.birds->birds.size(), worlds_.rods != nullptr);
    }

    Result<BakeFrames> next(std::uint32_t first, std::uint32_t count, const BakeNeeds& needs) override {
        if (needs.bird_diag || needs.chain_shapes) {
            return bad(names_.front() + ": part files hold bird poses and chain joints, not the diagnostics and rest shapes a trace needs");
        }
        payloads_.resize(parts_.size());
        std::vector<std::span<const std::byte>> spans;
        for (std::size_t p = 0; p < parts_.size(); ++p) {
            Part& part = parts_[p];
            ChunkHead head;
            KW_TRY(part.read(&head.first, sizeof head.first, "a chunk's header"));
            KW_TRY(part.read(&head.count, sizeof head.count, "a chunk's header"));
            KW_TRY(part.read(&head.bytes, sizeof head.bytes, "a chunk's header"));
            if (head.first != first || head.count != count || head.bytes != part.layout.bytes(count)) {
                return bad(part.path + ": expected frames " + std::to_string(first) + ".." + std::to_string(first + count - 1) +
                           " (" + std::to_string(part.layout.bytes(count)) + " bytes), found frames " +
                           std::to_string(head.first) + " + " + std::to_string(head.count) + " (" + std::to_string(head.bytes) +
                           " bytes)");
            }
            payloads_[p].resize(head.bytes);
            KW_TRY(part.read(payloads_[p].data(), head.bytes, "a chunk of frames"));
            spans.emplace_back(payloads_[p]);
            if (first + count == worlds_.frames) {
                std::string end(kEndMark.size(), '\0');
                KW_TRY(part.read(end.data(), end.size(), "its end mark"));
                if (end != kEndMark || std::fgetc(part.file) != EOF) {
                    return bad(part.path + ": does not end after its last frame with \"KODAWARI-PART-END\"");
                }
            }
        }
        auto frames = assembler_->assemble(first, count, spans, names_);
        if (!frames) return frames.error();
        if (!worlds_.rods) frames.value().chains = nullptr;
        return frames;
    }

private:
    std::vector<Part> parts_;
    std::vector<std::string> names_;
    Scene scene_;
    detail::SceneWorlds worlds_;
    std::string backend_;
    std::optional<detail::FrameAssembler> assembler_;
    std::vector<std::vector<std::byte>> payloads_;
};

}  // namespace

std::unique_ptr<BakeSink> make_part_sink(std::string path, const ShardInfo& shard) {
    return std::make_unique<PartSink>(std::move(path), shard);
}

Result<std::unique_ptr<BakeSource>> open_parts(std::span<const std::string> paths, const MergeOptions& options) {
    if (paths.empty()) return bad("merge: no part files given");
    std::vector<Part> parts;
    for (const std::string& path : paths) {
        auto part = open_part(path);
        if (!part) return part.error();
        parts.push_back(std::move(part).value());
    }
    // Every part of one bake: the same scene, frames, shard count, backend and totals.
    const Part& a = parts.front();
    for (const char* key : {"scene_fnv1a64", "frames", "backend", "kodawari"}) {
        for (const Part& b : parts) {
            if (b.header.value(key, nlohmann::json()) != a.header.value(key, nlohmann::json())) {
                return bad(b.path + ": header field \"" + key + "\" is " + b.header.value(key, nlohmann::json()).dump() + ", but " +
                           a.path + "'s is " + a.header.value(key, nlohmann::json()).dump() +
                           ": the parts are not of one bake");
            }
        }
    }
    std::vector<const Part*> by_index(a.shard.count, nullptr);
    for (const Part& b : parts) {
        if (b.shard.count != a.shard.count || b.scene_birds != a.scene_birds || b.scene_characters != a.scene_characters) {
            return bad(b.path + ": shard " + std::to_string(b.shard.index) + " of " + std::to_string(b.shard.count) +
                       " does not belong with " + a.path + "'s shard " + std::to_string(a.shard.index) + " of " +
                       std::to_string(a.shard.count));
        }
        if (by_index[b.shard.index] != nullptr) {
            return bad(b.path + ": shard " + std::to_string(b.shard.index) + " is given twice (also " +
                       by_index[b.shard.index]->path + ")");
        }
        by_index[b.shard.index] = &b;
    }
    for (std::uint32_t i = 0; i < a.shard.count; ++i) {
        if (by_index[i] == nullptr) {
            return bad("merge: shard " + std::to_string(i) + " of " + std::to_string(a.shard.count) + " is missing");
        }
    }
    std::sort(parts.begin(), parts.end(), [](const Part& x, const Part& y) { return x.shard.index < y.shard.index; });

    const std::string scene_path = options.scene.empty() ? a.header["scene"].get<std::string>() : options.scene;
    auto hash = hash_file(scene_path);
    if (!hash) return hash.error();
    const std::string recorded = a.header["scene_fnv1a64"].get<std::string>();
    if (hex(hash.value()) != recorded) {
        return bad(scene_path + ": the scene file changed since the parts were baked (FNV-1a 64 " + hex(hash.value()) +
                   ", the parts' \"scene_fnv1a64\" is " + recorded + ")");
    }
    auto scene = load_scene(scene_path);
    if (!scene) return scene.error();
    auto worlds = detail::build_scene_worlds(scene.value(), a.header["frames"].get<std::uint32_t>());
    if (!worlds) return worlds.error();
    // The whole world must be the parts' sum (the same scene gives the same counts).
    std::size_t joints = 0;
    for (const Part& p : parts) joints += p.layout.joints;
    const std::size_t world_joints = worlds.value().rods ? worlds.value().rods->world.joint_count : 0;
    const std::size_t world_characters = worlds.value().rods ? worlds.value().rods->instances.size() : 0;
    if (worlds.value().birds->birds.size() != a.scene_birds || world_characters != a.scene_characters || joints != world_joints) {
        return bad(scene_path + ": builds " + std::to_string(worlds.value().birds->birds.size()) + " birds, " +
                   std::to_string(world_characters) + " characters and " + std::to_string(world_joints) +
                   " joints; the parts hold " + std::to_string(a.scene_birds) + ", " + std::to_string(a.scene_characters) +
                   " and " + std::to_string(joints));
    }
    const std::string backend = a.header["backend"].get<std::string>();
    return std::unique_ptr<BakeSource>(
        std::make_unique<PartsSource>(std::move(parts), std::move(scene).value(), std::move(worlds).value(), backend));
}

}  // namespace kodawari
