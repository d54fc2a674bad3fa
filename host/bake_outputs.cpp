// The outputs of a bake (bake_outputs.hpp).
#include "bake_outputs.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "kodawari/core/atomic_file.hpp"

namespace kodawari::cli {


std::vector<std::unique_ptr<BakeSink>> glb_sinks(const std::string& out, bool has_birds, bool has_chains,
                                                 const GlbCompaction& compaction) {
    // One file per kind of content.
    std::vector<std::unique_ptr<BakeSink>> sinks;
    const std::vector<std::string> paths = glb_bake_paths(out, has_birds, has_chains);
    if (has_birds) sinks.push_back(make_birds_glb_sink(paths.front(), compaction));
    if (has_chains) sinks.push_back(make_chains_glb_sink(paths.back(), compaction));
    return sinks;
}

void require_glb_name(const std::optional<std::string>& out) {
    if (!out) return;
    if (const std::string problem = glb_name_problem(*out); !problem.empty()) throw UsageError{"--out " + *out + ": " + problem};
}

Result<void> refuse_overwriting_inputs(const Scene& scene, const std::vector<std::string>& outputs, const std::string& what,
                                       const std::string& extension) {
    for (const std::string& out : outputs) {
        const std::string input = scene.reads(out);
        if (input.empty()) continue;
        // The characters' file beside the birds' is named after --out: a new --out is the cure.
        const bool beside = out != outputs.front();
        const std::filesystem::path p(outputs.front());
        const std::string option = extension == ".jsonl" ? "--trace" : "--out";
        const std::string other = (p.parent_path() / (p.stem().string() + "-bake" + extension)).string();
        return make_error(Error::Kind::InvalidInput,
                          out + ": " + (beside ? "the characters' file beside " + what + " " + outputs.front() : what) + " is " +
                              (input == "the scene file" ? input + " itself" : input + " of the scene " + scene.path) +
                              "; the bake would replace it. Give " + option + " another path (for example " + option + " " + other + ")");
    }
    return {};
}

CLI::Option* add_compaction_option(CLI::App& app, std::optional<std::string>& into, bool& meshopt) {
    app.add_flag("--meshopt", meshopt,
                 "with --compact: quantize the kept keys per channel and write them with meshopt's codec "
                 "(EXT_meshopt_compression, a required extension: three.js with MeshoptDecoder, gltf-transform, "
                 "Blender 5.2+ read it; docs/compact.md)");
    // A flag, whose value comes only after "=": `--compact SCENE` leaves SCENE a positional.
    static const std::string description =
        "drop the animation keys that linear interpolation reproduces within METRES (translations) and RADIANS "
        "(rotations, relative scales), 16/8-bit rotations (docs/compact.md) (default: off; --compact alone: 0.001)";
    return app.add_flag("--compact", description)
        ->each([&into](const std::string& value) { into = value; })
        ->option_text("[=METRES[,RADIANS]]");
}

// ERROR is METRES or METRES,RADIANS. One number bounds all three kinds as the
// displacement of a point 1 m from the joint: a rotation of E rad, or a scale off by E
// relative, moves it E m, as a translation error of E m does. A second number sets the
// rotation (and scale) bound on its own.
GlbCompaction read_compaction(const std::optional<std::string>& option, bool meshopt) {
    GlbCompaction compaction;
    if (meshopt && !option) {
        throw UsageError{"--meshopt: compresses compacted keys, give it with --compact (e.g. --compact --meshopt)"};
    }
    if (!option) return compaction;
    compaction.enabled = true;
    compaction.meshopt = meshopt;
    // CLI11 gives a flag without a value as "true".
    if (*option == "true") return compaction;
    const std::string& text = *option;
    const auto fail = [&]() -> UsageError {
        return UsageError{"--compact: expected --compact, --compact=METRES or --compact=METRES,RADIANS (numbers >= 0, e.g. "
                          "--compact=0.001 or --compact=0.002,0.005), got \"" + text + "\""};
    };
    const auto number = [&](const std::string& part) {
        char* end = nullptr;
        const double v = part.empty() || part[0] == '-' || part[0] == '+' || std::isspace(static_cast<unsigned char>(part[0]))
                             ? -1.0
                             : std::strtod(part.c_str(), &end);
        if (end == nullptr || *end != '\0' || !std::isfinite(v) || v < 0.0 || v > 1e6) throw fail();
        return static_cast<float>(v);
    };
    const std::size_t comma = text.find(',');
    compaction.position_m = number(text.substr(0, comma));
    compaction.rotation_rad = comma == std::string::npos ? compaction.position_m : number(text.substr(comma + 1));
    compaction.scale_rel = compaction.rotation_rad;
    return compaction;
}

namespace {

void print_compaction(const GlbCompactionStats& s) {
    const auto size = [](std::uint64_t bytes) {
        char text[32];
        const double b = static_cast<double>(bytes);
        if (bytes >= (1u << 20)) {
            std::snprintf(text, sizeof text, "%.1f MiB", b / (1 << 20));
        } else {
            std::snprintf(text, sizeof text, "%.1f KiB", b / (1 << 10));
        }
        return std::string(text);
    };
    std::printf("kodawari:   compact: %llu of %llu keys kept (%.1f%%), animation data %s -> %s (%.1fx); "
                "largest error %.4g mm, %.4g mrad",
                static_cast<unsigned long long>(s.kept), static_cast<unsigned long long>(s.keys),
                s.keys > 0 ? 100.0 * static_cast<double>(s.kept) / static_cast<double>(s.keys) : 100.0,
                size(s.bytes_before).c_str(), size(s.bytes_after).c_str(),
                s.bytes_after > 0 ? static_cast<double>(s.bytes_before) / static_cast<double>(s.bytes_after) : 1.0,
                1e3 * s.position_m, 1e3 * s.rotation_rad);
    if (s.scale_rel > 0.0) std::printf(", scale %.4g%%", 100.0 * s.scale_rel);
    if (s.byte_rotations > 0) {
        std::printf("; %llu of %llu rotation channels at 8 bits", static_cast<unsigned long long>(s.byte_rotations),
                    static_cast<unsigned long long>(s.rotations));
    }
    std::printf("\n");
}

}  // namespace

std::string default_output(const std::string& scene_name, const std::string& extension) {
    std::error_code ec;
    std::filesystem::create_directories("out", ec);
    return "out/" + scene_name + extension;
}

Result<void> make_parent_folder(const std::string& path, const std::string& option) {
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    if (folder.empty()) return {};
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec || !std::filesystem::is_directory(folder)) {
        return make_error(Error::Kind::Io, option + " " + path + ": cannot create the folder " + folder.string() +
                                               (ec ? " (" + ec.message() + ")" : std::string(" (a file is in the way)")));
    }
    return {};
}

void print_wrote(const BakeOutput& file) {
    if (file.format == BakeOutput::Format::Trace) {
        std::printf("kodawari: wrote trace %s\n", file.path.c_str());
        return;
    }
    std::error_code ec;
    const auto size = std::filesystem::file_size(file.path, ec);
    std::printf("kodawari: wrote %s (%.1f MiB, %s%s%s)\n", file.path.c_str(), ec ? 0.0 : static_cast<double>(size) / (1 << 20),
                file.format == BakeOutput::Format::Part ? "kodawari part file" : "glTF 2.0 binary",
                file.description.empty() ? "" : ", ", file.description.c_str());
    if (file.compaction) print_compaction(*file.compaction);
}

std::vector<BakeSink*> sink_pointers(const std::vector<std::unique_ptr<BakeSink>>& sinks) {
    std::vector<BakeSink*> out;
    for (const auto& sink : sinks) out.push_back(sink.get());
    return out;
}

}  // namespace kodawari::cli
