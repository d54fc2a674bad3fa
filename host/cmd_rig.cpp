// `kodawari rig CHARACTER`: the one-command chain setup of a rigged character (SPEC A.7).
// The scene is checked by the scene loader before it is written, so what this command
// writes is a scene `kodawari run` accepts.
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "kodawari/atomic_file.hpp"
#include "kodawari/gltf/rig_scene.hpp"

namespace kodawari::cli {
namespace {

std::vector<std::string> split_list(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        if (!item.empty()) out.push_back(item);
    }
    return out;
}


struct RigArguments {
    std::optional<std::string> character;
    std::optional<std::string> chains;
    std::optional<std::string> roots;
    std::optional<std::string> animation;
    std::optional<std::string> name;
    std::optional<std::string> out;
};

int cmd_rig(const RigArguments& o) {
    gltf::RigOptions options;
    const auto& chains = o.chains;
    const auto& roots = o.roots;
    if (chains && roots) throw UsageError{"rig: give --chains or --roots, not both"};
    if (chains) {
        gltf::ChainSearch search;
        search.patterns = split_list(*chains);
        if (search.patterns.empty()) throw UsageError{"rig: --chains needs one or more name patterns, comma-separated"};
        options.search = search;
    }
    if (roots) {
        gltf::ChainSearch search;
        search.roots = split_list(*roots);
        if (search.roots.empty()) throw UsageError{"rig: --roots needs one or more node names, comma-separated"};
        options.search = search;
    }
    if (o.animation) options.clip = *o.animation;
    if (o.name) options.name = *o.name;
    std::string out_path = o.out.value_or("");
    if (!o.character) throw UsageError{"rig needs exactly one CHARACTER file (.gltf, .glb or .vrm)"};
    const std::string& character = *o.character;
    if (out_path.empty()) out_path = std::filesystem::path(character).stem().string() + ".json";

    auto rig = gltf::make_rig_scene(character, out_path, options);
    if (!rig) {
        std::fprintf(stderr, "kodawari: %s\n", rig.error().message.c_str());
        return rig.error().kind == Error::Kind::Io ? kExitFailure : kExitBadInput;
    }
    const gltf::RigScene& r = rig.value();
    for (const std::string& w : r.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());

    // The loader must accept what we write; a failure here is our bug, not the user's.
    auto check = parse_scene(r.json, out_path);
    if (!check) {
        std::fprintf(stderr, "kodawari: internal error: the scene written for %s does not load: %s\n", character.c_str(),
                     check.error().message.c_str());
        return kExitFailure;
    }
    auto file = AtomicFile::open(out_path);
    if (!file) return report(file.error());
    file.value().write(r.json);
    if (auto done = file.value().commit(); !done) return report(done.error());

    std::printf("%s: %zu chain%s from %s, %u collider%s, size %.3g m, reference joint \"%s\", %s\n", character.c_str(),
                r.chains.size(), r.chains.size() == 1 ? "" : "s", r.source.c_str(), r.colliders, r.colliders == 1 ? "" : "s",
                static_cast<double>(r.size), r.reference.c_str(),
                r.clip.empty() ? "rest pose (no animation)" : ("animation \"" + r.clip + "\"").c_str());
    for (const gltf::RigChain& c : r.chains) {
        std::printf("  %-24s root %-24s %2u joints  %.3f m  thickness %.2g m\n", c.name.c_str(), c.root.c_str(), c.joints,
                    static_cast<double>(c.length), static_cast<double>(c.thickness));
    }
    std::printf("wrote %s (kodawari run %s)\n", out_path.c_str(), out_path.c_str());
    return kExitOk;
}

}  // namespace

Command add_rig(CLI::App& app) {
    auto o = std::make_shared<RigArguments>();
    CLI::App* c = app.add_subcommand("rig", "find the chains and colliders of a rigged .gltf/.glb/.vrm character and write a scene "
                                            "that simulates it (docs/rigged-characters.md)");
    add_text(*c, "character", o->character, "CHARACTER", "the character file (.gltf, .glb or .vrm)");
    add_text(*c, "--chains", o->chains, "PATTERNS",
             "find the chains by node name patterns, comma-separated (default: VRM spring bones, else the built-in patterns)");
    add_text(*c, "--roots", o->roots, "NAMES", "the chains' root nodes by name, comma-separated, instead of --chains");
    add_text(*c, "--animation", o->animation, "CLIP", "the animation clip the instances play (default: the file's first, else the rest pose)");
    add_text(*c, "--name", o->name, "NAME", "the scene's and the character's name (default: the file's stem)");
    add_text(*c, "--out", o->out, "SCENE.json", "the scene file to write (default: ./<character>.json)");
    return {c, [o] { return cmd_rig(*o); }};
}

}  // namespace kodawari::cli
