// Loading a rigged glTF 2.0 character (SPEC A.7). tinygltf parses the file; everything
// this module later indexes or reads is checked here first, because tinygltf 2.7 leaves
// many of those checks to the caller (accessor ranges, node trees, skins). Every problem
// becomes "<file>: <glTF path>: <what>". Section numbers: glTF 2.0.1 specification.

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
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
#include <tiny_gltf.h>  // a system header: its warnings are not ours

#include "kodawari/gltf/character.hpp"

#include "core/binary_file.hpp"

namespace kodawari::gltf {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kGlbMagic = 0x46546C67u;      // "glTF", §4.4 (GLB header)
constexpr std::uint32_t kChunkJson = 0x4E4F534Au;     // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942u;      // "BIN\0"
constexpr std::size_t kGlbHeaderBytes = 12;
constexpr std::size_t kChunkHeaderBytes = 8;

// Builds the errors of one file.
struct Context {
    std::string file;

    [[nodiscard]] Error invalid(const std::string& path, const std::string& what) const {
        return make_error(Error::Kind::InvalidInput, file + ": " + path + ": " + what);
    }
    [[nodiscard]] Error unsupported(const std::string& path, const std::string& what) const {
        return make_error(Error::Kind::Unsupported, file + ": " + path + ": " + what);
    }
};

std::string at(const std::string& path, std::size_t index) { return path + "[" + std::to_string(index) + "]"; }

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
        if (ec) return make_error(Error::Kind::Io, ctx.file + ": " + path + ".uri: cannot read " + file.string());
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

// Also sets `extensions` to the root `extensions` object as JSON text ("" when absent).
Result<tinygltf::Model> parse(const Context& ctx, const std::vector<unsigned char>& bytes, const fs::path& base_dir,
                              std::string& extensions) {
    const bool binary = bytes.size() >= 4 && read_u32(bytes, 0) == kGlbMagic;
    const bool named_glb = fs::path(ctx.file).extension() == ".glb";
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

std::size_t component_bytes(int type) {
    switch (type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
        default: return 0;
    }
}

std::size_t component_count(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return 1;
        case TINYGLTF_TYPE_VEC2: return 2;
        case TINYGLTF_TYPE_VEC3: return 3;
        case TINYGLTF_TYPE_VEC4: return 4;
        case TINYGLTF_TYPE_MAT2: return 4;
        case TINYGLTF_TYPE_MAT3: return 9;
        case TINYGLTF_TYPE_MAT4: return 16;
        default: return 0;
    }
}

std::string type_name(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return "SCALAR";
        case TINYGLTF_TYPE_VEC2: return "VEC2";
        case TINYGLTF_TYPE_VEC3: return "VEC3";
        case TINYGLTF_TYPE_VEC4: return "VEC4";
        case TINYGLTF_TYPE_MAT2: return "MAT2";
        case TINYGLTF_TYPE_MAT3: return "MAT3";
        case TINYGLTF_TYPE_MAT4: return "MAT4";
        default: return "type " + std::to_string(type);
    }
}

// The bytes an element occupies, with §3.6.2.4's column padding of 1- and 2-byte
// matrices (each column starts on a 4-byte boundary).
std::size_t element_bytes(int component_type, int type) {
    const std::size_t c = component_bytes(component_type);
    if (type == TINYGLTF_TYPE_MAT2 && c == 1) return 8;
    if (type == TINYGLTF_TYPE_MAT3 && c == 1) return 12;
    if (type == TINYGLTF_TYPE_MAT3 && c == 2) return 24;
    return c * component_count(type);
}

