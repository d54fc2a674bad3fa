// Levels of detail against full simulation where it shows: on the scene camera's image
// (issue 35: "every on-screen character's joints stay within 1 pixel, at 1920x1080 on
// the scene camera, of full simulation"). scenes/crowd-10k.json (its `lod`: full from 48
// px) cut to 600 chibis (a 25 x 25 grid, 29 m across) over the whole 8 s of its camera's
// flight, from 90 m out to 12 m, where the nearest characters are a few metres away
// (most start posed and turn full as the camera nears), stepped on every backend with
// the scene's `lod` on and off, and a third time with the reduced level on too
// (lod.reduced_pixels 32: reduced from 48 px down to 32 px). Each frame the runs' joints
// are projected with that frame's camera, as LodView frames it (the settings' 1920 x 1080 and the scene's
// 50 degrees), and the distance between the two images of every joint of every
// character on the image is measured. Every kind steps far posed and hidden chains at
// their levels' rate (rods::chain_rests). The vulkan case writes the rod input on the
// device, where every clip is evaluated every frame; the cpu kinds evaluate those
// characters' clips at the same rate (CrowdAnimator), so both paths are held to the pixel.
//
// Seen failing: with every character posed (bias -4), 1.42 px (before the rate); with the
// rate but the keys measured every frame instead of over the frames a chain kept, 1.60 px.
// Measured at other thresholds before the rate (docs/level-of-detail.md): full from 24 px
// 0.10 px, 48 px 0.22 px, 96 px 0.92 px. With the rate the posed figure is 0.74 px, at
// frames 60 to 66 (one character's tail at 92 m still settling from the start), 0.22 px
// from frame 80 on. The reduced level (cpu/avx512, from frame 60 on): reduced characters
// within 0.16 px at 40 px, 0.13 px at 32 px, 0.10 px at 24 px; posed ones 0.74, 0.91 and
// 1.02 px, all at frame 60 on the character at 92 m still settling from the start (it
// steps every frame within twice the reduced distance): 24 px fails here. From frame 80
// on, at 24 px: full 0.044, reduced 0.098, posed 0.100 px (without the reduced level
// 0.217 and 0.222 px); at 32 px: 0.045, 0.130, 0.134 px.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "kodawari/domains/chains.hpp"
#include "kodawari/rods/lod.hpp"
#include "kodawari/scene/scene.hpp"
#include "kodawari/simulation/simulation.hpp"
#include "test_paths.hpp"

using namespace kodawari;

namespace {

constexpr std::uint32_t kCount = 600;
constexpr std::uint32_t kFrames = 480;
// The first second is measured apart. Every chain starts at rest on its rest shape, and
// as the walk's keyed example of the tail (0.52 m) turns on, full simulation swings the
// tail up through it while a posed tail eases onto it: the two differ by up to 0.6 m
// (10 px at 68 m) in frames 10 to 28, 2 px at frame 31, within a pixel from frame 36 on
// (docs/level-of-detail.md, "What posed leaves out").
constexpr std::uint32_t kSettled = 60;

struct Pixel {
    glm::vec2 at{0.0f};
    bool on_image = false;
};

// `p` on the image of `view`'s camera (pixels from the image's middle), and whether it is
// in front of the camera and inside the image.
Pixel project(const rods::LodView& view, const rods::LodSettings& lod, glm::vec3 p) {
    const glm::vec3 r = p - view.position;
    const float depth = glm::dot(r, view.forward);
    Pixel out;
    if (!(depth > 1e-3f)) return out;
    const float half_h = 0.5f * lod.viewport_height, half_w = half_h * lod.aspect;
    out.at = {glm::dot(r, view.right) / (depth * view.tan_x) * half_w, glm::dot(r, view.up) / (depth * view.tan_y) * half_h};
    out.on_image = std::abs(out.at.x) <= half_w && std::abs(out.at.y) <= half_h;
    return out;
}

std::unique_ptr<Simulation> open(const testing_support::BackendCase& kind, bool lod, float reduced_pixels = 0.0f) {
    auto loaded = load_scene(std::string(KODAWARI_SOURCE_DIR) + "/scenes/crowd-10k.json");
    EXPECT_TRUE(loaded.ok()) << loaded.error().message;
    if (!loaded.ok()) return nullptr;
    Scene scene = std::move(loaded).value();
    scene.crowds[0].count = kCount;
    scene.lod.enabled = lod;
    scene.lod.reduced_pixels = reduced_pixels;
    auto made = Simulation::create(std::move(scene), {.backend = kind.kind, .options = testing_support::backend_options(kind),
                                                      .frames = kFrames});
    EXPECT_TRUE(made.ok()) << made.error().message;
    return made.ok() ? std::move(made).value() : nullptr;
}

class LodPixels : public ::testing::TestWithParam<testing_support::BackendCase> {};

}  // namespace

