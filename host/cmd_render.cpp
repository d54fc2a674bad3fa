// `kodawari render`: simulates a scene as `run` does (Simulation) and draws frames
// offscreen to PNG files (and a contact sheet), for previews, documentation and tests.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <cerrno>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include "commands.hpp"
#include "level_dots.hpp"
#include "kodawari/render/apng.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/domains/scene_draw.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/domains/birds.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/simulation/simulation.hpp"

namespace kodawari::cli {

namespace {


// Frames first, first + step, ... below end: [first, end), end exclusive.
struct FrameRange {
    std::uint32_t first = 0, end = 0, step = 1;
};

std::optional<std::uint32_t> parse_u32(std::string_view text) {
    std::uint32_t value = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || ptr != text.data() + text.size() || text.empty()) return std::nullopt;
    return value;
}

// "A:B" or "A:B:STEP" (B exclusive), or "N" for the one frame N.
Result<FrameRange> parse_frames(const std::string& text, std::uint32_t scene_frames) {
    const auto bad = [&](const std::string& why) {
        return make_error(Error::Kind::InvalidInput, "--frames " + text + ": " + why);
    };
    std::vector<std::string_view> parts;
    std::string_view rest = text;
    for (std::size_t colon; (colon = rest.find(':')) != std::string_view::npos; rest.remove_prefix(colon + 1)) {
        parts.push_back(rest.substr(0, colon));
    }
    parts.push_back(rest);
    if (parts.size() > 3) return bad("expected A:B, A:B:STEP or N");
    std::array<std::uint32_t, 3> values{};
    for (std::size_t i = 0; i < parts.size(); ++i) {
        const auto value = parse_u32(parts[i]);
        if (!value) return bad("expected A:B, A:B:STEP or N with non-negative integers");
        values[i] = *value;
    }
    FrameRange range;
    range.first = values[0];
    if (parts.size() == 1 && values[0] == UINT32_MAX) return bad("frame number out of range");
    range.end = parts.size() == 1 ? values[0] + 1 : values[1];
    range.step = parts.size() == 3 ? values[2] : 1;
    if (range.step == 0) return bad("the step must be at least 1");
    if (range.first >= range.end) return bad("the range [A, B) is empty (B is exclusive)");
    if (range.end > scene_frames) {
        return bad("the scene has frames 0 to " + std::to_string(scene_frames - 1) + " (B is exclusive: at most " +
                   std::to_string(scene_frames) + ")");
    }
    return range;
}

std::string frame_file(const std::string& dir, const std::string& scene, std::uint32_t frame) {
    char number[16];
    std::snprintf(number, sizeof(number), "%05u", frame);
    return (std::filesystem::path(dir) / (scene + "_" + number + ".png")).string();
}

// What one render writes: the frames (and contact sheet) and the directories it created.
// Unless keep() is called, destruction removes them, so a render that fails part-way (a
// full disk, a device lost at frame 40, a validation message) leaves nothing of its own
// behind: the files it wrote (one of which may have replaced an earlier run's frame), then
// its directories, deepest first, when they are empty.
class RenderOutputs {
public:
    RenderOutputs() = default;
    RenderOutputs(const RenderOutputs&) = delete;
    RenderOutputs& operator=(const RenderOutputs&) = delete;
    ~RenderOutputs() {
        if (kept_) return;
        std::error_code ec;
        for (const std::string& file : files_) std::filesystem::remove(file, ec);
        if (!files_.empty()) {
            std::fprintf(stderr, "kodawari: render failed: removed the %zu file%s it wrote\n", files_.size(),
                         files_.size() == 1 ? "" : "s");
        }
        for (auto dir = created_.rbegin(); dir != created_.rend(); ++dir) std::filesystem::remove(*dir, ec);
    }