// Every bufferView inside its buffer and every accessor inside its bufferView
// (§3.6.1, §3.6.2), so that reading any accessor later is in bounds.
Result<void> check_storage(const Context& ctx, const tinygltf::Model& model) {
    for (std::size_t v = 0; v < model.bufferViews.size(); ++v) {
        const tinygltf::BufferView& view = model.bufferViews[v];
        const std::string path = at("$.bufferViews", v);
        if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size()) {
            return ctx.invalid(path + ".buffer", "buffer " + std::to_string(view.buffer) + " does not exist");
        }
        const std::size_t size = model.buffers[static_cast<std::size_t>(view.buffer)].data.size();
        if (view.byteOffset > size || view.byteLength > size - view.byteOffset) {
            return ctx.invalid(path, "bytes [" + std::to_string(view.byteOffset) + ", " +
                                         std::to_string(view.byteOffset + view.byteLength) + ") run past the end of buffer " +
                                         std::to_string(view.buffer) + " (" + std::to_string(size) + " bytes)");
        }
    }
    for (std::size_t a = 0; a < model.accessors.size(); ++a) {
        const tinygltf::Accessor& accessor = model.accessors[a];
        const std::string path = at("$.accessors", a);
        const std::size_t element = element_bytes(accessor.componentType, accessor.type);
        if (element == 0) return ctx.invalid(path, "unknown componentType or type");
        if (accessor.sparse.isSparse) continue;  // read nowhere yet; rejected where used
        if (accessor.bufferView < 0) continue;   // all zeros (§3.6.2.1); rejected where used
        if (static_cast<std::size_t>(accessor.bufferView) >= model.bufferViews.size()) {
            return ctx.invalid(path + ".bufferView", "bufferView " + std::to_string(accessor.bufferView) + " does not exist");
        }
        const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(accessor.bufferView)];
        const std::size_t stride = view.byteStride == 0 ? element : view.byteStride;
        if (stride < element) {
            return ctx.invalid(at("$.bufferViews", static_cast<std::size_t>(accessor.bufferView)) + ".byteStride",
                               "stride " + std::to_string(stride) + " is shorter than accessor " + std::to_string(a) +
                                   "'s " + std::to_string(element) + "-byte elements");
        }
        if (accessor.count == 0) continue;
        // count - 1 strides then one element, all within the view; the first test keeps
        // the product below from overflowing.
        const bool fits = accessor.byteOffset <= view.byteLength && accessor.count - 1 <= view.byteLength &&
                          (accessor.count - 1) * stride + element <= view.byteLength - accessor.byteOffset;
        if (!fits) {
            return ctx.invalid(path, std::to_string(accessor.count) + " elements of " + std::to_string(element) +
                                         " bytes, stride " + std::to_string(stride) + ", from byteOffset " +
                                         std::to_string(accessor.byteOffset) + " run past the end of bufferView " +
                                         std::to_string(accessor.bufferView) + " (" + std::to_string(view.byteLength) +
                                         " bytes)");
        }
    }
    return {};
}

#define KW_GLTF_ASSIGN(lhs, expr)                       \
    do {                                                \
        auto kw_gltf_result_ = (expr);                  \
        if (!kw_gltf_result_.ok()) return kw_gltf_result_.error(); \
        (lhs) = std::move(kw_gltf_result_).value();     \
    } while (false)

// The accessor `index` if it exists and its data is a plain buffer-view range (no sparse
// accessors, no bufferView-less zeros), as the readers below need.
Result<const tinygltf::Accessor*> dense_accessor(const Context& ctx, const tinygltf::Model& model, int index,
                                                 const std::string& where) {
    if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) {
        return ctx.invalid(where, "accessor " + std::to_string(index) + " does not exist");
    }
    const tinygltf::Accessor& accessor = model.accessors[static_cast<std::size_t>(index)];
    const std::string path = at("$.accessors", static_cast<std::size_t>(index));
    if (accessor.sparse.isSparse) return ctx.unsupported(path + ".sparse", "sparse accessors are not supported");
    if (accessor.bufferView < 0) return ctx.unsupported(path, "accessors without a bufferView are not supported");
    return &accessor;
}

// Where an accessor's elements are (check_storage has checked they fit).
struct Elements {
    const unsigned char* first = nullptr;
    std::size_t components = 0, component_bytes = 0, stride = 0;
};

Elements elements_of(const tinygltf::Model& model, const tinygltf::Accessor& accessor) {
    const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(accessor.bufferView)];
    const std::vector<unsigned char>& data = model.buffers[static_cast<std::size_t>(view.buffer)].data;
    const int ct = accessor.componentType;
    return {data.data() + view.byteOffset + accessor.byteOffset, component_count(accessor.type), component_bytes(ct),
            view.byteStride == 0 ? element_bytes(ct, accessor.type) : view.byteStride};
}

