// JSON Lines traces (docs/trace-format.md). Written by hand rather than through a JSON
// library: a trace of a large flock has millions of records, and formatting straight
// into one growing buffer is several times faster than building DOM objects.

#include <array>
#include <cassert>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "kodawari/birds/rig.hpp"
#include "kodawari/birds/wingbeat.hpp"
#include "kodawari/export/export.hpp"

namespace kodawari {
namespace {

/// The buffer goes to the file once it holds this much.
constexpr std::size_t kFlushBytes = std::size_t{1} << 20;

template <typename Number>
void append_number(std::string& out, Number value) {
    // A non-finite value means the simulation broke; JSON has no spelling for it.
    assert(std::isfinite(value) && "non-finite value in a trace");
    if (!std::isfinite(value)) {
        out += "null";
        return;
    }
    char text[32];
    const auto result = std::to_chars(text, text + sizeof(text), value);
    assert(result.ec == std::errc());
    out.append(text, result.ptr);
}

void append_integer(std::string& out, std::uint64_t value) {
    char text[24];
    const auto result = std::to_chars(text, text + sizeof(text), value);
    assert(result.ec == std::errc());
    out.append(text, result.ptr);
}

/// A JSON string literal; bytes from 0x80 up pass through (the input is UTF-8).
void append_string(std::string& out, std::string_view text) {
    static constexpr char kHex[] = "0123456789abcdef";
    out += '"';
    for (const char c : text) {
        const auto byte = static_cast<unsigned char>(c);
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\n': out += "\\n"; break;
            case '\r': out += "\\r"; break;
            case '\t': out += "\\t"; break;
            default:
                if (byte < 0x20) {
                    out += "\\u00";
                    out += kHex[byte >> 4];
                    out += kHex[byte & 0xF];
                } else {
                    out += c;
                }
        }
    }
    out += '"';
}

// [a, b, ...]: a point, a direction, or a rotation as [x, y, z, w] (glTF's order).
void append_numbers(std::string& out, std::initializer_list<float> values) {
    out += '[';
    for (const float v : values) {
        if (out.back() != '[') out += ',';
        append_number(out, v);
    }
    out += ']';
}

void append_vec3(std::string& out, float x, float y, float z) { append_numbers(out, {x, y, z}); }
void append_quat(std::string& out, float x, float y, float z, float w) { append_numbers(out, {x, y, z, w}); }

const char* mode_of(float value) {
    const long mode = std::lround(value);
    assert(mode >= 0 && mode < static_cast<long>(KW_MODE_COUNT) && "diagnostic mode out of range");
    if (mode < 0 || mode >= static_cast<long>(KW_MODE_COUNT)) return "level";
    return birds::mode_name(static_cast<birds::FlightMode>(mode));
}

}  // namespace

Result<TraceWriter> TraceWriter::open(const std::string& path, const TraceHeader& header) {
    auto file = AtomicFile::open(path);
    if (!file) return file.error();
    TraceWriter writer(std::move(file).value());
    std::string& out = writer.buffer_;
    out.reserve(kFlushBytes + 4096);
    out += "{\"kind\":\"header\",\"scene\":";
    append_string(out, header.scene);
    out += ",\"fps\":";
    append_number(out, header.fps);
    out += ",\"frames\":";
    append_integer(out, header.frames);
    out += ",\"backend\":";
    append_string(out, header.backend);
    out += "}\n";
    return writer;
}

