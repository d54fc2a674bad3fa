// Humanoid bone maps (issue 18): VRM Animation's VRMC_vrm_animation 1.0 humanoid, a VRM
// model's humanoid (VRMC_vrm 1.0 or VRM 0.x) and name map files. The JSON is read here,
// as in vrm.cpp, because tinygltf keeps extensions loosely typed; every field read is
// checked and problems name the file and the JSON path. See motion.hpp.

#include <algorithm>
#include <array>
#include <cctype>
#include <exception>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/binary_file.hpp"
#include "kodawari/gltf/motion.hpp"

namespace kodawari::gltf {
namespace {

using nlohmann::json;

// VRMC_vrm 1.0 humanoid.md, "List of humanoid bones", row by row.
const std::vector<std::string_view> kBones = {
    "hips", "spine", "chest", "upperChest", "neck",
    "head", "leftEye", "rightEye", "jaw",
    "leftUpperLeg", "leftLowerLeg", "leftFoot", "leftToes",
    "rightUpperLeg", "rightLowerLeg", "rightFoot", "rightToes",
    "leftShoulder", "leftUpperArm", "leftLowerArm", "leftHand",
    "rightShoulder", "rightUpperArm", "rightLowerArm", "rightHand",
    "leftThumbMetacarpal", "leftThumbProximal", "leftThumbDistal",
    "leftIndexProximal", "leftIndexIntermediate", "leftIndexDistal",
    "leftMiddleProximal", "leftMiddleIntermediate", "leftMiddleDistal",
    "leftRingProximal", "leftRingIntermediate", "leftRingDistal",
    "leftLittleProximal", "leftLittleIntermediate", "leftLittleDistal",
    "rightThumbMetacarpal", "rightThumbProximal", "rightThumbDistal",
    "rightIndexProximal", "rightIndexIntermediate", "rightIndexDistal",
    "rightMiddleProximal", "rightMiddleIntermediate", "rightMiddleDistal",
    "rightRingProximal", "rightRingIntermediate", "rightRingDistal",
    "rightLittleProximal", "rightLittleIntermediate", "rightLittleDistal",
};
// The rows marked "Required".
constexpr std::array<std::string_view, 15> kRequired = {
    "hips", "spine", "head", "leftUpperLeg", "leftLowerLeg", "leftFoot", "rightUpperLeg", "rightLowerLeg",
    "rightFoot", "leftUpperArm", "leftLowerArm", "leftHand", "rightUpperArm", "rightLowerArm", "rightHand",
};

std::size_t bone_rank(std::string_view name) {
    return static_cast<std::size_t>(std::find(kBones.begin(), kBones.end(), name) - kBones.begin());
}
bool is_bone(std::string_view name) { return bone_rank(name) < kBones.size(); }

// A member's JSON path: `.key` for plain names, `["key"]` for anything else.
std::string member_path(const std::string& path, const std::string& key) {
    const bool plain = !key.empty() && std::all_of(key.begin(), key.end(), [](unsigned char c) {
        return std::isalnum(c) != 0 || c == '_';
    });
    return plain ? path + "." + key : path + "[" + json(key).dump() + "]";
}

Error invalid(const std::string& file, const std::string& path, const std::string& what) {
    return make_error(Error::Kind::InvalidInput, file + ": " + path + ": " + what);
}

Facing facing_of(const json& extensions) {
    // VRM 0.x models face -Z (UniVRM 0.x); a file with VRMC_vrm is 1.0 whatever else it has.
    if (extensions.is_object() && !extensions.contains("VRMC_vrm") && extensions.contains("VRM")) return Facing::MinusZ;
    return Facing::PlusZ;
}

json parse_extensions(const animation::Character& c) {
    if (c.extensions.empty()) return json::object();
    return json::parse(c.extensions, nullptr, /*allow_exceptions=*/false);
}

// Adds bone `name` on `node` (an integer JSON value at `path`), checked, to `out`.
Result<void> add_bone(const animation::Character& c, HumanoidMap& out, const std::string& name, const json& node, const std::string& path) {
    if (!node.is_number_integer()) return invalid(c.source, path, "expected a node index (an integer)");
    const auto index = node.get<long long>();
    if (index < 0 || static_cast<unsigned long long>(index) >= c.nodes.size()) {
        return invalid(c.source, path, "node " + std::to_string(index) + " does not exist (" + std::to_string(c.nodes.size()) + " nodes)");
    }
    for (const HumanBone& other : out.bones) {
        if (other.node == index) {
            return invalid(c.source, path, "node " + std::to_string(index) + " is already bone \"" + other.name +
                                               "\" (a node is one humanoid bone)");
        }
        if (other.name == name) return invalid(c.source, path, "bone \"" + name + "\" is given twice");
    }
    out.bones.push_back(HumanBone{name, static_cast<int>(index), c.source + ": " + path});
    return {};
}

void sort_bones(HumanoidMap& map) {
    std::stable_sort(map.bones.begin(), map.bones.end(),
                     [](const HumanBone& a, const HumanBone& b) { return bone_rank(a.name) < bone_rank(b.name); });
}

}  // namespace

const std::vector<std::string_view>& humanoid_bone_names() { return kBones; }

bool is_required_humanoid_bone(std::string_view bone) {
    return std::find(kRequired.begin(), kRequired.end(), bone) != kRequired.end();
}

const HumanBone* HumanoidMap::find(std::string_view name) const {
    const auto it = std::find_if(bones.begin(), bones.end(), [&](const HumanBone& b) { return b.name == name; });
    return it == bones.end() ? nullptr : &*it;
}

Result<HumanoidMap> read_vrm_animation_humanoid(const animation::Character& c) {
    try {
        const json ext = parse_extensions(c);
        const std::string root = "$.extensions.VRMC_vrm_animation";
        if (!ext.is_object() || !ext.contains("VRMC_vrm_animation")) {
            return invalid(c.source, root, "missing (not a VRM Animation file; a glTF clip for another skeleton needs a \"map\")");
        }
        const json& vrma = ext["VRMC_vrm_animation"];
        if (!vrma.is_object()) return invalid(c.source, root, "expected an object");
        const auto version = vrma.find("specVersion");
        if (version == vrma.end()) return invalid(c.source, root, "missing \"specVersion\"");
        if (!version->is_string() || (*version != "1.0" && *version != "1.0-draft")) {
            return invalid(c.source, root + ".specVersion", "expected \"1.0\" (or \"1.0-draft\"), got " + version->dump());
        }
        HumanoidMap out;
        out.facing = Facing::PlusZ;  // VRM Animation's model space is VRM 1.0's
        const auto humanoid = vrma.find("humanoid");
        if (humanoid == vrma.end()) {
            return invalid(c.source, root + ".humanoid.humanBones", "missing: a VRM Animation without humanoid bones moves no bone");
        }
        if (!humanoid->is_object()) return invalid(c.source, root + ".humanoid", "expected an object");
        const std::string bones_path = root + ".humanoid.humanBones";
        const auto bones = humanoid->find("humanBones");
        if (bones == humanoid->end()) return invalid(c.source, bones_path, "missing: a VRM Animation without humanoid bones moves no bone");
        if (!bones->is_object()) return invalid(c.source, bones_path, "expected an object {\"<bone>\": {\"node\": <index>}}");
        out.where = c.source + ": " + bones_path;
        for (const auto& [name, bone] : bones->items()) {
            const std::string path = member_path(bones_path, name);
            if (!is_bone(name)) {
                out.warnings.push_back(c.source + ": " + path + ": not a VRM humanoid bone name; ignored");
                continue;
            }
            if (name == "leftEye" || name == "rightEye") {
                out.warnings.push_back(c.source + ": " + path + ": eye bones are not animated (VRM Animation gives them to lookAt); ignored");
                continue;
            }
            if (!bone.is_object()) return invalid(c.source, path, "expected an object {\"node\": <index>}");
            const auto node = bone.find("node");
            if (node == bone.end()) return invalid(c.source, path, "missing \"node\"");
            KW_TRY(add_bone(c, out, name, *node, path + ".node"));
        }
        if (out.bones.empty()) return invalid(c.source, bones_path, "no humanoid bone: a VRM Animation without humanoid bones moves no bone");
        for (const char* unused : {"expressions", "lookAt"}) {
            if (vrma.contains(unused)) {
                out.warnings.push_back(c.source + ": " + root + "." + unused + ": not used (only humanoid bones are retargeted)");
            }
        }
        sort_bones(out);
        return out;
    } catch (const std::exception& e) {
        return invalid(c.source, "$.extensions", e.what());
    }
}

Result<HumanoidMap> read_vrm_humanoid(const animation::Character& c) {
    try {
        const json ext = parse_extensions(c);
        HumanoidMap out;
        out.facing = facing_of(ext);
        if (ext.is_object() && ext.contains("VRMC_vrm")) {
            const std::string root = "$.extensions.VRMC_vrm.humanoid";
            const json& vrm = ext["VRMC_vrm"];
            if (!vrm.is_object() || !vrm.contains("humanoid") || !vrm["humanoid"].is_object()) {
                return invalid(c.source, root, "missing or not an object");
            }
            const json& humanoid = vrm["humanoid"];
            const std::string bones_path = root + ".humanBones";
            if (!humanoid.contains("humanBones") || !humanoid["humanBones"].is_object()) {
                return invalid(c.source, bones_path, "missing or not an object");
            }
            out.where = c.source + ": " + bones_path;
            for (const auto& [name, bone] : humanoid["humanBones"].items()) {
                const std::string path = member_path(bones_path, name);
                if (!is_bone(name)) {
                    out.warnings.push_back(c.source + ": " + path + ": not a VRM humanoid bone name; ignored");
                    continue;
                }
                if (!bone.is_object() || !bone.contains("node")) return invalid(c.source, path, "expected an object {\"node\": <index>}");
                KW_TRY(add_bone(c, out, name, bone["node"], path + ".node"));
            }
        } else if (ext.is_object() && ext.contains("VRM")) {
            const std::string root = "$.extensions.VRM.humanoid";
            const json& vrm = ext["VRM"];
            if (!vrm.is_object() || !vrm.contains("humanoid") || !vrm["humanoid"].is_object()) {
                return invalid(c.source, root, "missing or not an object");
            }
            const std::string bones_path = root + ".humanBones";
            const json& humanoid = vrm["humanoid"];
            if (!humanoid.contains("humanBones") || !humanoid["humanBones"].is_array()) {
                return invalid(c.source, bones_path, "missing or not an array");
            }
            out.where = c.source + ": " + bones_path;
            const json& list = humanoid["humanBones"];
            for (std::size_t i = 0; i < list.size(); ++i) {
                const std::string path = bones_path + "[" + std::to_string(i) + "]";
                const json& bone = list[i];
                if (!bone.is_object() || !bone.contains("bone") || !bone["bone"].is_string() || !bone.contains("node")) {
                    return invalid(c.source, path, "expected an object {\"bone\": <name>, \"node\": <index>}");
                }
                std::string name = bone["bone"].get<std::string>();
                // VRM 0.x thumbs are one bone further out than 1.0's (UniVRM's migration).
                for (const char* side : {"left", "right"}) {
                    const std::string s(side);
                    if (name == s + "ThumbProximal") {
                        name = s + "ThumbMetacarpal";
                    } else if (name == s + "ThumbIntermediate") {
                        name = s + "ThumbProximal";
                    }
                }
                if (!is_bone(name)) {
                    out.warnings.push_back(c.source + ": " + path + ".bone: \"" + name + "\" is not a VRM humanoid bone name; ignored");
                    continue;
                }
                if (bone["node"].is_number_integer() && bone["node"].get<long long>() < 0) continue;  // UniVRM writes -1 for "none"
                KW_TRY(add_bone(c, out, name, bone["node"], path + ".node"));
            }
        } else {
            return invalid(c.source, "$.extensions", "no VRM humanoid (neither VRMC_vrm nor VRM); name its bones with a map file");
        }
        if (out.bones.empty()) return invalid(c.source, out.where.substr(c.source.size() + 2), "no humanoid bone");
        sort_bones(out);
        return out;
    } catch (const std::exception& e) {
        return invalid(c.source, "$.extensions", e.what());
    }
}

Result<HumanoidMap> read_humanoid_name_map(const std::string& map_path, const animation::Character& c) {
    auto bytes = core::read_binary_file(map_path);
    if (!bytes) return bytes.error();
    json doc;
    try {
        doc = json::parse(bytes.value().begin(), bytes.value().end());
    } catch (const std::exception& e) {
        return invalid(map_path, "$", std::string("invalid JSON: ") + e.what());
    }
    if (!doc.is_object()) {
        return invalid(map_path, "$", "expected an object {\"<humanoid bone>\": \"<node name>\", ...}");
    }
    HumanoidMap out;
    out.where = map_path + ": $";
    out.facing = facing_of(parse_extensions(c));
    for (const auto& [bone, value] : doc.items()) {
        const std::string path = member_path("$", bone);
        if (!is_bone(bone)) {
            std::string names;
            for (std::size_t i = 0; i < 5; ++i) names += std::string(kBones[i]) + ", ";
            return invalid(map_path, path, "\"" + bone + "\" is not a VRM humanoid bone name (" + names + "... leftUpperArm, ...)");
        }
        if (!value.is_string()) return invalid(map_path, path, "expected the name of a node of " + c.source);
        const std::string name = value.get<std::string>();
        int found = -1;
        for (std::size_t i = 0; i < c.nodes.size(); ++i) {
            if (c.nodes[i].name != name) continue;
            if (found >= 0) {
                return invalid(map_path, path, "\"" + name + "\" names two nodes of " + c.source + " (" + std::to_string(found) +
                                                   " and " + std::to_string(i) + ")");
            }
            found = static_cast<int>(i);
        }
        if (found < 0) return invalid(map_path, path, "no node of " + c.source + " is called \"" + name + "\"");
        for (const HumanBone& other : out.bones) {
            if (other.node == found) {
                return invalid(map_path, path, "node \"" + name + "\" is already bone \"" + other.name + "\" (a node is one humanoid bone)");
            }
        }
        out.bones.push_back(HumanBone{bone, found, map_path + ": " + path});
    }
    if (out.bones.empty()) return invalid(map_path, "$", "no bone: name the node of at least \"hips\"");
    sort_bones(out);
    return out;
}

}  // namespace kodawari::gltf
