#pragma once
/// @file
/// How the bird domain draws on a render::Renderer: every bird as its part meshes (lit,
/// in its wing type's colour), one instanced draw per wing type, a render layer drawn from
/// the poses where the vulkan bird backend keeps them when it shares the renderer's device
/// (BackendOptions::context = Renderer::device_context(); nothing read back), else from
/// poses uploaded. Simulation::show_on() and draw_on() call these; a caller with its own
/// backend can too.

#include <span>

#include <kodawari/shared/birds.h>

#include "kodawari/core/api.hpp"
#include "kodawari/backends/backend.hpp"
#include "kodawari/birds/world.hpp"
#include "kodawari/core/result.hpp"

namespace kodawari {

namespace render {
class Renderer;
}  // namespace render

/// Birds smaller than this wingspan in pixels are drawn scaled up to it, so that a far
/// flock stays visible (a preview aid: the birds' positions are exact, their size not).
inline constexpr float kBirdMinPixels = 8.0f;

/// Draws the birds of `world` in every following frame (null: none), their poses set per
/// frame by draw_birds(). `world` must outlive its use there.
[[nodiscard]] KODAWARI_API Result<void> show_birds(render::Renderer& renderer, const birds::BirdWorld* world);
/// This frame's poses where a vulkan bird backend made on the renderer's device keeps
/// them (its last simulated frame); an error for any other backend.
[[nodiscard]] KODAWARI_API Result<void> draw_birds(render::Renderer& renderer, const BirdBackend& backend);
/// This frame's poses, one per bird, uploaded.
[[nodiscard]] KODAWARI_API Result<void> draw_birds(render::Renderer& renderer, std::span<const gpu::BirdPose> poses);

}  // namespace kodawari
