// `kodawari rig CHARACTER`: the one-command chain setup of a rigged character (SPEC A.7);
// `kodawari rig BIRD --bird`: a user's rigged bird mapped onto the 7-part rig and measured
// (docs/bird-models.md). The scene is checked by the scene loader before it is written,
// so what this command writes is a scene `kodawari run` accepts.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bake_outputs.hpp"
#include "commands.hpp"
#include "kodawari/core/atomic_file.hpp"
#include "kodawari/gltf/bird_model_import.hpp"
#include "kodawari/gltf/rig_scene.hpp"
#include "kodawari/scene/route_check.hpp"

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
    bool bird = false;
    std::optional<std::string> map;
    std::vector<std::string> motions;
    std::optional<std::string> motion_map;
};

// `path` as the scene at `scene` names it: relative to the scene's folder.
std::string relative_to_scene(const std::string& path, const std::string& scene) {
    namespace fs = std::filesystem;
    const fs::path folder = fs::absolute(fs::path(scene)).parent_path();
    return fs::absolute(fs::path(path)).lexically_normal().lexically_relative(folder.lexically_normal()).generic_string();
}

// Writes the scene `json` made from `source` to `out_path` (a temporary file renamed),
// after the scene loader has accepted it: a scene it rejects is our bug, not the user's.
// kExitOk, or the exit code of what went wrong (reported).
int write_checked_scene(const std::string& json, const std::string& source, const std::string& out_path, bool out_given,
                        std::string& run_command) {
    auto check = parse_scene(json, out_path);
    if (!check) {
        std::fprintf(stderr, "kodawari: internal error: the scene written for %s does not load: %s\n", source.c_str(),
                     check.error().message.c_str());
        return kExitFailure;
    }
    const Scene& scene = check.value();
    // (The scene's own path is out_path: only its inputs can clash.)
    for (const SceneInput& input : scene.inputs) {
        if (!same_file(out_path, input.path)) continue;
        return report(make_error(Error::Kind::InvalidInput, out_path + ": " + (out_given ? "--out" : "the default output") + " is " +
                                                                input.what + ", which the scene reads; give --out a .json path of its own"));
    }
    // The command that bakes it: `run`'s default output unless that is the model itself
    // (a model in out/ named as its scene), which run refuses to write over.
    run_command = "kodawari run " + out_path;
    const std::string bake = "out/" + scene.name + ".glb";
    if (!refuse_overwriting_inputs(scene, {bake}, "the default output", ".glb")) {
        run_command += " --out out/" + scene.name + "-bake.glb";
    }
    auto out = AtomicFile::open(out_path);
    if (!out) return report(out.error());
    out.value().write(json);
    if (auto done = out.value().commit(); !done) return report(done.error());
    return kExitOk;
}

int cmd_rig_bird(const RigArguments& o) {
    if (o.chains || o.roots || o.animation || !o.motions.empty() || o.motion_map) {
        throw UsageError{"rig --bird: --chains, --roots, --animation, --motion and --motion-map are for characters"};
    }
    if (!o.character) throw UsageError{"rig --bird needs exactly one BIRD file (.gltf or .glb)"};
    const std::string& file = *o.character;
    const std::string out_path = o.out.value_or(std::filesystem::path(file).stem().string() + ".json");
    auto loaded = gltf::load_bird_model(file, o.map.value_or(""));
    if (!loaded) return report(loaded.error());
    const birds::BirdModel& m = loaded.value();
    gltf::BirdSceneOptions scene;
    scene.name = as_scene_name(o.name.value_or(m.name), "bird");  // it names the bake's files
    scene.model_file = relative_to_scene(file, out_path);
    if (o.map) scene.map_file = relative_to_scene(*o.map, out_path);
    // The generated route grows, 10 % at a time, until the bird flies it within its own
    // limits (turns at its cruise speed, climbs, dives), so that `run` on the scene gives
    // no route warning. Steps rather than a jump by the worst excess: the route variants'
    // jitter is in metres and does not scale, so the demands are not monotonic in the size,
    // and the smallest route that passes keeps the bird large in the camera's view.
    std::string json;
    for (int step = 0;; ++step) {
        scene.route_scale = static_cast<float>(std::pow(1.1, step));
        json = gltf::bird_scene_json(scene);
        auto parsed = parse_scene(json, out_path);
        if (!parsed) break;  // write_checked_scene says so
        auto warnings = check_routes(parsed.value());
        if (!warnings) return report(warnings.error());
        if (warnings.value().empty()) break;
        if (step == 48) {  // 1.1^48, about 100 times the example's size
            std::fprintf(stderr, "kodawari: internal error: no route size found that %s can fly: %s\n", file.c_str(),
                         warnings.value().front().message.c_str());
            return kExitFailure;
        }
    }
    std::string run_command;
    if (const int written = write_checked_scene(json, file, out_path, o.out.has_value(), run_command); written != kExitOk) return written;

    std::printf("%s: a bird, bones mapped by %s\n", file.c_str(), m.mapped_by.c_str());
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        std::printf("  %-18s %s\n", std::string(birds::kModelPartKeys[part]).c_str(),
                    m.character.nodes[static_cast<std::size_t>(m.bones[part])].name.c_str());
    }
    const birds::DerivedFlight& f = m.flight;
    std::printf("  wingspan %.3f m, wing area %.4f m^2, mean chord %.3f m, aspect ratio %.2f, body length %.3f m, "
                "mass %.3g kg (estimated)\n",
                static_cast<double>(m.measure.wingspan), static_cast<double>(m.measure.wing_area),
                static_cast<double>(m.mean_chord), static_cast<double>(f.aspect_ratio),
                static_cast<double>(m.measure.body_length), static_cast<double>(f.mass));
    std::printf("  flight: wingbeat %.3g Hz, amplitude %.3g, glide ratio %.3g, cruise speed %.3g m/s\n",
                static_cast<double>(f.flap_frequency), static_cast<double>(f.amplitude), static_cast<double>(f.glide_ratio),
                static_cast<double>(f.cruise_speed));
    std::printf("  route: a generated loop %.0f m across, sized for the bird's turns at its cruise speed\n",
                std::round(90.0 * static_cast<double>(scene.route_scale)));
    std::printf("wrote %s (%s)\n", out_path.c_str(), run_command.c_str());
    return kExitOk;
}

