// The outputs of a bake (bake_outputs.hpp).
#include "bake_outputs.hpp"

#include <cstdio>
#include <filesystem>

namespace kodawari::cli {

std::vector<std::unique_ptr<BakeSink>> glb_sinks(const std::string& out, bool has_birds, bool has_chains) {
    // One file per kind of content.
    std::vector<std::unique_ptr<BakeSink>> sinks;
    if (has_birds) sinks.push_back(make_birds_glb_sink(out));
    if (has_chains) {
        sinks.push_back(make_chains_glb_sink(
            has_birds ? out.substr(0, out.size() - (out.ends_with(".glb") ? 4 : 0)) + "-characters.glb" : out));
    }
    return sinks;
}

std::string default_output(const std::string& scene_name, const std::string& extension) {
    std::error_code ec;
    std::filesystem::create_directories("out", ec);
    return "out/" + scene_name + extension;
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
}

std::vector<BakeSink*> sink_pointers(const std::vector<std::unique_ptr<BakeSink>>& sinks) {
    std::vector<BakeSink*> out;
    for (const auto& sink : sinks) out.push_back(sink.get());
    return out;
}

}  // namespace kodawari::cli