// Reads an accessor (checked by check_storage) as floats, normalized integers mapped as
// in §3.11's table (signed: max(c / max, -1)).
Result<std::vector<float>> read_floats(const Context& ctx, const tinygltf::Model& model, int index,
                                       const std::string& where, bool allow_normalized) {
    const tinygltf::Accessor* found = nullptr;
    KW_GLTF_ASSIGN(found, dense_accessor(ctx, model, index, where));
    const tinygltf::Accessor& accessor = *found;
    const std::string path = at("$.accessors", static_cast<std::size_t>(index));
    const int ct = accessor.componentType;
    const bool is_float = ct == TINYGLTF_COMPONENT_TYPE_FLOAT;
    const bool is_norm = accessor.normalized && ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT && !is_float;
    if (!is_float && !(allow_normalized && is_norm)) {
        return ctx.invalid(path + ".componentType", where + " needs FLOAT" +
                                                        std::string(allow_normalized ? " or normalized integer" : "") +
                                                        " components, got componentType " + std::to_string(ct));
    }
    const Elements elements = elements_of(model, accessor);
    const std::size_t comps = elements.components, csize = elements.component_bytes, stride = elements.stride;
    std::vector<float> out;
    out.reserve(accessor.count * comps);
    for (std::size_t i = 0; i < accessor.count; ++i) {
        const unsigned char* element = elements.first + i * stride;
        for (std::size_t c = 0; c < comps; ++c) {
            const unsigned char* p = element + c * csize;
            float value = 0.0f;
            switch (ct) {
                case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&value, p, 4); break;
                case TINYGLTF_COMPONENT_TYPE_BYTE: {
                    std::int8_t v = 0;
                    std::memcpy(&v, p, 1);
                    value = std::max(static_cast<float>(v) / 127.0f, -1.0f);
                    break;
                }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: value = static_cast<float>(*p) / 255.0f; break;
                case TINYGLTF_COMPONENT_TYPE_SHORT: {
                    std::int16_t v = 0;
                    std::memcpy(&v, p, 2);
                    value = std::max(static_cast<float>(v) / 32767.0f, -1.0f);
                    break;
                }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                    std::uint16_t v = 0;
                    std::memcpy(&v, p, 2);
                    value = static_cast<float>(v) / 65535.0f;
                    break;
                }
                default: break;
            }
            if (!std::isfinite(value)) {
                return ctx.invalid(at(where, i), "component " + std::to_string(c) + " of element " + std::to_string(i) +
                                                     " of accessor " + std::to_string(index) + " is not a finite number");
            }
            out.push_back(value);
        }
    }
    return out;
}

const tinygltf::Accessor& accessor_of(const tinygltf::Model& model, int index) {
    return model.accessors[static_cast<std::size_t>(index)];
}

// Reads an accessor (checked by check_storage) of unsigned integers (UNSIGNED_BYTE,
// UNSIGNED_SHORT or UNSIGNED_INT, not normalized): indices and JOINTS_0 (§3.7.2.1).
Result<std::vector<std::uint32_t>> read_uints(const Context& ctx, const tinygltf::Model& model, int index,
                                              const std::string& where) {
    const tinygltf::Accessor* found = nullptr;
    KW_GLTF_ASSIGN(found, dense_accessor(ctx, model, index, where));
    const tinygltf::Accessor& accessor = *found;
    const std::string path = at("$.accessors", static_cast<std::size_t>(index));
    const int ct = accessor.componentType;
    if ((ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
         ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) ||
        accessor.normalized) {
        return ctx.invalid(path + ".componentType", where + " needs unsigned integer components, got componentType " +
                                                        std::to_string(ct));
    }
    const Elements elements = elements_of(model, accessor);
    const std::size_t comps = elements.components, csize = elements.component_bytes, stride = elements.stride;
    std::vector<std::uint32_t> out;
    out.reserve(accessor.count * comps);
    for (std::size_t i = 0; i < accessor.count; ++i) {
        const unsigned char* element = elements.first + i * stride;
        for (std::size_t c = 0; c < comps; ++c) {
            const unsigned char* p = element + c * csize;
            std::uint32_t value = 0;
            if (csize == 1) {
                value = *p;
            } else if (csize == 2) {
                std::uint16_t v = 0;
                std::memcpy(&v, p, 2);
                value = v;
            } else {
                std::memcpy(&value, p, 4);
            }
            out.push_back(value);
        }
    }
    return out;
}

