// The scene file format (docs/scene-format.md): reads and checks every key, so a
// scene that loads is one the builder can turn into a BirdWorld. The flocks are read by
// flock_loader.cpp, the characters by character_loader.cpp. Checks that need the
// route's geometry (coincident control points, cusps) stay in BirdWorld::add_route,
// which reports them with the route's JSON path.

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

#include <kodawari/core/atomic_file.hpp>
#include <kodawari/scene/scene.hpp>

#include "scene/character_loader.hpp"
#include "scene/flock_loader.hpp"

#include "scene/json_reader.hpp"

namespace kodawari {
namespace {

using scene_detail::JsonNode;
using scene_detail::JsonReader;
using scene_detail::NumberRange;
using scene_detail::optional_member;
using scene_detail::read_direction;
using scene_detail::read_point;

constexpr double kMaxCoordinate = 1e6;            // BirdWorld::add_route's limit (m)
constexpr double kDegToRad = std::numbers::pi / 180.0;

// Keys that only version 2 knows: in a version-1 file they are reported as such rather
// than as unknown, so the fix (the version) is in the message.
Result<void> require_version_2(const JsonReader& r, const JsonNode& node, std::uint32_t version,
                               std::initializer_list<std::string_view> keys) {
    if (version >= 2) return {};
    for (const std::string_view key : keys) {
        const JsonNode n = r.member(node, key);
        if (n.present()) return r.fail(n.path, "needs \"version\": 2 (version 1 scenes describe birds only)");
    }
    return {};
}

Result<void> read_camera(const JsonReader& r, const JsonNode& node, std::uint32_t version, CameraSpec& camera) {
    KW_TRY(require_version_2(r, node, version, {"projection", "orbit", "path", "keyframes"}));
    KW_TRY(r.object(node, {"position", "target", "fov_deg", "projection", "orbit", "path", "keyframes"}));
    const NumberRange coordinate = NumberRange::closed(-kMaxCoordinate, kMaxCoordinate);
    const auto vec = [&](const JsonNode& n) { return r.vec3(n, coordinate); };
    KW_TRY(optional_member(r, node, "position", camera.position, vec));
    KW_TRY(optional_member(r, node, "target", camera.target, vec));
    if (camera.target == camera.position) {
        return r.expected(r.member(node, "target"), "a point other than the camera position (the camera needs a direction)");
    }
    KW_TRY(optional_member(r, node, "fov_deg", camera.fov_deg,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::open(0.0, 180.0)); }));
    return scene_detail::read_camera_motion(r, node, camera);
}

// The climb thresholds are read in degrees and must nest so the hysteresis works:
// descend_enter < descend_exit <= ascend_exit < ascend_enter.
Result<void> read_climb_thresholds(const JsonReader& r, const JsonNode& node, birds::FlightSettings& flight) {
    struct Threshold {
        const char* key;
        float* target;
        double degrees;
        bool given;
    };
    std::array<Threshold, 4> t = {{
        {"ascend_enter_deg", &flight.ascend_enter, 0.0, false},
        {"ascend_exit_deg", &flight.ascend_exit, 0.0, false},
        {"descend_enter_deg", &flight.descend_enter, 0.0, false},
        {"descend_exit_deg", &flight.descend_exit, 0.0, false},
    }};
    for (Threshold& th : t) {
        // Defaults are stored in radians; round them back to the degrees a person wrote.
        th.degrees = std::round(static_cast<double>(*th.target) / kDegToRad * 1e6) / 1e6;
        const JsonNode n = r.member(node, th.key);
        if (n.present()) {
            KW_SCENE_ASSIGN(th.degrees, r.number(n, NumberRange::open(-90.0, 90.0)));
            th.given = true;
        }
    }
    // Blame the left-hand key of the relation when the file gave it, else the other.
    const auto check = [&](const Threshold& low, const Threshold& high, bool strict) -> Result<void> {
        if (strict ? low.degrees < high.degrees : low.degrees <= high.degrees) return {};
        if (low.given || !high.given) {
            return r.expected(r.member(node, low.key), std::string("a number ") + (strict ? "below " : "at or below ") +
                                                           high.key + " (" + scene_detail::format_number(high.degrees) + ")");
        }
        return r.expected(r.member(node, high.key), std::string("a number ") + (strict ? "above " : "at or above ") +
                                                        low.key + " (" + scene_detail::format_number(low.degrees) + ")");
    };
    KW_TRY(check(t[1], t[0], true));   // ascend_exit < ascend_enter
    KW_TRY(check(t[2], t[3], true));   // descend_enter < descend_exit
    KW_TRY(check(t[3], t[1], false));  // descend_exit <= ascend_exit
    for (const Threshold& th : t) *th.target = static_cast<float>(th.degrees * kDegToRad);
    return {};
}

