#include "scene/json_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace kodawari::scene_detail {
namespace {

using nlohmann::json;

bool is_identifier(std::string_view key) {
    if (key.empty()) return false;
    for (std::size_t i = 0; i < key.size(); ++i) {
        const char c = key[i];
        const bool letter = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
        const bool digit = c >= '0' && c <= '9';
        if (!letter && !(digit && i > 0)) return false;
    }
    return true;
}

std::string quote(std::string_view text) {
    // error_handler_t::replace: a message must never fail on bytes that are not UTF-8.
    return json(std::string(text)).dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string list_keys(std::initializer_list<std::string_view> keys) {
    std::string out;
    for (const std::string_view key : keys) {
        if (!out.empty()) out += ", ";
        out += key;
    }
    return out;
}

// Builds the document from nlohmann's SAX events while tracking the JSON path of the
// value being read. The path lets two problems that nlohmann's own DOM parser cannot
// place be reported where they are: a key given twice (nlohmann keeps the last one
// silently) and a number too large for a double (1e999, which it rejects with only a
// byte offset).
class DocumentBuilder final : public json::json_sax_t {
public:
    bool null() override { return add(json(nullptr)); }
    bool boolean(bool value) override { return add(json(value)); }
    bool number_integer(json::number_integer_t value) override { return add(json(value)); }
    bool number_unsigned(json::number_unsigned_t value) override { return add(json(value)); }
    bool number_float(json::number_float_t value, const json::string_t& /*text*/) override { return add(json(value)); }
    bool string(json::string_t& value) override { return add(json(std::move(value))); }
    bool binary(json::binary_t& value) override { return add(json::binary(std::move(value))); }
    bool start_object(std::size_t /*elements*/) override { return open(json::object()); }
    bool start_array(std::size_t /*elements*/) override { return open(json::array()); }
    bool end_object() override { return close(); }
    bool end_array() override { return close(); }
    bool key(json::string_t& value) override {
        Frame& top = frames_.back();
        top.key = value;
        if (top.container->contains(value) && !duplicate_) duplicate_ = current_path();
        return true;
    }
    bool parse_error(std::size_t position, const std::string& last_token, const nlohmann::detail::exception& e) override {
        error_position_ = position;
        error_token_ = last_token;
        error_id_ = e.id;
        error_what_ = e.what();
        error_path_ = current_path();
        return false;
    }

    [[nodiscard]] json& document() { return root_; }
    [[nodiscard]] const std::optional<std::string>& duplicate() const { return duplicate_; }
    [[nodiscard]] std::size_t error_position() const { return error_position_; }
    [[nodiscard]] int error_id() const { return error_id_; }
    [[nodiscard]] const std::string& error_what() const { return error_what_; }
    [[nodiscard]] const std::string& error_token() const { return error_token_; }
    [[nodiscard]] const std::string& error_path() const { return error_path_; }

private:
    struct Frame {
        json* container;
        std::string key;  // the member being read, objects only
    };

    // Where a new value goes: the root, the end of an array, or the current key.
    json* slot() {
        if (frames_.empty()) return &root_;
        Frame& top = frames_.back();
        if (top.container->is_array()) {
            top.container->push_back(nullptr);
            return &top.container->back();
        }
        return &(*top.container)[top.key];
    }
    bool add(json value) {
        *slot() = std::move(value);
        return true;
    }
    bool open(json container) {
        json* target = slot();
        *target = std::move(container);
        frames_.push_back(Frame{target, {}});
        return true;
    }
    bool close() {
        frames_.pop_back();
        return true;
    }

    // The path of the value being read: an array's element index is its size while the
    // element is not added yet, and size - 1 once it is (nested containers are added
    // when they open).
    [[nodiscard]] std::string current_path() const {
        std::string path = "$";
        for (std::size_t i = 0; i < frames_.size(); ++i) {
            const Frame& frame = frames_[i];
            if (frame.container->is_object()) {
                path = member_path(path, frame.key);
            } else {
                const std::size_t size = frame.container->size();
                path = element_path(path, i + 1 < frames_.size() ? size - 1 : size);
            }
        }
        return path;
    }

    json root_;
    std::vector<Frame> frames_;
    std::optional<std::string> duplicate_;
    std::size_t error_position_ = 0;
    int error_id_ = 0;
    std::string error_what_;
    std::string error_token_;
    std::string error_path_;
};

// nlohmann's what() repeats the id and its own position ("[json.exception.parse_error.101]
// parse error at line 3, column 5: ..."); the message we print leads with file:line:column.
std::string syntax_message(const std::string& what) {
    std::string message = what;
    if (message.rfind("[json.exception.", 0) == 0) {
        const std::size_t close = message.find("] ");
        if (close != std::string::npos) message.erase(0, close + 2);
    }
    if (message.rfind("parse error", 0) == 0) {
        const std::size_t colon = message.find(": ");
        if (colon != std::string::npos) message.erase(0, colon + 2);
    }
    return message;
}

}  // namespace

bool NumberRange::contains(double v) const {
    if (std::isnan(v)) return false;
    if (min_open ? !(v > min) : !(v >= min)) return false;
    if (max_open ? !(v < max) : !(v <= max)) return false;
    return true;
}

std::string NumberRange::describe() const {
    const bool has_min = std::isfinite(min);
    const bool has_max = std::isfinite(max);
    if (has_min && has_max) {
        return "a finite number in " + std::string(min_open ? "(" : "[") + format_number(min) + ", " +
               format_number(max) + (max_open ? ")" : "]");
    }
    if (has_min) return std::string("a finite number ") + (min_open ? "> " : ">= ") + format_number(min);
    if (has_max) return std::string("a finite number ") + (max_open ? "< " : "<= ") + format_number(max);
    return "a finite number";
}

std::string format_number(double v) {
    if (std::isnan(v)) return "NaN";
    if (std::isinf(v)) return v > 0 ? "infinity" : "-infinity";
    // Shortest round-trip text would print 1e7 as "1e+07"; ranges read better in full.
    if (v == std::trunc(v) && std::fabs(v) < 1e15) return std::to_string(static_cast<long long>(v));
    std::array<char, 32> buffer{};
    const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v);
    if (ec != std::errc()) return "?";
    return std::string(buffer.data(), end);
}

