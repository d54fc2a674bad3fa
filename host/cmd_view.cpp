// `kodawari view SCENE`: the interactive viewer (issue 5). A GLFW window presented with
// Vulkan: each frame is simulated as `render` does (rod backend + crowd animator, bird
// backend), drawn by the renderer and blitted into the window's swapchain image
// (Renderer::present). The simulation runs on the renderer's device: the chains, colliders,
// birds and rigged characters' skinned meshes are drawn from the vulkan backends' own
// buffers, and the rigged characters' rod input is written from their poses there
// (CrowdAnimator::write_inputs_on), so nothing is read back per frame (the end line and
// the status line say how much was). Read back: a rigged crowd's frame 0 (the rod
// backend's load() takes it on the host), and on demand the picked chain and the sketched
// frame's input while sketching.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <stb/stb_easy_font.h>

#include "commands.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/render/scene_draw.hpp"
#include "kodawari/rod_scene.hpp"
#include "kodawari/rods/kinematics.hpp"
#include "kodawari/rods/sketch.hpp"
#include "kodawari/scene_edit.hpp"

namespace kodawari::cli {
namespace {

constexpr render::Rgba8 kStrokeColor{250, 220, 40};
constexpr render::Rgba8 kPickedColor{40, 200, 250};
constexpr render::Rgba8 kTextColor{255, 255, 255};
constexpr render::Rgba8 kTextBackColor{20, 24, 32};
constexpr double kPickRadiusPx = 30.0;

std::string number(float value) {
    char text[32];
    std::snprintf(text, sizeof(text), "%g", static_cast<double>(value));
    return text;
}

// An orbit camera around a target: yaw about +Y, pitch above the horizon, distance.
struct OrbitCamera {
    glm::vec3 target{0.0f};
    float yaw = 0.0f, pitch = 0.0f, distance = 3.0f, fov_deg = 50.0f;
    bool orthographic = false;  // as tall as the perspective frustum at the target (rods::ImageCamera)

    // The scene camera at `time` (s), orbiting its target (scene_camera() looks 1 m along
    // forward instead, which would make a tiny orbit), with its projection; a camera whose
    // target is its position orbits a point 10 m ahead.
    static OrbitCamera from(const Scene& scene, float time = 0.0f) {
        const rods::CameraPose pose = rods::camera_pose(scene.camera.motion, time);
        OrbitCamera c;
        c.orthographic = pose.projection == rods::Camera::Projection::Orthographic;
        c.fov_deg = scene.camera.fov_deg;
        c.target = glm::length(pose.target - pose.position) > 1e-3f ? pose.target : pose.position + 10.0f * pose.forward;
        const glm::vec3 offset = pose.position - c.target;
        c.distance = std::max(glm::length(offset), 1e-3f);
        c.pitch = std::asin(std::clamp(offset.y / c.distance, -1.0f, 1.0f));
        c.yaw = std::atan2(offset.x, offset.z);
        return c;
    }
    [[nodiscard]] glm::vec3 position() const {
        return target + distance * glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
    }
    [[nodiscard]] render::CameraView view() const {
        render::CameraView v;
        v.position = position();
        v.target = target;
        v.fov_deg = fov_deg;
        // Near 1% of the distance within [0.01, 1] m, as scene_camera; far at least 1 km, so
        // that zooming in on one character keeps the rest of a crowd in view.
        v.near = std::clamp(0.01f * distance, 0.01f, 1.0f);
        v.far = std::max(1000.0f * v.near, 1000.0f);
        v.orthographic = orthographic;
        v.ortho_height = 2.0f * distance * std::tan(0.5f * glm::radians(fov_deg));
        return v;
    }
    [[nodiscard]] rods::ImageCamera image(std::uint32_t w, std::uint32_t h) const {
        rods::ImageCamera c;
        c.projection = orthographic ? rods::Camera::Projection::Orthographic : rods::Camera::Projection::Perspective;
        c.position = position();
        c.target = target;
        c.fov_deg = fov_deg;
        c.width = w;
        c.height = h;
        return c;
    }
};

struct Viewer {
    std::string scene_path;
    std::string text;  // the scene file's text with the sketches so far (saved by W / Ctrl+S)
    bool dirty = false;
    std::unique_ptr<Simulation> sim;
    BackendChoice choice;  // the backend 1/2/3 chose last (none: auto)
    OrbitCamera camera;
    std::uint32_t width = 0, height = 0;  // the renderer's image
    GLFWwindow* window = nullptr;
    bool playing = true;
    bool quit = false;
    bool screenshot_now = false;
    render::Renderer* renderer = nullptr;
    // Mouse.
    bool left = false, middle = false;
    double last_x = 0.0, last_y = 0.0;
    bool cursor_seen = false;  // a motion event has set last_x, last_y
    // Sketching.
    bool sketch_mode = false;
    std::optional<std::uint32_t> picked;  // chain instance
    std::vector<glm::dvec2> stroke;       // image pixels
    float influence = 4.0f;
    std::vector<std::string> sketched;  // chain names, for undo
    std::string message;                // the last sketch/save outcome, shown on the status line
    std::optional<Error> failure;       // a simulation error ends the loop
    ChainSnapshot snapshot;             // the chains read back for picking and sketching

