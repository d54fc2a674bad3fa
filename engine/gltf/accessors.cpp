// The accessors of a glTF model: their storage checked against the buffers, their elements read.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "gltf/import_detail.hpp"

namespace kodawari::gltf::detail {
namespace {

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

}  // namespace

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

namespace {

// The bytes an element occupies, with §3.6.2.4's column padding of 1- and 2-byte
// matrices (each column starts on a 4-byte boundary).
std::size_t element_bytes(int component_type, int type) {
    const std::size_t c = component_bytes(component_type);
    if (type == TINYGLTF_TYPE_MAT2 && c == 1) return 8;
    if (type == TINYGLTF_TYPE_MAT3 && c == 1) return 12;
    if (type == TINYGLTF_TYPE_MAT3 && c == 2) return 24;
    return c * component_count(type);
}

}  // namespace

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

namespace {

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

}  // namespace

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

}  // namespace kodawari::gltf::detail