Result<void> read_flight(const JsonReader& r, const JsonNode& node, birds::FlightSettings& flight) {
    KW_TRY(r.object(node, {"bank_rule", "max_bank_deg", "bank_time_constant", "mode_rule", "ascend_enter_deg", "ascend_exit_deg",
                           "descend_enter_deg", "descend_exit_deg", "seed_accel_threshold", "blend_rates", "gravity"}));
    const JsonNode bank_rule = r.member(node, "bank_rule");
    if (bank_rule.present()) {
        std::size_t index = 0;
        KW_SCENE_ASSIGN(index, r.choice(bank_rule, {"coordinated", "seed"}));
        flight.bank_rule = index == 0 ? birds::BankRule::Coordinated : birds::BankRule::Seed;
    }
    const JsonNode max_bank = r.member(node, "max_bank_deg");
    if (max_bank.present()) {
        double degrees = 0.0;
        KW_SCENE_ASSIGN(degrees, r.number(max_bank, NumberRange::closed(0.0, 89.0)));
        flight.max_bank = static_cast<float>(degrees * kDegToRad);
    }
    // Seconds; 0 rolls instantly (docs/flight-modes.md F.6). 10 s: a bird that takes
    // longer than that to roll into a turn has flown out of it.
    KW_TRY(optional_member(r, node, "bank_time_constant", flight.bank_time,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 10.0)); }));
    const JsonNode mode_rule = r.member(node, "mode_rule");
    if (mode_rule.present()) {
        std::size_t index = 0;
        KW_SCENE_ASSIGN(index, r.choice(mode_rule, {"climb", "seed"}));
        flight.mode_rule = index == 0 ? birds::ModeRule::Climb : birds::ModeRule::Seed;
    }
    KW_TRY(read_climb_thresholds(r, node, flight));
    KW_TRY(optional_member(r, node, "seed_accel_threshold", flight.seed_accel_threshold,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    const JsonNode rates = r.member(node, "blend_rates");
    if (rates.present()) {
        KW_TRY(r.object(rates, {"level", "ascend", "descend"}));
        const auto rate = [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1.0)); };
        KW_TRY(optional_member(r, rates, "level", flight.blend_rates[0], rate));
        KW_TRY(optional_member(r, rates, "ascend", flight.blend_rates[1], rate));
        KW_TRY(optional_member(r, rates, "descend", flight.blend_rates[2], rate));
    }
    KW_TRY(optional_member(r, node, "gravity", flight.gravity,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    return {};
}

// The characters' levels of detail (docs/level-of-detail.md): on unless "enabled" is false.
// The vertical field of view is the camera's, set where the rod world is built
// (build_rod_scene), as for a scene built in code.
Result<void> read_lod(const JsonReader& r, const JsonNode& node, rods::LodSettings& lod) {
    KW_TRY(r.object(node, {"enabled", "size", "full_pixels", "reduced_pixels", "hysteresis", "bias", "settle_rate", "blend_time", "lower_rate",
                         "viewport", "budget_ms", "costs"}));
    lod.enabled = true;
    if (const JsonNode enabled = r.member(node, "enabled"); enabled.present()) KW_SCENE_ASSIGN(lod.enabled, r.boolean(enabled));
    KW_TRY(optional_member(r, node, "size", lod.size, [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    KW_TRY(optional_member(r, node, "full_pixels", lod.full_pixels,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 100000.0)); }));
    KW_TRY(optional_member(r, node, "reduced_pixels", lod.reduced_pixels,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 100000.0)); }));
    if (const JsonNode reduced = r.member(node, "reduced_pixels"); reduced.present() && !(lod.reduced_pixels < lod.full_pixels)) {
        return r.expected(reduced, "a number of pixels below full_pixels");
    }
    KW_TRY(optional_member(r, node, "hysteresis", lod.hysteresis,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 0.9)); }));
    KW_TRY(optional_member(r, node, "bias", lod.bias, [&](const JsonNode& n) { return r.real(n, NumberRange::closed(-8.0, 8.0)); }));
    KW_TRY(optional_member(r, node, "settle_rate", lod.settle_rate,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 1000.0)); }));
    KW_TRY(optional_member(r, node, "blend_time", lod.blend_time,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 100.0)); }));
    if (const JsonNode rate = r.member(node, "lower_rate"); rate.present()) KW_SCENE_ASSIGN(lod.lower_rate, r.boolean(rate));
    KW_TRY(optional_member(r, node, "budget_ms", lod.budget_ms,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 100000.0)); }));
    if (const JsonNode costs = r.member(node, "costs"); costs.present()) {
        KW_TRY(r.object(costs, {"full_chain_us", "reduced_chain_us", "posed_chain_us", "full_clip_us", "posed_clip_us"}));
        rods::LodCosts& c = lod.costs;
        for (auto [name, field] : {std::pair{"full_chain_us", &c.full_chain_us}, std::pair{"reduced_chain_us", &c.reduced_chain_us},
                                   std::pair{"posed_chain_us", &c.posed_chain_us},
                                   std::pair{"full_clip_us", &c.full_clip_us}, std::pair{"posed_clip_us", &c.posed_clip_us}}) {
            KW_TRY(optional_member(r, costs, name, *field,
                                   [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.0, 1.0e6)); }));
        }
        if (c.full_chain_us < c.posed_chain_us) {
            return r.expected(r.member(costs, "full_chain_us").present() ? r.member(costs, "full_chain_us") : costs,
                              "full_chain_us at least posed_chain_us (a full chain costs more than a posed one)");
        }
        if (c.full_clip_us < c.posed_clip_us) {
            return r.expected(r.member(costs, "full_clip_us").present() ? r.member(costs, "full_clip_us") : costs,
                              "full_clip_us at least posed_clip_us");
        }
    }
    if (const JsonNode viewport = r.member(node, "viewport"); viewport.present()) {
        std::size_t count = 0;
        KW_SCENE_ASSIGN(count, r.array(viewport, "[width, height] in pixels"));
        if (count != 2) return r.expected(viewport, "[width, height] in pixels");
        double size[2] = {};
        for (std::size_t i = 0; i < 2; ++i) KW_SCENE_ASSIGN(size[i], r.number(r.element(viewport, i), NumberRange::closed(1.0, 100000.0)));
        lod.viewport_height = static_cast<float>(size[1]);
        lod.aspect = static_cast<float>(size[0] / size[1]);
    }
    return {};
}

