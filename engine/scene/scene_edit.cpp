// Editing a scene file's text in place (scene_edit.hpp). nlohmann reads the file to find
// the chain and its examples; a small scanner finds where they are in the text, and the
// edit splices only there, so the rest of the file keeps its bytes.

#include "kodawari/scene/scene_edit.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kodawari/core/atomic_file.hpp"
#include "kodawari/rods/sketch.hpp"
#include "kodawari/rods/world.hpp"
#include "scene/character_loader.hpp"
#include "scene/json_reader.hpp"
#include "scene/scene_edit_text.hpp"

namespace kodawari::scene_edit_detail {
namespace {

// The white space that starts the line of `pos`, when only white space precedes it there.
std::optional<std::string> line_indent(const std::string& t, std::size_t pos) {
    const std::size_t nl = t.rfind('\n', pos == 0 ? 0 : pos - 1);
    const std::size_t start = nl == std::string::npos ? 0 : nl + 1;
    const std::string lead = t.substr(start, pos - start);
    if (lead.find_first_not_of(" \t") != std::string::npos) return std::nullopt;
    return lead;
}

}  // namespace

// ---- the chain

Error fail(const std::string& path, const std::string& json_path, const std::string& message) {
    return make_error(Error::Kind::InvalidInput, path + ": " + json_path + ": " + message);
}

Result<ChainPlace> find_chain(const std::string& text, const std::string& path, const std::string& chain_id) {
    Json root;
    try {
        root = Json::parse(text);
    } catch (const Json::exception& e) {
        return make_error(Error::Kind::InvalidInput, path + ": not valid JSON: " + e.what());
    }
    const std::size_t slash = chain_id.find('/');
    if (slash == std::string::npos || slash == 0 || slash + 1 == chain_id.size() ||
        chain_id.find('/', slash + 1) != std::string::npos) {
        return make_error(Error::Kind::InvalidInput,
                          "chain \"" + chain_id + "\": expected CHARACTER/CHAIN, e.g. \"bunny/ear_l\"");
    }
    const std::string character = chain_id.substr(0, slash);
    const std::string name = chain_id.substr(slash + 1);
    if (!root.is_object() || !root.contains("characters") || !root["characters"].is_array()) {
        return fail(path, "$.characters", "the scene has no characters, so no chain \"" + chain_id + "\"");
    }
    const Json& characters = root["characters"];
    std::vector<std::string> character_names;
    std::size_t c = 0;
    for (; c < characters.size(); ++c) {
        const Json& ch = characters[c];
        const std::string n = ch.is_object() && ch.contains("name") && ch["name"].is_string() ? ch["name"].get<std::string>() : "";
        if (n == character) break;
        character_names.push_back("\"" + n + "\"");
    }
    if (c == characters.size()) {
        std::string list;
        for (const auto& n : character_names) list += (list.empty() ? "" : ", ") + n;
        return fail(path, "$.characters", "no character \"" + character + "\" (characters: " + list + ")");
    }
    const std::string character_path = "$.characters[" + std::to_string(c) + "]";
    const Json& chains = characters[c].contains("chains") ? characters[c]["chains"] : Json::array();
    std::vector<std::string> chain_names;
    std::size_t j = 0;
    for (; j < chains.size(); ++j) {
        const Json& ch = chains[j];
        const std::string n = ch.is_object() && ch.contains("name") && ch["name"].is_string() ? ch["name"].get<std::string>() : "";
        if (n == name) break;
        if (ch.is_object() && ch.contains("mirror") && ch["mirror"].is_string() && ch["mirror"].get<std::string>() == name) {
            return fail(path, character_path + ".chains[" + std::to_string(j) + "].mirror",
                        "\"" + name + "\" is the mirrored copy of \"" + n +
                            "\", which the loader generates from it (with its view examples mirrored); sketch \"" +
                            character + "/" + n + "\" instead");
        }
        chain_names.push_back("\"" + n + "\"");
    }
    if (j == chains.size()) {
        std::string list;
        for (const auto& n : chain_names) list += (list.empty() ? "" : ", ") + n;
        return fail(path, character_path + ".chains",
                    "character \"" + character + "\" has no chain \"" + name + "\" (chains: " + list + ")");
    }

    ChainPlace place;
    place.chain = chains[j];
    place.json_path = character_path + ".chains[" + std::to_string(j) + "]";
    place.character = c;
    // The same walk in the text.
    const std::size_t top = skip_ws(text, text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0);  // after a UTF-8 BOM
    const auto top_members = members(text, top);
    const Member* chars = find_member(top_members, "characters");
    assert(chars != nullptr);
    const Span ch_span = elements(text, chars->value.begin)[c];
    const auto ch_members = members(text, ch_span.begin);
    const Member* chains_member = find_member(ch_members, "chains");
    assert(chains_member != nullptr);
    const Span chain_span = elements(text, chains_member->value.begin)[j];
    place.members = members(text, chain_span.begin);
    for (std::size_t m = 0; m < place.members.size(); ++m) {
        ArrayPlace* a = place.members[m].key == "views" ? &place.views : place.members[m].key == "keyed" ? &place.keyed : nullptr;
        if (a == nullptr) continue;
        const Span v = place.members[m].value;
        if (text[v.begin] != '[') return fail(path, place.json_path + "." + place.members[m].key, "expected an array");
        a->member = m;
        a->spans = elements(text, v.begin);
    }
    return place;
}

std::optional<long> sketch_number(const Json& example) {
    if (!example.is_object() || !example.contains("name") || !example["name"].is_string()) return std::nullopt;
    const std::string name = example["name"].get<std::string>();
    const std::string prefix = "sketch ";
    if (name.rfind(prefix, 0) != 0 || name.size() == prefix.size() || name.size() > prefix.size() + 9) return std::nullopt;
    const std::string digits = name.substr(prefix.size());
    if (digits.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
    return std::stol(digits);
}

long highest_sketch(const Json& chain) {
    long highest = 0;
    for (const char* key : {"views", "keyed"}) {
        if (!chain.contains(key) || !chain[key].is_array()) continue;
        for (const Json& e : chain[key]) {
            if (auto n = sketch_number(e)) highest = std::max(highest, *n);
        }
    }
    return highest;
}

std::string append_element(const std::string& text, const ChainPlace& place, const ArrayPlace& a, const std::string& key,
                           const std::function<std::string(const std::string& indent)>& element) {
    std::string out = text;
    if (a.member && !a.spans.empty()) {
        // After the last example, on a line of its own when it sits on one.
        const Span last = a.spans.back();
        const auto indent = line_indent(text, last.begin);
        out.insert(last.end, indent ? ",\n" + *indent + element(*indent) : ", " + element(""));
    } else if (a.member) {
        out.insert(place.members[*a.member].value.begin + 1, element(""));
    } else {
        // No such array yet: a new last member of the chain.
        const Member& last = place.members.back();
        const auto indent = line_indent(text, last.key_begin);
        const std::string member = "\"" + key + "\": [" + element(indent.value_or("")) + "]";
        out.insert(last.value.end, indent ? ",\n" + *indent + member : ", " + member);
    }
    return out;
}

std::string erase_element(const std::string& text, const ChainPlace& place, const ArrayPlace& a, std::size_t k) {
    assert(a.member && k < a.spans.size());
    std::string out = text;
    const std::vector<Span>& e = a.spans;
    const std::size_t mi = *a.member;
    const Member& v = place.members[mi];
    const bool only_element_in_brackets = e.size() == 1 && e[0].begin == v.value.begin + 1 && e[0].end + 1 == v.value.end;
    if (e.size() == 1 && !only_element_in_brackets) {
        // The chain had the array with only whitespace in it (append_element inserts
        // right after its `[`): the example goes, the whitespace stays.
        out.erase(v.value.begin + 1, e[0].end - (v.value.begin + 1));
    } else if (e.size() == 1) {
        // The whole member goes, with the separator before it (or after it when it is the
        // first member): the exact inverse of adding the first example to a chain without
        // the array. A chain that had an empty `"views": []` loses it too (the same scene,
        // one member shorter): the two texts after the add are the same.
        if (mi > 0) {
            const std::size_t from = place.members[mi - 1].value.end;
            out.erase(from, v.value.end - from);
        } else if (place.members.size() > 1) {
            out.erase(v.key_begin, place.members[1].key_begin - v.key_begin);
        }
    } else if (k > 0) {
        out.erase(e[k - 1].end, e[k].end - e[k - 1].end);
    } else {
        out.erase(e[0].begin, e[1].begin - e[0].begin);
    }
    return out;
}

// ---- writing a view example

// Six significant digits: what a person reads and edits, well inside the loader's
// tolerances (and only the segment directions of an example matter, SPEC A.2).
std::string num(double v) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", v);
    const std::string s(text);
    return s == "-0" ? "0" : s;
}

std::string vec(glm::vec3 v) { return "[" + num(v.x) + ", " + num(v.y) + ", " + num(v.z) + "]"; }

std::string shape_text(const rods::ChainShape& shape, const std::string& indent) {
    std::string out = "\"shape\": {\"positions\": [";
    for (std::size_t i = 0; i < shape.positions.size(); ++i) {
        out += (i ? ", " : "") + (i == 0 ? std::string("[0, 0, 0]") : vec(shape.positions[i]));
    }
    out += "],\n" + indent + "           \"orientations\": [";
    for (std::size_t i = 0; i < shape.orientations.size(); ++i) {
        // Normalized, so that 6 digits stay within the loader's 1e-3 of unit length.
        const glm::quat q = glm::normalize(shape.orientations[i]);
        out += std::string(i ? ", " : "") + "[" + num(q.x) + ", " + num(q.y) + ", " + num(q.z) + ", " + num(q.w) + "]";
    }
    return out + "]}";
}

Result<void> check_shape(const rods::ChainShape& shape, const std::function<Error(const std::string&)>& bad) {
    const auto& p = shape.positions;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const std::string at = "shape joint " + std::to_string(i) + ": ";
        for (int k = 0; k < 3; ++k) {
            if (!(static_cast<double>(std::abs(p[i][k])) <= scene_detail::kMaxShape)) {
                return bad(at + "expected coordinates in [-" + num(scene_detail::kMaxShape) + ", " +
                           num(scene_detail::kMaxShape) + "] m, got " + vec(p[i]));
            }
        }
        if (i > 0 && !(glm::length(p[i] - p[i - 1]) >= 1e-6f)) return bad(at + "expected a point at least 1e-6 m from the previous joint");
    }
    for (std::size_t i = 0; i < shape.orientations.size(); ++i) {
        const glm::quat q = shape.orientations[i];
        const float length = glm::length(q);
        if (!(std::isfinite(length) && length > 1e-6f)) {
            return bad("shape joint " + std::to_string(i) + ": expected a non-zero finite orientation quaternion");
        }
    }
    return {};
}

}  // namespace kodawari::scene_edit_detail

