// `kodawari sketch SCENE --chain CHARACTER/CHAIN --stroke STROKE.json`: the sketching tool
// of SPEC A.6 without a window. The chain takes the stroke's shape, seen from the camera,
// as a new view example for that view direction, or with --key as a keyed example keyed by
// the character's motion or pose at that frame (docs/keyed-examples.md), written back into
// the scene file (which is checked by the loader before and after it is written).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "bake_outputs.hpp"
#include "commands.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/rods/sketch.hpp"
#include "kodawari/scene/scene_edit.hpp"
#include "kodawari/scene/sketch_key.hpp"

namespace kodawari::cli {
namespace {

std::string vec_text(glm::vec3 v) {
    char text[96];
    std::snprintf(text, sizeof(text), "[%.4g, %.4g, %.4g]", static_cast<double>(v.x), static_cast<double>(v.y),
                  static_cast<double>(v.z));
    return text;
}


struct SketchOptions {
    std::optional<std::string> scene;
    std::optional<std::string> chain;
    std::optional<std::string> stroke;
    std::optional<std::uint64_t> frame;
    std::optional<std::string> camera;
    std::optional<std::string> size;
    std::optional<std::string> influence;
    std::optional<std::string> out;
    bool in_place = false;
    bool undo = false;
    std::optional<std::string> key;
    std::optional<std::string> joint;
    std::optional<std::string> measure;
    std::optional<std::string> smoothing;
};

// What --key and its options ask for; none without --key (a view example).
std::optional<SketchKeyOptions> key_options(const SketchOptions& o) {
    if (!o.key) {
        if (o.joint || o.measure || o.smoothing) throw UsageError{"--joint, --measure and --smoothing need --key motion|pose"};
        return std::nullopt;
    }
    SketchKeyOptions k;
    if (*o.key == "motion") {
        k.kind = rods::KeyKind::Motion;
    } else if (*o.key == "pose") {
        k.kind = rods::KeyKind::Pose;
        if (o.measure || o.smoothing) throw UsageError{"--measure and --smoothing need --key motion (a pose key has neither)"};
    } else {
        throw UsageError{"--key: expected motion or pose, got \"" + *o.key + "\""};
    }
    if (o.joint) {
        if (o.joint->empty()) throw UsageError{"--joint: expected a joint name, got \"\""};
        k.joint = *o.joint;
    }
    if (o.measure) {
        if (*o.measure == "speed") {
            k.measure = rods::MotionMeasure::Speed;
        } else if (*o.measure == "acceleration") {
            k.measure = rods::MotionMeasure::Acceleration;
        } else if (*o.measure == "angular_speed") {
            k.measure = rods::MotionMeasure::AngularSpeed;
        } else {
            throw UsageError{"--measure: expected speed, acceleration or angular_speed, got \"" + *o.measure + "\""};
        }
    }
    if (o.smoothing) {
        k.smoothing = parse_real("--smoothing", *o.smoothing);
        if (!(k.smoothing >= 0.0f && k.smoothing <= rods::kMaxSmoothing)) {
            throw UsageError{"--smoothing: expected seconds in [0, 60], got \"" + *o.smoothing + "\""};
        }
    }
    if (o.influence) {
        const float p = parse_real("--influence", *o.influence);
        const bool pose = k.kind == rods::KeyKind::Pose;
        if (!(p > 0.0f && p <= (pose ? 360.0f : 1e4f))) {
            throw UsageError{std::string("--influence: expected ") +
                             (pose ? "degrees in (0, 360]" : "a number in (0, 1e4] in the measure's units") + ", got \"" +
                             *o.influence + "\""};
        }
        k.influence = p;
    }
    return k;
}

// Writes the edited text of the scene at `scene_path` to `out_path`, its relative file
// paths rewritten for `out_path`'s folder (`--out out/B.json` of scenes/A.json still reads
// scenes/characters/...), whose folder is made when missing, as run's --out.
Result<void> write_edit(const std::string& scene_path, const std::string& out_path, const std::string& text) {
    auto moved = move_scene_text(text, scene_path, out_path);
    if (!moved) return moved.error();
    KW_TRY(make_parent_folder(out_path, "--out"));
    return write_scene_text(out_path, moved.value());
}

int cmd_sketch(const SketchOptions& o) {
    const auto& stroke_path = o.stroke;
    const auto& frame_index = o.frame;
    const auto& camera_text = o.camera;
    const auto& size_text = o.size;
    // Not a structured binding: the lambdas below use them (clang < 16 cannot capture one).
    const auto image = image_size(size_text);
    const auto width = image.first, height = image.second;
    const auto& influence_text = o.influence;
    const auto& out_option = o.out;
    const bool undo = o.undo;
    if (!o.scene) throw UsageError{"sketch needs exactly one SCENE file"};
    if (!o.chain) throw UsageError{"sketch needs --chain CHARACTER/CHAIN"};
    if (undo && (stroke_path || camera_text || size_text || influence_text || frame_index || o.key || o.joint ||
                 o.measure || o.smoothing)) {
        throw UsageError{"sketch --undo takes only SCENE, --chain and --out or --in-place"};
    }
    if (!undo && !stroke_path) throw UsageError{"sketch needs --stroke STROKE.json (or --undo)"};
    // An artist's scene is never rewritten by accident: the edit goes to --out, or to the
    // scene itself only when asked with --in-place.
    if (!out_option && !o.in_place) {
        throw UsageError{"sketch writes the edited scene to --out SCENE2.json, or over SCENE with --in-place; "
                         "neither was given (nothing written)"};
    }
    if (out_option && o.in_place) throw UsageError{"--out and --in-place exclude each other: give one"};
    const std::string& scene_path = *o.scene;
    const std::string out_path = out_option.value_or(scene_path);
    // CHARACTER#N/CHAIN, as `run --trace` and `validate` name a chain, picks instance N of
    // the character to draw over; the scene's examples belong to CHARACTER/CHAIN.
    std::string chain_text = *o.chain;
    std::optional<std::uint32_t> wanted_instance;
    if (const auto hash = chain_text.find('#'), slash = chain_text.find('/');
        hash != std::string::npos && slash != std::string::npos && hash < slash) {
        const std::string digits = chain_text.substr(hash + 1, slash - hash - 1);
        if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) {
            throw UsageError{"--chain: expected CHARACTER/CHAIN or CHARACTER#N/CHAIN, got \"" + chain_text + "\""};
        }
        wanted_instance = static_cast<std::uint32_t>(std::stoul(digits));
        chain_text.erase(hash, slash - hash);
    }
    const std::optional<std::string> chain = chain_text;

