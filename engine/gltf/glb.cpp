// The glTF container (GLB chunks, JSON, buffer URIs) read into a tinygltf model, with its buffers checked.

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "gltf/import_detail.hpp"

namespace kodawari::gltf::detail {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kGlbMagic = 0x46546C67u;      // "glTF", §4.4 (GLB header)
constexpr std::uint32_t kChunkJson = 0x4E4F534Au;     // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942u;      // "BIN\0"
constexpr std::size_t kGlbHeaderBytes = 12;
constexpr std::size_t kChunkHeaderBytes = 8;

std::uint32_t read_u32(const std::vector<unsigned char>& bytes, std::size_t offset) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + offset, sizeof v);  // GLB is little-endian, like every target we build for
    return v;
}

// The four magic bytes as text a person can read: "glTF", or escapes for the rest.
std::string printable(const unsigned char* bytes, std::size_t n) {
    std::string out = "\"";
    for (std::size_t i = 0; i < n; ++i) {
        const unsigned char c = bytes[i];
        if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') {
            out += static_cast<char>(c);
        } else {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", c);
            out += hex;
        }
    }
    return out + "\"";
}

std::string percent_decode(std::string_view uri) {
    std::string out;
    for (std::size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() &&
            std::isxdigit(static_cast<unsigned char>(uri[i + 1])) != 0 &&
            std::isxdigit(static_cast<unsigned char>(uri[i + 2])) != 0) {
            out += static_cast<char>(std::stoi(std::string(uri.substr(i + 1, 2)), nullptr, 16));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

// What the GLB container holds (§4 GLB File Format: header, JSON chunk, optional BIN).
struct GlbChunks {
    std::string json;
    std::size_t bin_bytes = 0;
    bool has_bin = false;
};

Result<GlbChunks> split_glb(const Context& ctx, const std::vector<unsigned char>& bytes) {
    const std::string header = "GLB header";
    if (bytes.size() < 4 || read_u32(bytes, 0) != kGlbMagic) {
        return ctx.invalid(header, "magic is " + printable(bytes.data(), std::min<std::size_t>(bytes.size(), 4)) +
                                       ", expected \"glTF\" (not a binary glTF file)");
    }
    if (bytes.size() < kGlbHeaderBytes) {
        return ctx.invalid(header, "the file has " + std::to_string(bytes.size()) +
                                       " bytes, fewer than the 12-byte header (truncated)");
    }
    const std::uint32_t version = read_u32(bytes, 4);
    if (version != 2) return ctx.invalid(header, "version " + std::to_string(version) + ", expected 2");
    const std::size_t length = read_u32(bytes, 8);
    if (length > bytes.size()) {
        return ctx.invalid(header, "declares " + std::to_string(length) + " bytes, the file has " +
                                       std::to_string(bytes.size()) + " (truncated)");
    }
    GlbChunks chunks;
    std::size_t offset = kGlbHeaderBytes;
    for (std::size_t chunk = 0; offset < length; ++chunk) {
        const std::string where = "GLB chunk " + std::to_string(chunk);
        if (length - offset < kChunkHeaderBytes) {
            return ctx.invalid(where, "its 8-byte header runs past the end of the file (truncated)");
        }
        const std::size_t size = read_u32(bytes, offset);
        const std::uint32_t type = read_u32(bytes, offset + 4);
        offset += kChunkHeaderBytes;
        if (size > length - offset) {
            return ctx.invalid(where, "declares " + std::to_string(size) + " bytes, only " +
                                          std::to_string(length - offset) + " follow (truncated)");
        }
        if (chunk == 0) {
            if (type != kChunkJson) return ctx.invalid(where, "the first chunk must be JSON");
            chunks.json.assign(reinterpret_cast<const char*>(bytes.data() + offset), size);
        } else if (chunk == 1 && type == kChunkBin) {
            chunks.has_bin = true;
            chunks.bin_bytes = size;
        }
        offset += size;
    }
    if (offset == kGlbHeaderBytes) return ctx.invalid(header, "no JSON chunk (truncated)");
    return chunks;
}

// Checks the buffers before tinygltf loads them, so that a missing or short buffer gets
// its glTF path (§3.6.1 Buffers and Buffer Views).
Result<void> check_buffers(const Context& ctx, const nlohmann::json& doc, const fs::path& base_dir,
                           const GlbChunks* glb) {
    if (!doc.is_object()) return ctx.invalid("$", "expected a JSON object");
    const auto it = doc.find("buffers");
    if (it == doc.end() || !it->is_array()) return {};
    std::size_t i = 0;
    for (const nlohmann::json& buffer : *it) {
        const std::string path = at("$.buffers", i++);
        if (!buffer.is_object()) return ctx.invalid(path, "expected an object");
        const auto length = buffer.find("byteLength");
        if (length == buffer.end() || !length->is_number_unsigned()) {
            return ctx.invalid(path + ".byteLength", "expected a byte count");
        }
        const auto declared = length->get<std::uint64_t>();
        const auto uri = buffer.find("uri");
        if (uri == buffer.end()) {
            // §4 GLB: a buffer without uri is the BIN chunk (only buffer 0 may be).
            if (glb == nullptr || i != 1 || !glb->has_bin) {
                return ctx.invalid(path, "has no uri and there is no GLB BIN chunk for it");
            }
            if (glb->bin_bytes < declared) {
                return ctx.invalid(path, "byteLength is " + std::to_string(declared) + " but the BIN chunk has " +
                                             std::to_string(glb->bin_bytes) + " bytes (truncated)");
            }
            continue;
        }
        if (!uri->is_string()) return ctx.invalid(path + ".uri", "expected a string");
        const std::string text = uri->get<std::string>();
        if (text.rfind("data:", 0) == 0) continue;  // tinygltf decodes and checks data URIs
        const fs::path file = base_dir / percent_decode(text);
        std::error_code ec;
        if (!fs::is_regular_file(file, ec)) {
            return ctx.invalid(path + ".uri", "external buffer \"" + text + "\" not found (looked for " +
                                                  file.string() + ")");
        }
        const auto size = fs::file_size(file, ec);
        if (ec) return make_error(Error::Kind::InvalidInput, ctx.file + ": " + path + ".uri: cannot read " + file.string());
        if (size < declared) {
            return ctx.invalid(path, "byteLength is " + std::to_string(declared) + " but \"" + text + "\" has " +
                                         std::to_string(size) + " bytes (truncated)");
        }
    }
    return {};
}

// Images are not needed for the skeleton; skipping their decoding also keeps image-codec
// bugs out of the loader.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
    return true;
}

}  // namespace