    bool follow_scene = false;  // C: the scene's camera (its motion and projection) instead of the orbit camera

    // The camera of the current frame: the orbit camera, or the scene's at that frame.
    [[nodiscard]] rods::ImageCamera image_camera() const {
        if (!follow_scene) return camera.image(width, height);
        const Scene& scene = sim->scene();
        const float fps = scene.fps > 0.0f ? scene.fps : 60.0f;
        const rods::CameraPose pose = rods::camera_pose(scene.camera.motion, static_cast<float>(current()) / fps);
        return rods::ImageCamera::from_pose(pose, scene.camera.fov_deg, width, height);
    }
    [[nodiscard]] render::CameraView view() const {
        return follow_scene ? render::scene_camera(sim->scene(), current()) : camera.view();
    }
    // What drives the view-dependent shapes of the frames simulated next: the orbit
    // camera, or (none) the scene's camera at each frame, as `run` and `render` have it.
    [[nodiscard]] std::optional<rods::Camera> rod_camera() const {
        if (follow_scene) return std::nullopt;
        return camera.image(width, height).view_camera();
    }

    // Window coordinates to image pixels (the window may have been resized).
    [[nodiscard]] glm::dvec2 to_image(double x, double y) const {
        int ww = 1, wh = 1;
        glfwGetWindowSize(window, &ww, &wh);
        return {x * width / std::max(ww, 1), y * height / std::max(wh, 1)};
    }

    // A sketch / undo / save outcome: on the status line and on stdout (scripts read it).
    void say(std::string line) {
        message = std::move(line);
        std::printf("kodawari: %s\n", message.c_str());
        std::fflush(stdout);
    }

