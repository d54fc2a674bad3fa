// A user's rigged bird mapped onto the 7-part rig (issue 14; docs/bird-models.md): which
// bone is which part (name patterns, or a mapping file), each part's axes in its bone's
// frame, and the wing measured from the skinned mesh in its rest pose.

#include "kodawari/gltf/bird_model_import.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kodawari/gltf/import.hpp"

namespace kodawari::gltf {
namespace {

using birds::kPartCount;

// What each part is called by the people who rig birds (Blender's Rigify and the usual
// tutorials, Mixamo-like humanoid names reused for wings, anatomy), most specific first:
// a part takes the bones of its first pattern that any bone matches. The wing parts also
// need a side mark (side() below); body, head and tail must have none.
const std::array<std::vector<std::string>, kPartCount> kPatterns = {{
    {"spine", "body", "pelvis", "hips", "hip", "torso", "chest", "root"},
    {"head", "skull", "neck"},
    {"tail", "pygostyle"},
    {"upperarm", "upper_arm", "upperwing", "upper_wing", "wing1", "wing_1", "humerus", "shoulder", "wing", "arm"},
    {"forearm", "lowerarm", "lower_arm", "lowerwing", "lower_wing", "wing2", "wing_2", "ulna", "radius", "hand", "wrist"},
    {"upperarm", "upper_arm", "upperwing", "upper_wing", "wing1", "wing_1", "humerus", "shoulder", "wing", "arm"},
    {"forearm", "lowerarm", "lower_arm", "lowerwing", "lower_wing", "wing2", "wing_2", "ulna", "radius", "hand", "wrist"},
}};

// The parts in words, for messages.
constexpr std::array<const char*, kPartCount> kPartWords = {"body",       "head",        "tail",       "left upper wing",
                                                            "left lower wing", "right upper wing", "right lower wing"};

enum class Side { None, Left, Right };

std::string lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

// The side a bone's name marks: "wing.L", "wing_l", "wing-L", "L_wing", "l.wing",
// "LeftWing", "wing_left" (Blender's duplicates' ".001" ignored).
Side side(std::string name) {
    name = lower(std::move(name));
    while (name.size() > 4 && name[name.size() - 4] == '.' && std::isdigit(static_cast<unsigned char>(name.back()))) {
        name.resize(name.size() - 4);
    }
    const auto marked = [&](char s, const char* word) {
        if (name.find(word) != std::string::npos) return true;
        for (const char sep : {'.', '_', '-', ' '}) {
            if (name.size() >= 2 && name[name.size() - 1] == s && name[name.size() - 2] == sep) return true;
            if (name.size() >= 2 && name[0] == s && name[1] == sep) return true;
        }
        return false;
    };
    const bool left = marked('l', "left");
    const bool right = marked('r', "right");
    if (left == right) return Side::None;
    return left ? Side::Left : Side::Right;
}

Side part_side(std::size_t part) {
    if (part == KW_PART_LEFT_ARM1 || part == KW_PART_LEFT_ARM2) return Side::Left;
    if (part == KW_PART_RIGHT_ARM1 || part == KW_PART_RIGHT_ARM2) return Side::Right;
    return Side::None;
}

bool is_wing(std::size_t part) { return part_side(part) != Side::None; }

int depth(const animation::Character& c, int node) {
    int d = 0;
    for (int n = c.nodes[static_cast<std::size_t>(node)].parent; n >= 0; n = c.nodes[static_cast<std::size_t>(n)].parent) ++d;
    return d;
}

std::string patterns_text(std::size_t part) {
    std::string out;
    for (const std::string& p : kPatterns[part]) out += (out.empty() ? "" : ", ") + p;
    if (is_wing(part)) out += part_side(part) == Side::Left ? " with a left mark (.L, _l, Left...)" : " with a right mark (.R, _r, Right...)";
    return out;
}

// The bone of `part` by name patterns among the skin's joints not taken yet: the first
// pattern any bone matches, the bone nearest the root among its matches (then the first).
std::optional<int> find_by_pattern(const animation::Character& c, const animation::Skin& skin, std::size_t part, const std::vector<int>& taken) {
    for (const std::string& pattern : kPatterns[part]) {
        std::optional<int> best;
        for (const int joint : skin.joints) {
            if (std::find(taken.begin(), taken.end(), joint) != taken.end()) continue;
            const std::string& name = c.nodes[static_cast<std::size_t>(joint)].name;
            if (lower(name).find(pattern) == std::string::npos || side(name) != part_side(part)) continue;
            if (!best || depth(c, joint) < depth(c, *best)) best = joint;
        }
        if (best) return best;
    }
    return std::nullopt;
}

Error bad(const std::string& where, const std::string& what) { return make_error(Error::Kind::InvalidInput, where + ": " + what); }

// The mapping file's bones: part -> node, -1 for the parts it leaves to the patterns.
Result<std::array<int, kPartCount>> read_map(const std::string& map_path, const std::string& path, const animation::Character& c,
                                            std::size_t skin_index) {
    std::array<int, kPartCount> bones{};
    bones.fill(-1);
    std::ifstream in(map_path, std::ios::binary);
    if (!in) return make_error(Error::Kind::InvalidInput, map_path + ": cannot read the mapping file");
    std::stringstream text;
    text << in.rdbuf();
    const nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, false);
    if (doc.is_discarded()) return bad(map_path, "not JSON (expected an object {\"body\": \"bone name\", ...})");
    if (!doc.is_object()) return bad(map_path, std::string("$: expected an object {\"body\": \"bone name\", ...}, found ") + doc.type_name());
    const animation::Skin& skin = c.skins[skin_index];
    for (const auto& [key, value] : doc.items()) {
        const auto it = std::find(birds::kModelPartKeys.begin(), birds::kModelPartKeys.end(), key);
        if (it == birds::kModelPartKeys.end()) {
            return bad(map_path, "$." + key + ": unknown part (expected body, head, tail, left_upper_wing, left_lower_wing, "
                                              "right_upper_wing or right_lower_wing)");
        }
        if (!value.is_string()) return bad(map_path, "$." + key + ": expected a bone name, found " + value.type_name());
        const std::string name = value.get<std::string>();
        int found = -1;
        for (const int joint : skin.joints) {
            if (c.nodes[static_cast<std::size_t>(joint)].name == name) found = joint;
        }
        if (found < 0) {
            return bad(map_path, "$." + key + ": no bone \"" + name + "\" in " + path + " (skins[" + std::to_string(skin_index) +
                                     "].joints)");
        }
        bones[static_cast<std::size_t>(it - birds::kModelPartKeys.begin())] = found;
    }
    return bones;
}

glm::vec3 position_of(const glm::mat4& m) { return glm::vec3(m[3]); }

}  // namespace