    // Creates `dir` and its missing parents, remembering which were missing.
    Result<void> create_directory(const std::string& dir, const std::string& option) {
        std::vector<std::filesystem::path> missing;
        std::error_code ec;
        for (std::filesystem::path p = std::filesystem::path(dir).lexically_normal(); !p.empty() && p != p.parent_path();
             p = p.parent_path()) {
            if (std::filesystem::exists(std::filesystem::symlink_status(p, ec))) break;
            missing.push_back(p);
        }
        ec.clear();
        std::filesystem::create_directories(dir, ec);
        for (auto p = missing.rbegin(); p != missing.rend(); ++p) {
            if (std::filesystem::is_directory(*p)) created_.push_back(p->string());
        }
        if (ec || !std::filesystem::is_directory(dir)) {
            return make_error(Error::Kind::Io, option + " " + dir + ": cannot create the directory" +
                                                   (ec ? " (" + ec.message() + ")" : std::string(" (a file is in the way)")));
        }
        return {};
    }
    void wrote(const std::string& file) { files_.push_back(file); }
    void keep() { kept_ = true; }

private:
    std::vector<std::string> files_;
    std::vector<std::string> created_;  // outermost first
    bool kept_ = false;
};

// --zoom F: the scene camera's field of view narrowed F times about its target. Only the
// picture changes: the camera stays where the scene puts it, so the view directions that
// blend the chains' rest shapes (SPEC A) are the scene's own.
float parse_zoom(const std::optional<std::string>& text) {
    if (!text) return 1.0f;
    const float value = parse_real("--zoom", *text);
    if (!(value >= 0.1f && value <= 100.0f)) throw UsageError{"--zoom: expected a number in [0.1, 100], got \"" + *text + "\""};
    return value;
}

render::CameraView zoomed(render::CameraView camera, float zoom) {
    camera.fov_deg = 2.0f * glm::degrees(std::atan(std::tan(glm::radians(0.5f * camera.fov_deg)) / zoom));
    camera.ortho_height /= zoom;
    return camera;
}

// --camera EX,EY,EZ,TX,TY,TZ: draw from this eye looking at this target (the scene's
// field of view) instead of the scene camera. Only the picture changes: the simulation
// keeps the scene's camera, so view-dependent chains keep the shapes the scene's camera
// gives them (a close-up of something the scene camera passes at a distance, such as a
// flock).
std::optional<std::pair<glm::vec3, glm::vec3>> parse_camera(const std::optional<std::string>& text) {
    if (!text) return std::nullopt;
    float v[6] = {};
    char extra = 0;
    if (std::sscanf(text->c_str(), "%f,%f,%f,%f,%f,%f%c", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &extra) != 6 ||
        !std::all_of(std::begin(v), std::end(v), [](float x) { return std::isfinite(x); })) {
        throw UsageError{"--camera: expected EYE_X,EYE_Y,EYE_Z,TARGET_X,TARGET_Y,TARGET_Z, got \"" + *text + "\""};
    }
    const glm::vec3 eye(v[0], v[1], v[2]), target(v[3], v[4], v[5]);
    if (!(glm::length(target - eye) > 1e-6f)) throw UsageError{"--camera: the target equals the eye"};
    return std::pair{eye, target};
}

// The scene camera at `frame`, or the --camera eye and target with the scene's field of
// view and near and far planes for that distance (kodawari::scene_camera's rule).
render::CameraView drawing_camera(const Scene& scene, std::uint32_t frame, const std::optional<std::pair<glm::vec3, glm::vec3>>& camera) {
    render::CameraView view = kodawari::scene_camera(scene, frame);
    if (!camera) return view;
    view.position = camera->first;
    view.target = camera->second;
    view.orthographic = false;
    const float distance = glm::length(camera->second - camera->first);
    view.near = std::clamp(0.01f * distance, 0.01f, 1.0f);
    view.far = 1000.0f * view.near;
    return view;
}

// The options as given; add_render() defines them.
struct RenderOptions {
    std::optional<std::string> scene;
    BackendFlags backend;
    std::optional<std::string> frames;
    std::optional<std::string> out;
    std::optional<std::string> contact_sheet;
    std::optional<std::uint64_t> columns;
    std::optional<std::string> size;
    std::optional<std::string> animation;
    std::optional<std::string> animation_size;
    std::optional<std::string> zoom;
    std::optional<std::string> camera;
    bool joints = false;
    LodFlags lod;
    bool show_lod = false;
};

int cmd_render(const RenderOptions& o) {
    BackendChoice choice = read_backend_choice(o.backend);
    const auto& frames_text = o.frames;
    const auto& out_dir = o.out;
    const auto& sheet_path = o.contact_sheet;
    const auto& columns_option = o.columns;
    if (!out_dir) throw UsageError{"render needs --out DIR (the directory of the PNG files; created when missing)"};
    if (columns_option && !sheet_path) throw UsageError{"--columns goes with --contact-sheet"};
    const auto [width, height] = image_size(o.size);
    const auto& animation_path = o.animation;
    if (o.animation_size && !animation_path) throw UsageError{"--animation-size goes with --animation"};
    // By default the frames' own size; smaller for a README preview.
    const auto animation_size =
        o.animation_size ? parse_image_size("--animation-size", *o.animation_size, width, height) : std::pair{width, height};
    const float zoom = parse_zoom(o.zoom);
    // An animated PNG is written under a .png (or .apng) name only: a viewer goes by the name.
    if (animation_path) {
        std::string extension = std::filesystem::path(*animation_path).extension().string();
        for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        if (extension != ".png" && extension != ".apng") {
            throw UsageError{"--animation " + *animation_path + ": writes an animated PNG (APNG): name it .png or .apng"};
        }
    }
    const auto camera = parse_camera(o.camera);
    auto loaded = load_scene(scene_or_default(o.scene));
    if (!loaded) return report(loaded.error());
    apply_lod(o.lod, loaded.value());
    if (o.show_lod) {
        if (loaded.value().characters.empty()) {
            throw UsageError{"--show-lod: scene " + loaded.value().path + " has no characters (levels of detail are the characters' chains')"};
        }
        loaded.value().lod.enabled = true;
    }
    const std::uint32_t scene_frames = loaded.value().frame_count();
    FrameRange range{0, scene_frames, 1};
    if (frames_text) {
        auto parsed = parse_frames(*frames_text, scene_frames);
        if (!parsed) return report(parsed.error());
        range = parsed.value();
    }
    render::RendererOptions renderer_settings = renderer_options(choice, width, height);
    renderer_settings.joints = o.joints;
    auto renderer = render::Renderer::create(renderer_settings);
    if (!renderer) return report(renderer.error());
    render::Renderer& r = *renderer.value();
    // The simulation runs on the renderer's device, which then draws the vulkan backends'
    // chains, birds and skinned meshes from their own buffers.
    choice.options.context = r.device_context();
    auto made = make_simulation(std::move(loaded).value(), choice, std::nullopt);
    if (!made) return report(made.error());
    Simulation& sim = *made.value();
    const Scene& scene = sim.scene();
    if (auto s = sim.show_on(r); !s) return report(s.error());
    const std::uint32_t count = (range.end - range.first + range.step - 1) / range.step;
    std::printf("kodawari: rendering scene \"%s\" (%s): %u frames of [%u, %u) step %u at %ux%u on %s\n", scene.name.c_str(),
                scene.path.c_str(), count, range.first, range.end, range.step, width, height, r.device().c_str());
    std::fflush(stdout);
    // The directory only now that the renderer and the simulation are open: a run that
    // cannot start (no Vulkan device, a bad scene) creates nothing.
    RenderOutputs outputs;
    if (auto made_dir = outputs.create_directory(*out_dir, "--out"); !made_dir) return report(made_dir.error());
    // The contact sheet's and the animation's folders too, and that they take files: found
    // now, not after every frame is drawn.
    for (const auto& [option, path] : {std::pair{"--contact-sheet", sheet_path}, std::pair{"--animation", animation_path}}) {
        if (!path) continue;
        const std::filesystem::path folder = std::filesystem::absolute(*path).parent_path();
        if (auto folder_made = outputs.create_directory(folder.string(), option); !folder_made) return report(folder_made.error());
        if (::access(folder.c_str(), W_OK) != 0) {
            return report(make_error(Error::Kind::Io, std::string(option) + " " + *path + ": cannot write into " +
                                                          folder.string() + " (" + std::strerror(errno) + "); nothing drawn"));
        }
    }
    // Frames go into the animation as they are drawn; only its frame count is needed now.
    std::optional<render::ApngWriter> animation;
    if (animation_path) {
        auto opened = render::ApngWriter::open(
            *animation_path, {animation_size.first, animation_size.second, count, render::frame_delay(range.step, scene.fps), 0});
        if (!opened) return report(opened.error());
        animation.emplace(std::move(opened).value());
    }

    const std::uint32_t columns = columns_option ? static_cast<std::uint32_t>(*columns_option) : std::min(count, 4u);
    const std::uint32_t cell_width = std::max(1u, width / columns), cell_height = std::max(1u, height / columns);
    std::vector<render::Image> cells;
    std::vector<glm::vec3> grid_points;
    // Where the birds perch: a pass over every bird, found with the grid, once.
    kodawari::Perches perches;
    double render_seconds = 0.0;
    const bool show_progress = stderr_is_terminal() && range.end > 100;
    std::vector<rods::Level> levels;
    for (std::uint32_t f = 0; f < range.end; ++f) {
        const bool drawn = f >= range.first && (f - range.first) % range.step == 0;
        if (auto s = sim.step(); !s) return report(s.error());
        if (show_progress) progress("simulating", f + 1, range.end);
        if (!drawn) continue;
        if (auto s = sim.draw_on(r); !s) return report(s.error());
        const auto start = std::chrono::steady_clock::now();
        render::DrawList list(zoomed(drawing_camera(scene, f, camera), zoom), width, height);
        // The grid covers where the content is at the first drawn frame and then stays put,
        // so that it does not jump from frame to frame.
        if (grid_points.empty()) {
            grid_points = kodawari::content_points(rod_scene(sim), rod_scene(sim) ? &chain_input(sim) : nullptr,
                                                 bird_world(sim).birds.empty() ? nullptr : &bird_world(sim));
            if (grid_points.empty()) grid_points.emplace_back(0.0f);
            if (!bird_world(sim).birds.empty()) perches = kodawari::perches_of(bird_world(sim));
        }
        render::add_ground_grid(list, grid_points);
        if (rod_scene(sim)) kodawari::add_characters(list, *rod_scene(sim), f);
        kodawari::add_perches(list, perches);
        if (o.show_lod) {
            auto counts = add_level_dots(list, sim, levels);
            if (!counts) return report(counts.error());
            std::printf("kodawari: frame %u: characters %s\n", f,
                        levels_text(counts.value(), sim.scene().lod.reduced_pixels > 0.0f, ", ").c_str());
        }
        auto image = r.render(list);
        if (!image) return report(image.error());
        render_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const std::string path = frame_file(*out_dir, scene.name, f);
        if (auto s = render::write_png(path, image.value()); !s) return report(s.error());
        outputs.wrote(path);
        if (show_progress) std::fputc('\n', stderr);
        std::printf("kodawari: wrote %s\n", path.c_str());
        if (sheet_path) cells.push_back(render::downscale(image.value(), cell_width, cell_height));
        if (animation) {
            auto added = animation_size == std::pair{width, height}
                             ? animation->add_frame(image.value())
                             : animation->add_frame(render::downscale(image.value(), animation_size.first, animation_size.second));
            if (!added) return report(added.error());
        }
    }
    std::printf("kodawari: %.1f ms per frame to draw and read back\n", 1e3 * render_seconds / count);
    if (sheet_path) {
        const render::Image sheet = render::contact_sheet(cells, columns, cell_width, cell_height);
        if (auto s = render::write_png(*sheet_path, sheet); !s) return report(s.error());
        outputs.wrote(*sheet_path);
        std::printf("kodawari: wrote contact sheet %s (%u frames, %u columns, %ux%u)\n", sheet_path->c_str(), count, columns,
                    sheet.width, sheet.height);
    }
    if (animation) {
        if (auto s = animation->commit(); !s) return report(s.error());
        outputs.wrote(*animation_path);
        const render::FrameDelay delay = render::frame_delay(range.step, scene.fps);
        std::printf("kodawari: wrote animation %s (%u frames, %ux%u, %u/%u s each, looping)\n", animation_path->c_str(), count,
                    animation_size.first, animation_size.second, delay.numerator, delay.denominator);
    }
    // The vulkan backends share the renderer's device and so its count of messages.
    if (validation_failed(r.validation_messages())) return kExitFailure;
    outputs.keep();
    return kExitOk;
}

}  // namespace