int cmd_rig(const RigArguments& o) {
    if (o.bird) return cmd_rig_bird(o);
    if (o.map) throw UsageError{"rig: --map is for --bird"};
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
    if (o.motion_map && o.motions.empty()) throw UsageError{"rig: --motion-map is the map of --motion files; give --motion"};
    options.motions = o.motions;
    options.motion_map = o.motion_map.value_or("");
    if (o.name) options.name = *o.name;
    std::string out_path = o.out.value_or("");
    if (!o.character) throw UsageError{"rig needs exactly one CHARACTER file (.gltf, .glb or .vrm)"};
    const std::string& character = *o.character;
    if (out_path.empty()) out_path = std::filesystem::path(character).stem().string() + ".json";

    auto rig = gltf::make_rig_scene(character, out_path, options);
    if (!rig) return report(rig.error());
    const gltf::RigScene& r = rig.value();
    for (const std::string& w : r.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());

    std::string run_command;
    if (const int written = write_checked_scene(r.json, character, out_path, o.out.has_value(), run_command); written != kExitOk) {
        return written;
    }

    std::printf("%s: %zu chain%s from %s, %u collider%s, size %.3g m, reference joint \"%s\", %s\n", character.c_str(),
                r.chains.size(), r.chains.size() == 1 ? "" : "s", r.source.c_str(), r.colliders, r.colliders == 1 ? "" : "s",
                static_cast<double>(r.size), r.reference.c_str(),
                r.clip.empty() ? "rest pose (no animation)" : ("animation \"" + r.clip + "\"").c_str());
    for (const gltf::RigMotion& m : r.motions) {
        char hips[64] = "";
        if (m.hips) std::snprintf(hips, sizeof(hips), ", hips displacement x%.3g", static_cast<double>(m.leg_ratio));
        std::printf("  motion %-17s %s: %zu bones, %zu keys, %.3g s%s%s\n", ("\"" + m.name + "\"").c_str(), m.file.c_str(),
                    m.bones, m.keys, static_cast<double>(m.duration), hips, m.mapped ? " (through --motion-map)" : "");
    }
    for (const gltf::RigChain& c : r.chains) {
        std::printf("  %-24s root %-24s %2u joints  %.3f m  thickness %.2g m\n", c.name.c_str(), c.root.c_str(), c.joints,
                    static_cast<double>(c.length), static_cast<double>(c.thickness));
    }
    std::printf("wrote %s (%s)\n", out_path.c_str(), run_command.c_str());
    return kExitOk;
}

}  // namespace

Command add_rig(CLI::App& app) {
    auto o = std::make_shared<RigArguments>();
    CLI::App* c = app.add_subcommand("rig", "find the chains and colliders of a rigged .gltf/.glb/.vrm character and write a scene "
                                            "that simulates it (docs/rigged-characters.md)");
    add_text(*c, "character", o->character, "CHARACTER", "the character file (.gltf, .glb or .vrm)");
    add_text(*c, "--chains", o->chains, "PATTERNS",
             "find the chains by node name patterns, comma-separated, case-insensitive: a word matches within a name "
             "(\"ear\" finds J_Sec_Ear_L), * and ? match whole names as a shell does (\"tail*\") (default: VRM spring "
             "bones, else the built-in patterns)");
    add_text(*c, "--roots", o->roots, "NAMES", "the chains' root nodes by name, comma-separated, instead of --chains");
    add_text(*c, "--animation", o->animation, "CLIP",
             "the animation clip the instances play, a --motion's name too (default: the first --motion, else the file's first "
             "clip, else the rest pose)");
    c->add_option("--motion", o->motions,
                  "a clip for another skeleton to retarget onto the character: a VRM Animation (.vrma), or a .gltf/.glb clip with "
                  "--motion-map; repeatable, each a clip named after its file (docs/motions.md) (default: none)")
        ->type_name("MOTION.vrma")
        ->allow_extra_args(false);
    add_text(*c, "--motion-map", o->motion_map, "MAP.json",
             "the humanoid bone -> node name map of the --motion files that are not VRM Animations {\"hips\": ..., "
             "\"spine\": ...} (default: none; such a file must then be a VRM model)");
    add_text(*c, "--name", o->name, "NAME", "the scene's and the character's name (default: the file's stem)");
    add_text(*c, "--out", o->out, "SCENE.json", "the scene file to write (default: ./<character>.json)");
    c->add_flag("--bird", o->bird, "the file is a rigged bird: map its bones onto the 7-part bird rig, measure its wing and "
                                   "write a scene with a flock of it (docs/bird-models.md) (default: the file is a character)");
    add_text(*c, "--map", o->map, "MAP.json",
             "with --bird: a JSON object naming the bone of each part {\"body\": ..., \"left_upper_wing\": ...} (default: "
             "name patterns)");
    return {c, [o] { return cmd_rig(*o); }};
}

}  // namespace kodawari::cli