    // A scripted stroke (--keys drag:X1:Y1:X2:Y2, image pixels): press at the start (picks
    // the chain), a straight drag in 16 steps, release (sketches), as the mouse would.
    void scripted_drag(glm::dvec2 a, glm::dvec2 b) {
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

    void fail(Error e) {
        if (!failure) failure = std::move(e);
        quit = true;
    }

    // The frame shown: the one simulated last.
    [[nodiscard]] std::uint32_t current() const { return sim->frame().value_or(0); }

    void seek(std::uint32_t f) {
        // The frames simulated from now on take their view from the camera shown.
        sim->set_view_camera(rod_camera());
        if (auto r = sim->seek(f); !r) fail(r.error());
    }

    // A new simulation of `scene_text` at the current frame (a sketch, an undo, a backend
    // switch): re-simulated from frame 0, the simplest way to rebuild every backend's state.
    // On failure (a backend that cannot open here) the old simulation stays and the status
    // line says why.
    [[nodiscard]] bool rebuild(const std::string& scene_text, std::optional<BackendKind> backend) {
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

    void pick(glm::dvec2 at) {
        picked.reset();
        if (!sim->rod_scene()) return;
        if (auto r = sim->read_chains(snapshot); !r) {
            fail(r.error());
            return;
        }
        const rods::ImageCamera cam = image_camera();
        const rods::RodWorld& w = sim->rod_scene()->world;
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

    void apply_sketch() {
        if (!picked || stroke.size() < 2) return;
        const rods::RodWorld& w = sim->rod_scene()->world;
        const rods::ChainInstance& ci = w.chains[*picked];
        const std::string name = w.templ(ci).name;
        rods::SketchInput input;
        input.camera = image_camera();
        auto kinematic = sim->host_chain_input();
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
        ViewSpec view;
        view.view = result.value().view;
        view.shape = result.value().shape;
        auto edit = add_view_example(text, scene_path, name, view);
        if (!edit) {
            say("sketch failed: " + edit.error().message);
            return;
        }
        if (!rebuild(edit.value().text, choice.backend)) return;
        text = edit.value().text;
        dirty = true;
        sketched.push_back(name);
        say("sketch " + name + ": view example \"" + edit.value().name + "\" " +
            (edit.value().replaced ? "replaces \"" + edit.value().replaced_name + "\"" : "added") + ", influence " +
            number(influence) + ", " + std::to_string(result.value().joints_on_stroke) +
            " joints on the stroke (unsaved: W saves)");
    }

    void undo() {
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

    void save() {
        if (auto r = write_scene_text(scene_path, text); !r) {
            say("save failed: " + r.error().message);
            return;
        }
        dirty = false;
        say("saved " + scene_path);
    }

    void key(int key, int mods) {
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
            case GLFW_KEY_EQUAL:
            case GLFW_KEY_KP_ADD: influence = std::min(influence * 1.25f, 1000.0f); break;
            case GLFW_KEY_MINUS:
            case GLFW_KEY_KP_SUBTRACT: influence = std::max(influence / 1.25f, 0.1f); break;
            case GLFW_KEY_P:
            case GLFW_KEY_F12: screenshot_now = true; break;
            default: break;
        }
    }

    void mouse_button(int button, int action, int mods) {
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

    void cursor(double x, double y) {
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

    // A left drag by (dx, dy) window pixels: 0.01 rad per pixel.
    void orbit(double dx, double dy) {
        take_camera();
        camera.yaw -= static_cast<float>(dx) * 0.01f;
        camera.pitch = std::clamp(camera.pitch + static_cast<float>(dy) * 0.01f, -1.55f, 1.55f);
    }

    void scroll(double dy) {
        take_camera();
        camera.distance = std::clamp(camera.distance * std::pow(0.9f, static_cast<float>(dy)), 0.01f, 1e4f);
    }

    // Orbiting, panning or zooming while following the scene's camera takes over from
    // where that camera is now.
    void take_camera() {
        if (!follow_scene) return;
        follow_scene = false;
        const float fps = sim->scene().fps > 0.0f ? sim->scene().fps : 60.0f;
        camera = OrbitCamera::from(sim->scene(), static_cast<float>(current()) / fps);
        say("camera: orbit, from the scene camera's pose");
    }
};

Viewer* from(GLFWwindow* w) { return static_cast<Viewer*>(glfwGetWindowUserPointer(w)); }

std::optional<int> key_by_name(const std::string& name) {
    static const std::pair<const char*, int> kNames[] = {
        {"space", GLFW_KEY_SPACE}, {"right", GLFW_KEY_RIGHT}, {"left", GLFW_KEY_LEFT},   {"home", GLFW_KEY_HOME},
        {"[", GLFW_KEY_LEFT_BRACKET}, {"]", GLFW_KEY_RIGHT_BRACKET}, {"1", GLFW_KEY_1},  {"2", GLFW_KEY_2},
        {"3", GLFW_KEY_3},         {"s", GLFW_KEY_S},         {"w", GLFW_KEY_W},         {"u", GLFW_KEY_U},
        {"c", GLFW_KEY_C},         {"o", GLFW_KEY_O},
        {"+", GLFW_KEY_EQUAL},     {"-", GLFW_KEY_MINUS},     {"p", GLFW_KEY_P},         {"q", GLFW_KEY_Q},
        {"escape", GLFW_KEY_ESCAPE}};
    for (const auto& [n, k] : kNames) {
        if (name == n) return k;
    }
    return std::nullopt;
}

// The status line in stb_easy_font's pixel font (scaled 2x from 1200 columns), on a dark band.
void add_status(render::DrawList& list, const std::string& line) {
    static std::vector<char> buffer(1 << 16);
    const float scale = list.width() >= 1200 ? 2.0f : 1.0f;
    const int quads = stb_easy_font_print(0.0f, 0.0f, const_cast<char*>(line.c_str()), nullptr, buffer.data(),
                                          static_cast<int>(buffer.size()));
    const float band = 14.0f * scale;
    const float w = static_cast<float>(list.width()), h = static_cast<float>(list.height());
    const glm::vec2 origin{4.0f * scale, h - band + 3.0f * scale};
    for (int q = 0; q < quads; ++q) {
        glm::vec2 p[4];
        for (int i = 0; i < 4; ++i) {
            float xy[2];
            std::memcpy(xy, buffer.data() + (q * 4 + i) * 16, sizeof(xy));
            p[i] = origin + scale * glm::vec2(xy[0], xy[1]);
        }
        list.add_screen_triangle(p[0], p[1], p[2], kTextColor);
        list.add_screen_triangle(p[0], p[2], p[3], kTextColor);
    }
    // The band after the glyphs: overlays share depth 0 and the depth test is "less", so
    // the first drawn wins.
    list.add_screen_triangle({0.0f, h - band}, {w, h - band}, {w, h}, kTextBackColor);
    list.add_screen_triangle({0.0f, h - band}, {w, h}, {0.0f, h}, kTextBackColor);
}

}  // namespace

int cmd_view(Args args) {
    BackendChoice choice = read_backend_choice(args);
    const auto max_frames = args.count("frames", 1, 100'000'000);
    const auto screenshot = args.option("screenshot");
    const auto keys_text = args.option("keys");
    auto [width, height] = image_size(args.option("size"));
    // --keys: one step per drawn frame. Besides key names, scripted mouse actions and a
    // window resize (which remakes the swapchain), so that a test can reach them.
    struct Step {
        enum class Kind { Key, Drag, Orbit, Resize } kind = Kind::Key;
        int key = 0;
        std::array<double, 4> values{};
    };
    std::vector<Step> scripted;
    if (keys_text) {
        static constexpr const char* kKnown =
            "space right left home [ ] 1 2 3 s w u c o + - p q escape, drag:X1:Y1:X2:Y2, orbit:DX:DY, resize:W:H";
        std::stringstream list(*keys_text);
        for (std::string name; std::getline(list, name, ',');) {
            Step step;
            auto& d = step.values;
            char extra = 0;
            if (name.starts_with("drag:")) {
                step.kind = Step::Kind::Drag;
                if (std::sscanf(name.c_str(), "drag:%lf:%lf:%lf:%lf%c", &d[0], &d[1], &d[2], &d[3], &extra) != 4) {
                    throw UsageError{"--keys: expected drag:X1:Y1:X2:Y2 (image pixels), got \"" + name + "\""};
                }
            } else if (name.starts_with("orbit:")) {
                step.kind = Step::Kind::Orbit;
                if (std::sscanf(name.c_str(), "orbit:%lf:%lf%c", &d[0], &d[1], &extra) != 2) {
                    throw UsageError{"--keys: expected orbit:DX:DY (a left drag in pixels), got \"" + name + "\""};
                }
            } else if (name.starts_with("resize:")) {
                step.kind = Step::Kind::Resize;
                if (std::sscanf(name.c_str(), "resize:%lf:%lf%c", &d[0], &d[1], &extra) != 2 || !(d[0] >= 1 && d[0] <= 8192) ||
                    !(d[1] >= 1 && d[1] <= 8192)) {
                    throw UsageError{"--keys: expected resize:W:H (window pixels, 1 to 8192), got \"" + name + "\""};
                }
            } else {
                const auto k = key_by_name(name);
                if (!k) throw UsageError{"--keys: unknown key \"" + name + "\" (known: " + kKnown + ")"};
                step.key = *k;
            }
            scripted.push_back(step);
        }
    }
    // The scene first: a bad scene is reported without opening a window.
    auto loaded = load_scene(scene_argument(args.positionals(), "view"));
    if (!loaded) return report(loaded.error());
    Viewer v;
    v.scene_path = loaded.value().path;
    auto text = read_text_file(v.scene_path);
    if (!text) return report(text.error());
    v.text = std::move(text).value();
    v.width = width;
    v.height = height;
    v.choice = choice;
    v.camera = OrbitCamera::from(loaded.value());

    if (glfwInit() != GLFW_TRUE) {
        const char* why = nullptr;
        glfwGetError(&why);
        return report(make_error(Error::Kind::Unsupported,
                                 std::string("cannot open a window (no display server? under CI use xvfb-run): ") +
                                     (why != nullptr ? why : "glfwInit failed")));
    }
    struct GlfwTerminate {
        ~GlfwTerminate() { glfwTerminate(); }
    } terminate_glfw;
    if (glfwVulkanSupported() != GLFW_TRUE) {
        return report(make_error(Error::Kind::Unsupported, "GLFW found no Vulkan loader with surface support"));
    }
    glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
    struct WindowOwner {
        GLFWwindow* w;
        ~WindowOwner() {
            if (w != nullptr) glfwDestroyWindow(w);
        }
    } window{glfwCreateWindow(static_cast<int>(width), static_cast<int>(height), "kodawari view", nullptr, nullptr)};
    if (window.w == nullptr) return report(make_error(Error::Kind::Unsupported, "glfwCreateWindow failed"));
    v.window = window.w;

    std::uint32_t extension_count = 0;
    const char** extensions = glfwGetRequiredInstanceExtensions(&extension_count);
    render::RendererOptions options{.width = width,
                                    .height = height,
                                    .device = choice.options.device,
                                    .validation = choice.options.validation,
                                    .instance_extensions = std::vector<std::string>(extensions, extensions + extension_count),
                                    .create_surface = [&](VkInstance instance) -> Result<VkSurfaceKHR> {
                                        VkSurfaceKHR surface = VK_NULL_HANDLE;
                                        const VkResult r = glfwCreateWindowSurface(instance, window.w, nullptr, &surface);
                                        if (r != VK_SUCCESS) {
                                            return make_error(Error::Kind::Vulkan, "glfwCreateWindowSurface failed (VkResult " +
                                                                                       std::to_string(static_cast<int>(r)) + ")");
                                        }
                                        return surface;
                                    }};
    // The renderer owns the surface; it is destroyed (with the renderer) before the window.
    auto renderer = render::Renderer::create(options);
    if (!renderer) return report(renderer.error());
    v.renderer = renderer.value().get();
    // One device: the vulkan backends run on the renderer's, which draws from their buffers.
    v.choice.options.context = renderer.value()->device_context();
    auto made = make_simulation(std::move(loaded).value(), v.choice, std::nullopt);
    if (!made) return report(made.error());
    v.sim = std::move(made).value();
    if (auto r = v.sim->show_on(*renderer.value()); !r) return report(r.error());

    glfwSetWindowUserPointer(window.w, &v);
    glfwSetKeyCallback(window.w, [](GLFWwindow* w, int key, int, int action, int mods) {
        if (action == GLFW_PRESS || action == GLFW_REPEAT) from(w)->key(key, mods);
    });
    glfwSetMouseButtonCallback(window.w, [](GLFWwindow* w, int button, int action, int mods) { from(w)->mouse_button(button, action, mods); });
    glfwSetCursorPosCallback(window.w, [](GLFWwindow* w, double x, double y) { from(w)->cursor(x, y); });
    glfwSetScrollCallback(window.w, [](GLFWwindow* w, double, double dy) { from(w)->scroll(dy); });

    std::printf("kodawari: viewing scene \"%s\" (%s), %u frames at %g fps, %ux%u on %s\n", v.sim->scene().name.c_str(),
                v.scene_path.c_str(), v.sim->frame_count(), static_cast<double>(v.sim->scene().fps), width, height,
                renderer.value()->device().c_str());
    std::fflush(stdout);

    std::vector<glm::vec3> grid_points;
    std::optional<render::DrawList> last_list;
    std::uint64_t drawn = 0, screenshots = 0;
    double frame_ms = 0.0;
    // Simulation state read back to the host: in all, and over the last frame.
    const std::uint64_t read_back_start = renderer.value()->read_back_bytes();
    std::uint64_t read_back_before = read_back_start, read_back_frame = 0;
    std::size_t next_key = 0;
    while (!v.quit && glfwWindowShouldClose(window.w) == GLFW_FALSE) {
        const auto start = std::chrono::steady_clock::now();
        glfwPollEvents();
        // One scripted key per frame, before the frame is simulated and drawn.
        if (next_key < scripted.size()) {
            const Step& step = scripted[next_key++];
            const auto& d = step.values;
            switch (step.kind) {
                case Step::Kind::Key: v.key(step.key, 0); break;
                case Step::Kind::Drag: v.scripted_drag({d[0], d[1]}, {d[2], d[3]}); break;
                case Step::Kind::Orbit: v.orbit(d[0], d[1]); break;
                case Step::Kind::Resize:
                    glfwSetWindowSize(window.w, static_cast<int>(d[0]), static_cast<int>(d[1]));
                    glfwPollEvents();
                    break;
            }
        }
        if (v.quit) break;
        if (!v.sim->frame()) {
            v.seek(0);
        } else if (v.playing) {
            // Playing past the last frame starts again.
            v.seek(v.current() + 1 < v.sim->frame_count() ? v.current() + 1 : 0);
        }
        if (v.failure) break;
        Simulation& s = *v.sim;

        render::DrawList list(v.view(), width, height);
        if (grid_points.empty()) {
            grid_points = render::content_points(s.rod_scene(), s.rod_scene() ? &s.chain_input() : nullptr,
                                                 s.bird_world().birds.empty() ? nullptr : &s.bird_world());
            if (grid_points.empty()) grid_points.emplace_back(0.0f);
        }
        render::add_ground_grid(list, grid_points);
        if (s.rod_scene()) render::add_characters(list, *s.rod_scene(), v.current());
        if (auto r = s.draw_on(*renderer.value()); !r) return report(r.error());
        if (v.sketch_mode && v.picked && s.rod_scene()) {
            // The picked chain's joints on the host while sketching (it may have been stepped).
            if (auto r = s.read_chains(v.snapshot); !r) return report(r.error());
            const auto& ci = s.rod_scene()->world.chains[*v.picked];
            const std::size_t joints = s.rod_scene()->world.templ(ci).basis.lengths.size() + 1;
            for (std::size_t j = 0; j < joints; ++j) {
                list.add_dot(v.snapshot.positions[ci.joint_begin + j], 0.0f, 5.0f, kPickedColor);
            }
        }
        for (std::size_t i = 1; i < v.stroke.size(); ++i) list.add_screen_line(glm::vec2(v.stroke[i - 1]), glm::vec2(v.stroke[i]), kStrokeColor);

        read_back_frame = renderer.value()->read_back_bytes() - read_back_before;
        read_back_before = renderer.value()->read_back_bytes();
        char status[512];
        std::snprintf(status, sizeof(status),
                      "frame %u  t %.2f s  %s  backend %s  %.1f ms/frame  %llu B read back  camera %s %s  %zu characters %zu chains %zu birds%s%s",
                      v.current(), static_cast<double>(v.current()) / static_cast<double>(s.scene().fps), v.playing ? "playing" : "paused",
                      std::string(backend_name(s.backend())).c_str(), frame_ms, static_cast<unsigned long long>(read_back_frame),
                      v.follow_scene ? "scene" : "orbit", list.camera().orthographic ? "ortho" : "persp",
                      s.rod_scene() ? static_cast<std::size_t>(s.rod_scene()->world.character_count) : 0,
                      s.rod_scene() ? s.rod_scene()->world.chains.size() : 0, s.bird_world().birds.size(),
                      v.sketch_mode ? ("  [sketch: influence " + number(v.influence) + "]").c_str() : "",
                      v.message.empty() ? "" : ("  " + v.message).c_str());
        add_status(list, status);
        glfwSetWindowTitle(window.w, (std::string("kodawari view - ") + status).c_str());

        int fb_w = 0, fb_h = 0;
        glfwGetFramebufferSize(window.w, &fb_w, &fb_h);
        if (auto r = renderer.value()->present(list, static_cast<std::uint32_t>(std::max(fb_w, 0)),
                                               static_cast<std::uint32_t>(std::max(fb_h, 0)));
            !r) {
            return report(r.error());
        }
        if (v.screenshot_now) {
            v.screenshot_now = false;
            char name[64];
            std::snprintf(name, sizeof(name), "kodawari_view_%05u_%llu.png", v.current(), static_cast<unsigned long long>(screenshots++));
            auto image = renderer.value()->render(list);
            if (!image) return report(image.error());
            if (auto r = render::write_png(name, image.value()); !r) return report(r.error());
            v.say(std::string("wrote screenshot ") + name);
        }
        last_list.emplace(std::move(list));
        ++drawn;
        frame_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        if (max_frames && drawn >= *max_frames) break;
    }
    if (v.failure) return report(*v.failure);
    if (screenshot && last_list) {
        // The last frame drawn again offscreen and read back (present() does not read back).
        auto image = renderer.value()->render(*last_list);
        if (!image) return report(image.error());
        if (auto r = render::write_png(*screenshot, image.value()); !r) return report(r.error());
        std::printf("kodawari: wrote screenshot %s (%ux%u)\n", screenshot->c_str(), width, height);
    }
    std::printf("kodawari: view ended at frame %u (t %.3f s, %s) on backend %s after %llu drawn frames%s\n", v.current(),
                static_cast<double>(v.current()) / static_cast<double>(v.sim->scene().fps), v.playing ? "playing" : "paused",
                std::string(backend_name(v.sim->backend())).c_str(), static_cast<unsigned long long>(drawn),
                v.dirty ? "; unsaved sketches discarded" : "");
    std::printf("kodawari: simulation and drawing on one device (%s); %llu bytes of simulation state read back in %llu frames\n",
                renderer.value()->device().c_str(),
                static_cast<unsigned long long>(renderer.value()->read_back_bytes() - read_back_start),
                static_cast<unsigned long long>(drawn));
    // The vulkan backends share the renderer's device and so its count of messages.
    return validation_failed(renderer.value()->validation_messages()) ? kExitFailure : kExitOk;
}

}  // namespace kodawari::cli
