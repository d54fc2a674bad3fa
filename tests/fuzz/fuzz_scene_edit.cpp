// Fuzz target: the scene editor behind `kodawari sketch` and the viewer's sketch mode
// (engine/scene/scene_edit.cpp), which splices a view example into scene text and takes
// the last one out again. The input is a 24-byte header (which chain, the example's
// direction, influence and shape offsets; see below) followed by the scene text.
//
// Invariants:
// - any text is edited or refused with a message naming the file;
// - when the text loads as a scene and the edit succeeds, the edited text loads too;
// - undoing an appended (not replacing) sketch gives back the text from before it, byte
//   for byte, but for an empty `"views": []`, which goes with it (scene_edit.hpp promises
//   this).
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "fuzz_support.hpp"
#include "kodawari/scene.hpp"
#include "kodawari/scene_edit.hpp"

namespace {

nlohmann::json without_empty_views(nlohmann::json j) {
    if (j.is_object()) {
        if (j.contains("views") && j["views"].is_array() && j["views"].empty()) j.erase("views");
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
    const std::string text = size > kHeader ? std::string(reinterpret_cast<const char*>(data) + kHeader, size - kHeader)
                                            : std::string();
    const std::string path = "fuzz-scene.json";

    // The chain: one of the scene's when it loads (its base shape, bent), else a name
    // the editor has to refuse.
    std::string chain = "character/chain";
    std::vector<std::pair<std::string, const ChainSpec*>> chains;
    auto scene = parse_scene(text, path);
    if (scene) {
        for (const CharacterSpec& c : scene.value().characters) {
            for (const ChainSpec& s : c.chains) chains.emplace_back(c.name + "/" + s.name, &s);
        }
    }
    if (!chains.empty()) {
        const auto& [name, spec] = chains[pick % chains.size()];
        chain = name;
        view.shape = spec->base;
        for (std::size_t k = 1; k < view.shape.positions.size(); ++k) view.shape.positions[k].x += bend * static_cast<float>(k);
    } else {
        view.shape.positions = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.1f, 0.0f}};
        view.shape.orientations.resize(2);
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
    return 0;
}