std::string format_number(float v) {
    if (!std::isfinite(v) || (v == std::trunc(v) && std::fabs(v) < 1e15f)) return format_number(static_cast<double>(v));
    std::array<char, 32> buffer{};
    const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v);
    if (ec != std::errc()) return "?";
    return std::string(buffer.data(), end);
}

std::string describe_value(const JsonNode& node) {
    if (node.value == nullptr) return "nothing (required key missing)";
    const json& v = *node.value;
    switch (v.type()) {
        case json::value_t::null:
            return "null";
        case json::value_t::boolean:
            return v.get<bool>() ? "true" : "false";
        case json::value_t::number_integer:
            return std::to_string(v.get<std::int64_t>());
        case json::value_t::number_unsigned:
            return std::to_string(v.get<std::uint64_t>());
        case json::value_t::number_float:
            return format_number(v.get<double>());
        case json::value_t::string: {
            const std::string& text = v.get_ref<const std::string&>();
            constexpr std::size_t kShown = 60;
            if (text.size() <= kShown) return quote(text);
            return quote(text.substr(0, kShown)) + "... (" + std::to_string(text.size()) + " characters)";
        }
        case json::value_t::array: {
            if (v.empty()) return "an empty array";
            // A point, a direction, a quaternion: the numbers themselves say what was wrong.
            const bool numbers = v.size() <= 4 && std::all_of(v.begin(), v.end(), [](const json& e) { return e.is_number(); });
            if (numbers) {
                std::string out = "[";
                for (std::size_t i = 0; i < v.size(); ++i) {
                    out += (i > 0 ? ", " : "") + describe_value(JsonNode{&v[i], ""});
                }
                return out + "]";
            }
            return "an array of " + std::to_string(v.size()) + (v.size() == 1 ? " element" : " elements");
        }
        case json::value_t::object:
            return v.empty() ? "an empty object" : "an object";
        case json::value_t::binary:
        case json::value_t::discarded:
            break;
    }
    return "an unreadable value";
}

