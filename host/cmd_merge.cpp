// `kodawari merge PARTS... --out FILE.glb`: joins the part files of `run --shard I/N` into
// the files one `run` writes, byte for byte (kodawari/simulation/shards.hpp).
#include <cstdio>

#include "kodawari/core/atomic_file.hpp"
#include "bake_outputs.hpp"
#include "commands.hpp"
#include "kodawari/simulation/shards.hpp"

namespace kodawari::cli {

namespace {

struct MergeArguments {
    std::vector<std::string> parts;
    std::optional<std::string> out;
    std::optional<std::string> scene;
    std::optional<std::string> compact;
    bool meshopt = false;
    std::optional<std::uint64_t> threads;
};

int cmd_merge(const MergeArguments& o) {
    const auto& out_option = o.out;
    MergeOptions options;
    if (o.scene) options.scene = *o.scene;
    GlbCompaction compaction = read_compaction(o.compact, o.meshopt);
    if (o.threads) compaction.threads = static_cast<unsigned>(*o.threads);
    require_glb_name(out_option);
    const std::vector<std::string>& parts = o.parts;
    if (parts.empty()) throw UsageError{"merge takes the part files of every shard (written by `run --shard I/N`)"};
    auto source = open_parts(parts, options);
    if (!source) return report(source.error());
    const BakeWorld world = source.value()->world();
    const birds::BirdWorld& birds = bird_world_of(world);
    const RodScene* rods = rod_scene_of(world);
    const bool has_birds = !birds.birds.empty();
    const bool has_chains = rods != nullptr;
    std::printf("kodawari: merging %s of scene \"%s\" (%s): %s, %s, %s\n", counted(parts.size(), "part").c_str(),
                world.scene->name.c_str(), world.scene->path.c_str(), counted(birds.birds.size(), "bird").c_str(),
                counted(has_chains ? rods->instances.size() : std::size_t{0}, "character").c_str(),
                counted(world.frames, "frame").c_str());
    std::fflush(stdout);
    if (out_option) {
        if (auto made = make_parent_folder(*out_option, "--out"); !made) return report(made.error());
    }
    const std::string out = out_option ? *out_option : default_output(world.scene->name);
    // Never over the scene, a file it reads or a part being merged.
    if (auto refused = refuse_overwriting_inputs(*world.scene, glb_bake_paths(out, has_birds, has_chains),
                                                 out_option ? "--out" : "the default output", ".glb");
        !refused) {
        return report(refused.error());
    }
    for (const std::string& file : glb_bake_paths(out, has_birds, has_chains)) {
        for (const std::string& part : parts) {
            if (!same_file(file, part)) continue;
            return report(make_error(Error::Kind::InvalidInput, file + ": is " + part +
                                                                   ", a part being merged; give --out another path"));
        }
    }
    auto sinks = glb_sinks(out, has_birds, has_chains, compaction);
    auto written = bake(*source.value(), sink_pointers(sinks));
    if (!written) return report(written.error());
    for (const BakeOutput& file : written.value()) print_wrote(file);
    return kExitOk;
}

}  // namespace

Command add_merge(CLI::App& app) {
    auto o = std::make_shared<MergeArguments>();
    CLI::App* c = app.add_subcommand("merge", "join the part files of every shard of one bake into the files one run writes");
    c->add_option("parts", o->parts, "the part files of every shard (written by `run --shard I/N`)")->type_name("PART");
    add_text(*c, "--out", o->out, "FILE.glb", "the glTF file (default: out/<scene>.glb)");
    add_text(*c, "--scene", o->scene, "SCENE.json",
             "the scene file, when it moved since the bake; its bytes must be unchanged (default: the path in the parts)");
    add_compaction_option(*c, o->compact, o->meshopt);
    add_count(*c, "--threads", o->threads, 1, 1024, "--compact's encoder's threads (default: one per hardware thread)");
    return {c, [o] { return cmd_merge(*o); }};
}

}  // namespace kodawari::cli
