// The source of the rigged crowd's glTF export (export.hpp, RiggedGlbWriter::create):
// the character's own file loaded with tinygltf, its images' bytes kept undecoded, and
// what the writer needs of its nodes (gltf_rigged.cpp writes the crowd).

#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "core/binary_file.hpp"
#include "export/gltf_rigged_writer.hpp"

namespace kodawari {
namespace {

namespace fs = std::filesystem;
using namespace gltf;

constexpr std::uint32_t kGlbMagic = 0x46546C67u;  // "glTF"

// tinygltf hands every image's bytes to this callback. Images in buffer views stay
// there; the bytes of images given by URI (external files, data URIs) are kept as they
// are, undecoded, to be moved into the GLB buffer (no re-encoding, no image codecs).
bool keep_image_bytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
    if (image->bufferView < 0 && size > 0) image->image.assign(bytes, bytes + size);
    return true;
}

// The MIME type of image bytes from their signature, "" when unknown.
std::string sniff_mime_type(const std::vector<unsigned char>& b) {
    auto starts = [&](std::initializer_list<unsigned char> magic, std::size_t at = 0) {
        if (b.size() < at + magic.size()) return false;
        return std::equal(magic.begin(), magic.end(), b.begin() + static_cast<std::ptrdiff_t>(at));
    };
    if (starts({0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A})) return "image/png";
    if (starts({0xFF, 0xD8, 0xFF})) return "image/jpeg";
    if (starts({'R', 'I', 'F', 'F'}) && starts({'W', 'E', 'B', 'P'}, 8)) return "image/webp";
    if (starts({0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, 0x0D, 0x0A, 0x1A, 0x0A})) return "image/ktx2";
    return "";
}

// Loads the source with tinygltf: .glb/.vrm by their magic, anything else as JSON.
Result<tinygltf::Model> load_source(const std::string& path) {
    auto read = core::read_binary_file(path);
    if (!read) return read.error();
    std::vector<unsigned char> bytes = std::move(read).value();
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) {
        return make_error(Error::Kind::Unsupported, path + ": files over 4 GiB are not supported");
    }
    std::uint32_t magic = 0;
    if (bytes.size() >= 4) std::memcpy(&magic, bytes.data(), 4);
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&keep_image_bytes, nullptr);
    std::string err;
    std::string warn;
    const std::string dir = fs::path(path).parent_path().string();
    const bool loaded =
        magic == kGlbMagic
            ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), static_cast<unsigned int>(bytes.size()), dir)
            : loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()),
                                         static_cast<unsigned int>(bytes.size()), dir);
    if (!loaded) {
        while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
        return make_error(Error::Kind::InvalidInput, path + ": tinygltf: " + (err.empty() ? std::string("cannot load") : err));
    }
    return model;
}

}  // namespace