// Mesh geometry for display (§3.7.2): TRIANGLES primitives with POSITION, and NORMAL,
// JOINTS_0 and WEIGHTS_0 where given.
Result<void> load_meshes(const Context& ctx, const tinygltf::Model& model, Character& out) {
    for (std::size_t m = 0; m < model.meshes.size(); ++m) {
        const tinygltf::Mesh& src = model.meshes[m];
        Mesh mesh{src.name, src.primitives.size(), {}};
        for (std::size_t k = 0; k < src.primitives.size(); ++k) {
            const tinygltf::Primitive& prim = src.primitives[k];
            const std::string path = at(at("$.meshes", m) + ".primitives", k);
            if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES) continue;
            const auto attribute = [&](const char* name) {
                const auto it = prim.attributes.find(name);
                return it == prim.attributes.end() ? -1 : it->second;
            };
            if (attribute("POSITION") < 0) return ctx.invalid(path + ".attributes", "a triangle primitive needs POSITION");
            Mesh::Triangles t;
            std::vector<float> values;
            KW_GLTF_ASSIGN(values, read_floats(ctx, model, attribute("POSITION"), path + ".attributes.POSITION", false));
            if (accessor_of(model, attribute("POSITION")).type != TINYGLTF_TYPE_VEC3) {
                return ctx.invalid(path + ".attributes.POSITION", "expected a VEC3 accessor");
            }
            const std::size_t n = values.size() / 3;
            for (std::size_t i = 0; i < n; ++i) t.positions.emplace_back(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
            const auto same_count = [&](int accessor, const char* name, int type) -> Result<void> {
                if (accessor_of(model, accessor).count != n || accessor_of(model, accessor).type != type) {
                    return ctx.invalid(path + ".attributes." + name,
                                       "expected " + std::to_string(n) + " elements of type " + type_name(type) + " (as POSITION)");
                }
                return {};
            };
            if (const int a = attribute("NORMAL"); a >= 0) {
                KW_TRY(same_count(a, "NORMAL", TINYGLTF_TYPE_VEC3));
                KW_GLTF_ASSIGN(values, read_floats(ctx, model, a, path + ".attributes.NORMAL", false));
                for (std::size_t i = 0; i < n; ++i) {
                    const glm::vec3 v(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
                    const float len = glm::length(v);
                    t.normals.push_back(len > 0.0f ? v / len : glm::vec3(0.0f, 1.0f, 0.0f));
                }
            }
            const int joints = attribute("JOINTS_0");
            const int weights = attribute("WEIGHTS_0");
            if ((joints >= 0) != (weights >= 0)) {
                return ctx.invalid(path + ".attributes", "JOINTS_0 and WEIGHTS_0 go together (§3.7.3.3)");
            }
            if (joints >= 0) {
                KW_TRY(same_count(joints, "JOINTS_0", TINYGLTF_TYPE_VEC4));
                KW_TRY(same_count(weights, "WEIGHTS_0", TINYGLTF_TYPE_VEC4));
                std::vector<std::uint32_t> ids;
                KW_GLTF_ASSIGN(ids, read_uints(ctx, model, joints, path + ".attributes.JOINTS_0"));
                KW_GLTF_ASSIGN(values, read_floats(ctx, model, weights, path + ".attributes.WEIGHTS_0", true));
                for (std::size_t i = 0; i < n; ++i) {
                    t.joints.emplace_back(ids[4 * i], ids[4 * i + 1], ids[4 * i + 2], ids[4 * i + 3]);
                    t.weights.emplace_back(values[4 * i], values[4 * i + 1], values[4 * i + 2], values[4 * i + 3]);
                }
            }
            if (prim.indices >= 0) {
                if (accessor_of(model, prim.indices).type != TINYGLTF_TYPE_SCALAR) {
                    return ctx.invalid(path + ".indices", "expected a SCALAR accessor");
                }
                KW_GLTF_ASSIGN(t.indices, read_uints(ctx, model, prim.indices, path + ".indices"));
                for (std::size_t i = 0; i < t.indices.size(); ++i) {
                    if (t.indices[i] >= n) {
                        return ctx.invalid(at(path + ".indices", i), "index " + std::to_string(t.indices[i]) + " >= " +
                                                                         std::to_string(n) + " vertices");
                    }
                }
            } else {
                for (std::uint32_t i = 0; i < n; ++i) t.indices.push_back(i);
            }
            t.indices.resize(t.indices.size() / 3 * 3);
            if (prim.material >= 0 && static_cast<std::size_t>(prim.material) < model.materials.size()) {
                const auto& f = model.materials[static_cast<std::size_t>(prim.material)].pbrMetallicRoughness.baseColorFactor;
                if (f.size() == 4) t.color = glm::vec4(f[0], f[1], f[2], f[3]);
            }
            mesh.triangles.push_back(std::move(t));
        }
        out.meshes.push_back(std::move(mesh));
    }
    return {};
}


bool finite(const std::vector<double>& values) {
    return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

// TRS of a matrix without shear (§3.5.3): columns are the scaled rotated axes.
void decompose(const glm::mat4& m, Node& node) {
    node.translation = glm::vec3(m[3]);
    glm::vec3 s{glm::length(glm::vec3(m[0])), glm::length(glm::vec3(m[1])), glm::length(glm::vec3(m[2]))};
    if (glm::determinant(glm::mat3(m)) < 0.0f) s.x = -s.x;
    node.scale = s;
    glm::mat3 r(1.0f);
    for (int c = 0; c < 3; ++c) {
        if (s[c] != 0.0f) r[c] = glm::vec3(m[c]) / s[c];
    }
    node.rotation = glm::normalize(glm::quat_cast(r));
}

Result<void> load_nodes(const Context& ctx, const tinygltf::Model& model, Character& out) {
    const std::size_t n = model.nodes.size();
    out.nodes.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const tinygltf::Node& src = model.nodes[i];
        Node& node = out.nodes[i];
        const std::string path = at("$.nodes", i);
        node.name = src.name;
        if (src.mesh >= 0 && static_cast<std::size_t>(src.mesh) >= model.meshes.size()) {
            return ctx.invalid(path + ".mesh", "mesh " + std::to_string(src.mesh) + " does not exist");
        }
        if (src.skin >= 0 && static_cast<std::size_t>(src.skin) >= model.skins.size()) {
            return ctx.invalid(path + ".skin", "skin " + std::to_string(src.skin) + " does not exist");
        }
        node.mesh = src.mesh;
        node.skin = src.skin;
        if (!src.matrix.empty()) {
            if (src.matrix.size() != 16 || !finite(src.matrix)) {
                return ctx.invalid(path + ".matrix", "expected 16 finite numbers");
            }
            glm::mat4 m(1.0f);
            for (int c = 0; c < 4; ++c) {
                for (int r = 0; r < 4; ++r) m[c][r] = static_cast<float>(src.matrix[static_cast<std::size_t>(c * 4 + r)]);
            }
            node.matrix = m;
            decompose(m, node);
        } else {
            if (!src.translation.empty()) {
                if (src.translation.size() != 3 || !finite(src.translation)) {
                    return ctx.invalid(path + ".translation", "expected 3 finite numbers");
                }
                node.translation = {src.translation[0], src.translation[1], src.translation[2]};
            }
            if (!src.rotation.empty()) {
                if (src.rotation.size() != 4 || !finite(src.rotation)) {
                    return ctx.invalid(path + ".rotation", "expected 4 finite numbers");
                }
                const glm::quat q(static_cast<float>(src.rotation[3]), static_cast<float>(src.rotation[0]),
                                  static_cast<float>(src.rotation[1]), static_cast<float>(src.rotation[2]));
                if (!(glm::length(q) > 1e-6f)) return ctx.invalid(path + ".rotation", "a zero quaternion is not a rotation");
                node.rotation = glm::normalize(q);
            }
            if (!src.scale.empty()) {
                if (src.scale.size() != 3 || !finite(src.scale)) return ctx.invalid(path + ".scale", "expected 3 finite numbers");
                node.scale = {src.scale[0], src.scale[1], src.scale[2]};
            }
        }
    }
    // §3.5.2: the hierarchy is a set of disjoint strict trees: every child exists, no
    // node has two parents, no node is its own ancestor.
    for (std::size_t i = 0; i < n; ++i) {
        const std::vector<int>& children = model.nodes[i].children;
        for (std::size_t k = 0; k < children.size(); ++k) {
            const int c = children[k];
            const std::string path = at(at("$.nodes", i) + ".children", k);
            if (c < 0 || static_cast<std::size_t>(c) >= n) {
                return ctx.invalid(path, "node " + std::to_string(c) + " does not exist");
            }
            if (static_cast<std::size_t>(c) == i) {
                return ctx.invalid(path, "node " + std::to_string(c) + " is its own child (a cycle in the node tree)");
            }
            Node& child = out.nodes[static_cast<std::size_t>(c)];
            if (child.parent >= 0) {
                return ctx.invalid(path, "node " + std::to_string(c) + " already has parent node " +
                                             std::to_string(child.parent) + " (a node has at most one parent)");
            }
            child.parent = static_cast<int>(i);
            out.nodes[i].children.push_back(c);
        }
    }
    // With one parent each, a cycle is a loop of parent links: follow them from every
    // node, marking the walk; meeting the current walk again closes a cycle.
    std::vector<int> walk_of(n, -1);
    for (std::size_t start = 0; start < n; ++start) {
        int at_node = static_cast<int>(start);
        while (at_node >= 0 && walk_of[static_cast<std::size_t>(at_node)] < 0) {
            walk_of[static_cast<std::size_t>(at_node)] = static_cast<int>(start);
            at_node = out.nodes[static_cast<std::size_t>(at_node)].parent;
        }
        if (at_node < 0 || walk_of[static_cast<std::size_t>(at_node)] != static_cast<int>(start)) continue;
        // at_node is on a cycle: list it parent -> child, starting at its lowest index.
        std::vector<int> cycle{at_node};
        for (int p = out.nodes[static_cast<std::size_t>(at_node)].parent; p != at_node;
             p = out.nodes[static_cast<std::size_t>(p)].parent) {
            cycle.push_back(p);
        }
        std::reverse(cycle.begin(), cycle.end());
        std::rotate(cycle.begin(), std::min_element(cycle.begin(), cycle.end()), cycle.end());
        const int child = cycle.front();
        const int parent = out.nodes[static_cast<std::size_t>(child)].parent;
        const std::vector<int>& siblings = model.nodes[static_cast<std::size_t>(parent)].children;
        const auto k = static_cast<std::size_t>(std::find(siblings.begin(), siblings.end(), child) - siblings.begin());
        std::string text;
        for (const int c : cycle) text += std::to_string(c) + " -> ";
        text += std::to_string(child);
        return ctx.invalid(at(at("$.nodes", static_cast<std::size_t>(parent)) + ".children", k),
                           "node " + std::to_string(child) + " is its own ancestor (cycle " + text + ")");
    }
    // Parents first: breadth-first from every root.
    for (std::size_t i = 0; i < n; ++i) {
        if (out.nodes[i].parent < 0) out.order.push_back(static_cast<int>(i));
    }
    for (std::size_t k = 0; k < out.order.size(); ++k) {
        const Node& node = out.nodes[static_cast<std::size_t>(out.order[k])];
        out.order.insert(out.order.end(), node.children.begin(), node.children.end());
    }
    // §3.5.1 Scenes: the scene's nodes are roots. No scene: every root is shown.
    if (model.scenes.empty()) {
        for (std::size_t i = 0; i < n; ++i) {
            if (out.nodes[i].parent < 0) out.roots.push_back(static_cast<int>(i));
        }
        return {};
    }
    const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
    if (static_cast<std::size_t>(scene) >= model.scenes.size()) {
        return ctx.invalid("$.scene", "scene " + std::to_string(scene) + " does not exist");
    }
    const std::vector<int>& roots = model.scenes[static_cast<std::size_t>(scene)].nodes;
    for (std::size_t k = 0; k < roots.size(); ++k) {
        const std::string path = at(at("$.scenes", static_cast<std::size_t>(scene)) + ".nodes", k);
        const int r = roots[k];
        if (r < 0 || static_cast<std::size_t>(r) >= n) return ctx.invalid(path, "node " + std::to_string(r) + " does not exist");
        if (out.nodes[static_cast<std::size_t>(r)].parent >= 0) {
            return ctx.invalid(path, "node " + std::to_string(r) + " is not a root (its parent is node " +
                                         std::to_string(out.nodes[static_cast<std::size_t>(r)].parent) + ")");
        }
        out.roots.push_back(r);
    }
    return {};
}

// A matrix is usable as an inverse bind matrix when it is finite and far from singular
// relative to its size: |det| / (product of column lengths) is 1 for a rotation times
// any scale and 0 for a singular matrix (Hadamard's inequality). Float storage gives
// about 7 digits, so 1e-6 separates the two.
bool invertible(const glm::mat4& m, double& det_out) {
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) {
            if (!std::isfinite(m[c][r])) {
                det_out = std::numeric_limits<double>::quiet_NaN();
                return false;
            }
        }
    }
    const glm::dmat4 d(m);
    const bool affine = d[0][3] == 0.0 && d[1][3] == 0.0 && d[2][3] == 0.0 && d[3][3] == 1.0;
    // For an affine matrix the translation column does not change the determinant, so
    // it is left out of the bound (a far-away joint is not "nearly singular").
    const int columns = affine ? 3 : 4;
    double bound = 1.0;
    for (int c = 0; c < columns; ++c) {
        bound *= affine ? glm::length(glm::dvec3(d[c])) : glm::length(d[c]);
    }
    det_out = glm::determinant(d);
    return std::isfinite(det_out) && bound > 0.0 && std::abs(det_out) > 1e-6 * bound;
}