void TraceWriter::write_frame(std::uint32_t frame, const birds::BirdWorld& world,
                              std::span<const gpu::BirdPose> poses, std::span<const gpu::BirdDiag> diag) {
    const std::size_t bird_count = world.birds.size();
    assert(poses.size() == bird_count && diag.size() == bird_count);

    // Per wing type, then per user's model, the constant part of every record's "parts"
    // that is not Body, and the type's name.
    std::vector<std::array<std::array<float, 3>, birds::kPartCount>> offsets(birds::kWingTypeCount + world.models.size());
    std::vector<std::string_view> names(offsets.size());
    for (std::size_t t = 0; t < offsets.size(); ++t) {
        if (t < birds::kWingTypeCount) {
            offsets[t] = birds::part_offsets(static_cast<birds::WingType>(t));
            names[t] = birds::wing_type_spec(static_cast<birds::WingType>(t)).name;
        } else {
            offsets[t] = world.models[t - birds::kWingTypeCount]->offsets;
            names[t] = world.models[t - birds::kWingTypeCount]->name;
        }
    }
    const double time = static_cast<double>(frame) / static_cast<double>(world.fps);

    std::string& out = buffer_;
    for (std::size_t b = 0; b < bird_count; ++b) {
        const gpu::BirdPose& pose = poses[b];
        const gpu::BirdDiag& d = diag[b];
        const std::uint32_t type = world.birds[b].ids.y;
        assert(type < offsets.size());

        out += "{\"kind\":\"bird\",\"frame\":";
        append_integer(out, frame);
        out += ",\"time\":";
        append_number(out, time);
        out += ",\"id\":";
        append_integer(out, b);
        out += ",\"wing_type\":\"";
        out += names[type];
        out += "\",\"mode\":\"";
        out += mode_of(d.acceleration.w);
        out += "\",\"phase\":";
        append_number(out, d.attitude.w);
        out += ",\"blend\":";
        append_number(out, d.velocity.w);
        out += ",\"position\":";
        append_vec3(out, pose.position.x, pose.position.y, pose.position.z);
        out += ",\"velocity\":";
        append_vec3(out, d.velocity.x, d.velocity.y, d.velocity.z);
        out += ",\"acceleration\":";
        append_vec3(out, d.acceleration.x, d.acceleration.y, d.acceleration.z);
        out += ",\"yaw\":";
        append_number(out, d.attitude.x);
        out += ",\"pitch\":";
        append_number(out, d.attitude.y);
        out += ",\"bank\":";
        append_number(out, d.attitude.z);
        out += ",\"speed_fraction\":";
        append_number(out, d.flight.x);
        out += ",\"extra_pitch\":";
        append_number(out, d.flight.y);
        out += ",\"tail_spread\":";
        append_number(out, d.flight.z);
        out += ",\"glided\":";
        append_number(out, d.flight.w);
        out += ",\"angles\":{\"arm1_pitch\":";
        append_number(out, d.angles.x);
        out += ",\"arm2_pitch\":";
        append_number(out, d.angles.y);
        out += ",\"arm1_heading\":";
        append_number(out, d.angles.z);
        out += ",\"arm2_heading\":";
        append_number(out, d.angles.w);
        out += "},\"parts\":{";
        for (std::size_t part = 0; part < birds::kPartCount; ++part) {
            if (part > 0) out += ',';
            out += '"';
            out += birds::kPartNames[part];
            out += "\":{\"t\":";
            if (part == KW_PART_BODY) {
                append_vec3(out, pose.position.x, pose.position.y, pose.position.z);
            } else {
                const auto& t = offsets[type][part];
                append_vec3(out, t[0], t[1], t[2]);
            }
            const gpu::vec4& r = pose.rotation[part];
            out += ",\"r\":";
            append_quat(out, r.x, r.y, r.z, r.w);
            out += '}';
        }
        out += "}}\n";

        if (out.size() >= kFlushBytes) {
            file_.write(out);
            out.clear();
        }
    }
}

void TraceWriter::write_chains(std::uint32_t frame, float time, const rods::RodWorld& world,
                               std::span<const std::uint32_t> characters, std::span<const std::uint32_t> chains_in_character,
                               std::span<const std::string> names, const ChainSnapshot& snapshot) {
    assert(characters.size() == world.chains.size() && chains_in_character.size() == world.chains.size());
    assert(names.empty() || names.size() == world.chains.size());
    constexpr std::size_t kWeights = rods::kMaxViewExamples + 1;
    std::string& out = buffer_;
    for (std::size_t c = 0; c < world.chains.size(); ++c) {
        const rods::ChainInstance& chain = world.chains[c];
        const std::uint32_t n = world.templ(chain).chain.joint_count;
        // Views, then keyed examples (docs/keyed-examples.md K.4).
        const std::size_t m = world.templ(chain).views.size() + world.templ(chain).keyed.size();
        out += "{\"kind\":\"chain\",\"frame\":";
        append_integer(out, frame);
        out += ",\"time\":";
        append_number(out, time);
        out += ",\"character\":";
        append_integer(out, characters[c]);
        out += ",\"chain\":";
        append_integer(out, chains_in_character[c]);
        if (!names.empty()) {
            out += ",\"name\":";
            append_string(out, names[c]);
        }
        const glm::vec3 d = snapshot.view_directions[c];
        out += ",\"view_dir\":";
        append_vec3(out, d.x, d.y, d.z);
        out += ",\"weights\":[";
        for (std::size_t k = 0; k <= m; ++k) {
            if (k > 0) out += ',';
            append_number(out, snapshot.weights[c * kWeights + k]);
        }
        out += "],\"rest\":[";
        for (std::uint32_t i = 0; i < n; ++i) {
            if (i > 0) out += ',';
            const glm::vec3 r = snapshot.rest[chain.joint_begin + i];
            append_vec3(out, r.x, r.y, r.z);
        }
        out += "],\"joints\":[";
        for (std::uint32_t i = 0; i < n; ++i) {
            if (i > 0) out += ',';
            const glm::vec3 x = snapshot.positions[chain.joint_begin + i];
            append_vec3(out, x.x, x.y, x.z);
        }
        out += "],\"orientations\":[";
        for (std::uint32_t i = 0; i < n; ++i) {
            if (i > 0) out += ',';
            const glm::quat q = snapshot.orientations[chain.joint_begin + i];
            append_quat(out, q.x, q.y, q.z, q.w);
        }
        out += "]}\n";
        if (out.size() >= kFlushBytes) {
            file_.write(out);
            out.clear();
        }
    }
}

Result<void> TraceWriter::finish() {
    file_.write(buffer_);
    buffer_.clear();
    buffer_.shrink_to_fit();
    return file_.commit();
}

}  // namespace kodawari