Command add_render(CLI::App& app) {
    auto o = std::make_shared<RenderOptions>();
    CLI::App* c = app.add_subcommand("render", "simulate a scene as run does and draw frames offscreen to PNG files "
                                               "DIR/<scene>_<frame, 5 digits>.png (docs/command-line.md)");
    add_scene(*c, o->scene);
    add_text(*c, "--out", o->out, "DIR", "the directory of the PNG files, created when missing (required)");
    add_text(*c, "--frames", o->frames, "A:B[:STEP]|N",
             "frames A, A+STEP, ... below B (B exclusive), or the one frame N (default: the whole scene)");
    add_size(*c, o->size, "the images");
    add_switch(*c, "--joints", o->joints, "a dot at every simulated joint of the strands (default: off, the strands alone)");
    add_lod_options(*c, o->lod);
    add_switch(*c, "--show-lod", o->show_lod,
               "a dot over each character in the colour of its level of detail: green full, amber posed, blue hidden; turns --lod "
               "on, and prints how many characters are at each level (default: off)");
    add_text(*c, "--contact-sheet", o->contact_sheet, "FILE.png", "also the frames shrunk into one grid (default: none)");
    add_count(*c, "--columns", o->columns, 1, 64, "the contact sheet's columns (default: min(frames, 4))");
    add_text(*c, "--zoom", o->zoom, "F",
             "narrow the scene camera's field of view F times about its target, in [0.1, 100]; the camera "
             "and so the view-dependent shapes stay the scene's (default: 1)");
    add_text(*c, "--camera", o->camera, "EX,EY,EZ,TX,TY,TZ",
             "draw from this eye looking at this target, in metres (the scene's field of view); the simulation "
             "keeps the scene camera (default: the scene camera)");
    add_text(*c, "--animation", o->animation, "FILE.png",
             "also the frames as one looping animated PNG at the scene's fps / STEP (default: none)");
    add_text(*c, "--animation-size", o->animation_size, "WxH",
             "the animation's size, at most --size (default: the frames' own size)");
    add_backend_options(*c, o->backend);
    return {c, [o] { return cmd_render(*o); }};
}

}  // namespace kodawari::cli
