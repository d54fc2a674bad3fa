#pragma once
// The viewer's state and what the user does to it (keys, mouse, sketching, backend
// switches); `kodawari view` (cmd_view.cpp) owns the window and the frame loop around it.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <GLFW/glfw3.h>

#include "../cli_common.hpp"
#include "kodawari/render/renderer.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "orbit_camera.hpp"

namespace kodawari::cli {

inline constexpr render::Rgba8 kStrokeColor{250, 220, 40};
inline constexpr render::Rgba8 kPickedColor{40, 200, 250};

/// `value` as %g.
std::string number(float value);

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
    float influence = 4.0f;             // a view example's; keyed examples take sketch_key.hpp's defaults
    // K: what the next sketch makes (docs/sketch.md, "Keyed sketches").
    enum class SketchKind { View, Motion, Pose } sketch_kind = SketchKind::View;
    std::vector<std::string> sketched;  // chain names, for undo
    std::string message;                // the last sketch/save outcome, shown on the status line
    std::optional<Error> failure;       // a simulation error ends the loop
    ChainSnapshot snapshot;             // the chains read back for picking and sketching

    bool follow_scene = false;  // C: the scene's camera (its motion and projection) instead of the orbit camera
    bool show_lod = false;      // L (--show-lod): each character's level of detail as a dot

    // The camera of the current frame: the orbit camera, or the scene's at that frame.
    [[nodiscard]] rods::ImageCamera image_camera() const;
    [[nodiscard]] render::CameraView view() const;
    // What drives the view-dependent shapes of the frames simulated next: the orbit
    // camera, or (none) the scene's camera at each frame, as `run` and `render` have it.
    [[nodiscard]] std::optional<rods::Camera> rod_camera() const;

    // Window coordinates to image pixels (the window may have been resized).
    [[nodiscard]] glm::dvec2 to_image(double x, double y) const;

    // A sketch / undo / save outcome: on the status line and on stdout (scripts read it).
    void say(std::string line);

    // A scripted stroke (--keys drag:X1:Y1:X2:Y2, image pixels): press at the start (picks
    // the chain), a straight drag in 16 steps, release (sketches), as the mouse would.
    void scripted_drag(glm::dvec2 a, glm::dvec2 b);

    void fail(Error e);

    // The frame shown: the one simulated last.
    [[nodiscard]] std::uint32_t current() const { return sim->frame().value_or(0); }

    void seek(std::uint32_t f);

    // A new simulation of `scene_text` at the current frame (a sketch, an undo, a backend
    // switch): re-simulated from frame 0, the simplest way to rebuild every backend's state.
    // On failure (a backend that cannot open here) the old simulation stays and the status
    // line says why.
    [[nodiscard]] bool rebuild(const std::string& scene_text, std::optional<BackendKind> backend);

    void pick(glm::dvec2 at);

    void apply_sketch();

    // The scene text a sketch of `chain` edited: simulated anew, kept (unsaved) and
    // remembered for undo. False (the old scene stays) when it does not rebuild.
    bool take_sketch(const std::string& edited, const std::string& chain);
    // A sketch that makes a keyed example of chain `name` (of character instance
    // `character`) with the stroke's `shape`, keyed at the frame shown.
    void apply_keyed_sketch(const std::string& name, std::uint32_t character, const rods::ChainShape& shape);

    // The status line's sketch mode: what the next sketch makes, with its influence.
    [[nodiscard]] std::string sketch_status() const;

    void undo();

    void save();

    void key(int key, int mods);

    void mouse_button(int button, int action, int mods);

    void cursor(double x, double y);

    // A left drag by (dx, dy) window pixels: 0.01 rad per pixel.
    void orbit(double dx, double dy);

    void scroll(double dy);

    // Orbiting, panning or zooming while following the scene's camera takes over from
    // where that camera is now.
    void take_camera();
};

/// The GLFW key of a --keys name ("space", "[", "1", ...); none when unknown.
std::optional<int> key_by_name(const std::string& name);

/// The status line in stb_easy_font's pixel font (scaled 2x from 1200 columns), on a dark band.
void add_status(render::DrawList& list, const std::string& line);

}  // namespace kodawari::cli