Result<void> load_skins(const Context& ctx, const tinygltf::Model& model, Character& out) {
    for (std::size_t s = 0; s < model.skins.size(); ++s) {
        const tinygltf::Skin& src = model.skins[s];
        const std::string path = at("$.skins", s);
        Skin skin;
        skin.name = src.name;
        // §3.7.3: joints is required and non-empty.
        if (src.joints.empty()) return ctx.invalid(path + ".joints", "a skin needs at least one joint, it has none");
        for (std::size_t j = 0; j < src.joints.size(); ++j) {
            const int node = src.joints[j];
            if (node < 0 || static_cast<std::size_t>(node) >= out.nodes.size()) {
                return ctx.invalid(at(path + ".joints", j), "node " + std::to_string(node) + " does not exist");
            }
        }
        skin.joints = src.joints;
        if (src.skeleton >= 0 && static_cast<std::size_t>(src.skeleton) >= out.nodes.size()) {
            return ctx.invalid(path + ".skeleton", "node " + std::to_string(src.skeleton) + " does not exist");
        }
        skin.skeleton = src.skeleton;
        if (src.inverseBindMatrices < 0) {
            // §3.7.3: absent inverse bind matrices are identities.
            skin.inverse_bind_matrices.assign(skin.joints.size(), glm::mat4(1.0f));
        } else {
            const std::string where = path + ".inverseBindMatrices";
            auto floats = read_floats(ctx, model, src.inverseBindMatrices, where, false);
            if (!floats) return floats.error();
            const tinygltf::Accessor& accessor = accessor_of(model, src.inverseBindMatrices);
            if (accessor.type != TINYGLTF_TYPE_MAT4) {
                return ctx.invalid(where, "accessor " + std::to_string(src.inverseBindMatrices) + " is " +
                                              type_name(accessor.type) + ", expected MAT4");
            }
            if (accessor.count < skin.joints.size()) {
                return ctx.invalid(where, "accessor " + std::to_string(src.inverseBindMatrices) + " has " +
                                              std::to_string(accessor.count) + " matrices for " +
                                              std::to_string(skin.joints.size()) + " joints");
            }
            const std::vector<float>& f = floats.value();
            for (std::size_t j = 0; j < skin.joints.size(); ++j) {
                glm::mat4 m(1.0f);
                for (int c = 0; c < 4; ++c) {
                    for (int r = 0; r < 4; ++r) m[c][r] = f[j * 16 + static_cast<std::size_t>(c * 4 + r)];
                }
                double det = 0.0;
                if (!invertible(m, det)) {
                    return ctx.invalid(at(where, j), "the inverse bind matrix of joint node " +
                                                         std::to_string(skin.joints[j]) + " is not invertible (determinant " +
                                                         std::to_string(det) + ")");
                }
                skin.inverse_bind_matrices.push_back(m);
            }
        }
        out.skins.push_back(std::move(skin));
    }
    return {};
}