Result<birds::BirdModel> load_bird_model(const std::string& path, const std::string& map_path, float mass) {
    auto loaded = load_character(path);
    if (!loaded) return loaded.error();
    birds::BirdModel model;
    model.source = path;
    model.name = std::filesystem::path(path).stem().string();
    model.character = std::move(loaded).value();
    const animation::Character& c = model.character;
    if (c.skins.empty()) {
        return bad(path, "skins: the file has no skin; a rigged bird needs its bones in one (export it with its armature)");
    }
    // The bird's skin: the first one a mesh uses, else the first.
    std::size_t skin_index = 0;
    for (const animation::Node& node : c.nodes) {
        if (node.mesh >= 0 && node.skin >= 0) {
            skin_index = static_cast<std::size_t>(node.skin);
            break;
        }
    }
    model.skin = static_cast<int>(skin_index);
    const animation::Skin& skin = c.skins[skin_index];
    const std::string skin_path = "skins[" + std::to_string(skin_index) + "].joints";

    // Which bone is which part: the mapping file's, then the name patterns.
    std::array<int, kPartCount> bones{};
    bones.fill(-1);
    if (!map_path.empty()) {
        auto mapped = read_map(map_path, path, c, skin_index);
        if (!mapped) return mapped.error();
        bones = mapped.value();
    }
    model.mapped_by = map_path.empty() ? "name patterns" : map_path;
    for (std::size_t part = 0; part < kPartCount; ++part) {
        if (bones[part] >= 0) continue;
        std::vector<int> taken(bones.begin(), bones.end());
        const auto found = find_by_pattern(c, skin, part, taken);
        if (!found) {
            return bad(path, skin_path + ": no bone for the " + std::string(kPartWords[part]) + " (names tried: " +
                                 patterns_text(part) + "); name it in a mapping file (rig --bird --map MAP.json, " +
                                 "docs/bird-models.md)");
        }
        bones[part] = *found;
    }
    for (std::size_t a = 0; a < kPartCount; ++a) {
        for (std::size_t b = a + 1; b < kPartCount; ++b) {
            if (bones[a] == bones[b]) {
                return bad(map_path.empty() ? path : map_path,
                           std::string(birds::kModelPartKeys[b]) + ": bone \"" + c.nodes[static_cast<std::size_t>(bones[b])].name +
                               "\" is the " + kPartWords[a] + "'s already");
            }
        }
    }
    model.bones = bones;

    // The rest pose and the skinned mesh in it (glTF 2.0 §3.7.3: joint world matrix x
    // inverse bind matrix, weighted), each triangle on the part its weights lean to. A
    // joint that is no part's bone belongs to the nearest part bone above it (feather
    // bones under a forearm are wing).
    const animation::Pose rest = rest_pose(c);
    std::vector<int> part_of_node(c.nodes.size(), -1);
    for (std::size_t n = 0; n < c.nodes.size(); ++n) {
        for (int up = static_cast<int>(n); up >= 0 && part_of_node[n] < 0; up = c.nodes[static_cast<std::size_t>(up)].parent) {
            for (std::size_t part = 0; part < kPartCount; ++part) {
                if (bones[part] == up) part_of_node[n] = static_cast<int>(part);
            }
        }
    }
    std::vector<glm::mat4> joint_matrix(skin.joints.size());
    for (std::size_t j = 0; j < skin.joints.size(); ++j) {
        joint_matrix[j] = rest.world[static_cast<std::size_t>(skin.joints[j])] * skin.inverse_bind_matrices[j];
    }
    struct Triangle {
        std::array<glm::vec3, 3> p;
        int part;
    };
    std::vector<Triangle> triangles;
    int mesh_index = -1;
    for (const animation::Node& node : c.nodes) {
        if (node.mesh < 0 || node.skin != static_cast<int>(skin_index)) continue;
        const animation::Mesh& mesh = c.meshes[static_cast<std::size_t>(node.mesh)];
        for (const animation::Mesh::Triangles& t : mesh.triangles) {
            if (t.joints.empty() || t.indices.empty()) continue;
            if (mesh_index < 0) mesh_index = node.mesh;
            std::vector<glm::vec3> skinned(t.positions.size());
            for (std::size_t v = 0; v < t.positions.size(); ++v) {
                glm::vec4 sum(0.0f);
                for (int k = 0; k < 4; ++k) sum += t.weights[v][k] * (joint_matrix[t.joints[v][k]] * glm::vec4(t.positions[v], 1.0f));
                skinned[v] = glm::vec3(sum);
            }
            for (std::size_t i = 0; i + 2 < t.indices.size(); i += 3) {
                std::array<float, kPartCount> weight{};
                Triangle tri{};
                for (std::size_t k = 0; k < 3; ++k) {
                    const std::uint32_t v = t.indices[i + k];
                    tri.p[k] = skinned[v];
                    for (int w = 0; w < 4; ++w) {
                        const int part = part_of_node[static_cast<std::size_t>(skin.joints[t.joints[v][w]])];
                        if (part >= 0) weight[static_cast<std::size_t>(part)] += t.weights[v][w];
                    }
                }
                tri.part = static_cast<int>(std::max_element(weight.begin(), weight.end()) - weight.begin());
                if (weight[static_cast<std::size_t>(tri.part)] <= 0.0f) tri.part = -1;
                triangles.push_back(tri);
            }
        }
    }
    if (triangles.empty()) {
        return bad(path, "meshes: no mesh is skinned to skins[" + std::to_string(skin_index) +
                             "] (a bird needs its triangles on its bones: JOINTS_0 and WEIGHTS_0)");
    }
    const std::string mesh_path = "meshes[" + std::to_string(mesh_index) + "]";

    // The wing: span tip to tip along the bird's left (+X), area projected onto its
    // horizontal plane (XZ). A closed wing's upper and lower faces both project onto the
    // planform, an open one's only one side: the larger of the two sums is the planform.
    float left_low = std::numeric_limits<float>::max(), left_high = -left_low;
    float right_low = left_low, right_high = -left_low;
    double up = 0.0, down = 0.0;
    float z_low = left_low, z_high = -left_low;
    for (const Triangle& t : triangles) {
        for (const glm::vec3& p : t.p) {
            z_low = std::min(z_low, p.z);
            z_high = std::max(z_high, p.z);
        }
        if (t.part < 0 || !is_wing(static_cast<std::size_t>(t.part))) continue;
        const bool left = part_side(static_cast<std::size_t>(t.part)) == Side::Left;
        for (const glm::vec3& p : t.p) {
            float& low = left ? left_low : right_low;
            float& high = left ? left_high : right_high;
            low = std::min(low, p.x);
            high = std::max(high, p.x);
        }
        const glm::vec3 a = t.p[1] - t.p[0], b = t.p[2] - t.p[0];
        const double projected = 0.5 * static_cast<double>(a.z * b.x - a.x * b.z);  // (a x b).y / 2
        (projected > 0 ? up : down) += std::abs(projected);
    }
    const float left_reach = left_high - left_low, right_reach = right_high - right_low;
    // 1 mm: below that a wing is a modelling accident, not a wing.
    constexpr float kMinReach = 1e-3f;
    if (!(left_reach > kMinReach) || !(right_reach > kMinReach)) {
        return bad(path, mesh_path + ": the " + std::string(!(left_reach > kMinReach) ? "left" : "right") +
                             " wing spans 0 m along the bird's left (+X): no triangle skinned mainly to its bones (" +
                             c.nodes[static_cast<std::size_t>(bones[!(left_reach > kMinReach) ? KW_PART_LEFT_ARM1 : KW_PART_RIGHT_ARM1])].name +
                             " and below) reaches out from the body");
    }
    const float span = std::max(left_high, right_high) - std::min(left_low, right_low);
    const auto area = static_cast<float>(std::max(up, down));
    if (!(area > 0.0f)) return bad(path, mesh_path + ": the wings have no area seen from above (Y)");
    model.measure.wingspan = span;
    model.measure.wing_area = area;
    model.measure.mass = mass;
    model.measure.body_length = z_high - z_low;
    model.mean_chord = area / span;
    model.flight = birds::derive_flight(model.measure);
    model.measure.mass = model.flight.mass;

    // The parts' axes. A rig part's frame in the model: the body's, head's and tail's are
    // the model's own (+Z forward, +Y up, +X left); a wing part's has its +X along the
    // span (toward the child wing bone; for a lower wing without one, along the axis of
    // its frame that the upper wing reaches along in its own; on the right wing the span
    // points along -X), +Z the body's forward made orthogonal to it, +Y = Z x X. C takes
    // the bone's frame to the part's: P^T R.
    std::array<glm::mat3, kPartCount> frames{};
    for (std::size_t part = 0; part < kPartCount; ++part) {
        frames[part] = glm::mat3(1.0f);
        if (!is_wing(part)) continue;
        const auto bone_world = [&](std::size_t p) { return rest.world[static_cast<std::size_t>(bones[p])]; };
        const glm::vec3 root = position_of(bone_world(part));
        glm::vec3 reach(0.0f);
        const bool upper = part == KW_PART_LEFT_ARM1 || part == KW_PART_RIGHT_ARM1;
        const std::vector<int>& children = c.nodes[static_cast<std::size_t>(bones[part])].children;
        if (upper) {
            reach = position_of(bone_world(part + 1)) - root;
        } else if (!children.empty()) {
            reach = position_of(rest.world[static_cast<std::size_t>(children.front())]) - root;  // a tip bone
        } else {
            // A last bone has nothing to point at; rigs keep one axis along a chain
            // (Blender's +Y), so the lower wing reaches along the axis of its own frame
            // that the upper wing reaches along in its.
            const glm::vec3 along = glm::inverse(glm::mat3(bone_world(part - 1))) *
                                    (position_of(bone_world(part)) - position_of(bone_world(part - 1)));
            reach = glm::mat3(bone_world(part)) * along;
        }
        // Reach projected on the horizontal plane, so a wing modelled drooping still
        // flaps about the body's forward axis; a bone reaching nowhere keeps the rig's.
        glm::vec3 x(reach.x, 0.0f, reach.z);
        if (part_side(part) == Side::Right) x = -x;
        x = glm::length(x) > 1e-6f ? glm::normalize(x) : glm::vec3(1.0f, 0.0f, 0.0f);
        glm::vec3 z = glm::vec3(0.0f, 0.0f, 1.0f) - x.z * x;
        z = glm::length(z) > 1e-6f ? glm::normalize(z) : glm::vec3(0.0f, 0.0f, 1.0f);
        frames[part] = glm::mat3(x, glm::cross(z, x), z);
    }
    for (std::size_t part = 0; part < kPartCount; ++part) {
        const glm::quat bone = animation::rigid_part(rest.world[static_cast<std::size_t>(bones[part])]).rotation;
        model.axes[part] = glm::normalize(glm::quat_cast(glm::transpose(frames[part])) * bone);
        const int parent = birds::kPartParents[part];
        if (parent < 0) continue;
        const glm::vec3 d = position_of(rest.world[static_cast<std::size_t>(bones[part])]) -
                            position_of(rest.world[static_cast<std::size_t>(bones[static_cast<std::size_t>(parent)])]);
        const glm::vec3 local = glm::transpose(frames[static_cast<std::size_t>(parent)]) * d;
        model.offsets[part] = {local.x, local.y, local.z};
    }
    return model;
}

