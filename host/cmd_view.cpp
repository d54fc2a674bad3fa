// `kodawari view SCENE`: the interactive viewer (issue 5): the window, the scripted keys
// and the frame loop. Each frame is simulated as `render` does (Simulation), drawn by the
// renderer and blitted into the window's swapchain image (Renderer::present). The
// simulation runs on the renderer's device: the chains, colliders, birds and rigged
// characters' skinned meshes are drawn from the vulkan backends' own buffers and the
// rigged characters' rod input is written from their poses there, so nothing is read back
// per frame (the end line and the status line say how much was). Read back: a rigged
// crowd's frame 0 (the rod backend's load() takes it on the host), and on demand the
// picked chain and the sketched frame's input while sketching (viewer/viewer.cpp).
#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include "commands.hpp"
#include "level_dots.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/domains/scene_draw.hpp"
#include "kodawari/scene/scene_edit.hpp"
#include "viewer/viewer.hpp"

namespace kodawari::cli {
namespace {

Viewer* from(GLFWwindow* w) { return static_cast<Viewer*>(glfwGetWindowUserPointer(w)); }

// The levels' budget at the last step (--budget-ms): the status line's and the end line's.
std::string budget_text(const LodBudgetState& b) {
    char text[160];
    const char* within = b.full_distance == std::numeric_limits<float>::infinity()    ? "every character the rule makes full"
                         : b.full_distance == -std::numeric_limits<float>::infinity() ? "no character full"
                                                                                     : nullptr;
    if (within != nullptr) {
        std::snprintf(text, sizeof text, "budget %g ms (%s x%.2f): %s", static_cast<double>(b.budget_ms),
                      b.measured ? "measured" : "model", static_cast<double>(b.scale), within);
    } else {
        std::snprintf(text, sizeof text, "budget %g ms (%s x%.2f): full within %.1f m", static_cast<double>(b.budget_ms),
                      b.measured ? "measured" : "model", static_cast<double>(b.scale), static_cast<double>(b.full_distance));
    }
    return text;
}


struct ViewOptions {
    std::optional<std::string> scene;
    BackendFlags backend;
    std::optional<std::uint64_t> frames;
    std::optional<std::string> screenshot;
    std::optional<std::string> keys;
    std::optional<std::string> size;
    bool joints = false;
    LodFlags lod;
    bool show_lod = false;
};

int cmd_view(const ViewOptions& o) {
    BackendChoice choice = read_backend_choice(o.backend);
    const auto& max_frames = o.frames;
    const auto& screenshot = o.screenshot;
    const auto& keys_text = o.keys;
    auto [width, height] = image_size(o.size);
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
            "space right left home [ ] 1 2 3 s k w u c o l + - p q escape, drag:X1:Y1:X2:Y2, orbit:DX:DY, resize:W:H";
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
                // The keys as viewer.md's table names them (L, W, Space) are taken too.
                std::string lower = name;
                for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
                const auto k = key_by_name(lower);
                if (!k) throw UsageError{"--keys: unknown key \"" + name + "\" (known: " + kKnown + ")"};
                step.key = *k;
            }
            scripted.push_back(step);
        }
    }
    // The scene first: a bad scene is reported without opening a window.
    auto loaded = load_scene(scene_or_default(o.scene));
    if (!loaded) return report(loaded.error());
    apply_lod(o.lod, loaded.value());
    if (o.show_lod && loaded.value().characters.empty()) {
        throw UsageError{"--show-lod: scene " + loaded.value().path + " has no characters (levels of detail are the characters' chains')"};
    }
    Viewer v;
    v.show_lod = o.show_lod;
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
    render::RendererOptions options = renderer_options(choice, width, height);
    options.joints = o.joints;
    options.instance_extensions = std::vector<std::string>(extensions, extensions + extension_count);
    options.create_surface = [&](VkInstance instance) -> Result<VkSurfaceKHR> {
        VkSurfaceKHR surface = VK_NULL_HANDLE;
        const VkResult r = glfwCreateWindowSurface(instance, window.w, nullptr, &surface);
        if (r != VK_SUCCESS) {
            Error e = make_error(Error::Kind::Vulkan, "glfwCreateWindowSurface failed (VkResult " + std::to_string(static_cast<int>(r)) + ")");
            e.vk_result = static_cast<int>(r);
            return e;
        }
        return surface;
    };
    // The renderer owns the surface; it is destroyed (with the renderer) before the window.
    auto renderer = render::Renderer::create(options);
    if (!renderer) return report(renderer.error());
    v.renderer = renderer.value().get();
    // One device: the vulkan backends run on the renderer's, which draws from their buffers.
    v.choice.options.context = renderer.value()->device_context();
    auto made = make_simulation(std::move(loaded).value(), v.choice, std::nullopt);
    if (!made) return report(made.error());
    v.sim = std::move(made).value();
    if (auto r = apply_measured_budget(o.lod, *v.sim); !r) return report(r.error());
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
    // Where the birds perch: a pass over every bird, found with the grid, once.
    kodawari::Perches perches;
    std::optional<render::DrawList> last_list;
    std::vector<rods::Level> levels;  // --show-lod: read back each frame
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
            grid_points = kodawari::content_points(rod_scene(s), rod_scene(s) ? &chain_input(s) : nullptr,
                                                 bird_world(s).birds.empty() ? nullptr : &bird_world(s));
            if (grid_points.empty()) grid_points.emplace_back(0.0f);
            if (!bird_world(s).birds.empty()) perches = kodawari::perches_of(bird_world(s));
        }
        render::add_ground_grid(list, grid_points);
        if (rod_scene(s)) kodawari::add_characters(list, *rod_scene(s), v.current());
        kodawari::add_perches(list, perches);
        // --show-lod, L: each character's level (read back: the status line counts it).
        std::string lod_status;
        if (v.show_lod && rod_scene(s)) {
            auto counts = add_level_dots(list, s, levels);
            if (!counts) return report(counts.error());
            lod_status = "  levels " + levels_text(counts.value(), s.scene().lod.reduced_pixels > 0.0f, " ");
        }
        // --budget-ms: what the budget did at the last step.
        if (const auto budget = lod_budget(s)) lod_status += "  " + budget_text(*budget);
        if (auto r = s.draw_on(*renderer.value()); !r) return report(r.error());
        if (v.sketch_mode && v.picked && rod_scene(s)) {
            // The picked chain's joints on the host while sketching (it may have been stepped).
            if (auto r = read_chains(s, v.snapshot); !r) return report(r.error());
            const auto& ci = rod_scene(s)->world.chains[*v.picked];
            const std::size_t joints = rod_scene(s)->world.templ(ci).basis.lengths.size() + 1;
            for (std::size_t j = 0; j < joints; ++j) {
                list.add_dot(v.snapshot.positions[ci.joint_begin + j], 0.0f, 5.0f, kPickedColor);
            }
        }
        for (std::size_t i = 1; i < v.stroke.size(); ++i) list.add_screen_line(glm::vec2(v.stroke[i - 1]), glm::vec2(v.stroke[i]), kStrokeColor);

        read_back_frame = renderer.value()->read_back_bytes() - read_back_before;
        read_back_before = renderer.value()->read_back_bytes();
        char status[512];
        std::snprintf(status, sizeof(status),
                      "frame %u  t %.2f s  %s  backend %s  %.1f ms/frame  %llu B read back  camera %s %s  %zu characters %zu chains %zu birds%s%s%s",
                      v.current(), static_cast<double>(v.current()) / static_cast<double>(s.scene().fps), v.playing ? "playing" : "paused",
                      std::string(backend_name(s.backend())).c_str(), frame_ms, static_cast<unsigned long long>(read_back_frame),
                      v.follow_scene ? "scene" : "orbit", list.camera().orthographic ? "ortho" : "persp",
                      rod_scene(s) ? static_cast<std::size_t>(rod_scene(s)->world.character_count) : 0,
                      rod_scene(s) ? rod_scene(s)->world.chains.size() : 0, bird_world(s).birds.size(), lod_status.c_str(),
                      v.sketch_mode ? ("  [sketch: " + v.sketch_status() + "]").c_str() : "",
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
    if (const auto budget = lod_budget(*v.sim)) std::printf("kodawari: at the last frame, %s\n", budget_text(*budget).c_str());
    std::printf("kodawari: simulation and drawing on one device (%s); %llu bytes of simulation state read back in %llu frames\n",
                renderer.value()->device().c_str(),
                static_cast<unsigned long long>(renderer.value()->read_back_bytes() - read_back_start),
                static_cast<unsigned long long>(drawn));
    // The vulkan backends share the renderer's device and so its count of messages.
    return validation_failed(renderer.value()->validation_messages()) ? kExitFailure : kExitOk;
}

}  // namespace