// Also sets `extensions` to the root `extensions` object as JSON text ("" when absent).
Result<tinygltf::Model> parse(const Context& ctx, const std::vector<unsigned char>& bytes, const fs::path& base_dir,
                              std::string& extensions) {
    const bool binary = bytes.size() >= 4 && read_u32(bytes, 0) == kGlbMagic;
    // A file named as a glTF binary (.glb, or VRM's .vrm, any case) that is not one: the
    // wrong magic, named, rather than the JSON parser's complaint about its first byte.
    std::string extension = fs::path(ctx.file).extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const bool named_glb = extension == ".glb" || extension == ".vrm";
    if (named_glb && !binary) KW_TRY(split_glb(ctx, bytes));  // reports the wrong magic
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) {
        return ctx.unsupported("$", "files over 4 GiB are not supported");
    }
    GlbChunks glb;
    std::string json_text;
    if (binary) {
        auto chunks = split_glb(ctx, bytes);
        if (!chunks) return chunks.error();
        glb = std::move(chunks).value();
        json_text = glb.json;
    } else {
        json_text.assign(reinterpret_cast<const char*>(bytes.data()), bytes.size());
        // Neither a GLB nor a JSON object (a README, an image, a .bin named as the model):
        // said as such, rather than as the JSON parser's complaint about its first byte.
        // An optional UTF-8 byte order mark and whitespace may come first.
        std::size_t first = json_text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
        while (first < json_text.size() && (json_text[first] == ' ' || json_text[first] == '\t' || json_text[first] == '\n' ||
                                            json_text[first] == '\r')) {
            ++first;
        }
        if (first == json_text.size()) return ctx.invalid("$", "not a glTF file: it is empty (or whitespace alone)");
        if (json_text[first] != '{') {
            return ctx.invalid("$", "not a glTF file: it starts with " +
                                        printable(bytes.data() + first, std::min<std::size_t>(bytes.size() - first, 8)) +
                                        ", where a .gltf starts with a JSON object ('{') and a .glb with \"glTF\"");
        }
    }
    nlohmann::json doc;
    try {
        doc = nlohmann::json::parse(json_text);
    } catch (const nlohmann::json::parse_error& e) {
        return ctx.invalid("$", std::string("invalid JSON at byte ") + std::to_string(e.byte) +
                                    (e.byte >= json_text.size() ? " (the end: truncated?)" : "") + ": " + e.what());
    } catch (const std::exception& e) {
        return ctx.invalid("$", std::string("invalid JSON: ") + e.what());
    }
    KW_TRY(check_buffers(ctx, doc, base_dir, binary ? &glb : nullptr));
    if (doc.is_object()) {
        const auto ext = doc.find("extensions");
        if (ext != doc.end()) extensions = ext->dump();
    }

    tinygltf::Model model;
    std::string err;
    std::string warn;
    bool loaded = false;
    try {
        tinygltf::TinyGLTF loader;
        loader.SetImageLoader(&skip_image, nullptr);
        const std::string dir = base_dir.string();
        if (binary) {
            loaded = loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(),
                                                 static_cast<unsigned int>(bytes.size()), dir);
        } else {
            loaded = loader.LoadASCIIFromString(&model, &err, &warn, json_text.data(),
                                                static_cast<unsigned int>(json_text.size()), dir);
        }
    } catch (const std::exception& e) {
        return ctx.invalid("$", std::string("tinygltf: ") + e.what());
    } catch (...) {
        return ctx.invalid("$", "tinygltf failed");
    }
    if (!loaded) {
        while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
        return ctx.invalid("$", "tinygltf: " + (err.empty() ? std::string("cannot load") : err));
    }
    return model;
}

}  // namespace kodawari::gltf::detail