std::string bird_scene_json(const BirdSceneOptions& o) {
    using Json = nlohmann::ordered_json;
    Json flock;
    flock["name"] = o.name;
    flock["model"] = o.model_file;
    if (!o.map_file.empty()) flock["map"] = o.map_file;
    flock["count"] = 20;
    flock["seed"] = 1;
    flock["speed_jitter"] = 0.05;
    flock["frequency_jitter"] = 0.1;
    // Rounded to centimetres: the file is read by people, and the scale is a search's result.
    const auto scaled = [&](double metres) { return std::round(metres * double{o.route_scale} * 100.0) / 100.0; };
    flock["generated_route"] = {
        {"seed", 3}, {"segments", 8}, {"center", {0, 40, 0}}, {"extent", {scaled(45), 8, scaled(45)}}, {"loop", true}};
    flock["formation"] = {{"spread", {10, 4, 10}}, {"route_variants", 4}, {"jitter", 2}, {"trail", 2}};
    Json scene;
    scene["format"] = "kodawari-scene";
    scene["version"] = 1;
    scene["name"] = o.name;
    scene["fps"] = 60;
    scene["duration"] = 10;
    scene["camera"] = {{"position", {0, 60, -scaled(150)}}, {"target", {0, 40, 0}}, {"fov_deg", 55}};
    scene["flocks"] = Json::array({flock});
    return scene.dump(2) + "\n";
}

}  // namespace kodawari::gltf
