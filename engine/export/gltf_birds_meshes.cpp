// The wing types' assets in the bird glTF export (gltf_birds.cpp): per wing type its
// material, one skinned mesh of its 7 parts and the skin's inverse bind matrices, shared
// by every bird of the type.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "birds/bird_meshes.hpp"
#include "export/gltf_birds_writer.hpp"

namespace kodawari {
namespace {

using namespace gltf;

/// Where each part's joint sits in the bind pose (the rest offsets summed up the chain,
/// no rotation): the parts' meshes are built in their joints' frames.
std::array<Vec3, birds::kPartCount> bind_positions(birds::WingType type) {
    const auto offsets = birds::part_offsets(type);
    std::array<Vec3, birds::kPartCount> at{};
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        const int parent = birds::kPartParents[part];
        for (std::size_t i = 0; i < 3; ++i) {
            at[part][i] = offsets[part][i] + (parent < 0 ? 0.0f : at[static_cast<std::size_t>(parent)][i]);
        }
    }
    return at;
}

}  // namespace

/// Adds the material, the skinned mesh and the inverse bind matrices of one wing type.
/// The 7 part meshes are merged into one primitive in the bind pose; JOINTS_0 names each
/// vertex's part (the skin lists the joints in part order) with weight 1, so the parts
/// stay rigid as before.
WingTypeAssets add_wing_type(tinygltf::Model& model, BufferWriter& writer, birds::WingType type) {
    const std::size_t type_index = static_cast<std::size_t>(type);
    const std::string type_name(birds::wing_type_spec(type).name);

    tinygltf::Material material;
    material.name = type_name;
    material.pbrMetallicRoughness.baseColorFactor.assign(birds::kBirdColours[type_index].begin(),
                                                        birds::kBirdColours[type_index].end());
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 0.8;
    model.materials.push_back(std::move(material));
    const int material_index = static_cast<int>(model.materials.size() - 1);

    const auto parts = birds::bird_part_meshes(type);
    const auto bind = bind_positions(type);
    MeshData merged;
    std::vector<std::array<std::uint8_t, 4>> joints;
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        const auto first = static_cast<std::uint16_t>(merged.positions.size());
        for (const Vec3& p : parts[part].positions) {
            merged.positions.push_back({p[0] + bind[part][0], p[1] + bind[part][1], p[2] + bind[part][2]});
            joints.push_back({static_cast<std::uint8_t>(part), 0, 0, 0});
        }
        merged.normals.insert(merged.normals.end(), parts[part].normals.begin(), parts[part].normals.end());
        for (const std::uint16_t i : parts[part].indices) merged.indices.push_back(static_cast<std::uint16_t>(first + i));
    }
    WingTypeAssets assets;
    assets.mesh = add_mesh(model, writer, merged, material_index, type_name);
    tinygltf::Primitive& primitive = model.meshes.back().primitives[0];
    const std::size_t vertices = merged.positions.size();
    const int joint_view = add_buffer_view(model, writer.append(joints.data(), vertices * 4), vertices * 4, kArrayBuffer);
    primitive.attributes["JOINTS_0"] =
        add_accessor(model, joint_view, 0, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, vertices, TINYGLTF_TYPE_VEC4);
    std::vector<std::array<float, 4>> weights(vertices, {1.0f, 0.0f, 0.0f, 0.0f});
    const int weight_view = add_buffer_view(model, writer.append(weights.data(), vertices * 16), vertices * 16, kArrayBuffer);
    primitive.attributes["WEIGHTS_0"] =
        add_accessor(model, weight_view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, vertices, TINYGLTF_TYPE_VEC4);

    // A joint's bind matrix is the translation to its bind position; its inverse (column
    // major, glTF 2.0 §3.7.3.2) the translation back.
    std::vector<float> inverse_bind(16 * birds::kPartCount, 0.0f);
    for (std::size_t part = 0; part < birds::kPartCount; ++part) {
        float* m = inverse_bind.data() + 16 * part;
        m[0] = m[5] = m[10] = m[15] = 1.0f;
        m[12] = -bind[part][0];
        m[13] = -bind[part][1];
        m[14] = -bind[part][2];
    }
    const std::size_t ibm_bytes = inverse_bind.size() * sizeof(float);
    const int ibm_view = add_buffer_view(model, writer.append(inverse_bind.data(), ibm_bytes), ibm_bytes, 0);
    assets.inverse_bind = add_accessor(model, ibm_view, 0, TINYGLTF_COMPONENT_TYPE_FLOAT, birds::kPartCount, TINYGLTF_TYPE_MAT4);
    assets.offsets = birds::part_offsets(type);
    return assets;
}

}  // namespace kodawari
