// `kodawari merge PARTS... --out FILE.glb`: joins the part files of `run --shard I/N` into
// the files one `run` writes, byte for byte (kodawari/shards.hpp).
#include <cstdio>

#include "bake_outputs.hpp"
#include "commands.hpp"
#include "kodawari/shards.hpp"

namespace kodawari::cli {

int cmd_merge(Args args) {
    const auto out_option = args.option("out");
    MergeOptions options;
    if (auto scene = args.option("scene")) options.scene = *scene;
    const GlbCompaction compaction = read_compaction(args);
    const std::vector<std::string> parts = args.positionals();
    if (parts.empty()) throw UsageError{"merge takes the part files of every shard (written by `run --shard I/N`)"};
    auto source = open_parts(parts, options);
    if (!source) return report(source.error());
    const BakeWorld world = source.value()->world();
    const bool has_birds = !world.birds->birds.empty();
    const bool has_chains = world.rods != nullptr;
    std::printf("kodawari: merging %zu parts of scene \"%s\" (%s): %zu birds, %zu characters, %u frames\n", parts.size(),
                world.scene->name.c_str(), world.scene->path.c_str(), world.birds->birds.size(),
                has_chains ? world.rods->instances.size() : std::size_t{0}, world.frames);
    std::fflush(stdout);
    auto sinks = glb_sinks(out_option ? *out_option : default_output(world.scene->name), has_birds, has_chains, compaction);
    auto written = bake(*source.value(), sink_pointers(sinks));
    if (!written) return report(written.error());
    for (const BakeOutput& file : written.value()) print_wrote(file);
    return kExitOk;
}

}  // namespace kodawari::cli