// Per level of each character (the LOD run's), the largest distance in pixels between a
// joint's images in the two runs, over every character with its reference joint on the
// image; and for scale, the largest a joint of full simulation moves on the image in a
// frame.
TEST_P(LodPixels, OnScreenJointsStayNearFullSimulation) {
    if (GetParam() == BackendKind::Vulkan) {
        if (const std::string why = testing_support::no_vulkan_device_reason(); !why.empty()) GTEST_SKIP() << why;
    }
    // The scene's levels, then with the reduced level on, each against full simulation.
    constexpr float kReducedPixels = 32.0f;
    std::array<std::unique_ptr<Simulation>, 2> runs = {open(GetParam(), true), open(GetParam(), true, kReducedPixels)};
    auto without = open(GetParam(), false);
    ASSERT_TRUE(runs[0] && runs[1] && without);
    const RodScene& scene = *rod_scene(*runs[0]);
    const rods::LodSettings& lod = scene.world.lod;
    ASSERT_TRUE(lod.enabled);
    ASSERT_EQ(lod.reduced_pixels, 0.0f);
    ASSERT_EQ(rod_scene(*runs[1])->world.lod.reduced_pixels, kReducedPixels);
    ASSERT_EQ(lod.viewport_height, 1080.0f);
    ASSERT_NEAR(lod.aspect, 1920.0f / 1080.0f, 1e-6f);

    ChainSnapshot a, b, before;
    std::vector<rods::Level> levels;
    std::array<std::array<double, 4>, 2> worst{};        // per run, per level (rods::Level), from kSettled on
    std::array<double, 2> start_worst{};                 // per run, before kSettled, every level
    std::array<std::array<std::uint64_t, 4>, 2> seen{};  // per run, on-image character-frames per level
    double worst_full_move = 0.0;
    for (std::uint32_t f = 0; f < kFrames; ++f) {
        ASSERT_TRUE(without->step().ok());
        ASSERT_TRUE(read_chains(*without, b).ok());
        auto host = host_chain_input(*without);
        ASSERT_TRUE(host.ok()) << host.error().message;
        const rods::RodFrame& input = *host.value();
        const rods::LodView view = rods::lod_view(lod, input.camera);
        ASSERT_TRUE(view.enabled);
        for (std::size_t run = 0; run < runs.size(); ++run) {
            ASSERT_TRUE(runs[run]->step().ok());
            ASSERT_TRUE(read_chains(*runs[run], a).ok());
            ASSERT_TRUE(read_chain_levels(*runs[run], levels).ok());
            for (std::uint32_t c = 0; c < scene.instances.size(); ++c) {
                if (!project(view, lod, input.reference[c].position).on_image) continue;
                const CharacterInstance& inst = scene.instances[c];
                const std::uint32_t chains = static_cast<std::uint32_t>(scene.characters[inst.character].chains.size());
                const auto level = static_cast<std::size_t>(levels[inst.chain_begin]);
                ASSERT_LT(level, 4u);
                ++seen[run][level];
                for (std::uint32_t k = inst.chain_begin; k < inst.chain_begin + chains; ++k) {
                    const rods::ChainInstance& ci = scene.world.chains[k];
                    EXPECT_EQ(static_cast<std::size_t>(levels[k]), level) << "one character's chains at one level";
                    for (std::uint32_t j = ci.joint_begin; j < ci.joint_begin + scene.world.templ(ci).chain.joint_count; ++j) {
                        const Pixel pa = project(view, lod, a.positions[j]), pb = project(view, lod, b.positions[j]);
                        const double dpx = glm::length(pa.at - pb.at);
                        double& w = f < kSettled ? start_worst[run] : worst[run][level];
                        w = std::max(w, dpx);
                        if (run == 0 && f > 0) {
                            const Pixel p0 = project(view, lod, before.positions[j]);
                            worst_full_move = std::max(worst_full_move, static_cast<double>(glm::length(pb.at - p0.at)));
                        }
                    }
                }
            }
        }
        before = b;
    }
    for (std::size_t run = 0; run < runs.size(); ++run) {
        const auto& n = seen[run];
        const auto& w = worst[run];
        std::printf("[ measured ] %s%s: on-image character-frames full %llu, reduced %llu, posed %llu; largest distance of a "
                    "joint's image from full simulation's at 1920x1080 from frame %u on: full %.3f px, reduced %.3f px, "
                    "posed %.3f px; in the first %u frames %.2f px (full simulation's joints move up to %.2f px a frame)\n",
                    testing_support::case_name(GetParam()).c_str(), run == 1 ? " (reduced level on, 32 px)" : "",
                    static_cast<unsigned long long>(n[0]), static_cast<unsigned long long>(n[3]),
                    static_cast<unsigned long long>(n[1]), kSettled, w[0], w[3], w[1], kSettled, start_worst[run],
                    worst_full_move);
        EXPECT_GT(n[0], 1000u) << "the run must show full characters";
        EXPECT_GT(n[1], 10000u) << "the run must show posed characters";
        if (run == 1) {
            EXPECT_GT(n[3], 1000u) << "the run must show reduced characters";
        } else {
            EXPECT_EQ(n[3], 0u) << "no reduced level in the scene's settings";
        }
        EXPECT_EQ(n[2], 0u) << "a character on the image is never hidden";
        // The bound: a pixel, once the start's swing has settled.
        EXPECT_LE(w[0], 1.0);
        EXPECT_LE(w[3], 1.0);
        EXPECT_LE(w[1], 1.0);
    }
}

INSTANTIATE_TEST_SUITE_P(All, LodPixels, testing_support::all_backend_kinds(), testing_support::backend_test_name);
