// A .glb whose JSON is written element by element (gltf_json_stream.hpp).
//
// tinygltf builds one nlohmann DOM of the whole model and dumps it to one string: for
// 100 000 birds (3 million nodes, accessors, channels and samplers) gigabytes. Here
// tinygltf serializes the small model only; its JSON, parsed back (small), gives every
// member but the streamed elements, in nlohmann's order (objects are std::maps: keys
// sorted). The root object is then written member by member, and the big arrays element
// by element, each element a small nlohmann object built as tinygltf 2.7's serializers
// build it (SerializeGltfNode, SerializeGltfAccessor, ...; those are static inside the
// library, so they are written again here) and dumped with the same settings.
//
// The JSON goes to a spill file, not through two passes of the generators: the .glb's
// header needs its length first, a second pass would serialize three million elements
// twice and ask generators to give the same elements twice, while the JSON (~300 bytes a
// bird) is small next to the keys written to the same disk.

#include "export/gltf_json_stream.hpp"

#include <algorithm>
#include <cstring>
#include <string_view>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "export/gltf_common.hpp"

namespace kodawari::gltf {
namespace {

using nlohmann::json;

// tinygltf passes strings as C strings (JsonFromString(value.c_str())): a string stops at
// its first NUL.
json string_json(const std::string& text) { return json(std::string(text.c_str())); }

// tinygltf's ValueToJson (nlohmann build): no value for null and binary values; an empty
// array or object is null, since elements are added to a null json.
bool value_json(const tinygltf::Value& value, json& out) {
    out = json();
    switch (value.Type()) {
        case tinygltf::REAL_TYPE: out = json(value.Get<double>()); return true;
        case tinygltf::INT_TYPE: out = json(value.Get<int>()); return true;
        case tinygltf::BOOL_TYPE: out = json(value.Get<bool>()); return true;
        case tinygltf::STRING_TYPE: out = json(value.Get<std::string>()); return true;
        case tinygltf::ARRAY_TYPE:
            for (const tinygltf::Value& element : value.Get<tinygltf::Value::Array>()) {
                json element_json;
                if (value_json(element, element_json)) out.push_back(std::move(element_json));
            }
            return true;
        case tinygltf::OBJECT_TYPE:
            for (const auto& [key, element] : value.Get<tinygltf::Value::Object>()) {
                json element_json;
                if (value_json(element, element_json)) out[key] = std::move(element_json);
            }
            return true;
        default: return false;
    }
}

void add_extras(json& o, const tinygltf::Value& extras) {
    if (extras.Type() == tinygltf::NULL_TYPE) return;
    json value;
    if (value_json(extras, value)) o["extras"] = std::move(value);
}

// An extension without a value is still named, as an empty object (tinygltf issue 97).
void add_extensions(json& o, const tinygltf::ExtensionMap& extensions) {
    if (extensions.empty()) return;
    json map;
    for (const auto& [name, value] : extensions) {
        json value_out;
        bool null = true;
        if (value_json(value, value_out)) {
            null = value_out.is_null();
            map[name.c_str()] = std::move(value_out);
        }
        if (null && !name.empty()) map[name.c_str()] = json::object();
    }
    o["extensions"] = std::move(map);
}

template <typename T>
void add_numbers(json& o, const char* key, const std::vector<T>& values) {
    if (values.empty()) return;
    json array = json::array();
    for (const T& v : values) array.push_back(json(v));
    o[key] = std::move(array);
}

json node_json(const tinygltf::Node& node) {
    json o;
    add_numbers(o, "translation", node.translation);
    add_numbers(o, "rotation", node.rotation);
    add_numbers(o, "scale", node.scale);
    add_numbers(o, "matrix", node.matrix);
    if (node.mesh != -1) o["mesh"] = node.mesh;
    if (node.skin != -1) o["skin"] = node.skin;
    if (node.camera != -1) o["camera"] = node.camera;
    add_numbers(o, "weights", node.weights);
    add_extras(o, node.extras);
    add_extensions(o, node.extensions);
    if (!node.name.empty()) o["name"] = string_json(node.name);
    add_numbers(o, "children", node.children);
    return o;
}

const char* accessor_type_name(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return "SCALAR";
        case TINYGLTF_TYPE_VEC2: return "VEC2";
        case TINYGLTF_TYPE_VEC3: return "VEC3";
        case TINYGLTF_TYPE_VEC4: return "VEC4";
        case TINYGLTF_TYPE_MAT2: return "MAT2";
        case TINYGLTF_TYPE_MAT3: return "MAT3";
        case TINYGLTF_TYPE_MAT4: return "MAT4";
        default: return "";
    }
}

json accessor_json(const tinygltf::Accessor& accessor) {
    json o;
    if (accessor.bufferView >= 0) o["bufferView"] = accessor.bufferView;
    // tinygltf writes int(byteOffset), negative past 2 GiB, which no reader can use (a
    // large flock's one animation view is longer than that): here the offset itself, the
    // same text wherever tinygltf's is right.
    if (accessor.byteOffset != 0) o["byteOffset"] = static_cast<std::uint64_t>(accessor.byteOffset);
    o["componentType"] = accessor.componentType;
    o["count"] = accessor.count;
    if (accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
        accessor.componentType == TINYGLTF_COMPONENT_TYPE_DOUBLE) {
        add_numbers(o, "min", accessor.minValues);
        add_numbers(o, "max", accessor.maxValues);
    } else {
        // Integer components' bounds are written as integers (tinygltf issue 301).
        const auto as_ints = [](const std::vector<double>& values) {
            std::vector<int> ints(values.size());
            std::transform(values.begin(), values.end(), ints.begin(), [](double v) { return static_cast<int>(v); });
            return ints;
        };
        add_numbers(o, "min", as_ints(accessor.minValues));
        add_numbers(o, "max", as_ints(accessor.maxValues));
    }
    if (accessor.normalized) o["normalized"] = true;
    o["type"] = accessor_type_name(accessor.type);
    if (!accessor.name.empty()) o["name"] = string_json(accessor.name);
    add_extras(o, accessor.extras);
    // tinygltf 2.7 writes no accessor extensions.
    if (accessor.sparse.isSparse) {
        const auto& sparse = accessor.sparse;
        json s;
        s["count"] = sparse.count;
        s["indices"] = json{{"bufferView", sparse.indices.bufferView},
                            {"byteOffset", sparse.indices.byteOffset},
                            {"componentType", sparse.indices.componentType}};
        s["values"] = json{{"bufferView", sparse.values.bufferView}, {"byteOffset", sparse.values.byteOffset}};
        o["sparse"] = std::move(s);
    }
    return o;
}

// tinygltf 2.7's SerializeGltfSkin writes neither extras nor extensions.
json skin_json(const tinygltf::Skin& skin) {
    json o;
    add_numbers(o, "joints", skin.joints);
    if (skin.inverseBindMatrices >= 0) o["inverseBindMatrices"] = skin.inverseBindMatrices;
    if (skin.skeleton >= 0) o["skeleton"] = skin.skeleton;
    if (!skin.name.empty()) o["name"] = string_json(skin.name);
    return o;
}

json channel_json(const tinygltf::AnimationChannel& channel) {
    json o;
    o["sampler"] = channel.sampler;
    json target;
    target["node"] = channel.target_node;
    target["path"] = string_json(channel.target_path);
    add_extensions(target, channel.target_extensions);
    o["target"] = std::move(target);
    add_extras(o, channel.extras);
    add_extensions(o, channel.extensions);
    return o;
}

json sampler_json(const tinygltf::AnimationSampler& sampler) {
    json o;
    o["input"] = sampler.input;
    o["output"] = sampler.output;
    o["interpolation"] = string_json(sampler.interpolation);
    add_extras(o, sampler.extras);
    return o;
}

// The JSON text on its way to the spill file, in blocks; the first failure is kept and
// reported once, at the end.
class JsonSink {
public:
    explicit JsonSink(SpillFile& spill) : spill_(spill) { block_.reserve(kBlock + 4096); }
    void put(std::string_view text) {
        block_.append(text);
        size_ += text.size();
        if (block_.size() >= kBlock) flush();
    }
    void put(char c) { put(std::string_view(&c, 1)); }
    [[nodiscard]] Result<void> finish() {
        flush();
        return std::move(status_);
    }
    [[nodiscard]] std::uint64_t size() const { return size_; }

private:
    static constexpr std::size_t kBlock = std::size_t{1} << 20;
    void flush() {
        if (status_.ok() && !block_.empty()) status_ = spill_.append(block_.data(), block_.size());
        block_.clear();
    }
    SpillFile& spill_;
    std::string block_;
    std::uint64_t size_ = 0;
    Result<void> status_;
};

// One array member of an object, opened (its key and '[') when told or at its first
// element: an array that only generated elements would fill is absent when they give none,
// as in tinygltf.
class ArrayMember {
public:
    ArrayMember(JsonSink& sink, bool& first_member, std::string_view key)
        : sink_(sink), first_member_(first_member), key_(key) {}
    void open() {
        if (opened_) return;
        if (!first_member_) sink_.put(',');
        first_member_ = false;
        sink_.put(json(key_).dump());
        sink_.put(":[");
        opened_ = true;
    }
    /// Starts an element the caller writes itself.
    void begin_element() {
        open();
        if (elements_++ > 0) sink_.put(',');
    }
    void element(const json& value) {
        begin_element();
        sink_.put(value.dump());
    }
    void close() {
        if (opened_) sink_.put(']');
    }
    [[nodiscard]] std::size_t elements() const { return elements_; }

private:
    JsonSink& sink_;
    bool& first_member_;
    std::string key_;
    bool opened_ = false;
    std::size_t elements_ = 0;
};

// `existing`'s elements (if any), then the generated ones; returns how many were generated.
template <typename T>
std::size_t write_array(ArrayMember& member, const json* existing, const ElementSource<T>& source,
                        json (*serialize)(const T&)) {
    if (existing != nullptr) {
        member.open();
        for (const json& element : *existing) member.element(element);
    }
    std::size_t generated = 0;
    std::vector<T> elements;
    for (std::size_t group = 0; group < source.groups; ++group) {
        elements.clear();
        source.fill(group, elements);
        for (const T& element : elements) member.element(serialize(element));
        generated += elements.size();
    }
    member.close();
    return generated;
}

void write_member(JsonSink& sink, bool& first_member, const std::string& key, const json& value) {
    if (!first_member) sink.put(',');
    first_member = false;
    sink.put(json(key).dump());
    sink.put(':');
    sink.put(value.dump());
}

// Animation 0 with the streamed channels and samplers; returns how many channels were
// generated.
std::size_t write_animation(JsonSink& sink, const json& animation, const StreamedElements& streamed) {
    sink.put('{');
    bool first = true;
    std::size_t channels = 0;
    for (const auto& [key, value] : animation.items()) {
        if (key == "channels") {
            ArrayMember member(sink, first, key);
            channels = write_array(member, &value, streamed.channels, channel_json);
        } else if (key == "samplers") {
            ArrayMember member(sink, first, key);
            write_array(member, &value, streamed.samplers, sampler_json);
        } else {
            write_member(sink, first, key, value);
        }
    }
    sink.put('}');
    return channels;
}

std::uint32_t padding(std::uint64_t size) { return static_cast<std::uint32_t>((4 - size % 4) % 4); }

}  // namespace

