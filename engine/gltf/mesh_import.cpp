// The meshes of a glTF model as display geometry (positions, normals, joints, weights, indices).

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "gltf/import_detail.hpp"

namespace kodawari::gltf::detail {

// Mesh geometry for display (§3.7.2): TRIANGLES primitives with POSITION, and NORMAL,
// JOINTS_0 and WEIGHTS_0 where given.
Result<void> load_meshes(const Context& ctx, const tinygltf::Model& model, animation::Character& out) {
    for (std::size_t m = 0; m < model.meshes.size(); ++m) {
        const tinygltf::Mesh& src = model.meshes[m];
        animation::Mesh mesh{src.name, src.primitives.size(), {}};
        for (std::size_t k = 0; k < src.primitives.size(); ++k) {
            const tinygltf::Primitive& prim = src.primitives[k];
            const std::string path = at(at("$.meshes", m) + ".primitives", k);
            if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES) continue;
            const auto attribute = [&](const char* name) {
                const auto it = prim.attributes.find(name);
                return it == prim.attributes.end() ? -1 : it->second;
            };
            if (attribute("POSITION") < 0) return ctx.invalid(path + ".attributes", "a triangle primitive needs POSITION");
            animation::Mesh::Triangles t;
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

}  // namespace kodawari::gltf::detail
