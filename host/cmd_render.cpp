// `kodawari render`: simulates a scene as `run` does and draws frames offscreen to PNG
// files (and a contact sheet), for previews, documentation and tests.

#include <algorithm>
#include <array>
#include <cstdint>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "kodawari/crowd_animator.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/render/scene_draw.hpp"
#include "kodawari/rod_scene.hpp"

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

}  // namespace

int cmd_render(Args args) {
    BackendChoice choice = read_backend_choice(args);
    const auto frames_text = args.option("frames");
    const auto out_dir = args.option("out");
    const auto sheet_path = args.option("contact-sheet");
    const auto columns_option = args.count("columns", 1, 64);
    if (!out_dir) throw UsageError{"render needs --out DIR (the directory of the PNG files; created when missing)"};
    if (columns_option && !sheet_path) throw UsageError{"--columns goes with --contact-sheet"};
    const auto [width, height] = image_size(args.option("size"));
    auto loaded = load_scene_arguments(args.positionals(), "render", std::nullopt);
    if (!loaded) return report(loaded.error());
    const Scene& scene = loaded.value().scene;
    const birds::BirdWorld& bird_world = loaded.value().world;
    const std::uint32_t scene_frames = scene.frame_count();
    FrameRange range{0, scene_frames, 1};
    if (frames_text) {
        auto parsed = parse_frames(*frames_text, scene_frames);
        if (!parsed) return report(parsed.error());
        range = parsed.value();
    }
    std::error_code ec;
    std::filesystem::create_directories(*out_dir, ec);
    if (ec || !std::filesystem::is_directory(*out_dir)) {
        return report(make_error(Error::Kind::Io, "--out " + *out_dir + ": cannot create the directory" +
                                                      (ec ? " (" + ec.message() + ")" : std::string(" (a file is in the way)"))));
    }

    auto renderer = render::Renderer::create(
        {.width = width, .height = height, .device = choice.options.device, .validation = choice.options.validation});
    if (!renderer) return report(renderer.error());
    // The vulkan backends run on the renderer's device, which draws their chains and
    // birds from their own buffers.
    choice.options.context = renderer.value()->device_context();

    // The simulation, as `run` steps it: birds by the bird backend, characters by the rod
    // backend with the crowd animator's kinematic input.
    const std::size_t bird_count = bird_world.birds.size();
    std::unique_ptr<BirdBackend> birds;
    if (bird_count > 0) {
        auto opened = open_backend(choice);
        if (!opened) return report(opened.error());
        birds = std::move(opened).value();
        if (auto r = birds->load(bird_world); !r) return report(r.error());
        if (auto r = renderer.value()->set_birds(&bird_world); !r) return report(r.error());
    }
    std::optional<RodScene> rod_scene;
    std::unique_ptr<RodBackend> rods;
    std::optional<CrowdAnimator> animator;
    if (!scene.characters.empty()) {
        auto built = build_rod_scene(scene);
        if (!built) return report(built.error());
        rod_scene.emplace(std::move(built).value());
        auto opened = open_rod_backend(choice);
        if (!opened) return report(opened.error());
        rods = std::move(opened).value();
        auto created = CrowdAnimator::create(*rod_scene, parse_backend(std::string(rods->name())).value_or(BackendKind::Cpu),
                                             choice.options);
        if (!created) return report(created.error());
        animator.emplace(std::move(created).value());
        if (auto r = renderer.value()->set_chains(&rod_scene->world); !r) return report(r.error());
        if (auto r = renderer.value()->set_skinned(&*rod_scene); !r) return report(r.error());
    }
    // A vulkan bird backend made on the renderer's device: its poses are drawn where they
    // are; the others' are read back each drawn frame.
    const bool birds_on_device = birds && birds->name() == "vulkan";
    const std::uint32_t count = (range.end - range.first + range.step - 1) / range.step;
    std::printf("kodawari: rendering scene \"%s\" (%s): %u frames of [%u, %u) step %u at %ux%u on %s\n", scene.name.c_str(),
                scene.path.c_str(), count, range.first, range.end, range.step, width, height, renderer.value()->device().c_str());
    std::fflush(stdout);

    const std::uint32_t columns = columns_option ? static_cast<std::uint32_t>(*columns_option) : std::min(count, 4u);
    const std::uint32_t cell_width = std::max(1u, width / columns), cell_height = std::max(1u, height / columns);
    std::vector<render::Image> cells;
    std::vector<glm::vec3> grid_points;
    std::vector<gpu::BirdPose> poses(bird_count);
    rods::RodFrame frame;
    double render_seconds = 0.0;
    const bool show_progress = stderr_is_terminal() && range.end > 100;
    for (std::uint32_t f = 0; f < range.end; ++f) {
        const bool drawn = f >= range.first && (f - range.first) % range.step == 0;
        if (birds) {
            // Poses on the host only where a drawn frame needs them (the CPU backends').
            const bool want_poses = drawn && !birds_on_device;
            if (auto r = birds->simulate(1, {.poses = want_poses ? std::span(poses) : std::span<gpu::BirdPose>(), .diag = {}}); !r) {
                return report(r.error());
            }
        }
        if (rods) {
            if (auto r = animator->frame(f, frame); !r) return report(r.error());
            // Frame 0 is the initial pose; every later frame is one step.
            if (auto r = f == 0 ? rods->load(rod_scene->world, frame) : rods->step(frame); !r) return report(r.error());
            if (f == 0) {
                // On one device the rigged characters' input is written where the chains step.
                if (auto r = animator->write_inputs_on(*rods); !r) return report(r.error());
            }
        }
        if (show_progress) progress("simulating", f + 1, range.end);
        if (!drawn) continue;
        if (rods) {
            // The chains and the skinned meshes (their hair bones follow the chains) drawn
            // from the backends' buffers where they share the renderer's device.
            if (auto r = renderer.value()->chains_from(*rods); !r) return report(r.error());
            if (auto r = renderer.value()->skinned_from(*animator, *rods, f); !r) return report(r.error());
            if (auto r = renderer.value()->colliders_from(*rods, frame); !r) return report(r.error());
        }
        if (birds) {
            if (auto r = birds_on_device ? renderer.value()->birds_from(*birds) : renderer.value()->birds_from(poses); !r) {
                return report(r.error());
            }
        }
        const auto start = std::chrono::steady_clock::now();
        render::DrawList list(render::scene_camera(scene, f), width, height);
        // The grid covers where the content is at the first drawn frame and then stays put,
        // so that it does not jump from frame to frame.
        if (grid_points.empty()) {
            grid_points = render::content_points(rod_scene ? &*rod_scene : nullptr, rods ? &frame : nullptr, birds ? &bird_world : nullptr);
            if (grid_points.empty()) grid_points.emplace_back(0.0f);
        }
        render::add_ground_grid(list, grid_points);
        if (rods) render::add_characters(list, *rod_scene, f);
        auto image = renderer.value()->render(list);
        if (!image) return report(image.error());
        render_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const std::string path = frame_file(*out_dir, scene.name, f);
        if (auto r = render::write_png(path, image.value()); !r) return report(r.error());
        if (show_progress) std::fputc('\n', stderr);
        std::printf("kodawari: wrote %s\n", path.c_str());
        if (sheet_path) cells.push_back(render::downscale(image.value(), cell_width, cell_height));
    }
    std::printf("kodawari: %.1f ms per frame to draw and read back\n", 1e3 * render_seconds / count);
    if (sheet_path) {
        const render::Image sheet = render::contact_sheet(cells, columns, cell_width, cell_height);
        if (auto r = render::write_png(*sheet_path, sheet); !r) return report(r.error());
        std::printf("kodawari: wrote contact sheet %s (%u frames, %u columns, %ux%u)\n", sheet_path->c_str(), count, columns,
                    sheet.width, sheet.height);
    }
    // The vulkan backends share the renderer's device and so its count of messages.
    return validation_failed(renderer.value()->validation_messages()) ? kExitFailure : kExitOk;
}

}  // namespace kodawari::cli
