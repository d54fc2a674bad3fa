// The budget mode of the levels of detail (kodawari/rods/lod_budget.hpp): a cost model of
// a character's frame at each level, and the full distance that keeps a frame within a
// budget, characters promoted to full nearest first.
#include "kodawari/rods/lod_budget.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace kodawari::rods {
namespace {

using Candidate = detail::LodCandidate;

// A character's modelled frame at the posed or hidden level, and what full or reduced
// (`level`) adds to it, us. A reduced character's clip plays every frame, as a full one's.
double posed_us(const LodCosts& c, std::uint32_t chains) {
    return static_cast<double>(c.posed_clip_us) + static_cast<double>(chains) * static_cast<double>(c.posed_chain_us);
}
double extra_us(const LodCosts& c, std::uint32_t chains, Level level) {
    const float chain_us = level == Level::Full ? c.full_chain_us : c.reduced_chain_us;
    return static_cast<double>(c.full_clip_us - c.posed_clip_us) +
           static_cast<double>(chains) * static_cast<double>(chain_us - c.posed_chain_us);
}

}  // namespace

Result<void> validate(const LodCosts& costs, const char* what) {
    auto bad = [&](const std::string& field, const std::string& expected) {
        return make_error(Error::Kind::InvalidInput, std::string(what) + "." + field + ": expected " + expected);
    };
    constexpr float kMost = 1.0e6f;  // a second a chain: a typo, not a cost
    for (const auto& [name, value] :
         {std::pair{"full_chain_us", costs.full_chain_us}, std::pair{"reduced_chain_us", costs.reduced_chain_us},
          std::pair{"posed_chain_us", costs.posed_chain_us}, std::pair{"full_clip_us", costs.full_clip_us},
          std::pair{"posed_clip_us", costs.posed_clip_us}}) {
        if (!(value >= 0.0f && value <= kMost)) return bad(name, "a number of microseconds in [0, 1e6]");
    }
    if (costs.full_chain_us < costs.posed_chain_us) return bad("full_chain_us", "at least posed_chain_us (a full chain costs more than a posed one)");
    if (costs.full_clip_us < costs.posed_clip_us) return bad("full_clip_us", "at least posed_clip_us");
    return {};
}

namespace {

// budget_distance() and the frame's modelled cost at the levels it leaves, in one pass over
// the characters; `candidates` is the caller's scratch (no allocation a frame once grown).
struct Choice {
    float distance;
    double frame_us;
};
Choice choose(const LodView& view, std::span<const glm::vec3> references, std::span<const std::uint32_t> chains,
              const LodCosts& costs, float budget_ms, float scale, std::vector<Candidate>& candidates) {
    assert(references.size() == chains.size() && "a chain count per character");
    // Everyone at the lower levels first; then the characters the view would make full
    // or reduced (chain_level() from posed: the projected-size rule stays the upper bound),
    // nearest first, while the frame stays within the budget. Ties by index: the same bits
    // always.
    double frame_us = 0.0;
    candidates.clear();
    for (std::uint32_t c = 0; c < references.size(); ++c) {
        frame_us += posed_us(costs, chains[c]);
        const Level level = chain_level(view, references[c], Level::Posed);
        if (!dynamic(level)) continue;
        candidates.push_back({glm::dot(references[c] - view.position, view.forward), c, extra_us(costs, chains[c], level)});
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
        return a.depth < b.depth || (a.depth == b.depth && a.character < b.character);
    });
    const double budget_us = double{budget_ms} * 1000.0 / double{scale};
    std::size_t promoted = 0;
    while (promoted < candidates.size() && frame_us + candidates[promoted].extra_us <= budget_us) {
        frame_us += candidates[promoted].extra_us;
        ++promoted;
    }
    if (promoted == candidates.size()) return {kNoDistanceCap, frame_us};
    // A character as deep as the first one left out would be full too: stop before the
    // depth they share.
    while (promoted > 0 && candidates[promoted - 1].depth == candidates[promoted].depth) {
        --promoted;
        frame_us -= candidates[promoted].extra_us;
    }
    return {promoted == 0 ? -kNoDistanceCap : candidates[promoted - 1].depth, frame_us};
}

}  // namespace

float budget_distance(const LodView& view, std::span<const glm::vec3> references, std::span<const std::uint32_t> chains,
                      const LodCosts& costs, float budget_ms, float scale) {
    if (!view.enabled) return kNoDistanceCap;
    std::vector<Candidate> candidates;
    return choose(view, references, chains, costs, budget_ms, scale, candidates).distance;
}

double modelled_ms(const LodView& view, std::span<const glm::vec3> references, std::span<const std::uint32_t> chains,
                   const LodCosts& costs) {
    assert(references.size() == chains.size() && "a chain count per character");
    double us = 0.0;
    for (std::size_t c = 0; c < references.size(); ++c) {
        us += posed_us(costs, chains[c]);
        const Level level = chain_level(view, references[c], Level::Posed);
        if (dynamic(level)) us += extra_us(costs, chains[c], level);
    }
    return us / 1000.0;
}

Result<LodBudget> LodBudget::create(float budget_ms, bool measured, const LodCosts& costs, const char* what) {
    if (!(std::isfinite(budget_ms) && budget_ms > 0.0f)) {
        return make_error(Error::Kind::InvalidInput,
                          std::string(what) + ": expected a positive finite number of milliseconds, got " + std::to_string(budget_ms));
    }
    KW_TRY(validate(costs));
    LodBudget out;
    out.budget_ms_ = budget_ms;
    out.measured_ = measured;
    out.costs_ = costs;
    return out;
}

float LodBudget::cap(const LodView& view, std::span<const glm::vec3> references, std::span<const std::uint32_t> chains) {
    if (!view.enabled) return kNoDistanceCap;
    const Choice choice = choose(view, references, chains, costs_, budget_ms_, scale_, candidates_);
    last_modelled_ms_ = choice.frame_us / 1000.0;
    return choice.distance;
}

void LodBudget::observe(double measured_ms) {
    if (!measured_ || !(std::isfinite(measured_ms) && measured_ms > 0.0) || !(last_modelled_ms_ > 0.0)) return;
    // The ratio of what the frame took to what the model priced it at, averaged over
    // about ten frames (an exponential mean) so that one slow frame does not swing the
    // levels; bounded so that a stall cannot make every character posed for long.
    const double ratio = std::clamp(measured_ms / last_modelled_ms_, 0.05, 20.0);
    scale_ = static_cast<float>(0.9 * double{scale_} + 0.1 * ratio);
}

}  // namespace kodawari::rods
