// Where values are in a scene's text (scene_edit_text.hpp): the small scanner the edits
// (scene_edit.cpp, scene_edit_keyed.cpp) and the paths' move (scene_paths.cpp) share. The
// text is valid JSON, nlohmann having parsed it first, so the scanner checks nothing.

#include <cassert>
#include <string>
#include <vector>

#include "scene/scene_edit_text.hpp"

namespace kodawari::scene_edit_detail {

std::size_t skip_ws(const std::string& t, std::size_t i) {
    while (i < t.size() && (t[i] == ' ' || t[i] == '\t' || t[i] == '\n' || t[i] == '\r')) ++i;
    return i;
}

std::size_t value_end(const std::string& t, std::size_t i) {
    assert(i < t.size());
    if (t[i] == '"') {
        ++i;
        while (i < t.size() && t[i] != '"') i += t[i] == '\\' ? 2 : 1;
        return i + 1;
    }
    if (t[i] == '{' || t[i] == '[') {
        int depth = 0;
        while (i < t.size()) {
            const char c = t[i];
            if (c == '"') {
                i = value_end(t, i);
                continue;
            }
            if (c == '{' || c == '[') ++depth;
            if ((c == '}' || c == ']') && --depth == 0) return i + 1;
            ++i;
        }
        return i;
    }
    while (i < t.size() && std::string(",]} \t\n\r").find(t[i]) == std::string::npos) ++i;
    return i;
}

// The members of the object at `i` ('{').
std::vector<Member> members(const std::string& t, std::size_t i) {
    assert(t[i] == '{');
    std::vector<Member> out;
    i = skip_ws(t, i + 1);
    while (i < t.size() && t[i] != '}') {
        Member m;
        m.key_begin = i;
        const std::size_t key_end = value_end(t, i);
        m.key = Json::parse(t.substr(i, key_end - i)).get<std::string>();
        i = skip_ws(t, key_end);
        assert(t[i] == ':');
        i = skip_ws(t, i + 1);
        m.value = {i, value_end(t, i)};
        out.push_back(m);
        i = skip_ws(t, m.value.end);
        if (i < t.size() && t[i] == ',') i = skip_ws(t, i + 1);
    }
    return out;
}

// The elements of the array at `i` ('[').
std::vector<Span> elements(const std::string& t, std::size_t i) {
    assert(t[i] == '[');
    std::vector<Span> out;
    i = skip_ws(t, i + 1);
    while (i < t.size() && t[i] != ']') {
        out.push_back({i, value_end(t, i)});
        i = skip_ws(t, out.back().end);
        if (i < t.size() && t[i] == ',') i = skip_ws(t, i + 1);
    }
    return out;
}

const Member* find_member(const std::vector<Member>& ms, const std::string& key) {
    for (const Member& m : ms) {
        if (m.key == key) return &m;
    }
    return nullptr;
}

}  // namespace kodawari::scene_edit_detail