    auto text = read_text_file(scene_path);
    if (!text) return report(text.error());
    auto scene = load_scene(scene_path);
    if (!scene) return report(scene.error());

    if (undo) {
        auto edit = remove_last_sketch(text.value(), scene_path, *chain);
        if (!edit) return report(edit.error());
        if (auto written = write_edit(scene_path, out_path, edit.value().text); !written) return report(written.error());
        const SceneEdit& e = edit.value();
        std::printf("removed %s example %u \"%s\" of %s%s; wrote %s\n", e.keyed ? "keyed" : "view", e.index, e.name.c_str(),
                    chain->c_str(), e.replaced ? (", putting back \"" + e.replaced_name + "\", which it had replaced").c_str() : "",
                    out_path.c_str());
        return kExitOk;
    }

    const std::optional<SketchKeyOptions> keyed = key_options(o);
    rods::SketchInput input;
    if (influence_text && !keyed) {
        input.influence = parse_real("--influence", *influence_text);
        if (!(input.influence > 0.0f && input.influence <= rods::kMaxInfluence)) {
            throw UsageError{"--influence: expected a number in (0, 1000], got \"" + *influence_text + "\""};
        }
    }

    auto stroke_text = read_text_file(*stroke_path, "the stroke file");
    if (!stroke_text) return report(stroke_text.error());
    auto stroke = parse_stroke(stroke_text.value(), *stroke_path);
    if (!stroke) return report(stroke.error());
    input.stroke = stroke.value();
    // A stroke drawn wholly off the image cannot have been drawn over the view.
    const bool on_image = std::any_of(input.stroke.begin(), input.stroke.end(), [&](const glm::dvec2& p) {
        return p.x >= 0.0 && p.y >= 0.0 && p.x <= width && p.y <= height;
    });
    if (!on_image) {
        return report(make_error(Error::Kind::InvalidInput,
                                 *stroke_path + ": $.points: expected points on the " + std::to_string(width) + "x" +
                                     std::to_string(height) + " image (--size), got none within it"));
    }

