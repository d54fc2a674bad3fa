// The skins of a glTF model: joints and inverse bind matrices, checked invertible.

#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "gltf/import_detail.hpp"

namespace kodawari::gltf::detail {
namespace {

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

}  // namespace

Result<void> load_skins(const Context& ctx, const tinygltf::Model& model, animation::Character& out) {
    for (std::size_t s = 0; s < model.skins.size(); ++s) {
        const tinygltf::Skin& src = model.skins[s];
        const std::string path = at("$.skins", s);
        animation::Skin skin;
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

}  // namespace kodawari::gltf::detail