Result<Scene> read_scene(const JsonReader& r, const nlohmann::json& document, const std::string& path) {
    const JsonNode root{&document, "$"};
    KW_TRY(r.object(root, {"format", "version", "name", "fps", "duration", "camera", "flight", "flocks", "characters", "crowds",
                           "wind", "lod", "$schema"}));
    // Editors find the JSON Schema (docs/scene.schema.json) through "$schema"; the loader
    // checks the same rules itself, so only the key's type matters here.
    const JsonNode schema = r.member(root, "$schema");
    if (schema.present()) KW_TRY(r.string(schema));

    const JsonNode format = r.member(root, "format");
    if (!format.present() || !format.value->is_string() || *format.value != "kodawari-scene") {
        return r.expected(format, "\"kodawari-scene\"");
    }
    const JsonNode version = r.member(root, "version");
    if (!version.present() || !version.value->is_number() ||
        (version.value->get<double>() != 1.0 && version.value->get<double>() != 2.0)) {
        return r.expected(version, "1 or 2 (the versions this build reads; 2 adds characters)");
    }

    Scene scene;
    scene.version = version.value->get<double>() == 2.0 ? 2u : 1u;
    KW_TRY(require_version_2(r, root, scene.version, {"characters", "crowds", "wind", "lod"}));
    scene.path = path;
    scene.name = as_scene_name(std::filesystem::path(path).stem().string(), "scene");
    const JsonNode name = r.member(root, "name");
    if (name.present()) {
        KW_SCENE_ASSIGN(scene.name, r.string(name));
        if (const std::string problem = scene_name_problem(scene.name); !problem.empty()) return r.expected(name, problem);
    }
    // At least 0.01 (a frame per 100 s): frame times f / fps stay finite for any frame
    // count (a denormal rate made them infinite, found by fuzzing).
    KW_TRY(optional_member(r, root, "fps", scene.fps,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::closed(0.01, 1000.0)); }));
    KW_TRY(optional_member(r, root, "duration", scene.duration,
                           [&](const JsonNode& n) { return r.real(n, NumberRange::left_open(0.0, 3600.0)); }));
    const JsonNode camera = r.member(root, "camera");
    if (camera.present()) {
        KW_TRY(read_camera(r, camera, scene.version, scene.camera));
    } else {
        scene.camera.motion.position = glm::vec3(scene.camera.position[0], scene.camera.position[1], scene.camera.position[2]);
        scene.camera.motion.target = glm::vec3(scene.camera.target[0], scene.camera.target[1], scene.camera.target[2]);
    }
    const JsonNode flight = r.member(root, "flight");
    if (flight.present()) KW_TRY(read_flight(r, flight, scene.flight));

    const JsonNode flocks = r.member(root, "flocks");
    const JsonNode characters = r.member(root, "characters");
    const JsonNode crowds = r.member(root, "crowds");
    // From version 2 a scene may hold characters only.
    if (flocks.present() || scene.version < 2) {
        KW_TRY(scene_detail::read_flocks(r, flocks, scene.flocks));
    } else if (!characters.present()) {
        return r.fail(root.path, "expected \"flocks\", \"characters\" or both, got neither");
    }
    // Before the characters: theirs are the scene's where they are silent.
    if (const JsonNode wind = r.member(root, "wind"); wind.present()) {
        rods::WindField field;
        KW_TRY(scene_detail::read_wind(r, wind, field));
        scene.wind = field;
    }
    if (const JsonNode lod = r.member(root, "lod"); lod.present()) KW_TRY(read_lod(r, lod, scene.lod));
    if (characters.present()) {
        KW_TRY(scene_detail::read_characters(r, characters, crowds, scene));
    } else if (crowds.present()) {
        return r.fail(crowds.path, "needs \"characters\" (a crowd is made of a scene's characters)");
    }
    // The other files it read, resolved as the readers above resolved them.
    const auto resolved = [&](const std::string& file) {
        const std::filesystem::path given(file);
        return given.is_absolute() ? file : (std::filesystem::path(r.file()).parent_path() / given).string();
    };
    for (std::size_t f = 0; f < scene.flocks.size(); ++f) {
        const FlockSpec& flock = scene.flocks[f];
        if (!flock.model_file.empty()) scene.inputs.push_back({resolved(flock.model_file), "the model of flock " + std::to_string(f)});
        if (!flock.map_file.empty()) scene.inputs.push_back({resolved(flock.map_file), "the bone map of flock " + std::to_string(f)});
    }
    for (const CharacterSpec& character : scene.characters) {
        if (!character.rig) continue;
        const std::string named = "character \"" + character.name + "\"";
        scene.inputs.push_back({character.rig->resolved, "the model of " + named});
        for (const std::string& file : character.rig->motion_files) scene.inputs.push_back({file, "a motion file of " + named});
    }
    return scene;
}

}  // namespace