std::string member_path(const std::string& object_path, std::string_view key) {
    if (is_identifier(key)) return object_path + "." + std::string(key);
    return object_path + "[" + quote(key) + "]";
}

std::string element_path(const std::string& array_path, std::size_t index) {
    return array_path + "[" + std::to_string(index) + "]";
}

Result<std::string> read_text_file(const std::string& path, const std::string& what) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        return make_error(Error::Kind::InvalidInput, path + ": cannot read " + what + ": it is a directory");
    }
    const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
    if (!file) {
        const int err = errno;
        return make_error(Error::Kind::InvalidInput, path + ": cannot open " + what + ": " + std::strerror(err));
    }
    std::string text;
    std::array<char, 65536> buffer{};
    while (true) {
        const std::size_t n = std::fread(buffer.data(), 1, buffer.size(), file.get());
        text.append(buffer.data(), n);
        if (n < buffer.size()) break;
    }
    if (std::ferror(file.get()) != 0) {
        return make_error(Error::Kind::Io, path + ": cannot read " + what + ": read error");
    }
    return text;
}

Result<json> parse_json(const std::string& text, const std::string& file) {
    DocumentBuilder builder;
    bool ok = false;
    try {
        ok = json::sax_parse(text, &builder);
    } catch (const json::exception& e) {
        return make_error(Error::Kind::InvalidInput, file + ": JSON error: " + std::string(e.what()));
    }
    if (!ok) {
        // out_of_range.406: a number literal beyond the range of a double.
        if (builder.error_id() == 406) {
            return make_error(Error::Kind::InvalidInput, file + ": " + builder.error_path() + ": expected a finite number, got " +
                                                             builder.error_token() + " (beyond the range of a double)");
        }
        // The position is 1-based: the last character read, the one that broke the syntax.
        const std::size_t position = builder.error_position();
        const std::size_t end = std::min(position == 0 ? std::size_t{0} : position - 1, text.size());
        std::size_t line = 1;
        std::size_t column = 1;
        for (std::size_t i = 0; i < end; ++i) {
            if (text[i] == '\n') {
                ++line;
                column = 1;
            } else {
                ++column;
            }
        }
        return make_error(Error::Kind::InvalidInput, file + ":" + std::to_string(line) + ":" + std::to_string(column) +
                                                         ": JSON syntax error: " + syntax_message(builder.error_what()));
    }
    if (builder.duplicate()) {
        return make_error(Error::Kind::InvalidInput,
                          file + ": " + *builder.duplicate() + ": duplicate key (each key may appear once per object)");
    }
    return std::move(builder.document());
}

Error JsonReader::expected(const JsonNode& node, std::string_view what) const {
    return make_error(Error::Kind::InvalidInput,
                      file_ + ": " + node.path + ": expected " + std::string(what) + ", got " + describe_value(node));
}

Error JsonReader::fail(const std::string& path, std::string_view message) const {
    return make_error(Error::Kind::InvalidInput, file_ + ": " + path + ": " + std::string(message));
}

Result<void> JsonReader::object(const JsonNode& node, std::initializer_list<std::string_view> allowed) const {
    if (node.value == nullptr || !node.value->is_object()) {
        return expected(node, "an object with keys from: " + list_keys(allowed));
    }
    for (const auto& item : node.value->items()) {
        bool known = false;
        for (const std::string_view key : allowed) known = known || key == item.key();
        if (!known) {
            return fail(member_path(node.path, item.key()), "unknown key (expected one of: " + list_keys(allowed) + ")");
        }
    }
    return {};
}

Result<std::size_t> JsonReader::array(const JsonNode& node, std::string_view what) const {
    if (node.value == nullptr || !node.value->is_array()) return expected(node, what);
    return node.value->size();
}

JsonNode JsonReader::member(const JsonNode& object, std::string_view key) const {
    JsonNode child;
    child.path = member_path(object.path, key);
    if (object.value != nullptr && object.value->is_object()) {
        const auto it = object.value->find(std::string(key));
        if (it != object.value->end()) child.value = &*it;
    }
    return child;
}

