#pragma once
// What scene_edit.cpp (view examples, undo) and scene_edit_keyed.cpp (keyed examples)
// share: where a chain and its example arrays are in a scene's text, splicing an element
// in or out of such an array, and the numbers and shapes as the edits write them.

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "kodawari/core/result.hpp"
#include "kodawari/rods/shape.hpp"

namespace kodawari::scene_edit_detail {

using Json = nlohmann::ordered_json;

struct Span {
    std::size_t begin = 0, end = 0;  // [begin, end)
};

struct Member {
    std::string key;
    std::size_t key_begin = 0;
    Span value;
};

// A chain's array member ("views" or "keyed") in the text: where it is, when present.
struct ArrayPlace {
    std::optional<std::size_t> member;  // index into ChainPlace::members
    std::vector<Span> spans;            // its elements
};

struct ChainPlace {
    Json chain;             // the chain object as parsed
    std::string json_path;  // "$.characters[0].chains[1]"
    std::size_t character = 0;  // its character's index in $.characters
    std::vector<Member> members;
    ArrayPlace views, keyed;
};

// ---- where values are in the text (scene_edit_text.cpp); `text` must be valid JSON and
// each position that of the value's first character.

// The first position at or after `i` that is not JSON white space.
std::size_t skip_ws(const std::string& text, std::size_t i);
// One past the end of the value (string, object, array, literal) that starts at `i`.
std::size_t value_end(const std::string& text, std::size_t i);
// The members of the object at `i` ('{'), in the text's order.
std::vector<Member> members(const std::string& text, std::size_t i);
// The elements of the array at `i` ('[').
std::vector<Span> elements(const std::string& text, std::size_t i);
// The member named `key`, or nullptr.
const Member* find_member(const std::vector<Member>& members, const std::string& key);

// The chain "character/chain" of scene text `text` (`path` for messages), or an error
// naming the file and the JSON path (not JSON, no such chain, a mirrored copy).
[[nodiscard]] Result<ChainPlace> find_chain(const std::string& text, const std::string& path, const std::string& chain_id);

Error fail(const std::string& path, const std::string& json_path, const std::string& message);

// The highest n of the "sketch <n>" names of the chain's view and keyed examples (0: none):
// the two arrays count together, so that undo knows which example a sketch added last.
long highest_sketch(const Json& chain);
// n of a "sketch <n>" name, or nullopt.
std::optional<long> sketch_number(const Json& example);

// `text` with `element(indent)` appended to the chain's array `key` (`a`), which is
// created as the chain's last member when absent; on a line of its own after the last
// element when that sits on one.
std::string append_element(const std::string& text, const ChainPlace& place, const ArrayPlace& a, const std::string& key,
                           const std::function<std::string(const std::string& indent)>& element);
// `text` without element k of the chain's array `a`: the exact inverse of append_element.
std::string erase_element(const std::string& text, const ChainPlace& place, const ArrayPlace& a, std::size_t k);

// Six significant digits (see scene_edit.cpp).
std::string num(double v);
std::string vec(glm::vec3 v);
// `"shape": {"positions": [...], "orientations": [...]}`, its second line indented by `indent`.
std::string shape_text(const rods::ChainShape& shape, const std::string& indent);
// The shape as the scene loader would take it back; `bad` makes the error.
Result<void> check_shape(const rods::ChainShape& shape, const std::function<Error(const std::string&)>& bad);

}  // namespace kodawari::scene_edit_detail