namespace {
// A character a file name cannot hold here: a separator or a control character.
bool not_in_file_names(char c) { return c == '/' || c == '\\' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f; }
}  // namespace

std::string scene_name_problem(const std::string& name) {
    if (name.empty() || name == "." || name == ".." || std::any_of(name.begin(), name.end(), not_in_file_names)) {
        return "a file name, as it names the scene's outputs (out/<name>.glb): not empty, \".\" or \"..\", without '/', "
               "'\\' or control characters";
    }
    return {};
}

std::string as_scene_name(std::string name, const std::string& fallback) {
    std::replace_if(name.begin(), name.end(), not_in_file_names, '_');
    return name.empty() || name == "." || name == ".." ? fallback : name;
}

std::string Scene::reads(const std::string& file) const {
    if (same_file(file, path)) return "the scene file";
    for (const SceneInput& input : inputs) {
        if (same_file(file, input.path)) return input.what;
    }
    return {};
}

std::uint32_t Scene::frame_count() const {
    const double frames = std::round(static_cast<double>(duration) * static_cast<double>(fps));
    // The loader bounds both factors (3600 s, 1000 fps); clamp anyway for hand-made scenes.
    if (!(frames >= 1.0)) return 1;
    if (frames > 4294967295.0) return 4294967295u;
    return static_cast<std::uint32_t>(frames);
}

Result<Scene> parse_scene(const std::string& text, const std::string& path) {
    nlohmann::json document;
    KW_SCENE_ASSIGN(document, scene_detail::parse_json(text, path));
    const JsonReader reader(path);
    return read_scene(reader, document, path);
}

Result<Scene> load_scene(const std::string& path) {
    std::string text;
    KW_SCENE_ASSIGN(text, scene_detail::read_text_file(path));
    return parse_scene(text, path);
}

}  // namespace kodawari