Result<void> write_streamed_glb(AtomicFile& file, tinygltf::Model& model, const StreamedElements& streamed,
                                std::uint64_t tail_bytes, const std::function<Result<void>()>& write_tail) {
    const std::string& path = file.path();
    if (model.buffers.empty() ? tail_bytes > 0 : !model.buffers[0].uri.empty()) {
        return make_error(Error::Kind::InvalidInput, path + ": a streamed .glb's data needs an embedded buffer 0");
    }
    const bool animated = streamed.channels.groups > 0 || streamed.samplers.groups > 0;
    if (animated && model.animations.empty()) {
        return make_error(Error::Kind::InvalidInput, path + ": streamed animation channels need an animation in the model");
    }

    // The small model's JSON, from tinygltf. Buffer 0's bytes are held out (they are
    // written from the model below, not copied through tinygltf's output), and an
    // animation whose channels are all streamed gets a stand-in one, dropped below, so
    // that tinygltf writes it.
    std::string small;
    const bool stand_in = animated && model.animations[0].channels.empty();
    {
        std::vector<unsigned char> head;
        if (!model.buffers.empty()) head.swap(model.buffers[0].data);
        if (stand_in) model.animations[0].channels.emplace_back();
        struct Restore {
            tinygltf::Model& model;
            std::vector<unsigned char>& head;
            bool stand_in;
            ~Restore() {
                if (!model.buffers.empty()) head.swap(model.buffers[0].data);
                if (stand_in) model.animations[0].channels.pop_back();
            }
        } restore{model, head, stand_in};
        std::ostringstream stream;
        tinygltf::TinyGLTF writer;
        if (!writer.WriteGltfSceneToStream(&model, stream, false, true) || !stream) {
            return make_error(Error::Kind::Io, path + ": glTF serialization failed");
        }
        small = std::move(stream).str();
    }
    std::uint32_t small_json = 0;
    if (small.size() < 20) return make_error(Error::Kind::Internal, path + ": tinygltf wrote no GLB header");
    std::memcpy(&small_json, small.data() + 12, 4);
    json root = json::parse(small.substr(20, small_json));  // the chunk's space padding is whitespace
    small.clear();
    small.shrink_to_fit();

    const std::uint64_t head_bytes = model.buffers.empty() ? 0 : model.buffers[0].data.size();
    const std::uint64_t bin_bytes = head_bytes + tail_bytes;
    if (!model.buffers.empty()) root.at("buffers").at(0)["byteLength"] = bin_bytes;
    if (stand_in) root.at("animations").at(0).at("channels").erase(0);
    if (const MeshoptJson& meshopt = streamed.meshopt; meshopt.fallback >= 0) {
        json& views = root.at("bufferViews");
        if (meshopt.fallback == 0 || static_cast<std::size_t>(meshopt.fallback) >= root.at("buffers").size() ||
            meshopt.first_view < 0 || static_cast<std::size_t>(meshopt.first_view) + meshopt.views.size() > views.size()) {
            return make_error(Error::Kind::Internal, path + ": meshopt views outside the model");
        }
        root["buffers"][static_cast<std::size_t>(meshopt.fallback)] =
            json{{"byteLength", meshopt.fallback_bytes}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}};
        for (std::size_t k = 0; k < meshopt.views.size(); ++k) {
            const MeshoptJson::View& v = meshopt.views[k];
            json extension{{"buffer", 0},        {"byteLength", v.byte_length}, {"byteStride", v.byte_stride},
                           {"count", v.count},   {"mode", "ATTRIBUTES"}};
            if (v.byte_offset != 0) extension["byteOffset"] = v.byte_offset;
            if (std::string_view(v.filter) != "NONE") extension["filter"] = v.filter;
            views[static_cast<std::size_t>(meshopt.first_view) + k]["extensions"]["EXT_meshopt_compression"] = std::move(extension);
        }
    }
    // Members that only streamed elements fill, in their place among the sorted keys.
    for (const char* key : {"accessors", "nodes", "skins"}) {
        if (!root.contains(key)) root[key] = nullptr;
    }

    const auto too_large = [&](std::uint64_t total) {
        return make_error(Error::Kind::InvalidInput,
                          path + ": " + std::to_string(total) + " bytes exceed the 4 GiB limit of a .glb");
    };
    const std::uint64_t bin_length = bin_bytes + padding(bin_bytes);
    const std::uint64_t bin_chunk = bin_bytes > 0 ? 8 + bin_length : 0;
    if (12 + 8 + bin_chunk > 0xFFFFFFFFull) return too_large(12 + 8 + bin_chunk);  // before writing any JSON

    auto spill = SpillFile::open(path);
    if (!spill) return spill.error();
    JsonSink sink(spill.value());
    sink.put('{');
    bool first = true;
    std::size_t animation_channels = 0;
    for (const auto& [key, value] : root.items()) {
        const json* existing = value.is_null() ? nullptr : &value;
        if (key == "accessors") {
            ArrayMember member(sink, first, key);
            write_array(member, existing, streamed.accessors, accessor_json);
        } else if (key == "nodes") {
            ArrayMember member(sink, first, key);
            write_array(member, existing, streamed.nodes, node_json);
        } else if (key == "skins") {
            ArrayMember member(sink, first, key);
            write_array(member, existing, streamed.skins, skin_json);
        } else if (key == "animations" && animated) {
            ArrayMember member(sink, first, key);
            member.open();
            for (std::size_t i = 0; i < value.size(); ++i) {
                if (i == 0) {
                    member.begin_element();
                    animation_channels = write_animation(sink, value[0], streamed);
                } else {
                    member.element(value[i]);
                }
            }
            member.close();
        } else {
            write_member(sink, first, key, value);
        }
    }
    sink.put('}');
    KW_TRY(sink.finish());
    if (stand_in && animation_channels == 0) {
        // tinygltf would have left the animation out; it is written already.
        return make_error(Error::Kind::InvalidInput, path + ": an animation whose channels are all streamed got none");
    }

    const std::uint64_t json_bytes = sink.size();
    const std::uint64_t json_length = json_bytes + padding(json_bytes);
    const std::uint64_t total = 12 + 8 + json_length + bin_chunk;
    if (total > 0xFFFFFFFFull) return too_large(total);
    // The container as tinygltf frames it (WriteBinaryGltfStream): JSON padded with
    // spaces, the buffer with zeros, no BIN chunk for an empty buffer.
    const auto word = [&](std::uint32_t value) { file.write(&value, sizeof value); };
    file.write("glTF", 4);
    word(2);
    word(static_cast<std::uint32_t>(total));
    word(static_cast<std::uint32_t>(json_length));
    word(0x4E4F534Au);
    std::vector<char> block(std::size_t{1} << 20);
    for (std::uint64_t at = 0; at < json_bytes; at += block.size()) {
        const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(block.size(), json_bytes - at));
        KW_TRY(spill.value().read(at, block.data(), n));
        file.write(block.data(), n);
    }
    file.write(std::string(padding(json_bytes), ' '));
    if (bin_bytes > 0) {
        word(static_cast<std::uint32_t>(bin_length));
        word(0x004E4942u);
        file.write(model.buffers[0].data.data(), model.buffers[0].data.size());
        if (write_tail) KW_TRY(write_tail());
        const char zeros[4] = {};
        file.write(zeros, padding(bin_bytes));
    }
    return {};
}

}  // namespace kodawari::gltf
