// What the user does in the viewer: frames, cameras, picking and sketching a chain's view
// example (SPEC A.6) or keyed example (docs/keyed-examples.md), undo and save of the scene
// text, backend switches.
#include "viewer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "kodawari/domains/chains.hpp"
#include "kodawari/rods/sketch.hpp"
#include "kodawari/domains/scene_draw.hpp"
#include "kodawari/scene/scene_edit.hpp"
#include "kodawari/scene/sketch_key.hpp"

namespace kodawari::cli {

namespace {
constexpr double kPickRadiusPx = 30.0;
}  // namespace

std::string number(float value) {
    char text[32];
    std::snprintf(text, sizeof(text), "%g", static_cast<double>(value));
    return text;
}

rods::ImageCamera Viewer::image_camera() const {
    if (!follow_scene) return camera.image(width, height);
    const Scene& scene = sim->scene();
    const float fps = scene.fps > 0.0f ? scene.fps : 60.0f;
    const rods::CameraPose pose = rods::camera_pose(scene.camera.motion, static_cast<float>(current()) / fps);
    return rods::ImageCamera::from_pose(pose, scene.camera.fov_deg, width, height);
}

render::CameraView Viewer::view() const {
    return follow_scene ? kodawari::scene_camera(sim->scene(), current()) : camera.view();
}

std::optional<rods::Camera> Viewer::rod_camera() const {
    if (follow_scene) return std::nullopt;
    return camera.image(width, height).view_camera();
}

glm::dvec2 Viewer::to_image(double x, double y) const {
    int ww = 1, wh = 1;
    glfwGetWindowSize(window, &ww, &wh);
    return {x * width / std::max(ww, 1), y * height / std::max(wh, 1)};
}

void Viewer::say(std::string line) {
    message = std::move(line);
    std::printf("kodawari: %s\n", message.c_str());
    std::fflush(stdout);
}

void Viewer::scripted_drag(glm::dvec2 a, glm::dvec2 b) {
    if (!sketch_mode) {
        say("drag ignored: not in sketch mode (S)");
        return;
    }
    pick(a);
    stroke.clear();
    if (!picked) return;
    for (int i = 0; i <= 16; ++i) stroke.push_back(glm::mix(a, b, i / 16.0));
    apply_sketch();
}

void Viewer::fail(Error e) {
    if (!failure) failure = std::move(e);
    quit = true;
}

void Viewer::seek(std::uint32_t f) {
    // The frames simulated from now on take their view from the camera shown.
    set_view_camera(*sim, rod_camera());
    if (auto r = sim->seek(f); !r) fail(r.error());
}

bool Viewer::rebuild(const std::string& scene_text, std::optional<BackendKind> backend) {
    auto scene = parse_scene(scene_text, scene_path);
    if (!scene) {
        say("cannot rebuild the scene: " + scene.error().message);
        return false;
    }
    BackendChoice next_choice = choice;
    next_choice.backend = backend;
    auto next = make_simulation(std::move(scene).value(), next_choice, std::nullopt);
    if (!next) {
        say("backend " + std::string(backend ? backend_name(*backend) : "auto") + ": " + next.error().message);
        return false;
    }
    const std::uint32_t at = current();
    sim = std::move(next).value();
    choice = next_choice;
    picked.reset();  // chain indices may differ in the new scene
    if (auto r = sim->show_on(*renderer); !r) {
        fail(r.error());
        return false;
    }
    seek(at);
    return true;
}

void Viewer::pick(glm::dvec2 at) {
    picked.reset();
    if (!rod_scene(*sim)) return;
    if (auto r = read_chains(*sim, snapshot); !r) {
        fail(r.error());
        return;
    }
    const rods::ImageCamera cam = image_camera();
    const rods::RodWorld& w = rod_scene(*sim)->world;
    double best = kPickRadiusPx;
    for (std::uint32_t c = 0; c < w.chains.size(); ++c) {
        const auto& ci = w.chains[c];
        for (std::uint32_t j = 0; j < w.templ(ci).basis.lengths.size() + 1; ++j) {
            const glm::dvec3 p = rods::project_to_pixels(cam, glm::dvec3(snapshot.positions[ci.joint_begin + j]));
            if (p.z <= 0.0) continue;
            const double d = glm::length(glm::dvec2(p) - at);
            if (d < best) {
                best = d;
                picked = c;
            }
        }
    }
    say(picked ? "picked " + w.templ(w.chains[*picked]).name : "no chain within 30 px");
}

void Viewer::apply_sketch() {
    if (!picked || stroke.size() < 2) return;
    const rods::RodWorld& w = rod_scene(*sim)->world;
    const rods::ChainInstance& ci = w.chains[*picked];
    const std::string name = w.templ(ci).name;
    rods::SketchInput input;
    input.camera = image_camera();
    auto kinematic = host_chain_input(*sim);
    if (!kinematic) {
        say("sketch failed: " + kinematic.error().message);
        return;
    }
    input.root = kinematic.value()->roots[*picked];
    input.reference = kinematic.value()->reference[ci.character];
    input.lengths = w.templ(ci).basis.lengths;
    input.stroke = stroke;
    input.influence = influence;
    stroke.clear();
    auto result = rods::sketch_view_example(input);
    if (!result) {
        say("sketch failed: " + result.error().message);
        return;
    }
    if (sketch_kind != SketchKind::View) {
        apply_keyed_sketch(name, ci.character, result.value().shape);
        return;
    }
    ViewSpec view;
    view.view = result.value().view;
    view.shape = result.value().shape;
    auto edit = add_view_example(text, scene_path, name, view);
    if (!edit) {
        say("sketch failed: " + edit.error().message);
        return;
    }
    if (!take_sketch(edit.value().text, name)) return;
    say("sketch " + name + ": view example \"" + edit.value().name + "\" " +
        (edit.value().replaced ? "replaces \"" + edit.value().replaced_name + "\"" : "added") + ", influence " +
        number(influence) + ", " + std::to_string(result.value().joints_on_stroke) +
        " joints on the stroke (unsaved: W saves)");
}

bool Viewer::take_sketch(const std::string& edited, const std::string& chain) {
    if (!rebuild(edited, choice.backend)) return false;
    text = edited;
    dirty = true;
    sketched.push_back(chain);
    return true;
}

void Viewer::apply_keyed_sketch(const std::string& name, std::uint32_t character, const rods::ChainShape& shape) {
    // The command's engine code (cmd_sketch.cpp), with its defaults: the reference joint,
    // speed smoothed as the scene format does, the default influences.
    SketchKeyOptions options;
    options.kind = sketch_kind == SketchKind::Pose ? rods::KeyKind::Pose : rods::KeyKind::Motion;
    auto key = measure_sketch_key(*rod_scene(*sim), character, current(), options);
    if (!key) {
        say("sketch failed: " + key.error().message);
        return;
    }
    KeyedSketch k = std::move(key).value();
    k.shape = shape;
    auto edit = add_keyed_example(text, scene_path, name, k);
    if (!edit) {
        say("sketch failed: " + edit.error().message);
        return;
    }
    if (!take_sketch(edit.value().text, name)) return;
    const std::string what = k.kind == rods::KeyKind::Motion
                                 ? "motion example \"" + edit.value().name + "\" added, " + k.joint + " " +
                                       measure_name(k.measure) + " " + number(k.value) + " " + measure_unit(k.measure) +
                                       ", influence " + number(k.influence)
                                 : "pose example \"" + edit.value().name + "\" added, " + k.joint + " as now, influence " +
                                       number(k.influence) + " degrees";
    say("sketch " + name + ": " + what + " (unsaved: W saves)");
}

std::string Viewer::sketch_status() const {
    switch (sketch_kind) {
        case SketchKind::View: return "influence " + number(influence);
        case SketchKind::Motion: return "motion example";
        case SketchKind::Pose: return "pose example";
    }
    return "";
}

void Viewer::undo() {
    if (sketched.empty()) {
        say("nothing to undo");
        return;
    }
    auto edit = remove_last_sketch(text, scene_path, sketched.back());
    if (!edit) {
        say("undo failed: " + edit.error().message);
        return;
    }
    if (!rebuild(edit.value().text, choice.backend)) return;
    say("undo " + sketched.back() + ": removed \"" + edit.value().name + "\"");
    sketched.pop_back();
    text = edit.value().text;
    dirty = true;
}

void Viewer::save() {
    if (auto r = write_scene_text(scene_path, text); !r) {
        say("save failed: " + r.error().message);
        return;
    }
    dirty = false;
    say("saved " + scene_path);
}

void Viewer::key(int key, int mods) {
    const std::uint32_t last = sim->frame_count() - 1;
    const std::uint32_t second = static_cast<std::uint32_t>(std::lround(sim->scene().fps));
    const std::uint32_t now = current();
    switch (key) {
        case GLFW_KEY_ESCAPE:
        case GLFW_KEY_Q: quit = true; break;
        case GLFW_KEY_SPACE: playing = !playing; break;
        case GLFW_KEY_RIGHT:
            if (!playing) seek(std::min(now + 1, last));
            break;
        case GLFW_KEY_LEFT:
            if (!playing && now > 0) seek(now - 1);
            break;
        case GLFW_KEY_HOME: seek(0); break;
        case GLFW_KEY_RIGHT_BRACKET: seek(std::min(now + second, last)); break;
        case GLFW_KEY_LEFT_BRACKET: seek(now > second ? now - second : 0); break;
        case GLFW_KEY_1: (void)rebuild(text, BackendKind::CpuReference); break;
        case GLFW_KEY_2: (void)rebuild(text, BackendKind::Cpu); break;
        case GLFW_KEY_3: (void)rebuild(text, BackendKind::Vulkan); break;
        case GLFW_KEY_S:
            if (mods & GLFW_MOD_CONTROL) {
                save();
            } else {
                sketch_mode = !sketch_mode;
                if (sketch_mode) playing = false;  // sketch over a still frame
                stroke.clear();
            }
            break;
        case GLFW_KEY_W: save(); break;
        case GLFW_KEY_K:
            sketch_kind = sketch_kind == SketchKind::View     ? SketchKind::Motion
                          : sketch_kind == SketchKind::Motion ? SketchKind::Pose
                                                              : SketchKind::View;
            say("the next sketch makes a " + std::string(sketch_kind == SketchKind::View     ? "view example"
                                                         : sketch_kind == SketchKind::Motion ? "motion example (keyed by the "
                                                                                               "reference joint's speed)"
                                                                                             : "pose example (keyed by the "
                                                                                               "reference joint's pose)"));
            break;
        case GLFW_KEY_C:
            follow_scene = !follow_scene;
            say(follow_scene ? "camera: the scene's (its motion and projection drive the view-dependent shapes)"
                             : "camera: orbit");
            break;
        case GLFW_KEY_O:
            camera.orthographic = !camera.orthographic;
            say(camera.orthographic ? "orbit camera: orthographic" : "orbit camera: perspective");
            break;
        case GLFW_KEY_U: undo(); break;
        case GLFW_KEY_L:
            if (!rod_scene(*sim)) {
                say("no characters: no levels of detail to show");
                break;
            }
            show_lod = !show_lod;
            say(show_lod ? "levels of detail shown (green full, amber posed, blue hidden)" : "levels of detail not shown");
            break;
        case GLFW_KEY_EQUAL:
        case GLFW_KEY_KP_ADD: influence = std::min(influence * 1.25f, 1000.0f); break;
        case GLFW_KEY_MINUS:
        case GLFW_KEY_KP_SUBTRACT: influence = std::max(influence / 1.25f, 0.1f); break;
        case GLFW_KEY_P:
        case GLFW_KEY_F12: screenshot_now = true; break;
        default: break;
    }
}

void Viewer::mouse_button(int button, int action, int mods) {
    const bool down = action == GLFW_PRESS;
    // Where the pointer was when the button went down: the last motion event before it.
    // glfwGetCursorPos asks the X server where the pointer is now, which after a fast
    // drag handled in one poll is the end of the drag (the orbit would add up to nothing
    // and a sketch would pick at the stroke's end); it serves before any motion event.
    if (!cursor_seen) glfwGetCursorPos(window, &last_x, &last_y);
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
        left = down;
        if (sketch_mode) {
            if (down) {
                pick(to_image(last_x, last_y));
                stroke.clear();
                if (picked) stroke.push_back(to_image(last_x, last_y));
            } else {
                apply_sketch();
            }
        } else if (mods & GLFW_MOD_SHIFT) {
            middle = down;  // shift + left drag pans
            left = false;
        }
    }
    if (button == GLFW_MOUSE_BUTTON_MIDDLE) middle = down;
    if (!down) left = middle = false;
}

