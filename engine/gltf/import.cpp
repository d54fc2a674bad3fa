// Loading a rigged glTF 2.0 character (SPEC A.7). tinygltf parses the file; everything
// this module later indexes or reads is checked here first, because tinygltf 2.7 leaves
// many of those checks to the caller (accessor ranges, node trees, skins). Every problem
// becomes "<file>: <glTF path>: <what>". Section numbers: glTF 2.0.1 specification.

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "kodawari/gltf/import.hpp"

#include "core/binary_file.hpp"
#include "gltf/import_detail.hpp"

namespace kodawari::gltf::detail {
namespace {

bool finite(const std::vector<double>& values) {
    return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

// TRS of a matrix without shear (§3.5.3): columns are the scaled rotated axes.
void decompose(const glm::mat4& m, animation::Node& node) {
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

Result<void> load_nodes(const Context& ctx, const tinygltf::Model& model, animation::Character& out) {
    const std::size_t n = model.nodes.size();
    out.nodes.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const tinygltf::Node& src = model.nodes[i];
        animation::Node& node = out.nodes[i];
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
            animation::Node& child = out.nodes[static_cast<std::size_t>(c)];
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
        const animation::Node& node = out.nodes[static_cast<std::size_t>(out.order[k])];
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

}  // namespace
}  // namespace kodawari::gltf::detail

namespace kodawari::gltf {

Result<animation::Character> load_character(const std::string& path) {
    namespace fs = std::filesystem;
    using namespace detail;  // the steps of the import, one file each (import_detail.hpp)
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
        animation::Character character;
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