Result<RiggedGlbWriter> RiggedGlbWriter::create(const std::string& source_path, const animation::Character& character,
                                                std::span<const RiggedInstance> instances, std::vector<bool> animated,
                                                float fps, std::string animation_name, std::string spill_beside,
                                                const GlbCompaction& compaction) {
    assert(animated.size() == character.nodes.size() && "one animated flag per node of the character");
    assert(fps > 0.0f && std::isfinite(fps));
    KW_TRY(check_compaction(spill_beside.empty() ? source_path : spill_beside, compaction));
    auto impl = std::make_unique<Impl>();
    impl->compaction = compaction;
    try {
        auto loaded = load_source(source_path);
        if (!loaded) return loaded.error();
        impl->model = std::move(loaded).value();
    } catch (const std::bad_alloc&) {
        return make_error(Error::Kind::InvalidInput, source_path + ": out of memory while loading (a corrupt size?)");
    } catch (const std::exception& e) {
        return make_error(Error::Kind::InvalidInput, source_path + ": tinygltf: " + e.what());
    }
    tinygltf::Model& model = impl->model;
    const std::size_t n = character.nodes.size();
    if (model.nodes.size() != n || model.skins.size() != character.skins.size()) {
        return make_error(Error::Kind::InvalidInput,
                          source_path + ": has " + std::to_string(model.nodes.size()) + " nodes and " +
                              std::to_string(model.skins.size()) + " skins, the character loaded from " +
                              character.source + " has " + std::to_string(n) + " and " +
                              std::to_string(character.skins.size()) + " (not the same file?)");
    }

    // EXT_meshopt_compression names buffers by index, which merging the buffers into one
    // would break.
    for (std::size_t v = 0; v < model.bufferViews.size(); ++v) {
        if (model.bufferViews[v].extensions.count("EXT_meshopt_compression") != 0) {
            return make_error(Error::Kind::Unsupported, source_path + ": $.bufferViews[" + std::to_string(v) +
                                                            "]: EXT_meshopt_compression is not supported");
        }
    }
    for (const RiggedInstance& instance : instances) {
        const glm::quat& q = instance.placement.rotation;
        if (!finite(instance.placement.position) || !finite(q) || !(glm::length(q) > 0.0f)) {
            return make_error(Error::Kind::InvalidInput,
                              "instance " + instance.name + ": the placement is not finite (or a zero rotation)");
        }
    }

    // Images given by URI: their bytes, with a MIME type a GLB buffer view needs.
    impl->image_bytes.resize(model.images.size());
    for (std::size_t i = 0; i < model.images.size(); ++i) {
        tinygltf::Image& image = model.images[i];
        if (image.bufferView >= 0) {
            image.image.clear();
            continue;
        }
        const std::string where = source_path + ": $.images[" + std::to_string(i) + "]";
        if (image.image.empty()) {
            return make_error(Error::Kind::InvalidInput, where + ".uri: cannot read image \"" + image.uri + "\"");
        }
        std::string mime = sniff_mime_type(image.image);
        if (mime.empty() && image.mimeType.rfind("image/", 0) == 0) mime = image.mimeType;
        if (mime.empty()) {
            return make_error(Error::Kind::InvalidInput,
                              where + ": unknown image format (not PNG, JPEG, WebP or KTX2, no image MIME type)");
        }
        image.mimeType = mime;
        impl->image_bytes[i] = std::move(image.image);
        image.image.clear();
    }

    impl->source_path = source_path;
    impl->instances.assign(instances.begin(), instances.end());
    impl->own_end = impl->instances.size();
    impl->fps = fps;
    impl->animation_name = std::move(animation_name);
    impl->spill_beside = std::move(spill_beside);
    impl->node_count = n;
    impl->roots = character.roots;
    impl->animated = std::move(animated);

    std::vector<bool> joint(n, false);
    for (const animation::Skin& skin : character.skins) {
        for (const int j : skin.joints) joint[static_cast<std::size_t>(j)] = true;
    }
    std::vector<bool> shown(n, false);  // in the displayed scene
    std::vector<int> stack(character.roots.begin(), character.roots.end());
    while (!stack.empty()) {
        const auto k = static_cast<std::size_t>(stack.back());
        stack.pop_back();
        shown[k] = true;
        stack.insert(stack.end(), character.nodes[k].children.begin(), character.nodes[k].children.end());
    }
    impl->moves.assign(n, false);
    impl->extra.assign(n, -1);
    for (std::size_t k = 0; k < n; ++k) {
        const animation::Node& node = character.nodes[k];
        impl->names.push_back(node.name.empty() ? "#" + std::to_string(k) : node.name);
        impl->matrix.push_back(node.matrix.has_value());
        impl->rest_translation.push_back(node.translation);
        impl->rest_rotation.push_back(node.rotation);
        impl->rest_scale.push_back(node.scale);
        impl->skinned.push_back(node.mesh >= 0 && node.skin >= 0);
        if (impl->animated[k]) impl->animated_nodes.push_back(static_cast<int>(k));
        if (!impl->skinned[k] || !shown[k]) continue;
        if (node.children.empty() && !joint[k] && !impl->animated[k]) {
            impl->moves[k] = true;
        } else {
            impl->extra[k] = static_cast<int>(impl->extra_count++);
        }
    }
    return RiggedGlbWriter(std::move(impl));
}

}  // namespace kodawari
