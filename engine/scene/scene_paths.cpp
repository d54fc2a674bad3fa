// A scene's text moved to another folder (move_scene_text, scene_edit.hpp). A scene names
// its files relative to its own folder (docs/scene-format.md), so a copy written elsewhere
// (`kodawari sketch A.json --out out/B.json`) must name them from there, as Blender's Save
// As remaps relative paths; only those strings are spliced, the rest keeps its bytes.

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kodawari/scene/scene_edit.hpp"
#include "scene/scene_edit_text.hpp"

namespace kodawari {
namespace {

using scene_edit_detail::elements;
using scene_edit_detail::find_member;
using scene_edit_detail::Member;
using scene_edit_detail::members;
using scene_edit_detail::skip_ws;
using scene_edit_detail::Span;
namespace fs = std::filesystem;

// The folder of a scene file, absolute and normalized (the loader resolves against the
// file's own folder, as given: no symbolic link is followed, so neither is here).
fs::path folder_of(const std::string& scene_path) { return fs::absolute(fs::path(scene_path)).lexically_normal().parent_path(); }

// A path the loader resolves against the scene's folder: not absolute and, for $schema
// (a URI reference), no scheme ("https:", "file:").
bool is_relative_file(const std::string& value, bool uri) {
    if (value.empty() || fs::path(value).is_absolute()) return false;
    if (uri) {
        const std::size_t colon = value.find(':');
        const std::size_t slash = value.find('/');
        if (colon != std::string::npos && (slash == std::string::npos || colon < slash)) return false;
    }
    return true;
}

// The string values at the scene's file members, in text order: $schema; flocks[i].model
// and .map; characters[i].gltf and .motions[j].file, .map and .target_map (the loaders'
// scene-relative files: scene_loader.cpp, rigged_character_loader.cpp).
struct FileValue {
    Span span;
    bool uri = false;
};

void add_strings(const std::string& text, const std::vector<Member>& ms, std::initializer_list<const char*> keys,
                 std::vector<FileValue>& out, bool uri = false) {
    for (const char* key : keys) {
        const Member* m = find_member(ms, key);
        if (m != nullptr && text[m->value.begin] == '"') out.push_back({m->value, uri});
    }
}

// The elements of top member `key`'s array that are objects, as their members.
std::vector<std::vector<Member>> object_elements(const std::string& text, const Member* m) {
    std::vector<std::vector<Member>> out;
    if (m == nullptr || text[m->value.begin] != '[') return out;
    for (const Span& e : elements(text, m->value.begin)) {
        if (text[e.begin] == '{') out.push_back(members(text, e.begin));
    }
    return out;
}

std::vector<FileValue> file_values(const std::string& text) {
    std::vector<FileValue> out;
    const std::size_t top = skip_ws(text, text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0);  // after a UTF-8 BOM
    if (top >= text.size() || text[top] != '{') return out;
    const std::vector<Member> root = members(text, top);
    add_strings(text, root, {"$schema"}, out, true);
    for (const auto& flock : object_elements(text, find_member(root, "flocks"))) add_strings(text, flock, {"model", "map"}, out);
    for (const auto& character : object_elements(text, find_member(root, "characters"))) {
        add_strings(text, character, {"gltf"}, out);
        for (const auto& motion : object_elements(text, find_member(character, "motions"))) {
            add_strings(text, motion, {"file", "map", "target_map"}, out);
        }
    }
    std::sort(out.begin(), out.end(), [](const FileValue& a, const FileValue& b) { return a.span.begin < b.span.begin; });
    return out;
}

}  // namespace

Result<std::string> move_scene_text(const std::string& text, const std::string& from, const std::string& to) {
    if (!nlohmann::json::accept(text)) {  // the scanner trusts the text to be JSON
        return make_error(Error::Kind::InvalidInput, from + ": not valid JSON");
    }
    const fs::path old_folder = folder_of(from);
    const fs::path new_folder = folder_of(to);
    if (old_folder == new_folder) return text;
    std::string out;
    std::size_t copied = 0;
    for (const FileValue& v : file_values(text)) {
        const std::string value = nlohmann::json::parse(text.substr(v.span.begin, v.span.end - v.span.begin)).get<std::string>();
        if (!is_relative_file(value, v.uri)) continue;
        // The file the scene at `from` names, named from `to`'s folder (lexically: "..", not
        // the links' targets, so that the copy reads exactly what the original read).
        const fs::path file = (old_folder / fs::path(value)).lexically_normal();
        fs::path moved = file.lexically_relative(new_folder);
        if (moved.empty()) moved = file;  // no relative path between them: the absolute one
        out.append(text, copied, v.span.begin - copied);
        out += nlohmann::json(moved.generic_string()).dump();
        copied = v.span.end;
    }
    out.append(text, copied, std::string::npos);
    return out;
}

}  // namespace kodawari