namespace kodawari {
namespace {

using namespace scene_edit_detail;

// `replaced`: the text of the example this one replaces, kept verbatim as its "replaces"
// member so that remove_last_sketch can put those very bytes back.
std::string view_text(const ViewSpec& view, const std::string& name, const std::string& indent,
                      const std::string& replaced = {}) {
    Json name_json = name;
    return "{\"name\": " + name_json.dump() + ", \"direction\": " + vec(glm::vec3(glm::normalize(glm::dvec3(view.view.direction)))) +
           ", \"influence\": " + num(view.view.influence) + ",\n" + indent + " " + shape_text(view.shape, indent) +
           (replaced.empty() ? "" : ",\n" + indent + " \"replaces\": " + replaced) + "}";
}

// The view as the scene loader would take it back (chain_loader.cpp's read_view): a
// finite non-zero direction, an influence in (0, kMaxInfluence], joint positions within
// kMaxShape and at least 1e-6 m apart, non-zero orientations. The caller's numbers, so
// the message names the argument rather than a JSON path.
Result<void> check_view(const std::string& path, const std::string& chain, const ViewSpec& view) {
    const std::string what = path + ": the sketch for chain \"" + chain + "\": ";
    const auto bad = [&](const std::string& m) { return make_error(Error::Kind::InvalidInput, what + m); };
    const glm::vec3 d = view.view.direction;
    // In double: the float length of (1e30, 1e30, 0) is infinite and normalizes to zeros.
    if (!(std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z) && glm::length(glm::dvec3(d)) > 1e-6)) {
        return bad("direction: expected a finite non-zero vector, got " + vec(d));
    }
    if (!(view.view.influence > 0.0f && view.view.influence <= rods::kMaxInfluence)) {
        return bad("influence: expected a number in (0, " + num(rods::kMaxInfluence) + "], got " + num(view.view.influence));
    }
    return check_shape(view.shape, bad);
}

}  // namespace

