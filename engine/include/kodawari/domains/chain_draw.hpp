#pragma once
/// @file
/// How the chain domain draws on a render::Renderer: the chains as lit tubes, the
/// procedural characters' colliders as lit capsules and the rigged characters with meshes
/// as skinned meshes, each a render layer drawn from device buffers: the vulkan backends'
/// own when they share the renderer's device (BackendOptions::context =
/// Renderer::device_context(); nothing read back), else read back and uploaded.
/// Simulation::show_on() and draw_on() call these; a caller with its own backends can too.

#include <array>
#include <cstdint>
#include <vector>

#include "kodawari/core/api.hpp"
#include "kodawari/render/draw.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/rods/chain_snapshot.hpp"
#include "kodawari/rods/world.hpp"

namespace kodawari {

class CrowdAnimator;
struct RodScene;
namespace render {
class Renderer;
}  // namespace render

/// The first chain's colour (chain 0 of every world: the one tests look for). Chains are
/// lit (ChainStyle), so a pixel of a chain is this colour scaled by a light factor in
/// [render::kAmbientLight, 1]; joint dots are unlit, exactly this colour.
inline constexpr render::Rgba8 kChainColor{235, 95, 20};
/// The colours chains cycle through (chain c: kChainPalette[c % size]): distinct hues, so
/// that neighbouring strands read apart, the same for the same world every time.
inline constexpr std::array<render::Rgba8, 6> kChainPalette{kChainColor,
                                                            render::Rgba8{40, 150, 160},
                                                            render::Rgba8{150, 85, 205},
                                                            render::Rgba8{225, 180, 40},
                                                            render::Rgba8{205, 45, 80},
                                                            render::Rgba8{60, 115, 215}};
/// Colliders: the procedural characters' bodies, solid capsules and spheres lit as the
/// chains are (f x this, f in [render::kAmbientLight, 1]). A muted clay.
inline constexpr render::Rgba8 kColliderColor{196, 172, 150};
/// At 720 rows (scaled by rows / 720 within [0.5, 2]), a chain is drawn at least this
/// many pixels wide and its joint dots at least this radius, so that a strand a few
/// millimetres thick reads in a preview. A chain too short on screen for its dots to
/// stay apart (its length under 3 dot radii per joint) gets none.
inline constexpr float kChainMinPixels = 4.0f;
inline constexpr float kJointDotMinPixels = 3.0f;

/// How chains are drawn: lit tubes (camera-facing ribbons shaded as cylinders) 2 x
/// thickness wide at the root, tapering to 40% of that at the tip, with minimum widths in
/// pixels; chain c in colors[c % colors.size()]. With RendererOptions::joints, a dot of
/// radius 1.5 x thickness at each joint, unlit in the chain's exact colour.
struct ChainStyle {
    std::vector<render::Rgba8> colors{kChainPalette.begin(), kChainPalette.end()};  ///< not empty
    float min_width_px = kChainMinPixels;                                           ///< at 720 rows
    float min_dot_px = kJointDotMinPixels;                                          ///< at 720 rows
};

/// Draws the chains of `world` (and its colliders) in every following frame (null:
/// none), their state set per frame by draw_chains(). `world` must outlive its use there.
[[nodiscard]] KODAWARI_API Result<void> show_chains(render::Renderer& renderer, const rods::RodWorld* world,
                                                    const ChainStyle& style = {});
/// This frame's chain state: a backend whose state lives on the renderer's device is drawn
/// from its own buffers (nothing read back), any other is read back and uploaded.
[[nodiscard]] KODAWARI_API Result<void> draw_chains(render::Renderer& renderer, RodBackend& backend);
/// This frame's chain state from a snapshot (joint positions, uploaded).
[[nodiscard]] KODAWARI_API Result<void> draw_chains(render::Renderer& renderer, const ChainSnapshot& snapshot);
/// Whether the last draw_chains() drew the backend's own buffers.
[[nodiscard]] KODAWARI_API bool chains_drawn_on_device(const render::Renderer& renderer);
/// This frame's colliders of the world given to show_chains() (drawn as lit capsules in
/// kColliderColor; not those of characters show_skinned() draws as meshes): the vulkan
/// rod backend's input buffer when it lives on the renderer's device, else `input`'s.
[[nodiscard]] KODAWARI_API Result<void> draw_colliders(render::Renderer& renderer, const RodBackend& backend,
                                                       const rods::RodFrame& input);

/// Draws the rigged characters of `scene` that have meshes as their skinned meshes
/// (glTF skins, lit) in every following frame (null: none), their poses set per frame by
/// draw_skinned(). `scene` must outlive its use there.
[[nodiscard]] KODAWARI_API Result<void> show_skinned(render::Renderer& renderer, const RodScene* scene);
/// Frame `frame`'s poses: the clip's with the hair bones where `rods` simulated them
/// (RodScene::rigged_world). When the animator's pose backends and `rods` keep their
/// buffers on the renderer's device, the node matrices are composed there by a kernel
/// (nothing read back); the animator must then be at frame `frame` and `rods`' state
/// frame `frame`'s. Otherwise `rods` is read back and the matrices are composed on the
/// CPU. The animator must pose the scene given to show_skinned().
[[nodiscard]] KODAWARI_API Result<void> draw_skinned(render::Renderer& renderer, const CrowdAnimator& animator, RodBackend& rods,
                                                     std::uint32_t frame);
/// Frame `frame`'s poses from a snapshot of the chains at that frame, composed on the CPU.
[[nodiscard]] KODAWARI_API Result<void> draw_skinned(render::Renderer& renderer, const ChainSnapshot& snapshot, std::uint32_t frame);
/// Whether the last draw_skinned() composed the poses on the device.
[[nodiscard]] KODAWARI_API bool skinned_drawn_on_device(const render::Renderer& renderer);

}  // namespace kodawari
