#pragma once
/// @file
/// A small checked reader over nlohmann::json for the scene loader. Every value is read
/// together with its JSON path ("$.flocks[2].route.points[4][1]"), so a problem becomes
/// one message of the form `<file>: <path>: expected <what>, got <what was there>`.
/// Nothing here throws: nlohmann's exceptions are caught at the parse and every access
/// checks the type first.

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>
#include <utility>

#include <nlohmann/json.hpp>

#include <kodawari/core/result.hpp>

namespace kodawari::scene_detail {

/// Assigns the value of `expr` (a Result) to `lhs`, or returns its error from the
/// enclosing function.
#define KW_SCENE_ASSIGN(lhs, expr)                                   \
    do {                                                             \
        auto kw_scene_result_ = (expr);                              \
        if (!kw_scene_result_.ok()) return kw_scene_result_.error(); \
        (lhs) = std::move(kw_scene_result_).value();                 \
    } while (false)

/// A JSON value and where it sits in its document. `value` is null when an object
/// member is absent; reading an absent node reports the key as missing.
struct JsonNode {
    const nlohmann::json* value = nullptr;
    std::string path = "$";

    /// Whether the member exists (optional keys keep their default when it does not).
    [[nodiscard]] bool present() const { return value != nullptr; }
};

/// An interval of accepted numbers; infinite bounds mean "no bound on that side".
struct NumberRange {
    double min = -std::numeric_limits<double>::infinity();
    double max = std::numeric_limits<double>::infinity();
    bool min_open = false;  ///< min itself excluded
    bool max_open = false;  ///< max itself excluded

    /// Any finite number.
    [[nodiscard]] static NumberRange any() { return {}; }
    /// (min, +inf)
    [[nodiscard]] static NumberRange above(double min) { return {min, std::numeric_limits<double>::infinity(), true, false}; }
    /// [min, +inf)
    [[nodiscard]] static NumberRange at_least(double min) { return {min, std::numeric_limits<double>::infinity(), false, false}; }
    /// [min, max]
    [[nodiscard]] static NumberRange closed(double min, double max) { return {min, max, false, false}; }
    /// (min, max]
    [[nodiscard]] static NumberRange left_open(double min, double max) { return {min, max, true, false}; }
    /// (min, max)
    [[nodiscard]] static NumberRange open(double min, double max) { return {min, max, true, true}; }

    [[nodiscard]] bool contains(double v) const;
    /// "a finite number in (0, 1000]", "a finite number >= 0", "a finite number".
    [[nodiscard]] std::string describe() const;
};

/// Shortest text that reads back as `v`, integers without exponent ("10000000", "0.9").
[[nodiscard]] std::string format_number(double v);
/// A value the loader already holds as a float: its shortest float text ("3.1", not the
/// double 3.0999999046325684 it widens to).
[[nodiscard]] std::string format_number(float v);

/// What a value is, for the "got ..." part of a message: `"sixty"`, `-3`, `infinity`,
/// `an array of 2 elements`, `an object`, `null`, or `nothing (required key missing)`.
[[nodiscard]] std::string describe_value(const JsonNode& node);

/// The path of an object member: `$.a.b`, or `$.a["odd key"]` for keys that are not
/// identifiers.
[[nodiscard]] std::string member_path(const std::string& object_path, std::string_view key);

/// The path of an array element: `$.a[3]`.
[[nodiscard]] std::string element_path(const std::string& array_path, std::size_t index);

/// Reads the whole file. An input the user named that cannot be read is bad input
/// (Error::Kind::InvalidInput, exit 2 on the command line), naming the file and `what` it
/// is ("the scene", "the stroke file").
[[nodiscard]] Result<std::string> read_text_file(const std::string& path, const std::string& what = "the scene");

/// Parses JSON text. A syntax error becomes `<file>:<line>:<column>: JSON syntax
/// error: ...`; a key given twice in one object is an error as well, because nlohmann
/// would silently keep the last one and a scene would not do what its file says.
[[nodiscard]] Result<nlohmann::json> parse_json(const std::string& text, const std::string& file);

/// Checked, typed access to the values of one document. All errors are
/// Error::Kind::InvalidInput and name the file and the value's JSON path.
class JsonReader {
public:
    explicit JsonReader(std::string file) : file_(std::move(file)) {}

    [[nodiscard]] const std::string& file() const { return file_; }

    /// `<file>: <path>: expected <what>, got <the value>`.
    [[nodiscard]] Error expected(const JsonNode& node, std::string_view what) const;
    /// `<file>: <path>: <message>`.
    [[nodiscard]] Error fail(const std::string& path, std::string_view message) const;

    /// Checks that `node` is an object whose keys are all in `allowed`; an unknown key
    /// is reported at its own path with the list of allowed keys.
    [[nodiscard]] Result<void> object(const JsonNode& node, std::initializer_list<std::string_view> allowed) const;
    /// Checks that `node` is an array; returns its size.
    [[nodiscard]] Result<std::size_t> array(const JsonNode& node, std::string_view what) const;

    /// The member `key` of an object node (already checked with object()); absent
    /// members give a node with a null value.
    [[nodiscard]] JsonNode member(const JsonNode& object, std::string_view key) const;
    /// Element `index` of an array node (already checked with array()).
    [[nodiscard]] JsonNode element(const JsonNode& array, std::size_t index) const;

    /// A finite number in `range` (integers are numbers too).
    [[nodiscard]] Result<double> number(const JsonNode& node, const NumberRange& range) const;
    /// As number(), converted to float; values that leave `range` or become infinite
    /// once rounded to float are rejected too, so no caller sees a 0 speed from 1e-50.
    [[nodiscard]] Result<float> real(const JsonNode& node, const NumberRange& range) const;
    /// An integer in [min, max]. Integral floats (3.0, 1e3) count as integers.
    [[nodiscard]] Result<std::uint64_t> integer(const JsonNode& node, std::uint64_t min, std::uint64_t max) const;
    /// true or false.
    [[nodiscard]] Result<bool> boolean(const JsonNode& node) const;
    /// A non-empty string.
    [[nodiscard]] Result<std::string> string(const JsonNode& node) const;
    /// One of the given strings; returns its index.
    [[nodiscard]] Result<std::size_t> choice(const JsonNode& node, std::initializer_list<std::string_view> choices) const;
    /// An array of exactly 3 numbers in `range`: [x, y, z].
    [[nodiscard]] Result<std::array<float, 3>> vec3(const JsonNode& node, const NumberRange& range) const;

private:
    std::string file_;
};

/// Reads `key` of `object` into `out` with `read(node)` when present; absent keys keep
/// the default already in `out`.
template <typename T, typename Read>
Result<void> optional_member(const JsonReader& r, const JsonNode& object, std::string_view key, T& out, Read read) {
    const JsonNode node = r.member(object, key);
    if (!node.present()) return {};
    KW_SCENE_ASSIGN(out, read(node));
    return {};
}

}  // namespace kodawari::scene_detail