Result<Sampler> load_sampler(const Context& ctx, const tinygltf::Model& model, const tinygltf::AnimationSampler& src,
                             const std::string& path, Path target) {
    Sampler sampler;
    if (src.interpolation == "LINEAR") {
        sampler.interpolation = Interpolation::Linear;
    } else if (src.interpolation == "STEP") {
        sampler.interpolation = Interpolation::Step;
    } else if (src.interpolation == "CUBICSPLINE") {
        sampler.interpolation = Interpolation::CubicSpline;
    } else {
        return ctx.invalid(path + ".interpolation", "expected LINEAR, STEP or CUBICSPLINE, got \"" + src.interpolation + "\"");
    }
    auto times = read_floats(ctx, model, src.input, path + ".input", false);
    if (!times) return times.error();
    if (accessor_of(model, src.input).type != TINYGLTF_TYPE_SCALAR) {
        return ctx.invalid(path + ".input", "accessor " + std::to_string(src.input) + " is " +
                                                type_name(accessor_of(model, src.input).type) + ", expected SCALAR");
    }
    sampler.times = std::move(times).value();
    const bool cubic = sampler.interpolation == Interpolation::CubicSpline;
    if (sampler.times.empty() || (cubic && sampler.times.size() < 2)) {
        return ctx.invalid(path + ".input", cubic ? "CUBICSPLINE needs at least two keys" : "no keys");
    }
    // §3.11: input times are strictly increasing.
    for (std::size_t k = 1; k < sampler.times.size(); ++k) {
        if (!(sampler.times[k] > sampler.times[k - 1])) {
            return ctx.invalid(path + ".input", "key times must increase: time " + std::to_string(k) + " is " +
                                                    std::to_string(sampler.times[k]) + " after " +
                                                    std::to_string(sampler.times[k - 1]));
        }
    }
    const std::size_t comps = target == Path::Rotation ? 4 : 3;
    auto values = read_floats(ctx, model, src.output, path + ".output", target == Path::Rotation);
    if (!values) return values.error();
    const tinygltf::Accessor& output = accessor_of(model, src.output);
    if (component_count(output.type) != comps || output.type == TINYGLTF_TYPE_MAT2) {
        return ctx.invalid(path + ".output", "accessor " + std::to_string(src.output) + " is " + type_name(output.type) +
                                                 ", a " + (target == Path::Rotation ? "rotation needs VEC4" : "translation or scale needs VEC3"));
    }
    const std::size_t expected = sampler.times.size() * (cubic ? 3 : 1);
    if (output.count != expected) {
        return ctx.invalid(path + ".output", "accessor " + std::to_string(src.output) + " has " + std::to_string(output.count) +
                                                 " values, " + std::to_string(sampler.times.size()) + " keys" +
                                                 (cubic ? " of CUBICSPLINE" : "") + " need " + std::to_string(expected));
    }
    const std::vector<float>& f = values.value();
    sampler.values.resize(expected, glm::vec4(0.0f));
    for (std::size_t i = 0; i < expected; ++i) {
        for (std::size_t c = 0; c < comps; ++c) sampler.values[i][static_cast<int>(c)] = f[i * comps + c];
    }
    return sampler;
}

