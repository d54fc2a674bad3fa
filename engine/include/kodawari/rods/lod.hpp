#pragma once
/// @file
/// Levels of detail of a crowd's chains (issue 35, docs/level-of-detail.md): each
/// character is simulated fully only where the camera sees it large enough for its
/// strands' motion to show; farther ones are posed (their chains carried by their roots
/// and eased onto the rest shape of the current view and pose examples), characters off
/// the camera's frustum hidden (updated as posed). The level is decided per chain by
/// every rod backend from its character's reference joint (shaders/lib/rod_lod.glsl, one
/// definition for GLSL and C++), with hysteresis; the eased posed frame and the
/// velocities it leaves keep every change of level free of a jump.

#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/solver.hpp"
#include "kodawari/rods/view.hpp"

namespace kodawari::rods {

/// A chain's level of detail (ChainState::level; shaders/shared/rods.h KW_RODS_LEVEL_*).
enum class Level : std::uint32_t {
    Full = 0,    ///< every substep (step())
    Posed = 1,   ///< no dynamics: step_posed()
    Hidden = 2,  ///< off the camera's frustum by more than the character's size: step_posed()
    Reduced = 3, ///< step() with reduced_params(): half the substeps and iterations
};

/// Whether a level runs the dynamics (full or reduced) rather than step_posed().
[[nodiscard]] constexpr bool dynamic(Level level) { return level == Level::Full || level == Level::Reduced; }

/// The solver settings a reduced chain steps with (LodSettings::reduced_pixels): twice
/// the longest substep (at most 0.05 s) and half the projection iterations, rounded up.
/// The stiffnesses are per reference substep and compound over the iterations, and damping
/// is a rate (SolverParams), so the reduced chain keeps the full one's stiffness, damping
/// and drag per second and differs by its coarser time steps only (SPEC A.4): about a
/// quarter of a full step's projection work and half the rest at 60 frames/s.
[[nodiscard]] KODAWARI_API SolverParams reduced_params(const SolverParams& params);

/// What a character's frame costs at each level, in microseconds: its clip and each of
/// its chains. Defaults: the cpu backend on 2 cores (AVX2) at scenes/crowd-10k.json
/// (`bench crowd --count 10000`: 87.8 ms of chains for 70 000 full chains, 16.2 ms at
/// every character posed or hidden with the rate; clips 23.2 ms at every frame, 11.9 ms
/// at the levels' rate), docs/level-of-detail.md.
struct LodCosts {
    float full_chain_us = 1.25f;    ///< a full chain's step (every substep)
    float reduced_chain_us = 0.45f; ///< a reduced chain's step (reduced_params()); not ordered against the others
    float posed_chain_us = 0.23f;   ///< a posed or hidden chain's, over its rate's kept frames
    float full_clip_us = 2.3f;      ///< a full character's clip, every frame
    float posed_clip_us = 1.2f;     ///< a posed or hidden character's clip, at its rate
};

/// Checks the costs (each finite and >= 0, full at least posed), naming `what`.field.
[[nodiscard]] KODAWARI_API Result<void> validate(const LodCosts& costs, const char* what = "lod.costs");

/// How a world chooses its characters' levels (RodWorld::lod). Off by default: a world
/// without it steps every chain fully, bit for bit as before.
struct LodSettings {
    bool enabled = false;
    /// The size of a character that its projection measures, m (> 0): what is compared
    /// with full_pixels, and how far it may stick out of the frustum while its reference
    /// joint is outside. 1 m: a chibi's height.
    float size = 1.0f;
    /// A character is full while its size projects to at least this many pixels (at
    /// viewport_height), posed below (> 0). On scenes/crowd-10k.json every joint on the
    /// image stays within 0.10 px of full simulation at 24 px, 0.22 px at 48 px (the
    /// scene's) and 0.92 px at 96 px (docs/level-of-detail.md).
    float full_pixels = 24.0f;
    /// The reduced level (Level::Reduced): 0 (off: full, then posed), or a size in pixels
    /// in (0, full_pixels) down to which a character below full_pixels is simulated at
    /// reduced_params(), posed below (with the same hysteresis).
    float reduced_pixels = 0.0f;
    /// A full character turns posed only below full_pixels x (1 - hysteresis), in [0, 0.9]:
    /// one on the boundary does not flicker between levels.
    float hysteresis = 0.25f;
    /// log2 of a scale on every projected size, in [-8, 8]: +1 treats every character as if
    /// it were twice as near (more of them full), -1 half as near.
    float bias = 0.0f;
    /// How fast a posed chain eases onto its rest shape, 1/s (> 0): each frame of dt it
    /// covers 1 - exp(-settle_rate dt) of the way (posed_blend()). 8/s: 12.5% a frame at
    /// 60 fps, 95% within 0.4 s.
    float settle_rate = 8.0f;
    /// How long a chain that turns full again takes to hand over from its posed motion to
    /// full simulation, s (> 0): its result is the posed frame's moved a share of the way
    /// to the simulated one that grows by dt / blend_time a frame (blend_in()), so that the
    /// dynamics the posed frames left out catch up without a jump. 0.25 s: 15 frames at 60 fps.
    float blend_time = 0.25f;
    /// Far posed and hidden chains step at their levels' rate (chain_rests(): a posed one
    /// every kPosedPeriod-th frame, a hidden one every kHiddenPeriod-th, over the frames it
    /// kept): false steps every chain every frame.
    bool lower_rate = true;
    /// The budget mode (lod_budget.hpp, docs/level-of-detail.md "The budget"): 0 (off), or
    /// a frame's cost in ms that the levels keep within, nearest characters full first,
    /// priced by `costs` (the cost model: a bake's levels never depend on the wall
    /// clock). full_pixels still bounds the full characters: a budget only makes fewer full.
    float budget_ms = 0.0f;
    LodCosts costs;
    /// The camera's projection: vertical field of view (degrees, in (0, 180)), the
    /// image's width over height and its height in pixels (> 0). The scene's camera's
    /// fov; 1920 x 1080 unless told.
    float vertical_fov_deg = 50.0f;
    float aspect = 16.0f / 9.0f;
    float viewport_height = 1080.0f;
};

/// Checks every field's range (InvalidInput naming `what`.field and what was expected).
[[nodiscard]] KODAWARI_API Result<void> validate(const LodSettings& lod, const char* what = "lod");

/// The settings as one frame's camera puts them (what rods_step.comp's push constants
/// carry): the camera's axes, the frustum's tangents and the two distances of the
/// decision. Not enabled for an orthographic camera (every chain full).
struct LodView {
    bool enabled = false;
    glm::vec3 position{0.0f}, forward{0.0f, 0.0f, -1.0f}, right{1.0f, 0.0f, 0.0f}, up{0.0f, 1.0f, 0.0f};
    float tan_x = 1.0f, tan_y = 1.0f;
    float margin = 0.0f;         ///< LodSettings::size
    float full_distance = 0.0f;  ///< depth within which a posed or hidden character turns full
    float stay_distance = 0.0f;  ///< depth within which a full one stays full (>= full_distance)
    /// Depth within which a posed or hidden character turns reduced (>= full_distance), and
    /// within which a full or reduced one stays simulated (>= reduced_distance, >=
    /// stay_distance); full_distance and stay_distance when the reduced level is off.
    float reduced_distance = 0.0f, reduced_stay = 0.0f;
    bool lower_rate = false;     ///< LodSettings::lower_rate (chain_rests())
};
/// RodFrame::full_distance_cap when no budget caps it (lod_budget.hpp).
inline constexpr float kNoDistanceCap = std::numeric_limits<float>::infinity();
/// `cap` (RodFrame::full_distance_cap, the budget's) bounds both distances from above.
[[nodiscard]] KODAWARI_API LodView lod_view(const LodSettings& lod, const Camera& camera, float cap = kNoDistanceCap);

/// The level of a chain whose character's reference joint is at `reference`, given its
/// level at its last step (shaders/lib/rod_lod.glsl). Full when `view` is not enabled.
[[nodiscard]] KODAWARI_API Level chain_level(const LodView& view, glm::vec3 reference, Level previous);

/// The posed and hidden levels' rate (docs/level-of-detail.md, "The rate"; shaders/shared/
/// rods.h KW_RODS_*_PERIOD): a posed chain far from full steps every kPosedPeriod-th frame,
/// a hidden one every kHiddenPeriod-th, over the frames it kept; characters take turns in
/// groups of kRateGroup consecutive ones of the scene, so that every frame costs about the
/// same. CrowdAnimator evaluates those characters' clips at the same rate.
inline constexpr std::uint32_t kPosedPeriod = 2, kHiddenPeriod = 4, kRateGroup = 16;
/// RodFrame::number of a frame made by hand: every chain steps every frame.
inline constexpr std::uint32_t kNoFrameNumber = 0xFFFFFFFFu;

/// The turn of the scene's character `character` at the frame numbered `number`: a chain
/// at a level of period P steps when it is a multiple of P.
[[nodiscard]] constexpr std::uint32_t rate_turn(std::uint32_t number, std::uint32_t character) {
    return number + character / kRateGroup;
}

/// Whether a chain keeps its state this frame instead of stepping (shaders/lib/rod_lod.glsl
/// rod_rests): its character's reference joint at `reference`, its level `level` this frame
/// (chain_level()) and `previous` at its last step, `turn` its character's rate_turn().
/// Never a full or reduced chain, one whose level changed, or one within twice its reduced
/// distance (the full one when the reduced level is off) of the camera unless it is hidden far off the view (off the frustum widened by 20 degrees,
/// rod_far_off_view); never when `view` is not enabled or not lower_rate.
[[nodiscard]] KODAWARI_API bool chain_rests(const LodView& view, glm::vec3 reference, Level level, Level previous,
                                            std::uint32_t turn);

/// The share of the way to its rest shape a posed chain covers in a frame of `dt` s:
/// 1 - exp(-settle_rate dt).
[[nodiscard]] KODAWARI_API float posed_blend(const LodSettings& lod, float dt);

/// The share of full simulation in a chain's result after a frame of `dt` s at `level`,
/// from `previous` (ChainState::blend_in): 0 at the posed and hidden levels, else (full or
/// reduced, dynamic()) min(1, previous + dt / blend_time). A world without levels of detail keeps every chain at 1.
[[nodiscard]] KODAWARI_API float blend_in(const LodSettings& lod, Level level, float previous, float dt);

}  // namespace kodawari::rods