JsonNode JsonReader::element(const JsonNode& array, std::size_t index) const {
    JsonNode child;
    child.path = element_path(array.path, index);
    if (array.value != nullptr && array.value->is_array() && index < array.value->size()) {
        child.value = &(*array.value)[index];
    }
    return child;
}

Result<double> JsonReader::number(const JsonNode& node, const NumberRange& range) const {
    if (node.value == nullptr || !node.value->is_number()) return expected(node, range.describe());
    const double v = node.value->get<double>();
    if (!std::isfinite(v) || !range.contains(v)) return expected(node, range.describe());
    return v;
}

Result<float> JsonReader::real(const JsonNode& node, const NumberRange& range) const {
    double v = 0.0;
    KW_SCENE_ASSIGN(v, number(node, range));
    const auto f = static_cast<float>(v);
    // Against the bounds rounded to float as well: a bound such as 0.01 or 1e-5, written
    // as itself, rounds to a float just below the decimal and must still be inside
    // [0.01, ...] (the solver compares floats too), while 1e-50 must not pass (0, ...] as 0.
    const NumberRange bounds{static_cast<double>(static_cast<float>(range.min)), static_cast<double>(static_cast<float>(range.max)),
                             range.min_open, range.max_open};
    if (!std::isfinite(f) || !bounds.contains(static_cast<double>(f))) {
        return expected(node, range.describe() + " (as a 32-bit float)");
    }
    return f;
}

Result<std::uint64_t> JsonReader::integer(const JsonNode& node, std::uint64_t min, std::uint64_t max) const {
    const std::string what = "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
    if (node.value == nullptr) return expected(node, what);
    const json& v = *node.value;
    std::uint64_t value = 0;
    if (v.is_number_unsigned()) {
        value = v.get<std::uint64_t>();
    } else if (v.is_number_integer()) {
        const auto signed_value = v.get<std::int64_t>();
        if (signed_value < 0) return expected(node, what);
        value = static_cast<std::uint64_t>(signed_value);
    } else if (v.is_number_float()) {
        const double d = v.get<double>();
        // 2^64 is the first double past the uint64 range.
        if (!std::isfinite(d) || d != std::trunc(d) || d < 0.0 || d >= 18446744073709551616.0) return expected(node, what);
        value = static_cast<std::uint64_t>(d);
    } else {
        return expected(node, what);
    }
    if (value < min || value > max) return expected(node, what);
    return value;
}

Result<bool> JsonReader::boolean(const JsonNode& node) const {
    if (node.value == nullptr || !node.value->is_boolean()) return expected(node, "true or false");
    return node.value->get<bool>();
}

Result<std::string> JsonReader::string(const JsonNode& node) const {
    if (node.value == nullptr || !node.value->is_string() || node.value->get_ref<const std::string&>().empty()) {
        return expected(node, "a non-empty string");
    }
    return node.value->get<std::string>();
}

Result<std::size_t> JsonReader::choice(const JsonNode& node, std::initializer_list<std::string_view> choices) const {
    std::string what = "one of ";
    bool first = true;
    for (const std::string_view c : choices) {
        if (!first) what += ", ";
        what += quote(c);
        first = false;
    }
    if (node.value == nullptr || !node.value->is_string()) return expected(node, what);
    const std::string& text = node.value->get_ref<const std::string&>();
    std::size_t index = 0;
    for (const std::string_view c : choices) {
        if (c == text) return index;
        ++index;
    }
    return expected(node, what);
}

Result<std::array<float, 3>> JsonReader::vec3(const JsonNode& node, const NumberRange& range) const {
    const std::string what = "an array of 3 numbers [x, y, z], each " + range.describe();
    std::size_t size = 0;
    KW_SCENE_ASSIGN(size, array(node, what));
    if (size != 3) return expected(node, what);
    std::array<float, 3> out{};
    for (std::size_t i = 0; i < 3; ++i) KW_SCENE_ASSIGN(out[i], real(element(node, i), range));
    return out;
}

}  // namespace kodawari::scene_detail