Result<void> load_animations(const Context& ctx, const tinygltf::Model& model, Character& out) {
    for (std::size_t a = 0; a < model.animations.size(); ++a) {
        const tinygltf::Animation& src = model.animations[a];
        const std::string path = at("$.animations", a);
        Animation animation;
        // Scenes pick clips by name, so an unnamed clip gets one (see Animation::name).
        animation.name = src.name.empty() ? "animation" + std::to_string(a) : src.name;
        animation.samplers.resize(src.samplers.size());
        std::vector<int> sampler_path(src.samplers.size(), -1);  // the Path a sampler was loaded for
        bool any = false;
        for (std::size_t c = 0; c < src.channels.size(); ++c) {
            const tinygltf::AnimationChannel& channel = src.channels[c];
            const std::string cpath = at(path + ".channels", c);
            if (channel.sampler < 0 || static_cast<std::size_t>(channel.sampler) >= src.samplers.size()) {
                return ctx.invalid(cpath + ".sampler", "sampler " + std::to_string(channel.sampler) + " does not exist");
            }
            if (channel.target_node < 0) continue;  // §3.11: no node = targeted by an extension
            if (static_cast<std::size_t>(channel.target_node) >= out.nodes.size()) {
                return ctx.invalid(cpath + ".target.node", "node " + std::to_string(channel.target_node) + " does not exist");
            }
            Path target = Path::Translation;
            if (channel.target_path == "translation") {
                target = Path::Translation;
            } else if (channel.target_path == "rotation") {
                target = Path::Rotation;
            } else if (channel.target_path == "scale") {
                target = Path::Scale;
            } else if (channel.target_path == "weights") {
                continue;  // morph targets do not move joints
            } else {
                return ctx.invalid(cpath + ".target.path", "expected translation, rotation, scale or weights, got \"" +
                                                               channel.target_path + "\"");
            }
            if (out.nodes[static_cast<std::size_t>(channel.target_node)].matrix) {
                return ctx.invalid(cpath + ".target.node", "node " + std::to_string(channel.target_node) +
                                                               " has a matrix; an animated node must use TRS (§3.5.3)");
            }
            for (const Channel& other : animation.channels) {
                if (other.node == channel.target_node && other.path == target) {
                    return ctx.invalid(cpath + ".target", "node " + std::to_string(channel.target_node) + "'s " +
                                                              channel.target_path + " is animated twice in this animation");
                }
            }
            const auto s = static_cast<std::size_t>(channel.sampler);
            const int wanted = target == Path::Rotation ? 4 : 3;
            if (sampler_path[s] < 0) {
                auto sampler = load_sampler(ctx, model, src.samplers[s], at(path + ".samplers", s), target);
                if (!sampler) return sampler.error();
                animation.samplers[s] = std::move(sampler).value();
                sampler_path[s] = wanted;
            } else if (sampler_path[s] != wanted) {
                return ctx.invalid(cpath + ".sampler", "sampler " + std::to_string(s) +
                                                           " also drives a property of another size");
            }
            animation.channels.push_back({channel.target_node, target, s});
            const Sampler& used = animation.samplers[s];
            animation.start = any ? std::min(animation.start, used.times.front()) : used.times.front();
            animation.end = any ? std::max(animation.end, used.times.back()) : used.times.back();
            any = true;
        }
        out.animations.push_back(std::move(animation));
    }
    return {};
}

}  // namespace

Result<Character> load_character(const std::string& path) {
    try {
        const Context ctx{path};
        auto bytes = core::read_binary_file(path);
        if (!bytes) return bytes.error();
        const fs::path base_dir = fs::path(path).parent_path();
        std::string extensions;
        auto parsed = parse(ctx, bytes.value(), base_dir, extensions);
        if (!parsed) return parsed.error();
        const tinygltf::Model& model = parsed.value();
        KW_TRY(check_storage(ctx, model));
        Character character;
        character.source = path;
        character.extensions = std::move(extensions);
        KW_TRY(load_meshes(ctx, model, character));
        KW_TRY(load_nodes(ctx, model, character));
        KW_TRY(load_skins(ctx, model, character));
        KW_TRY(load_animations(ctx, model, character));
        return character;
    } catch (const std::bad_alloc&) {
        return make_error(Error::Kind::InvalidInput, path + ": out of memory while loading (a corrupt size?)");
    } catch (const std::exception& e) {
        return make_error(Error::Kind::Internal, path + ": " + e.what());
    }
}

}  // namespace kodawari::gltf
