// Part files of a sharded bake (kodawari/simulation/shards.hpp): the sink that writes a shard's
// frames, and the source that reads every shard back as the whole scene's frames.
#include "kodawari/simulation/shards.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string_view>

#include <nlohmann/json.hpp>

#include "kodawari/core/atomic_file.hpp"
#include "kodawari/core/version.hpp"
#include "simulation/frame_payload.hpp"
#include "simulation/scene_worlds.hpp"

namespace kodawari {

namespace {

// Version 2: per-domain instance ranges and the channels' layout in the header (issue 31).
constexpr std::string_view kMagic = "KODAWARI-PART 2\n";
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
    PartSink(std::string path, const Simulation& sim) : path_(std::move(path)), shard_(sim.shard()) {
        // What the domains' .glb outputs need: every channel but the diagnostics.
        for (const Domain* domain : sim.domains()) {
            for (const ChannelInfo& info : domain->channels()) {
                if (!info.diagnostic) needs_.channels.push_back(info.name);
            }
        }
    }

    BakeNeeds needs() const override { return needs_; }

    Result<void> begin(const BakeWorld& world) override {
        auto hash = hash_file(world.scene->path);
        if (!hash) return hash.error();
        layout_ = detail::payload_layout(world.domains, needs_);
        nlohmann::json instances = nlohmann::json::object();
        for (const ShardPart& part : shard_.parts) {
            instances[part.instances] = {part.range.begin, part.range.end, part.scene_count};
        }
        nlohmann::json channels = nlohmann::json::array();
        for (const ChannelInfo& c : layout_.channels) channels.push_back({c.name, c.element_bytes, c.elements});
        std::error_code ec;
        const auto scene_path = std::filesystem::absolute(world.scene->path, ec);
        const nlohmann::json header = {
            {"kodawari", std::string(version())},
            {"scene", ec ? world.scene->path : scene_path.lexically_normal().string()},
            {"scene_fnv1a64", hex(hash.value())},
            {"frames", world.frames},
            {"shard", {shard_.shard.index, shard_.shard.count}},
            {"instances", instances},
            {"channels", channels},
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
    std::string path_;
    ShardInfo shard_;
    BakeNeeds needs_;
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
    std::vector<ShardPart> instances;  // per domain, in the header's order
    detail::PayloadLayout layout;

    Part() = default;
    Part(Part&& other) noexcept { *this = std::move(other); }
    Part& operator=(Part&& other) noexcept {
        std::swap(path, other.path);
        std::swap(file, other.file);
        std::swap(header, other.header);
        shard = other.shard;
        std::swap(instances, other.instances);
        std::swap(layout, other.layout);
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
        return bad(path + ": not a kodawari part file of this version (it does not start with \"KODAWARI-PART 2\"; `kodawari run "
                          "--shard I/N` writes them)");
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
    // "instances": {"birds": [begin, end, scene count], ...}, each range the shard's.
    const auto instances = part.header.find("instances");
    if (instances == part.header.end() || !instances->is_object()) {
        return bad(path + ": header field \"instances\" must be an object of [begin, end, count] per kind of instance");
    }
    for (const auto& [noun, value] : instances->items()) {
        const bool good = value.is_array() && value.size() == 3 &&
                          std::all_of(value.begin(), value.end(), [](const nlohmann::json& v) {
                              return v.is_number_unsigned() && v.get<std::uint64_t>() <= 0xffffffffull;
                          });
        if (!good) return bad(path + ": header field \"instances\": \"" + noun + "\": expected [begin, end, count], got " + value.dump());
        ShardPart share{noun, {value[0].get<std::uint32_t>(), value[1].get<std::uint32_t>()}, value[2].get<std::uint32_t>()};
        // The ranges follow from the shard; a part that says otherwise was not written by
        // `run --shard` (or by another version of the formula).
        const InstanceRange expected = shard_range(share.scene_count, part.shard);
        if (expected.begin != share.range.begin || expected.end != share.range.end) {
            return bad(path + ": header field \"instances\": \"" + noun + "\" is not shard " + std::to_string(part.shard.index) +
                       " of " + std::to_string(part.shard.count) + "'s range");
        }
        part.instances.push_back(std::move(share));
    }
    // "channels": [[name, element bytes, elements], ...], the payload's order.
    const auto channels = part.header.find("channels");
    if (channels == part.header.end() || !channels->is_array()) {
        return bad(path + ": header field \"channels\" must be an array of [name, element bytes, elements]");
    }
    for (const nlohmann::json& c : *channels) {
        const bool good = c.is_array() && c.size() == 3 && c[0].is_string() && c[1].is_number_unsigned() &&
                          c[1].get<std::uint64_t>() <= 0xffffffffull && c[2].is_number_unsigned();
        if (!good) return bad(path + ": header field \"channels\": expected [name, element bytes, elements], got " + c.dump());
        part.layout.channels.push_back({c[0].get<std::string>(), c[1].get<std::uint32_t>(), c[2].get<std::uint64_t>(), false});
    }
    KW_TRY(numbers(part, "frames", 1));
    KW_TRY(text(part, "scene"));
    KW_TRY(text(part, "scene_fnv1a64"));
    KW_TRY(text(part, "backend"));
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

    std::uint32_t chunk_frames() const override { return bake_chunk_frames(worlds_.views()); }

    Result<BakeFrames> next(std::uint32_t first, std::uint32_t count, const BakeNeeds& needs) override {
        // Part files hold what the .glb outputs need: a channel of the scene they do not
        // hold (a diagnostic) cannot be merged.
        for (const std::string& name : needs.channels) {
            const auto& held = parts_.front().layout.channels;
            if (std::any_of(held.begin(), held.end(), [&](const ChannelInfo& c) { return c.name == name; })) continue;
            for (const Domain* domain : worlds_.views()) {
                for (const ChannelInfo& info : domain->channels()) {
                    if (info.name == name && info.elements > 0) {
                        return bad(names_.front() + ": part files do not hold channel \"" + name +
                                   "\" (a diagnostic, what a trace needs): a merge writes the .glb files");
                    }
                }
            }
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
        return assembler_->assemble(first, count, spans, names_);
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

std::unique_ptr<BakeSink> make_part_sink(std::string path, const Simulation& sim) {
    return std::make_unique<PartSink>(std::move(path), sim);
}

namespace {

// Parts of one bake: the same kinds of instances with the same totals, and the same
// channels in the same order with the same element sizes.
bool same_bake(const Part& a, const Part& b) {
    if (a.instances.size() != b.instances.size() || a.layout.channels.size() != b.layout.channels.size()) return false;
    for (std::size_t i = 0; i < a.instances.size(); ++i) {
        if (a.instances[i].instances != b.instances[i].instances || a.instances[i].scene_count != b.instances[i].scene_count) {
            return false;
        }
    }
    for (std::size_t c = 0; c < a.layout.channels.size(); ++c) {
        if (a.layout.channels[c].name != b.layout.channels[c].name ||
            a.layout.channels[c].element_bytes != b.layout.channels[c].element_bytes) {
            return false;
        }
    }
    return true;
}

}  // namespace

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
        if (b.shard.count != a.shard.count || !same_bake(a, b)) {
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
    // The whole scene must be the parts' sum (the same scene gives the same counts): its
    // instances of every kind, and the elements of every channel the parts hold.
    const std::vector<const Domain*> whole = worlds.value().views();
    for (const ShardPart& share : a.instances) {
        const auto domain = std::find_if(whole.begin(), whole.end(), [&](const Domain* d) { return d->instance_noun() == share.instances; });
        const std::uint32_t built = domain == whole.end() ? 0 : (*domain)->scene_instances();
        if (built != share.scene_count) {
            return bad(scene_path + ": builds " + std::to_string(built) + " " + share.instances + "; the parts hold " +
                       std::to_string(share.scene_count));
        }
    }
    for (std::size_t c = 0; c < a.layout.channels.size(); ++c) {
        const std::string& name = a.layout.channels[c].name;
        std::uint64_t held = 0, built = 0;
        for (const Part& p : parts) held += p.layout.channels[c].elements;
        for (const Domain* d : whole) {
            for (const ChannelInfo& info : d->channels()) {
                if (info.name == name) built = info.elements;
            }
        }
        if (held != built) {
            return bad(scene_path + ": builds " + std::to_string(built) + " elements of channel \"" + name +
                       "\"; the parts hold " + std::to_string(held));
        }
    }
    const std::string backend = a.header["backend"].get<std::string>();
    return std::unique_ptr<BakeSource>(
        std::make_unique<PartsSource>(std::move(parts), std::move(scene).value(), std::move(worlds).value(), backend));
}

}  // namespace kodawari