Result<SceneEdit> add_view_example(const std::string& text, const std::string& path, const std::string& chain,
                                   const ViewSpec& view, float replace_deg) {
    assert(view.shape.positions.size() >= 2 && view.shape.positions.size() == view.shape.orientations.size());
    KW_TRY(check_view(path, chain, view));
    auto found = find_chain(text, path, chain);
    if (!found) return found.error();
    const ChainPlace& place = found.value();
    const Json views = place.views.member ? place.chain["views"] : Json::array();
    const std::size_t keyed = place.keyed.member ? place.chain["keyed"].size() : 0;

    // The example to replace: the nearest within replace_deg.
    const glm::vec3 d = glm::normalize(view.view.direction);
    std::optional<std::size_t> replace;
    float best = replace_deg;
    for (std::size_t k = 0; k < views.size(); ++k) {
        if (!views[k].is_object() || !views[k].contains("direction")) continue;
        const Json& dir = views[k]["direction"];
        if (!dir.is_array() || dir.size() != 3 || !dir[0].is_number() || !dir[1].is_number() || !dir[2].is_number()) continue;
        const glm::vec3 dk(dir[0].get<float>(), dir[1].get<float>(), dir[2].get<float>());
        if (!(glm::length(dk) > 0.0f)) continue;
        const float angle = glm::degrees(std::acos(std::clamp(glm::dot(glm::normalize(dk), d), -1.0f, 1.0f)));
        if (angle <= best) {
            best = angle;
            replace = k;
        }
    }
    // K.1: view and keyed examples share the limit of kMaxViewExamples.
    if (!replace && views.size() + keyed >= rods::kMaxViewExamples) {
        const std::string has = keyed == 0 ? std::to_string(views.size()) + " view examples"
                                           : std::to_string(views.size()) + " view examples and " + std::to_string(keyed) +
                                                 " keyed examples";
        return fail(path, place.json_path + ".views",
                    "chain \"" + chain + "\" already has " + has + ", the most a chain may have (" +
                        std::to_string(rods::kMaxViewExamples) + " in all); remove one, or sketch from within " +
                        num(replace_deg) + " degrees of a view example's direction to redraw it");
    }

    SceneEdit edit;
    edit.name = "sketch " + std::to_string(highest_sketch(place.chain) + 1);
    if (replace) {
        edit.text = text;
        const Span s = place.views.spans[*replace];
        const std::string indent = line_indent(text, s.begin).value_or("");
        edit.text.replace(s.begin, s.end - s.begin,
                          view_text(view, edit.name, indent, text.substr(s.begin, s.end - s.begin)));
        edit.index = static_cast<std::uint32_t>(*replace);
        edit.replaced = true;
        const Json& old = views[*replace];
        edit.replaced_name = old.contains("name") && old["name"].is_string() ? old["name"].get<std::string>() : "";
        return edit;
    }
    edit.index = static_cast<std::uint32_t>(views.size());
    edit.text = append_element(text, place, place.views, "views",
                               [&](const std::string& indent) { return view_text(view, edit.name, indent); });
    return edit;
}

