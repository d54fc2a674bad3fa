// Fuzz target: the scene editor behind `kodawari sketch` and the viewer's sketch mode
// (engine/scene/scene_edit.cpp, scene_edit_keyed.cpp, scene_paths.cpp), which splices a view or keyed
// example into scene text and takes the last one out again. The input is a 24-byte header
// (which chain, the example's direction, influence and shape offsets, then what is keyed
// and by which joint; see below) followed by the scene text.
//
// Invariants:
// - any text is edited or refused with a message naming the file;
// - when the text loads as a scene and the edit succeeds, the edited text loads too;
// - undoing an appended (not replacing) sketch gives back the text from before it, byte
//   for byte, but for an empty `"views": []` (or `"keyed": []`), which goes with it
//   (scene_edit.hpp promises this);
// - the same for a keyed example (motion or pose, of one of the character's joints), added
//   after the view example was undone; undo takes it, not a view example;
// - moving the text to another folder (move_scene_text) takes any JSON and gives JSON; a
//   scene that reads no file loads from the new folder too.
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "fuzz_support.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/scene/scene_edit.hpp"

namespace {

nlohmann::json without_empty_views(nlohmann::json j) {
    if (j.is_object()) {
        for (const char* key : {"views", "keyed"}) {
            if (j.contains(key) && j[key].is_array() && j[key].empty()) j.erase(key);
        }
        for (auto& [key, value] : j.items()) value = without_empty_views(value);
    } else if (j.is_array()) {
        for (auto& value : j) value = without_empty_views(value);
    }
    return j;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace kodawari;
    constexpr std::size_t kHeader = 24;
    fuzz::ByteReader head(data, size < kHeader ? size : kHeader);
    const std::uint8_t pick = head.byte();
    ViewSpec view;
    view.view.direction = {head.number(1.5f), head.number(1.5f), head.number(1.5f)};
    view.view.influence = head.number(20.0f);
    const float bend = head.number(0.1f);
    const std::uint8_t key_pick = head.byte();
    const std::string text = size > kHeader ? std::string(reinterpret_cast<const char*>(data) + kHeader, size - kHeader)
                                            : std::string();
    const std::string path = "fuzz-scene.json";

    // The chain: one of the scene's when it loads (its base shape, bent), else a name
    // the editor has to refuse.
    std::string chain = "character/chain";
    std::vector<std::pair<std::string, const ChainSpec*>> chains;
    std::vector<const CharacterSpec*> owners;
    auto scene = parse_scene(text, path);
    if (scene) {
        for (const CharacterSpec& c : scene.value().characters) {
            for (const ChainSpec& s : c.chains) {
                chains.emplace_back(c.name + "/" + s.name, &s);
                owners.push_back(&c);
            }
        }
    }
    KeyedSketch keyed;
    keyed.joint = "joint";
    keyed.reference_joint = "joint";
    keyed.kind = (key_pick & 1) != 0 ? rods::KeyKind::Pose : rods::KeyKind::Motion;
    keyed.measure = static_cast<rods::MotionMeasure>((key_pick >> 1) % 3);
    keyed.value = std::abs(view.view.direction.x) * 4.0f;
    keyed.influence = view.view.influence;
    keyed.smoothing = std::abs(view.view.direction.y);
    keyed.rotation = glm::quat(view.view.direction.z, view.view.direction.x, view.view.direction.y, 1.0f);
    if (!chains.empty()) {
        const auto& [name, spec] = chains[pick % chains.size()];
        const rods::Skeleton& skeleton = owners[pick % chains.size()]->skeleton;
        if (!skeleton.joints.empty()) {
            keyed.joint = skeleton.joints[(key_pick >> 3) % skeleton.joints.size()].name;
            keyed.reference_joint = skeleton.joints[skeleton.reference].name;
        }
        chain = name;
        view.shape = spec->base;
        for (std::size_t k = 1; k < view.shape.positions.size(); ++k) view.shape.positions[k].x += bend * static_cast<float>(k);
    } else {
        view.shape.positions = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.1f, 0.0f}};
        view.shape.orientations.resize(2);
    }

    // The text moved to another folder (move_scene_text, `sketch --out`): JSON is moved,
    // anything else refused naming the file; the moved text is JSON, and a scene that
    // loads and reads no other file loads from there too.
    const std::string elsewhere = "fuzz-sub/dir/fuzz-scene.json";
    auto moved = move_scene_text(text, path, elsewhere);
    if (!moved) {
        if (nlohmann::json::accept(text)) fuzz::finding("JSON text was not moved: " + moved.error().message);
        if (moved.error().message.find(path) == std::string::npos) {
            fuzz::finding("the move's error does not name the file: " + moved.error().message);
        }
    } else {
        if (!nlohmann::json::accept(moved.value())) fuzz::finding("the moved text is not JSON");
        if (scene && scene.value().inputs.empty()) {
            auto there = parse_scene(moved.value(), elsewhere);
            if (!there) fuzz::finding("the moved scene does not load: " + there.error().message);
        }
    }

    auto edit = add_view_example(text, path, chain, view);
    if (!edit) {
        if (edit.error().message.find(path) == std::string::npos) {
            fuzz::finding("the error does not name the file: " + edit.error().message);
        }
        return 0;
    }
    if (scene) {
        auto reloaded = parse_scene(edit.value().text, path);
        if (!reloaded) fuzz::finding("the edited scene does not load: " + reloaded.error().message);
    }
    auto undone = remove_last_sketch(edit.value().text, path, chain);
    if (!undone) fuzz::finding("the sketch just added cannot be removed: " + undone.error().message);
    if (!edit.value().replaced && undone.value().text != text) {
        // The one documented exception: an empty `"views": []` goes with the first sketch,
        // so the undone text is shorter and, as JSON, the same but for empty `views`.
        if (!(undone.value().text.size() < text.size() &&
              without_empty_views(nlohmann::json::parse(text)) ==
                  without_empty_views(nlohmann::json::parse(undone.value().text)))) {
            fuzz::finding("undoing an appended sketch did not give back the text before it");
        }
    }

    keyed.shape = view.shape;
    auto added = add_keyed_example(text, path, chain, keyed);
    if (!added) {
        if (added.error().message.find(path) == std::string::npos) {
            fuzz::finding("the keyed error does not name the file: " + added.error().message);
        }
        return 0;
    }
    // A procedural character's joint names are the loader's (rigged ones: node names, not
    // known here, so a rigged scene's edit need only parse).
    const bool named = scene && !owners.empty() && !owners[pick % chains.size()]->skeleton.joints.empty();
    if (named) {
        auto reloaded = parse_scene(added.value().text, path);
        if (!reloaded) fuzz::finding("the scene with a keyed sketch does not load: " + reloaded.error().message);
    }
    auto taken = remove_last_sketch(added.value().text, path, chain);
    if (!taken) fuzz::finding("the keyed sketch just added cannot be removed: " + taken.error().message);
    if (!taken.value().keyed) fuzz::finding("undo took a view example instead of the keyed sketch");
    if (taken.value().text != text &&
        !(taken.value().text.size() < text.size() &&
          without_empty_views(nlohmann::json::parse(text)) == without_empty_views(nlohmann::json::parse(taken.value().text)))) {
        fuzz::finding("undoing a keyed sketch did not give back the text before it");
    }
    return 0;
}
