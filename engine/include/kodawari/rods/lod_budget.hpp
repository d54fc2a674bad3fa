#pragma once
/// @file
/// The budget mode of the levels of detail (issue 35, docs/level-of-detail.md "The
/// budget"): instead of a projected size, a frame's cost decides how many characters are
/// full, nearest first. A cost model (LodCosts) prices a character's frame at each level;
/// budget_distance() promotes the nearest characters on the view to full while the
/// modelled frame stays within the budget, and the distance of the last one promoted caps
/// every rod backend's full distance for the frame (RodFrame::full_distance_cap). Bakes
/// price frames by the model alone, so they stay deterministic; an interactive caller
/// (`view`, `bench`) scales the model by what its frames measured (LodBudget).

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "kodawari/core/api.hpp"
#include "kodawari/core/result.hpp"
#include "kodawari/rods/lod.hpp"

namespace kodawari::rods {

/// The full distance that keeps a frame within `budget_ms` by the model `costs` scaled
/// by `scale` (1: the model alone), characters on the view promoted to full nearest
/// first: `references[c]` is character c's reference joint and `chains[c]` its number of
/// chains. Hidden characters (off the view, rod_level()) are never promoted. Returns the
/// depth of the last character promoted (every character at most as deep is full), or
/// -infinity when none fits; the same inputs give the same bits.
[[nodiscard]] KODAWARI_API float budget_distance(const LodView& view, std::span<const glm::vec3> references,
                                                 std::span<const std::uint32_t> chains, const LodCosts& costs,
                                                 float budget_ms, float scale = 1.0f);

/// The modelled cost of a frame, ms: every character at the level the view gives it
/// from `references` (its previous level taken as posed), by `costs`.
[[nodiscard]] KODAWARI_API double modelled_ms(const LodView& view, std::span<const glm::vec3> references,
                                              std::span<const std::uint32_t> chains, const LodCosts& costs);

namespace detail {
/// A character the view would make full, as budget_distance() ranks it.
struct LodCandidate {
    float depth;
    std::uint32_t character;
    double extra_us;  ///< what turning it full adds to the frame
};
}  // namespace detail

/// A frame budget over time. Bakes (measured false) price every frame by the model
/// alone; an interactive caller (measured true) reports each frame's measured cost
/// (observe()) and the model is scaled by their ratio, averaged over about ten frames,
/// so that the budget holds on this machine and backend.
class KODAWARI_API LodBudget {
public:
    /// budget_ms: a positive finite number of milliseconds (InvalidInput naming
    /// `what` otherwise).
    [[nodiscard]] static Result<LodBudget> create(float budget_ms, bool measured, const LodCosts& costs = {},
                                                  const char* what = "budget_ms");

    [[nodiscard]] float budget_ms() const { return budget_ms_; }
    [[nodiscard]] bool measured() const { return measured_; }
    [[nodiscard]] float scale() const { return scale_; }
    [[nodiscard]] const LodCosts& costs() const { return costs_; }
    /// The last cap()'s modelled frame, ms (before the scale; 0 before the first).
    [[nodiscard]] double modelled_ms() const { return last_modelled_ms_; }

    /// This frame's cap on the full distance (budget_distance() at the current scale),
    /// remembering the frame's modelled cost for observe().
    [[nodiscard]] float cap(const LodView& view, std::span<const glm::vec3> references, std::span<const std::uint32_t> chains);
    /// The frame's measured cost, ms (measured budgets only; ignored otherwise or when
    /// not finite and positive).
    void observe(double measured_ms);

private:
    float budget_ms_ = 0.0f;
    bool measured_ = false;
    LodCosts costs_;
    float scale_ = 1.0f;
    double last_modelled_ms_ = 0.0;
    std::vector<detail::LodCandidate> candidates_;  // cap()'s scratch
};

}  // namespace kodawari::rods
