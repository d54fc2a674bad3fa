#pragma once
/// @file
/// The engine's one entry point for simulating a scene (issue 19), what `kodawari run`,
/// `render`, `view` and `bench` and embedding applications use, as Box2D's `b2World_Step`
/// or Jolt's `PhysicsSystem::Update` are: it owns the backends of one kind on one device
/// and runs the frame protocol in its one correct order, so that no caller has to know it:
///
///   per frame f:  birds:  flap and fly one frame (SPEC B)
///                 chains: rigged characters' clips at f (pose backend)
///                         -> chain roots, reference joints, colliders, camera (RodFrame)
///                         -> f == 0: every chain at rest on its rest shape (load)
///                            f > 0:  one rod step (SPEC A.3-A.5)
///                         -> after frame 0, on one Vulkan device: the rigged characters'
///                            part of the input written on the device from then on
///
/// A Simulation is made from a scene file, a parsed Scene or a scene built in code; its
/// outputs are read back (bird poses per frame, the chains' snapshot) or, for drawing,
/// left where they were computed (draw_on()).

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "kodawari/api.hpp"
#include "backend.hpp"
#include "birds/world.hpp"
#include "result.hpp"
#include "rod_backend.hpp"
#include "rod_scene.hpp"
#include "rods/kinematics.hpp"
#include "scene.hpp"

namespace kodawari {

namespace render {
class Renderer;
}

/// One of `count` parts of a scene's instances, for baking a scene over several processes
/// or machines (issue 15; kodawari/shards.hpp). Shard `index` holds birds
/// [index * n / count, (index + 1) * n / count) of the scene's n birds and the character
/// instances of the same formula: contiguous ranges, in the scene's order, that cover it
/// once. The scene is built whole (every random draw made) before it is cut, so an
/// instance's frames do not depend on `count`.
struct Shard {
    std::uint32_t index = 0;
    std::uint32_t count = 1;  ///< 1: the whole scene
};

/// Instances [begin, end) of a scene.
struct InstanceRange {
    std::uint32_t begin = 0;
    std::uint32_t end = 0;
    [[nodiscard]] std::uint32_t size() const { return end - begin; }
};

/// The range shard `shard` holds of `n` instances (asserts index < count).
[[nodiscard]] KODAWARI_API InstanceRange shard_range(std::uint32_t n, Shard shard);

/// Which of a scene's instances a Simulation runs: bird_world() holds the scene's birds
/// `birds`, rod_scene() its character instances `characters`.
struct ShardInfo {
    Shard shard;
    InstanceRange birds;
    InstanceRange characters;
    std::uint32_t scene_birds = 0;       ///< the whole scene's
    std::uint32_t scene_characters = 0;  ///< the whole scene's
};

/// What a scene simulates, built from it with every random draw made but no backend:
/// the whole scene, as Simulation builds it before cutting out a shard. What a merge of
/// shards and the rank that writes a distributed bake's output hand to the outputs.
struct SceneWorlds {
    birds::BirdWorld birds;        ///< its frames set to `frames`
    std::optional<RodScene> rods;  ///< none without characters
    std::uint32_t frames = 1;
};

/// Builds the worlds of `scene` for `frames` frames (none: the scene's; >= 1). Errors:
/// the scene's (a route, a character), or frames == 0 (InvalidInput).
[[nodiscard]] KODAWARI_API Result<SceneWorlds> build_scene_worlds(const Scene& scene, std::optional<std::uint32_t> frames);

/// How a Simulation runs.
struct SimulationOptions {
    /// The backends' kind; none: "auto", vulkan when a GPU opens and can hold the scene
    /// (its buffers within the device's limits), else cpu (Simulation::fallback_reason()
    /// then says why): also when the device is a CPU (lavapipe; auto_passes_over()), where
    /// the cpu backend is several times faster, unless BackendOptions::device names it.
    /// A device asked for that matches none is an error, never a fallback.
    std::optional<BackendKind> backend{};
    /// Device, validation, cpu threads, and a device to run on (a renderer's); without
    /// one, the vulkan backends share one device the Simulation opens.
    BackendOptions options{};
    /// Simulate this many frames instead of the scene's (>= 1).
    std::optional<std::uint32_t> frames{};
    /// With the vulkan backends: write the rigged characters' rod input on the device
    /// from its poses there (nothing read back per frame); false keeps it on the host
    /// (benchmarks compare the two).
    bool rod_inputs_on_device = true;
    /// Simulate this part of the scene's instances only (the default: all of them).
    Shard shard{};
};

/// What step() hands back of the frames it simulates. Empty spans: nothing read back.
struct StepOutput {
    std::span<gpu::BirdPose> bird_poses;  ///< frames x birds, frame-major, or empty
    std::span<gpu::BirdDiag> bird_diag;   ///< frames x birds, or empty
};

/// Time spent so far, per domain, in the backends' own calls (the pose backends'
/// clip evaluation is counted apart from the chains' step).
///
/// The first call into a backend also compiles its kernels (lavapipe compiles a pipeline
/// at its first dispatch) and uploads its world, so it is kept apart: a per-frame figure
/// is the steady one, over what came after it.
struct SimulationTiming {
    double bird_seconds = 0.0;          ///< wall time in the bird backend after its first call
    std::uint64_t bird_frames = 0;      ///< the frames of those calls
    double bird_first_seconds = 0.0;    ///< wall time of the first call (kernels compiled)
    std::uint64_t bird_first_frames = 0;  ///< the frames of the first call
    double bird_first_gpu_ms = -1.0;    ///< its GPU time (< 0: none measured)
    double bird_gpu_ms = 0.0;           ///< GPU time of the calls after the first (when every call had timestamps)
    bool bird_gpu_timed = true;
    /// Frames 0 and 1 of the chains: loaded and put at rest, then the first step, each the
    /// first dispatch of its kernels (compiled then on lavapipe).
    double chain_warmup_seconds = 0.0;
    double chain_seconds = 0.0;         ///< wall time in the rod backend's steps from frame 2 on
    double chain_gpu_ms = 0.0;          ///< GPU time of those steps
    double pose_ms = 0.0;               ///< the pose backends' clip evaluation (and read back)
};

/// A scene simulated frame after frame on backends of one kind.
class KODAWARI_API Simulation {
public:
    /// Loads the scene file at `path` (SCENE.json) and opens its backends.
    [[nodiscard]] static Result<std::unique_ptr<Simulation>> open(const std::string& path, const SimulationOptions& options);
    /// Opens the backends for a scene parsed (parse_scene) or built in code.
    [[nodiscard]] static Result<std::unique_ptr<Simulation>> create(Scene scene, const SimulationOptions& options);

