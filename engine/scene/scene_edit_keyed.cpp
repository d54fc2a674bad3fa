// Adding a sketched keyed example to a scene's text (scene_edit.hpp, add_keyed_example):
// the element the keyed loader (keyed_loader.cpp) reads back, spliced in as views are, and
// the limits of docs/keyed-examples.md K.1 checked here so that the message names the
// chain and what was expected rather than the loader's JSON path in the edited text.

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <utility>

#include "kodawari/rods/world.hpp"
#include "kodawari/scene/scene_edit.hpp"
#include "kodawari/scene/sketch_key.hpp"
#include "scene/scene_edit_text.hpp"

namespace kodawari {
namespace {

using namespace scene_edit_detail;

// The keyed loader's bounds (keyed_loader.cpp): motion keys and influences up to 1e4 in
// the measure's units, pose influences up to 360 degrees.
constexpr double kMaxMotionKey = 1e4;
constexpr double kMaxPoseInfluenceDeg = 360.0;

std::string keyed_text(const KeyedSketch& k, const std::string& name, const std::string& indent) {
    const Json name_json = name;
    const Json joint_json = k.joint;
    std::string out = "{\"name\": " + name_json.dump();
    if (k.kind == rods::KeyKind::Motion) {
        out += std::string(", \"key\": \"motion\", \"joint\": ") + joint_json.dump() + ", \"measure\": \"" +
               measure_name(k.measure) + "\", \"frame\": \"magnitude\", \"value\": " + num(k.value) +
               ", \"influence\": " + num(k.influence) + ", \"smoothing\": " + num(k.smoothing);
    } else {
        // Normalized, so that 6 digits stay within the loader's 1e-3 of unit length;
        // float noise under the sixth digit (a pitch's y and z of 1e-9) written as 0.
        const glm::quat q = glm::normalize(k.rotation);
        const auto c = [](float v) { return num(std::abs(v) < 5e-7f ? 0.0 : static_cast<double>(v)); };
        out += ", \"key\": \"pose\", \"pose\": [{\"joint\": " + joint_json.dump() + ", \"rotation\": [" + c(q.x) + ", " +
               c(q.y) + ", " + c(q.z) + ", " + c(q.w) + "]}], \"influence\": " + num(k.influence);
    }
    return out + ",\n" + indent + " " + shape_text(k.shape, indent) + "}";
}

// The example as the keyed loader would take it back; the caller's numbers, so the message
// names the argument rather than a JSON path.
Result<void> check_keyed(const std::string& path, const std::string& chain, const KeyedSketch& k) {
    const std::string what = path + ": the keyed sketch for chain \"" + chain + "\": ";
    const auto bad = [&](const std::string& m) { return make_error(Error::Kind::InvalidInput, what + m); };
    if (k.joint.empty()) return bad("joint: expected a joint name, got \"\"");
    const double influence = static_cast<double>(k.influence);
    if (k.kind == rods::KeyKind::Motion) {
        const double value = static_cast<double>(k.value);
        if (!(value >= 0.0 && value <= kMaxMotionKey)) {
            return bad("value: expected a number in [0, " + num(kMaxMotionKey) + "], got " + num(value));
        }
        if (!(influence > 0.0 && influence <= kMaxMotionKey)) {
            return bad("influence: expected a number in (0, " + num(kMaxMotionKey) + "] (the measure's units), got " +
                       num(influence));
        }
        if (!(k.smoothing >= 0.0f && k.smoothing <= rods::kMaxSmoothing)) {
            return bad("smoothing: expected a number in [0, " + num(rods::kMaxSmoothing) + "] s, got " + num(k.smoothing));
        }
    } else {
        if (!(influence > 0.0 && influence <= kMaxPoseInfluenceDeg)) {
            return bad("influence: expected a number in (0, " + num(kMaxPoseInfluenceDeg) + "] degrees, got " +
                       num(influence));
        }
        const float length = glm::length(k.rotation);
        if (!(std::isfinite(length) && length > 1e-6f)) return bad("rotation: expected a finite non-zero quaternion");
    }
    return check_shape(k.shape, bad);
}

// The key sources (joint name, is a pose source) the chain's keyed examples read (K.1): a
// joint read as motion and as pose counts twice, as the loader counts it.
std::set<std::pair<std::string, bool>> key_sources(const Json& keyed, const std::string& reference_joint) {
    std::set<std::pair<std::string, bool>> out;
    for (const Json& e : keyed) {
        if (!e.is_object() || !e.contains("key") || !e["key"].is_string()) continue;
        if (e["key"] == "motion") {
            const bool named = e.contains("joint") && e["joint"].is_string();
            out.insert({named ? e["joint"].get<std::string>() : reference_joint, false});
        } else if (e.contains("pose") && e["pose"].is_array()) {
            for (const Json& p : e["pose"]) {
                if (p.is_object() && p.contains("joint") && p["joint"].is_string()) {
                    out.insert({p["joint"].get<std::string>(), true});
                }
            }
        }
    }
    return out;
}

}  // namespace

Result<SceneEdit> add_keyed_example(const std::string& text, const std::string& path, const std::string& chain,
                                    const KeyedSketch& keyed) {
    KW_TRY(check_keyed(path, chain, keyed));
    auto found = find_chain(text, path, chain);
    if (!found) return found.error();
    const ChainPlace& place = found.value();
    const std::size_t views = place.views.member ? place.chain["views"].size() : 0;
    const Json examples = place.keyed.member ? place.chain["keyed"] : Json::array();
    const std::string at = place.json_path + ".keyed";
    const std::string who = "chain \"" + chain + "\"";
    // K.1's limits, before the text is touched.
    if (examples.size() >= rods::kMaxKeyedExamples) {
        return fail(path, at,
                    who + " already has " + std::to_string(examples.size()) + " keyed examples, the most a chain may have (" +
                        std::to_string(rods::kMaxKeyedExamples) + "); remove one to sketch another");
    }
    if (views + examples.size() >= rods::kMaxViewExamples) {
        return fail(path, at,
                    who + " already has " + std::to_string(views) + " view examples and " + std::to_string(examples.size()) +
                        " keyed examples, the most a chain may have (" + std::to_string(rods::kMaxViewExamples) +
                        " in all); remove one to sketch another");
    }
    auto sources = key_sources(examples, keyed.reference_joint);
    sources.insert({keyed.joint, keyed.kind == rods::KeyKind::Pose});
    if (sources.size() > rods::kMaxKeySources) {
        return fail(path, at,
                    who + ": a " + (keyed.kind == rods::KeyKind::Pose ? "pose" : "motion") + " key of joint \"" +
                        keyed.joint + "\" would make its keyed examples read " + std::to_string(sources.size()) +
                        " key sources; expected at most " + std::to_string(rods::kMaxKeySources) +
                        " (a joint read as motion or as pose counts once each); key a joint they read already");
    }
    SceneEdit edit;
    edit.name = "sketch " + std::to_string(highest_sketch(place.chain) + 1);
    edit.index = static_cast<std::uint32_t>(examples.size());
    edit.keyed = true;
    edit.text = append_element(text, place, place.keyed, "keyed",
                               [&](const std::string& indent) { return keyed_text(keyed, edit.name, indent); });
    return edit;
}

}  // namespace kodawari