void Viewer::cursor(double x, double y) {
    if (!cursor_seen) {
        cursor_seen = true;
        last_x = x;
        last_y = y;
    }
    const double dx = x - last_x, dy = y - last_y;
    last_x = x;
    last_y = y;
    if (sketch_mode) {
        if (left && picked) stroke.push_back(to_image(x, y));
        return;
    }
    if (left) {
        orbit(dx, dy);
    } else if (middle) {
        take_camera();
        const render::CameraBasis b = render::camera_basis(camera.view());
        const float px = camera.distance * 2.0f * std::tan(0.5f * glm::radians(camera.fov_deg)) / static_cast<float>(height);
        camera.target += px * (-static_cast<float>(dx) * b.right + static_cast<float>(dy) * b.up);
    }
}

void Viewer::orbit(double dx, double dy) {
    take_camera();
    camera.yaw -= static_cast<float>(dx) * 0.01f;
    camera.pitch = std::clamp(camera.pitch + static_cast<float>(dy) * 0.01f, -1.55f, 1.55f);
}

void Viewer::scroll(double dy) {
    take_camera();
    camera.distance = std::clamp(camera.distance * std::pow(0.9f, static_cast<float>(dy)), 0.01f, 1e4f);
}

void Viewer::take_camera() {
    if (!follow_scene) return;
    follow_scene = false;
    const float fps = sim->scene().fps > 0.0f ? sim->scene().fps : 60.0f;
    camera = OrbitCamera::from(sim->scene(), static_cast<float>(current()) / fps);
    say("camera: orbit, from the scene camera's pose");
}

std::optional<int> key_by_name(const std::string& name) {
    static const std::pair<const char*, int> kNames[] = {
        {"space", GLFW_KEY_SPACE}, {"right", GLFW_KEY_RIGHT}, {"left", GLFW_KEY_LEFT},   {"home", GLFW_KEY_HOME},
        {"[", GLFW_KEY_LEFT_BRACKET}, {"]", GLFW_KEY_RIGHT_BRACKET}, {"1", GLFW_KEY_1},  {"2", GLFW_KEY_2},
        {"3", GLFW_KEY_3},         {"s", GLFW_KEY_S},         {"k", GLFW_KEY_K},         {"w", GLFW_KEY_W},         {"u", GLFW_KEY_U},
        {"c", GLFW_KEY_C},         {"o", GLFW_KEY_O},         {"l", GLFW_KEY_L},
        {"+", GLFW_KEY_EQUAL},     {"-", GLFW_KEY_MINUS},     {"p", GLFW_KEY_P},         {"q", GLFW_KEY_Q},
        {"escape", GLFW_KEY_ESCAPE}};
    for (const auto& [n, k] : kNames) {
        if (name == n) return k;
    }
    return std::nullopt;
}

}  // namespace kodawari::cli