    ~Simulation();
    Simulation(const Simulation&) = delete;
    Simulation& operator=(const Simulation&) = delete;

    [[nodiscard]] const Scene& scene() const;
    /// The birds (empty without flocks).
    [[nodiscard]] const birds::BirdWorld& bird_world() const;
    /// The part of the scene this simulation runs (SimulationOptions::shard).
    [[nodiscard]] const ShardInfo& shard() const;
    /// The characters' chains and kinematics; null without characters.
    [[nodiscard]] const RodScene* rod_scene() const;
    /// The kind every backend is of ("auto" resolved).
    [[nodiscard]] BackendKind backend() const;
    /// Why "auto" runs on the CPU ("" when it did not fall back).
    [[nodiscard]] const std::string& fallback_reason() const;
    /// What the backends run on ("llvmpipe (LLVM 15.0.6, 256 bits)", "2 threads").
    [[nodiscard]] std::string device() const;
    /// Frames of the simulation: SimulationOptions::frames, else the scene's.
    [[nodiscard]] std::uint32_t frame_count() const;
    /// The frame simulated last; none before the first step().
    [[nodiscard]] std::optional<std::uint32_t> frame() const;

    /// The camera that drives the view-dependent rest shapes of the frames simulated from
    /// now on (SPEC A.3); none: the scene's camera at each frame. A viewer's orbit camera.
    void set_view_camera(std::optional<rods::Camera> camera);

    /// Simulates the next `frames` frames (the first step() simulates frame 0); at most
    /// frame_count() in all. `out`'s spans hold frames x birds entries or are empty.
    [[nodiscard]] Result<void> step(std::uint32_t frames = 1, const StepOutput& out = {});
    /// Simulates up to frame `target` (clamped to the last): forwards from the current
    /// frame, or again from frame 0 when going back. Nothing when it is the current one.
    [[nodiscard]] Result<void> seek(std::uint32_t target);

    /// The chains' state after the last step (read back from a device).
    [[nodiscard]] Result<void> read_chains(ChainSnapshot& out);
    /// The last frame's kinematic input of the chains as given to the rod backend: on one
    /// Vulkan device the rigged characters' entries in it are not this frame's (they are
    /// written on the device), see host_chain_input().
    [[nodiscard]] const rods::RodFrame& chain_input() const;
    /// The last frame's kinematic input with every entry on the host (the pose matrices
    /// read back when they live on a device): a sketch's root, a paused frame's colliders.
    [[nodiscard]] Result<const rods::RodFrame*> host_chain_input();
    /// Whether the rigged characters' rod input is written on the device.
    [[nodiscard]] bool rod_inputs_on_device() const;

    /// How the state reaches a renderer.
    enum class DrawSource {
        Device,    ///< where it was computed when that is the renderer's device, else read back
        ReadBack,  ///< always read back and uploaded (what a renderer on its own device pays)
    };
    /// Hands the renderer what it draws of this simulation from now on (chains, skinned
    /// meshes, birds); the renderer must outlive that use or be given another simulation.
    [[nodiscard]] Result<void> show_on(render::Renderer& renderer);
    /// This frame's chains, colliders, skinned meshes and bird poses to the renderer given
    /// to show_on(). For a CPU bird backend the poses of the last step are kept for this
    /// (keep_bird_poses()).
    [[nodiscard]] Result<void> draw_on(render::Renderer& renderer, DrawSource source = DrawSource::Device);
    /// Keep the last frame's bird poses on the host at each step (drawing them from a
    /// CPU backend); on by show_on() for backends whose poses are not on the renderer's device.
    void keep_bird_poses(bool keep);

    [[nodiscard]] const SimulationTiming& timing() const;
    /// Validation messages of every backend (one device shared: its count).
    [[nodiscard]] std::uint32_t validation_messages() const;

private:
    struct Impl;
    explicit Simulation(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

/// "auto" and the backends' names: "cpu-reference", "cpu", "vulkan"; none for auto.
[[nodiscard]] KODAWARI_API Result<std::optional<BackendKind>> parse_backend_choice(std::string_view name);

}  // namespace kodawari
