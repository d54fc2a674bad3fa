// Each bird's elements in the bird glTF export (gltf_birds.cpp), made one bird at a time
// while the JSON is written: its armature's nodes, its skin, and its animation channels'
// accessors, samplers and channels.

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "export/gltf_birds_writer.hpp"

namespace kodawari {

using namespace gltf;

// The root, parent of every bird's armature. The mesh nodes are not under it: a skinned
// mesh ignores its node's transform, and glTF-Validator warns about one that has a parent
// (NODE_SKINNED_MESH_NON_ROOT); they are the scene's own roots.
void BirdGlbWriter::Impl::root_node(std::vector<tinygltf::Node>& out) const {
    tinygltf::Node& root = out.emplace_back();
    root.name = "Birds";
    root.children.reserve(count());
    for (std::size_t b = 0; b < count(); ++b) root.children.push_back(Layout::armature_node(b));
}

void BirdGlbWriter::Impl::bird_nodes(const Layout& layout, std::size_t b, std::vector<tinygltf::Node>& out) const {
    const std::uint32_t type = type_of(b);
    const std::string name = name_of(b);
    tinygltf::Node& armature = out.emplace_back();
    armature.name = name;
    armature.children.push_back(Layout::joint_node(b, KW_PART_BODY));
    const float* rest = first.data() + b * kRecordFloats;
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        tinygltf::Node& node = out.emplace_back();
        // Named as the rigged crowd's nodes are, "<instance>/<node>".
        node.name = name + "/" + std::string(birds::kPartNames[part]);
        // The rest pose is frame 0, so a viewer that ignores the animation still shows
        // the flock where it starts.
        const float* q0 = rest + 3 + 4 * part;
        node.rotation = {static_cast<double>(q0[0]), static_cast<double>(q0[1]), static_cast<double>(q0[2]),
                         static_cast<double>(q0[3])};
        if (part == KW_PART_BODY) {
            node.translation = {static_cast<double>(rest[0]), static_cast<double>(rest[1]), static_cast<double>(rest[2])};
        } else {
            const auto& o = layout.types[type].offsets[part];
            node.translation = {static_cast<double>(o[0]), static_cast<double>(o[1]), static_cast<double>(o[2])};
        }
        if (part == KW_PART_TAIL && tail_spread) {
            const float* s0 = rest + kTailScaleAt;
            node.scale = {static_cast<double>(s0[0]), static_cast<double>(s0[1]), static_cast<double>(s0[2])};
        }
        for (std::size_t child = 1; child < birds::kPartCount; ++child) {
            if (birds::kPartParents[child] == static_cast<int>(part)) node.children.push_back(Layout::joint_node(b, child));
        }
    }
    tinygltf::Node& mesh = out.emplace_back();
    mesh.name = name + "/mesh";
    mesh.mesh = layout.types[type].mesh;
    mesh.skin = static_cast<int>(b);
}

void BirdGlbWriter::Impl::bird_skin(const Layout& layout, std::size_t b, std::vector<tinygltf::Skin>& out) const {
    tinygltf::Skin& skin = out.emplace_back();
    skin.name = name_of(b);
    skin.inverseBindMatrices = layout.types[type_of(b)].inverse_bind;
    skin.skeleton = Layout::armature_node(b);
    for (std::size_t part = 0; part < birds::kPartCount; ++part) skin.joints.push_back(Layout::joint_node(b, part));
}

// Bird b's keys: the Body's translations, then each part's rotations, over all frames;
// compacted, each channel's kept keys and, where not shared, their times.
void BirdGlbWriter::Impl::bird_accessors(const Layout& layout, std::size_t b, std::vector<tinygltf::Accessor>& out) const {
    if (layout.compact) {
        layout.compact->item_accessors(b, layout.animation_view, out);
        return;
    }
    const auto add = [&](std::size_t offset, int type) {
        tinygltf::Accessor& accessor = out.emplace_back();
        accessor.bufferView = layout.animation_view;
        accessor.byteOffset = offset;
        accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        accessor.count = frames;
        accessor.type = type;
    };
    const std::size_t base = layout.time_bytes + b * layout.per_bird;
    add(base, TINYGLTF_TYPE_VEC3);
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        add(base + layout.translation_bytes + part * layout.rotation_bytes, TINYGLTF_TYPE_VEC4);
    }
    if (tail_spread) add(base + layout.translation_bytes + birds::kPartCount * layout.rotation_bytes, TINYGLTF_TYPE_VEC3);
}

void BirdGlbWriter::Impl::bird_samplers(const Layout& layout, std::size_t b,
                                        std::vector<tinygltf::AnimationSampler>& out) const {
    if (layout.compact) {
        std::vector<std::pair<int, int>> io;
        layout.compact->item_channels(b, layout.first_accessor + static_cast<int>(layout.compact->accessors_before(b)), io);
        for (const auto& [input, output] : io) {
            tinygltf::AnimationSampler& sampler = out.emplace_back();
            sampler.input = input;
            sampler.output = output;
            sampler.interpolation = "LINEAR";
        }
        return;
    }
    for (std::size_t k = 0; k < layout.channels; ++k) {
        tinygltf::AnimationSampler& sampler = out.emplace_back();
        sampler.input = layout.time_accessor;
        sampler.output = layout.first_accessor + static_cast<int>(b * layout.channels + k);
        sampler.interpolation = "LINEAR";
    }
}

void BirdGlbWriter::Impl::bird_channels(const Layout& layout, std::size_t b,
                                        std::vector<tinygltf::AnimationChannel>& out) const {
    for (std::size_t k = 0; k < layout.channels; ++k) {
        tinygltf::AnimationChannel& channel = out.emplace_back();
        channel.sampler = static_cast<int>(b * layout.channels + k);
        if (k == 0) {
            channel.target_node = Layout::joint_node(b, KW_PART_BODY);
            channel.target_path = "translation";
        } else if (k == kTailScaleField) {
            channel.target_node = Layout::joint_node(b, KW_PART_TAIL);
            channel.target_path = "scale";
        } else {
            channel.target_node = Layout::joint_node(b, k - 1);
            channel.target_path = "rotation";
        }
    }
}

}  // namespace kodawari