    auto rod_scene = build_rod_scene(scene.value());
    if (!rod_scene) return report(rod_scene.error());
    const RodScene& rs = rod_scene.value();
    const std::uint32_t frame = static_cast<std::uint32_t>(frame_index.value_or(0));
    if (frame >= rs.frames) {
        throw UsageError{"--frame: the scene has frames 0 to " + std::to_string(rs.frames - 1) + ", got " +
                         std::to_string(frame)};
    }
    // The chain's first instance shows it (every instance shares the template's examples).
    std::optional<std::uint32_t> instance;
    std::string names;
    for (std::uint32_t t = 0; t < rs.world.templates.size(); ++t) {
        names += (names.empty() ? "\"" : ", \"") + rs.world.templates[t].name + "\"";
        if (rs.world.templates[t].name != *chain) continue;
        std::uint32_t seen = 0;
        for (std::uint32_t c = 0; c < rs.world.chains.size() && !instance; ++c) {
            if (rs.world.chains[c].template_index != t) continue;
            if (seen++ == wanted_instance.value_or(0)) instance = c;
        }
        if (!instance && wanted_instance && seen > 0) {
            throw UsageError{"--chain: " + *o.chain + ": the character has instances #0 to #" + std::to_string(seen - 1)};
        }
        if (!instance) {
            return report(make_error(Error::Kind::InvalidInput, scene_path + ": $.crowds: no instance of the character of " +
                                                                    *chain + ", so it is never seen"));
        }
    }
    if (!instance) {
        return report(make_error(Error::Kind::InvalidInput, scene_path + ": $.characters: no chain \"" + *chain +
                                                                "\" (chains: " + names + ")"));
    }
    const rods::ChainInstance& ci = rs.world.chains[*instance];
    const rods::RodFrame f = rs.frame(frame);
    rods::CameraPose pose = rs.camera_pose(frame);
    if (camera_text) {
        float v[6] = {};
        char extra = 0;
        if (std::sscanf(camera_text->c_str(), "%f,%f,%f,%f,%f,%f%c", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &extra) != 6) {
            throw UsageError{"--camera: expected EYE_X,EYE_Y,EYE_Z,TARGET_X,TARGET_Y,TARGET_Z, got \"" + *camera_text + "\""};
        }
        pose.position = {v[0], v[1], v[2]};
        pose.target = {v[3], v[4], v[5]};
        if (!(glm::length(pose.target - pose.position) > 1e-6f)) throw UsageError{"--camera: the target equals the eye"};
        pose.forward = glm::normalize(pose.target - pose.position);
    }
    input.camera = rods::ImageCamera::from_pose(pose, rs.fov_deg, width, height);
    input.root = f.roots[*instance];
    input.reference = f.reference[ci.character];
    input.lengths = rs.world.templ(ci).basis.lengths;
    auto sketched = rods::sketch_view_example(input);
    if (!sketched) return report(sketched.error());
    const rods::SketchResult& s = sketched.value();
    const std::uint32_t joints = static_cast<std::uint32_t>(s.shape.positions.size());
    const auto print_camera = [&] {
        std::printf("sketch %s at frame %u: camera %s -> %s, %ux%u px, %s\n", chain->c_str(), frame,
                    vec_text(pose.position).c_str(), vec_text(pose.target).c_str(), width, height,
                    pose.projection == rods::Camera::Projection::Perspective ? "perspective" : "orthographic");
    };
    const auto print_stroke = [&] {
        std::printf("stroke moved by (%.1f, %.1f) px to start at the root; %u of %u joints on it, %.0f%% of it used\n",
                    s.stroke_offset.x, s.stroke_offset.y, s.joints_on_stroke, joints, 100.0 * s.stroke_used);
        std::printf("reprojection error %.3g px (joints past the stroke's end: up to %.3g px from it)\n", s.max_error_px,
                    s.max_overrun_px);
    };

