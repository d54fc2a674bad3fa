// Retargeting a humanoid clip onto another skeleton (issue 18). The equations and their
// references are in docs/motions.md; in short, with world rotations R (scale removed) in
// each skeleton's model space, rest values marked 0 and A the turn between the two
// models' facings:
//   G_b(t)      = R_src,b(t) R_src,b0^-1               the source bone's world delta
//   R_tgt,b(t)  = A G_b(t) A^-1 R_tgt,b0               the target bone's world rotation
//   q_tgt,b(t)  = R_tgt,parent(t)^-1 R_tgt,b(t)        its local rotation (glTF parent)
// which for bones whose parents both skeletons map is VRMC_vrm_animation's
// q_tgt = P_tgt0^-1 (P_src0 q_src W_src0^-1) P_tgt0 L_tgt0; the hips' world position is
//   p_tgt(t)    = p_tgt0 + k A (p_src(t) - p_src0),   k = leg height ratio.
// Everything is computed in double from the float inputs, in a fixed order, so the same
// inputs give the same bits.

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <system_error>
#include <new>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "kodawari/gltf/import.hpp"
#include "kodawari/gltf/motion.hpp"

namespace kodawari::gltf {
namespace {

Error invalid(const std::string& where, const std::string& what) {
    return make_error(Error::Kind::InvalidInput, where + ": " + what);
}

// The rotation of a world matrix's columns, scale divided out (as rigid_part()).
glm::dquat rotation_of(const glm::dmat4& world) {
    glm::dmat3 r(world);
    for (int c = 0; c < 3; ++c) {
        const double len = glm::length(r[c]);
        if (len > 0.0) r[c] /= len;
    }
    if (glm::determinant(r) < 0.0) r[0] = -r[0];
    return glm::normalize(glm::quat_cast(r));
}

glm::dmat4 local_matrix(const animation::Node& node, const glm::dvec3& t, const glm::dquat& r, const glm::dvec3& s) {
    if (node.matrix) return glm::dmat4(*node.matrix);
    return glm::translate(glm::dmat4(1.0), t) * glm::mat4_cast(r) * glm::scale(glm::dmat4(1.0), s);
}

// Local TRS of every node: the rest pose, then clip `clip` at `time` when clip is given.
struct Locals {
    std::vector<glm::dvec3> t;
    std::vector<glm::dquat> r;
    std::vector<glm::dvec3> s;
};

Locals locals_of(const animation::Character& c, const animation::Animation* clip, float time) {
    Locals l;
    for (const animation::Node& n : c.nodes) {
        l.t.emplace_back(n.translation);
        l.r.emplace_back(glm::dquat(n.rotation));
        l.s.emplace_back(n.scale);
    }
    if (clip == nullptr) return l;
    for (const animation::Channel& ch : clip->channels) {
        const glm::vec4 v = sample(clip->samplers[ch.sampler], ch.path, time);
        const auto i = static_cast<std::size_t>(ch.node);
        switch (ch.path) {
            case animation::Path::Translation: l.t[i] = glm::dvec3(glm::vec3(v)); break;
            case animation::Path::Rotation: l.r[i] = glm::normalize(glm::dquat(v.w, v.x, v.y, v.z)); break;
            case animation::Path::Scale: l.s[i] = glm::dvec3(glm::vec3(v)); break;
        }
    }
    return l;
}

std::vector<glm::dmat4> world_of(const animation::Character& c, const Locals& l) {
    std::vector<glm::dmat4> world(c.nodes.size(), glm::dmat4(1.0));
    for (const int index : c.order) {
        const auto i = static_cast<std::size_t>(index);
        const glm::dmat4 local = local_matrix(c.nodes[i], l.t[i], l.r[i], l.s[i]);
        world[i] = c.nodes[i].parent >= 0 ? world[static_cast<std::size_t>(c.nodes[i].parent)] * local : local;
    }
    return world;
}

// Leg length as VRMC_vrm_animation's "how_to_transform_human_pose" suggests (the hips'
// height), measured above the feet so that it does not depend on where the model's
// origin is: hips y minus the mean y of the mapped feet (the origin's 0 without feet).
double leg_height(const HumanoidMap& map, const std::vector<glm::dmat4>& rest) {
    const HumanBone* hips = map.find("hips");
    if (hips == nullptr) return 0.0;
    double ground = 0.0;
    int feet = 0;
    for (const char* foot : {"leftFoot", "rightFoot"}) {
        if (const HumanBone* b = map.find(foot)) {
            ground += rest[static_cast<std::size_t>(b->node)][3].y;
            ++feet;
        }
    }
    if (feet > 0) ground /= feet;
    return rest[static_cast<std::size_t>(hips->node)][3].y - ground;
}

std::string list_names(const HumanoidMap& map) {
    std::string out;
    for (std::size_t i = 0; i < map.bones.size(); ++i) {
        if (i == 6) return out + ", ... (" + std::to_string(map.bones.size()) + " bones)";
        out += (i == 0 ? "" : ", ") + map.bones[i].name;
    }
    return out.empty() ? "none" : out;
}

// The file part of a "<file>: <JSON path>" location.
std::string file_of(const std::string& where) { return where.substr(0, where.find(": ")); }

}  // namespace

Result<Retargeted> retarget(const animation::Character& source, std::size_t clip_index, const HumanoidMap& source_map,
                            const animation::Character& target, const HumanoidMap& target_map, const std::string& name) {
    try {
        if (clip_index >= source.animations.size()) {
            return invalid(source.source + ": $.animations", "animation " + std::to_string(clip_index) + " does not exist");
        }
        const animation::Animation& clip = source.animations[clip_index];
        Retargeted out;

        // The bones both skeletons have, in humanoid order.
        struct Pair {
            const HumanBone* src;
            const HumanBone* tgt;
        };
        std::vector<Pair> common;
        for (const HumanBone& b : source_map.bones) {
            if (const HumanBone* t = target_map.find(b.name)) common.push_back({&b, t});
        }
        if (common.empty()) {
            return invalid(source_map.where, "no humanoid bone in common with " + target_map.where + " (the source has " +
                                                 list_names(source_map) + "; the target has " + list_names(target_map) + ")");
        }

        // What the clip moves. VRMC_vrm_animation: humanoid bones are rotated, only the hips
        // translated, nothing scaled; other channels are ignored with a warning.
        const std::size_t ns = source.nodes.size();
        std::vector<bool> own_channel(ns, false);
        std::vector<bool> rotated(ns, false);
        std::vector<bool> any_channel(ns, false);
        for (std::size_t c = 0; c < clip.channels.size(); ++c) {
            const animation::Channel& ch = clip.channels[c];
            const auto n = static_cast<std::size_t>(ch.node);
            any_channel[n] = true;
            if (ch.path == animation::Path::Rotation) rotated[n] = true;
            const auto bone = std::find_if(source_map.bones.begin(), source_map.bones.end(),
                                           [&](const HumanBone& b) { return b.node == ch.node; });
            if (bone == source_map.bones.end()) continue;
            own_channel[n] = true;
            const std::string where = source.source + ": $.animations[" + std::to_string(clip_index) + "].channels[" +
                                      std::to_string(c) + "]";
            if (ch.path == animation::Path::Scale) {
                out.warnings.push_back(where + ": scales bone " + bone->name + "; ignored (humanoid bones are not scaled)");
            } else if (ch.path == animation::Path::Translation && bone->name != "hips") {
                out.warnings.push_back(where + ": translates bone " + bone->name + "; ignored (only the hips move)");
            }
        }
        // A bone's world rotation changes when it or an ancestor is rotated; the hips'
        // position when they are translated or anything above them moves.
        std::vector<bool> turns(ns, false);
        std::vector<bool> above_moves(ns, false);  // a strict ancestor has a channel
        for (const int index : source.order) {
            const auto i = static_cast<std::size_t>(index);
            const int p = source.nodes[i].parent;
            const bool parent_turns = p >= 0 && turns[static_cast<std::size_t>(p)];
            turns[i] = rotated[i] || parent_turns;
            above_moves[i] = p >= 0 && (above_moves[static_cast<std::size_t>(p)] || any_channel[static_cast<std::size_t>(p)]);
        }

        // Bones the clip animates that the target lacks: required ones are an error
        // (the motion cannot be shown), optional ones are skipped.
        for (const HumanBone& b : source_map.bones) {
            if (!own_channel[static_cast<std::size_t>(b.node)] || target_map.find(b.name) != nullptr) continue;
            if (is_required_humanoid_bone(b.name)) {
                return invalid(b.where, "the clip animates " + b.name + ", a required VRM humanoid bone, and " +
                                            target_map.where + " has no " + b.name);
            }
            out.warnings.push_back(b.where + ": the clip animates " + b.name + ", which " + file_of(target_map.where) +
                                   " does not have (an optional bone); skipped");
        }

        // The key times: every key of the clip, gaps longer than kMotionKeyGap split evenly.
        std::set<float> keys;
        for (const animation::Channel& ch : clip.channels) {
            const std::vector<float>& t = clip.samplers[ch.sampler].times;
            keys.insert(t.begin(), t.end());
        }
        if (keys.empty()) return invalid(source.source + ": $.animations[" + std::to_string(clip_index) + "]", "no channel moves a node");
        // How many keys the split makes, counted in double before any is made: key times
        // are any finite floats, and far from zero a float step exceeds kMotionKeyGap, so
        // a loop that counted the keys it placed could spin without placing one.
        // 1e-3: a gap that float rounding made a hair longer than kMotionKeyGap is not split.
        const auto pieces_of = [](double gap) { return std::ceil(gap / kMotionKeyGap - 1e-3); };
        double needed = static_cast<double>(keys.size());
        for (auto it = keys.begin(); std::next(it) != keys.end(); ++it) {
            needed += std::max(pieces_of(static_cast<double>(*std::next(it)) - static_cast<double>(*it)) - 1.0, 0.0);
        }
        if (needed > static_cast<double>(kMaxMotionKeys)) {
            return invalid(source.source + ": $.animations[" + std::to_string(clip_index) + "]",
                           "the clip needs more than " + std::to_string(kMaxMotionKeys) + " keys per channel (one at least every " +
                               std::to_string(kMotionKeyGap) + " s from " + std::to_string(*keys.begin()) + " to " +
                               std::to_string(*keys.rbegin()) + " s); cut it shorter");
        }
        std::vector<float> times;
        for (auto it = keys.begin(); it != keys.end(); ++it) {
            const auto next = std::next(it);
            times.push_back(*it);
            if (next == keys.end()) break;
            const double a = *it;
            const double gap = static_cast<double>(*next) - a;
            const auto pieces = static_cast<std::size_t>(pieces_of(gap));  // <= kMaxMotionKeys (counted above)
            for (std::size_t k = 1; k < pieces; ++k) {
                const auto t = static_cast<float>(a + gap * static_cast<double>(k) / static_cast<double>(pieces));
                if (t > times.back() && t < *next) times.push_back(t);
            }
        }

        // The channels to write.
        std::vector<Pair> rotations;
        for (const Pair& p : common) {
            if (turns[static_cast<std::size_t>(p.src->node)]) rotations.push_back(p);
        }
        const HumanBone* src_hips = source_map.find("hips");
        const HumanBone* tgt_hips = target_map.find("hips");
        const bool hips_move = src_hips != nullptr && tgt_hips != nullptr &&
                               (above_moves[static_cast<std::size_t>(src_hips->node)] ||
                                std::any_of(clip.channels.begin(), clip.channels.end(), [&](const animation::Channel& ch) {
                                    return ch.node == src_hips->node && ch.path == animation::Path::Translation;
                                }));
        if (rotations.empty() && !hips_move) {
            return invalid(source_map.where, "the clip moves none of the bones " + file_of(target_map.where) + " has");
        }
        for (const Pair& p : rotations) {
            if (target.nodes[static_cast<std::size_t>(p.tgt->node)].matrix) {
                return invalid(p.tgt->where, "node " + std::to_string(p.tgt->node) +
                                                 " has a matrix; an animated node must use TRS (glTF 2.0 §3.5.3)");
            }
        }
        if (hips_move && target.nodes[static_cast<std::size_t>(tgt_hips->node)].matrix) {
            return invalid(tgt_hips->where, "node " + std::to_string(tgt_hips->node) +
                                                " has a matrix; an animated node must use TRS (glTF 2.0 §3.5.3)");
        }

        // Rest frames, facing and leg ratio.
        const std::vector<glm::dmat4> src_rest = world_of(source, locals_of(source, nullptr, 0.0f));
        const Locals tgt_rest_locals = locals_of(target, nullptr, 0.0f);
        const std::vector<glm::dmat4> tgt_rest = world_of(target, tgt_rest_locals);
        // A: the half turn about +Y between a model facing +Z and one facing -Z.
        const glm::dquat facing = source_map.facing == target_map.facing ? glm::dquat(1.0, 0.0, 0.0, 0.0)
                                                                         : glm::dquat(0.0, 0.0, 1.0, 0.0);
        if (hips_move) {
            const double hs = leg_height(source_map, src_rest);
            const double ht = leg_height(target_map, tgt_rest);
            if (hs > 1e-6 && ht > 1e-6) {
                out.leg_ratio = static_cast<float>(ht / hs);
            } else {
                out.warnings.push_back(source_map.where + ": the hips are not above the feet in the rest pose of the source or "
                                                          "the target; the hips' displacement is not scaled");
            }
        }
        const double k = out.leg_ratio;

        // Per-node target work, parents first.
        const std::size_t nt = target.nodes.size();
        std::vector<int> rotation_of_node(nt, -1);  // index into `rotations`
        for (std::size_t i = 0; i < rotations.size(); ++i) rotation_of_node[static_cast<std::size_t>(rotations[i].tgt->node)] = static_cast<int>(i);
        std::vector<glm::dquat> src_rest_rotation(rotations.size());
        std::vector<glm::dquat> tgt_rest_rotation(rotations.size());
        for (std::size_t i = 0; i < rotations.size(); ++i) {
            src_rest_rotation[i] = rotation_of(src_rest[static_cast<std::size_t>(rotations[i].src->node)]);
            tgt_rest_rotation[i] = rotation_of(tgt_rest[static_cast<std::size_t>(rotations[i].tgt->node)]);
        }

        std::vector<std::vector<glm::vec4>> rotation_keys(rotations.size());
        std::vector<glm::vec4> hips_keys;
        for (const float t : times) {
            const std::vector<glm::dmat4> src_world = world_of(source, locals_of(source, &clip, t));
            Locals l = tgt_rest_locals;
            std::vector<glm::dmat4> world(nt, glm::dmat4(1.0));
            for (const int index : target.order) {
                const auto i = static_cast<std::size_t>(index);
                const animation::Node& node = target.nodes[i];
                const glm::dmat4 parent = node.parent >= 0 ? world[static_cast<std::size_t>(node.parent)] : glm::dmat4(1.0);
                if (const int r = rotation_of_node[i]; r >= 0) {
                    const auto ri = static_cast<std::size_t>(r);
                    const glm::dquat delta = rotation_of(src_world[static_cast<std::size_t>(rotations[ri].src->node)]) *
                                             glm::conjugate(src_rest_rotation[ri]);
                    const glm::dquat wanted = facing * delta * glm::conjugate(facing) * tgt_rest_rotation[ri];
                    l.r[i] = glm::normalize(glm::conjugate(rotation_of(parent)) * wanted);
                }
                if (hips_move && index == tgt_hips->node) {
                    const glm::dvec3 shift = glm::dvec3(src_world[static_cast<std::size_t>(src_hips->node)][3]) -
                                             glm::dvec3(src_rest[static_cast<std::size_t>(src_hips->node)][3]);
                    const glm::dvec3 wanted = glm::dvec3(tgt_rest[i][3]) + k * (facing * shift);
                    l.t[i] = glm::dvec3(glm::inverse(parent) * glm::dvec4(wanted, 1.0));
                    hips_keys.emplace_back(glm::vec3(l.t[i]), 0.0f);
                }
                world[i] = parent * local_matrix(node, l.t[i], l.r[i], l.s[i]);
                if (const int r = rotation_of_node[i]; r >= 0) {
                    std::vector<glm::vec4>& keys_r = rotation_keys[static_cast<std::size_t>(r)];
                    glm::vec4 q(static_cast<float>(l.r[i].x), static_cast<float>(l.r[i].y), static_cast<float>(l.r[i].z),
                                static_cast<float>(l.r[i].w));
                    // One sign throughout, so that each key is the shorter arc from the one before.
                    if (!keys_r.empty() && glm::dot(keys_r.back(), q) < 0.0f) q = -q;
                    keys_r.push_back(q);
                }
            }
        }

        animation::Animation& a = out.animation;
        a.name = name;
        const auto add = [&](int node, animation::Path path, std::vector<glm::vec4> values) {
            animation::Sampler s;
            s.times = times;
            s.values = std::move(values);
            s.interpolation = animation::Interpolation::Linear;
            a.channels.push_back(animation::Channel{node, path, a.samplers.size()});
            a.samplers.push_back(std::move(s));
        };
        if (hips_move) add(tgt_hips->node, animation::Path::Translation, std::move(hips_keys));
        for (std::size_t i = 0; i < rotations.size(); ++i) add(rotations[i].tgt->node, animation::Path::Rotation, std::move(rotation_keys[i]));
        a.start = times.front();
        a.end = times.back();
        out.bones = rotations.size();
        out.keys = times.size();
        return out;
    } catch (const std::bad_alloc&) {
        return invalid(source.source, "out of memory while retargeting");
    }
}

Result<Retargeted> load_motion(const MotionRequest& request, const animation::Character& target, MotionKey* key) {
    const auto at = [&](MotionKey k) {
        if (key != nullptr) *key = k;
    };
    // A file the request names that does not exist is the request's mistake (bad input),
    // not a failure to read.
    const std::pair<const std::string*, MotionKey> files[] = {
        {&request.file, MotionKey::File}, {&request.map, MotionKey::Map}, {&request.target_map, MotionKey::TargetMap}};
    for (const auto& [file, which] : files) {
        std::error_code ec;
        if (!file->empty() && !std::filesystem::exists(*file, ec)) {
            at(which);
            return make_error(Error::Kind::InvalidInput, *file + ": no such file");
        }
    }
    at(MotionKey::File);
    auto loaded = load_character(request.file);
    if (!loaded) return loaded.error();
    const animation::Character& source = loaded.value();

    HumanoidMap source_map;
    if (!request.map.empty()) {
        at(MotionKey::Map);
        auto map = read_humanoid_name_map(request.map, source);
        if (!map) return map.error();
        source_map = std::move(map).value();
    } else {
        const nlohmann::json ext = nlohmann::json::parse(source.extensions.empty() ? std::string("{}") : source.extensions,
                                                         nullptr, /*allow_exceptions=*/false);
        const bool vrma = ext.is_object() && ext.contains("VRMC_vrm_animation");
        auto map = vrma ? read_vrm_animation_humanoid(source) : read_vrm_humanoid(source);
        if (!map) {
            if (vrma) return map.error();
            return invalid(source.source + ": $.extensions.VRMC_vrm_animation",
                           "missing: not a VRM Animation, and the file has no VRM humanoid either; give a map file naming "
                           "its skeleton's humanoid bones (\"map\", --motion-map)");
        }
        source_map = std::move(map).value();
    }

    std::size_t clip = 0;
    if (source.animations.empty()) return invalid(source.source + ": $.animations", "no animation");
    if (!request.clip.empty()) {
        at(MotionKey::Clip);
        const auto it = std::find_if(source.animations.begin(), source.animations.end(),
                                     [&](const animation::Animation& a) { return a.name == request.clip; });
        if (it == source.animations.end()) {
            std::string names;
            for (const animation::Animation& a : source.animations) names += (names.empty() ? "\"" : ", \"") + a.name + "\"";
            return invalid(source.source + ": $.animations", "no animation is called \"" + request.clip + "\" (" + names + ")");
        }
        clip = static_cast<std::size_t>(it - source.animations.begin());
    }

    at(MotionKey::TargetMap);
    auto target_map = request.target_map.empty() ? read_vrm_humanoid(target) : read_humanoid_name_map(request.target_map, target);
    if (!target_map) {
        if (!request.target_map.empty()) return target_map.error();
        return make_error(Error::Kind::InvalidInput, target_map.error().message +
                                                         " (a character that is not a VRM avatar needs \"target_map\")");
    }

    at(MotionKey::File);
    auto result = retarget(source, clip, source_map, target, target_map.value(), request.name);
    if (!result) return result.error();
    Retargeted out = std::move(result).value();
    std::vector<std::string> warnings = source_map.warnings;
    warnings.insert(warnings.end(), target_map.value().warnings.begin(), target_map.value().warnings.end());
    warnings.insert(warnings.end(), out.warnings.begin(), out.warnings.end());
    out.warnings = std::move(warnings);
    return out;
}

}  // namespace kodawari::gltf