Command add_view(CLI::App& app) {
    auto o = std::make_shared<ViewOptions>();
    CLI::App* c = app.add_subcommand("view", "an interactive window (GLFW + Vulkan): orbit, pan, zoom, play, step, sketch "
                                             "(docs/viewer.md)");
    add_scene(*c, o->scene);
    add_size(*c, o->size, "the window");
    add_switch(*c, "--joints", o->joints, "a dot at every simulated joint of the strands (default: off, the strands alone)");
    add_count(*c, "--frames", o->frames, 1, 100'000'000, "quit after N drawn frames (default: run until closed)");
    add_text(*c, "--keys", o->keys, "K1,K2,...",
             "one key per drawn frame first: space right left home [ ] 1 2 3 s k w u c o l + - p q escape, drag:X1:Y1:X2:Y2, "
             "orbit:DX:DY, resize:W:H (default: none)");
    add_text(*c, "--screenshot", o->screenshot, "FILE.png", "write the last drawn frame (default: none)");
    add_lod_options(*c, o->lod);
    add_switch(*c, "--show-lod", o->show_lod,
               "a dot over each character in its level of detail's colour (green full, amber posed, blue hidden) and "
               "the counts on the status line, as render --show-lod; L toggles it (default: off)");
    add_backend_options(*c, o->backend);
    return {c, [o] { return cmd_view(*o); }};
}

}  // namespace kodawari::cli