    if (keyed) {
        auto key = measure_sketch_key(rs, ci.character, frame, *keyed);
        if (!key) {
            const Error& e = key.error();
            // The joint is the user's word: a usage error naming the option.
            if (keyed->joint.size() && e.message.rfind("joint \"", 0) == 0) throw UsageError{"--joint: " + e.message};
            return report(make_error(e.kind, scene_path + ": " + e.message));
        }
        KeyedSketch k = key.value();
        k.shape = s.shape;
        auto edit = add_keyed_example(text.value(), scene_path, *chain, k);
        if (!edit) return report(edit.error());
        if (auto written = write_edit(scene_path, out_path, edit.value().text); !written) return report(written.error());
        print_camera();
        if (k.kind == rods::KeyKind::Motion) {
            std::printf("motion key: %s %s %.6g %s (magnitude, smoothed over %g s), influence %.6g %s\n", k.joint.c_str(),
                        measure_name(k.measure), static_cast<double>(k.value), measure_unit(k.measure),
                        static_cast<double>(k.smoothing), static_cast<double>(k.influence), measure_unit(k.measure));
        } else {
            const glm::quat n = glm::normalize(k.rotation);
            const auto snap = [](float v) { return std::abs(v) < 5e-7f ? 0.0f : v; };  // as written (scene_edit_keyed.cpp)
            const glm::quat q(snap(n.w), snap(n.x), snap(n.y), snap(n.z));
            std::printf("pose key: %s rotation [%.4g, %.4g, %.4g, %.4g] relative to its parent (a turn of %.1f degrees), "
                        "influence %g degrees\n",
                        k.joint.c_str(), static_cast<double>(q.x), static_cast<double>(q.y), static_cast<double>(q.z),
                        static_cast<double>(q.w), glm::degrees(2.0 * std::acos(std::min(1.0, std::abs(static_cast<double>(q.w))))),
                        static_cast<double>(k.influence));
        }
        print_stroke();
        std::printf("keyed example %u \"%s\" added; wrote %s\n", edit.value().index, edit.value().name.c_str(),
                    out_path.c_str());
        return kExitOk;
    }

    ViewSpec view;
    view.view = s.view;
    view.shape = s.shape;
    auto edit = add_view_example(text.value(), scene_path, *chain, view);
    if (!edit) return report(edit.error());
    if (auto written = write_edit(scene_path, out_path, edit.value().text); !written) return report(written.error());

    print_camera();
    std::printf("view direction %s (reference joint's frame), influence %g\n", vec_text(s.view.direction).c_str(),
                static_cast<double>(s.view.influence));
    print_stroke();
    const SceneEdit& e = edit.value();
    std::printf("view example %u \"%s\" %s; wrote %s\n", e.index, e.name.c_str(),
                e.replaced ? ("replaces \"" + e.replaced_name + "\" (within " + std::to_string(static_cast<int>(kSketchReplaceDeg)) +
                              " degrees; kept in the file, --undo brings it back)").c_str()
                           : "added",
                out_path.c_str());
    return kExitOk;
}

}  // namespace

Command add_sketch(CLI::App& app) {
    auto o = std::make_shared<SketchOptions>();
    CLI::App* c = app.add_subcommand("sketch", "the chain takes the shape of a stroke drawn over the view, as a new view example, "
                                               "or with --key as a keyed example (docs/sketch.md); --undo removes the last "
                                               "one a sketch added");
    add_text(*c, "scene", o->scene, "SCENE", "the scene file to edit");
    add_text(*c, "--chain", o->chain, "CHARACTER/CHAIN",
             "the chain to shape (required); CHARACTER#N/CHAIN, as traces name it, draws over instance N");
    add_text(*c, "--stroke", o->stroke, "STROKE.json", "the stroke, points in image pixels (required unless --undo)");
    add_count(*c, "--frame", o->frame, 0, 1'000'000'000, "the frame whose pose the stroke is drawn over (default: 0)");
    add_text(*c, "--camera", o->camera, "EX,EY,EZ,TX,TY,TZ", "the camera's eye and target in metres (default: the scene's camera)");
    add_size(*c, o->size, "the image the stroke's pixels are in");
    add_text(*c, "--influence", o->influence, "P",
             "the example's influence: a view example's in (0, 1000] (default: 4); with --key motion in the measure's "
             "units (default: a quarter of the measured key), with --key pose in degrees (default: 20)");
    add_text(*c, "--out", o->out, "SCENE2.json", "the scene file to write (this or --in-place is required)");
    add_switch(*c, "--in-place", o->in_place, "write the edit over SCENE itself (default: off; this or --out is required)");
    add_switch(*c, "--undo", o->undo, "remove the last example (view or keyed) a sketch added to the chain");
    add_text(*c, "--key", o->key, "motion|pose",
             "make a keyed example instead of a view example, keyed by the character's motion or a joint's pose at --frame "
             "(docs/keyed-examples.md) (default: a view example)");
    add_text(*c, "--joint", o->joint, "NAME",
             "with --key: the joint (skeleton joint or glTF node) measured (default: the character's reference joint)");
    add_text(*c, "--measure", o->measure, "speed|acceleration|angular_speed",
             "with --key motion: what is measured of the joint (default: speed)");
    add_text(*c, "--smoothing", o->smoothing, "S",
             "with --key motion: the measure's smoothing time constant in s, in [0, 60] (default: 0.25)");
    return {c, [o] { return cmd_sketch(*o); }};
}

}  // namespace kodawari::cli