Result<SceneEdit> remove_last_sketch(const std::string& text, const std::string& path, const std::string& chain) {
    auto found = find_chain(text, path, chain);
    if (!found) return found.error();
    const ChainPlace& place = found.value();
    // The last example a sketch added is the one with the highest "sketch <n>", in either
    // array (add_view_example and add_keyed_example number them together).
    std::optional<std::size_t> target;
    bool in_keyed = false;
    long highest = 0;
    for (const bool keyed : {false, true}) {
        const char* key = keyed ? "keyed" : "views";
        if (!(keyed ? place.keyed : place.views).member) continue;
        const Json& examples = place.chain[key];
        for (std::size_t k = 0; k < examples.size(); ++k) {
            if (auto n = sketch_number(examples[k]); n && *n >= highest) {
                highest = *n;
                target = k;
                in_keyed = keyed;
            }
        }
    }
    if (!target) {
        return fail(path, place.json_path + ".views",
                    "the chain has no sketched view or keyed example (named \"sketch <n>\") to undo");
    }
    const ArrayPlace& a = in_keyed ? place.keyed : place.views;
    SceneEdit edit;
    edit.index = static_cast<std::uint32_t>(*target);
    edit.keyed = in_keyed;
    edit.name = place.chain[in_keyed ? "keyed" : "views"][*target]["name"].get<std::string>();
    // A sketch that replaced an example kept it as "replaces": it goes back in its place,
    // byte for byte.
    const Span s = a.spans[*target];
    const auto example_members = members(text, s.begin);
    if (const Member* replaced = find_member(example_members, "replaces"); replaced != nullptr && !in_keyed) {
        const std::string old = text.substr(replaced->value.begin, replaced->value.end - replaced->value.begin);
        const Json old_json = Json::parse(old);
        edit.replaced = true;
        edit.replaced_name = old_json.contains("name") && old_json["name"].is_string() ? old_json["name"].get<std::string>() : "";
        edit.text = text;
        edit.text.replace(s.begin, s.end - s.begin, old);
        return edit;
    }
    edit.text = erase_element(text, place, a, *target);
    return edit;
}

Result<std::vector<glm::dvec2>> parse_stroke(const std::string& text, const std::string& path) {
    Json root;
    try {
        root = Json::parse(text);
    } catch (const Json::exception& e) {
        return make_error(Error::Kind::InvalidInput, path + ": not valid JSON: " + e.what());
    }
    const std::string what = "an array of at least 2 points [x, y] in pixels";
    if (!root.is_object()) return fail(path, "$", "expected an object {\"points\": [[x, y], ...]}");
    for (const auto& item : root.items()) {
        if (item.key() != "points") return fail(path, "$." + item.key(), "unknown key (expected: points)");
    }
    if (!root.contains("points")) return fail(path, "$.points", "expected " + what + ", got nothing (required key missing)");
    const Json& points = root["points"];
    if (!points.is_array() || points.size() < 2) return fail(path, "$.points", "expected " + what + ", got " + points.dump());
    std::vector<glm::dvec2> out;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Json& p = points[i];
        const std::string at = "$.points[" + std::to_string(i) + "]";
        if (!p.is_array() || p.size() != 2) return fail(path, at, "expected a point [x, y], got " + p.dump());
        glm::dvec2 v(0.0);
        for (std::size_t k = 0; k < 2; ++k) {
            if (!p[k].is_number() || !std::isfinite(p[k].get<double>()) ||
                std::abs(p[k].get<double>()) > rods::kMaxStrokePixels) {
                return fail(path, at + "[" + std::to_string(k) + "]",
                            "expected a finite number in [-1e6, 1e6] (pixels), got " + p[k].dump());
            }
            v[static_cast<glm::length_t>(k)] = p[k].get<double>();
        }
        out.push_back(v);
    }
    return out;
}

Result<void> write_scene_text(const std::string& path, const std::string& text) {
    // Opened first, so that a folder that does not exist is named as such rather than as
    // the files the scene could not find from there (an unused file is removed).
    auto file = AtomicFile::open(path);
    if (!file) return file.error();
    auto check = parse_scene(text, path);
    if (!check) {
        return make_error(check.error().kind, "the edited scene does not load, so nothing was written: " + check.error().message);
    }
    // Never over a file the scene reads: `sketch chibi.json --out chibi.glb` would put the
    // scene's text where its model was (the scene's own path is `path`: only inputs clash).
    for (const SceneInput& input : check.value().inputs) {
        if (!same_file(path, input.path)) continue;
        return make_error(Error::Kind::InvalidInput, path + ": is " + input.what +
                                                         ", which the scene reads, so nothing was written; write the scene to a "
                                                         ".json path of its own");
    }
    file.value().write(text);
    KW_TRY(file.value().commit());
    auto reloaded = load_scene(path);
    if (!reloaded) {
        return make_error(Error::Kind::Internal, "the scene written to " + path + " does not load back: " +
                                                     reloaded.error().message);
    }
    return {};
}

Result<std::string> read_text_file(const std::string& path, const std::string& what) {
    return scene_detail::read_text_file(path, what);
}

}  // namespace kodawari
