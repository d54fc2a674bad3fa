// From a Scene to a BirdWorld: routes (given or generated, plus jittered variants) and
// every bird's constants. The output must be the same bits on every platform, so the
// random numbers come from std::mt19937_64 (its sequence is fixed by the standard) and
// are mapped to [0, 1) here rather than by std::uniform_*_distribution, whose
// algorithm each standard library chooses for itself.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <kodawari/birds/route_limits.hpp>
#include <kodawari/scene/scene.hpp>

#include "scene/json_reader.hpp"
#include "scene/seeded_random.hpp"

namespace kodawari {
namespace {

using Vec3 = std::array<double, 3>;

// The formation offsets placed so far, in cells at least as wide as their least distance
// (so the 27 cells round a point hold every offset nearer): whether a new one keeps that
// distance from each (a flocking flock's birds start no nearer one
// another than its collision distance, so that no two are within it at the first frame).
class Spacing {
public:
    explicit Spacing(double apart) : apart_(apart), cell_(std::max(apart, 1e-3)) {}
    [[nodiscard]] bool clear(const Vec3& p) const {
        const std::array<std::int64_t, 3> c = cell(p);
        for (std::int64_t dx = -1; dx <= 1; ++dx)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dz = -1; dz <= 1; ++dz) {
                    const auto found = cells_.find(key({c[0] + dx, c[1] + dy, c[2] + dz}));
                    if (found == cells_.end()) continue;
                    for (const Vec3& q : found->second) {
                        const double x = q[0] - p[0], y = q[1] - p[1], z = q[2] - p[2];
                        if (x * x + y * y + z * z < apart_ * apart_) return false;
                    }
                }
        return true;
    }
    void add(const Vec3& p) { cells_[key(cell(p))].push_back(p); }

private:
    [[nodiscard]] std::array<std::int64_t, 3> cell(const Vec3& p) const {
        return {static_cast<std::int64_t>(std::floor(p[0] / cell_)), static_cast<std::int64_t>(std::floor(p[1] / cell_)),
                static_cast<std::int64_t>(std::floor(p[2] / cell_))};
    }
    static std::uint64_t key(const std::array<std::int64_t, 3>& c) {
        // 24 bits an axis: cells further apart than 2^24 may share a key, which only adds
        // candidates (clear() compares the distances themselves).
        const auto u = [](std::int64_t v) { return static_cast<std::uint64_t>(v + (std::int64_t{1} << 23)) & 0xFFFFFFu; };
        return (u(c[0]) << 48) | (u(c[1]) << 24) | u(c[2]);
    }
    double apart_, cell_;
    std::unordered_map<std::uint64_t, std::vector<Vec3>> cells_;
};

// Purposes of the random streams. Each draws from its own generator so that, say,
// changing the trail does not move every bird's offset.
enum class Stream : std::uint64_t {
    Waypoints = 1,
    Variants = 2,
    Offset = 3,
    TimeOffset = 4,
    Speed = 5,
    Frequency = 6,
    Amplitude = 7,
    Phase = 8,
};

using Random = scene_detail::SeededRandom;

// a * b rounded on its own. Compilers may fuse `c + a * b` into one FMA (GCC does by
// default on targets that have one), which rounds once instead of twice and would make
// the scene's bits depend on the CPU; a product that comes back from a call that is
// not inlined cannot be fused.
[[gnu::noinline]] double separate_product(double a, double b) { return a * b; }

Vec3 to_vec3(const std::array<float, 3>& p) {
    return {static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2])};
}
std::array<float, 3> to_float3(const Vec3& p) {
    return {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
}
Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 div(const Vec3& a, double d) { return {a[0] / d, a[1] / d, a[2] / d}; }
double norm(const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// P'(u) / 3 and P''(u) / 6 of a cubic Bezier segment (constant factors cancel in
// the ratios they are used for, except the curvature, which puts them back).
Vec3 bezier_d1(const std::array<Vec3, 4>& b, double u) {
    const double v = 1.0 - u;
    Vec3 d{};
    for (std::size_t i = 0; i < 3; ++i) {
        d[i] = v * v * (b[1][i] - b[0][i]) + 2.0 * u * v * (b[2][i] - b[1][i]) + u * u * (b[3][i] - b[2][i]);
    }
    return d;
}
Vec3 bezier_d2(const std::array<Vec3, 4>& b, double u) {
    const double v = 1.0 - u;
    Vec3 d{};
    for (std::size_t i = 0; i < 3; ++i) {
        d[i] = v * (b[2][i] - 2.0 * b[1][i] + b[0][i]) + u * (b[3][i] - 2.0 * b[2][i] + b[1][i]);
    }
    return d;
}

// The Bezier control points of segment k through the waypoints, C1 at every junction:
// Catmull-Rom tangents turned into handles, B1 = P_k + (P_{k+1} - P_{k-1}) / 6 and
// B2 = P_{k+1} - (P_{k+2} - P_k) / 6. Open ends use a mirrored phantom waypoint, so the
// end handles point at the neighbouring waypoint.
std::array<Vec3, 4> segment_controls(const std::vector<Vec3>& w, std::size_t k, bool loop) {
    const auto n = static_cast<std::ptrdiff_t>(w.size());
    const auto at = [&](std::ptrdiff_t i) -> Vec3 {
        if (loop) return w[static_cast<std::size_t>(((i % n) + n) % n)];
        if (i < 0) return sub(add(w[0], w[0]), w[1]);
        if (i >= n) return sub(add(w[w.size() - 1], w[w.size() - 1]), w[w.size() - 2]);
        return w[static_cast<std::size_t>(i)];
    };
    const auto i = static_cast<std::ptrdiff_t>(k);
    const Vec3 p0 = at(i);
    const Vec3 p1 = at(i + 1);
    return {p0, add(p0, div(sub(p1, at(i - 1)), 6.0)), sub(p1, div(sub(at(i + 2), p0), 6.0)), p1};
}

// Limits that make a generated route one a bird could fly (SPEC B.7 lists "routes a
// real bird could not fly" among the seed's gaps): waypoints apart, no turn sharper
// than 120 degrees at a waypoint, no chord steeper than 30 degrees, and on the curve no
// climb or dive steeper than 45 degrees or the bird's own limits, and no radius below
// the bird's tightest turn at its speed (FlyableLimits).

// sin and cos of the limits as literals: libm's trigonometry may differ in the last bit
// between platforms, and a threshold that moves could flip a draw.
constexpr double kCosMaxTurn = -0.5;                   // cos 120 deg
constexpr double kSinMaxChordClimb = 0.5;              // sin 30 deg
constexpr double kSinMaxCurveClimb = 0.70710678118654752;  // sin 45 deg

// sin of an angle in [0, pi/2] by its Taylor series (terms to x^17, error < 1e-15):
// arithmetic only, so the limits below are the same bits everywhere, as the literals
// above are.
double portable_sin(double x) {
    double term = x;
    double sum = x;
    for (int n = 1; n <= 8; ++n) {
        term = -term * x * x / static_cast<double>((2 * n) * (2 * n + 1));
        sum += term;
    }
    return sum;
}
double portable_cos(double x) { return portable_sin(1.5707963267948966 - x); }

// What the flock's bird can fly (docs/wing-types.md "Route limits"): generated routes and
// route variants are drawn within these, so `kodawari run` has nothing to warn about.
struct FlyableLimits {
    double sin_climb = kSinMaxCurveClimb;  // never steeper than the generator's own 45 deg
    double sin_dive = kSinMaxCurveClimb;
    double min_radius = 0.0;  // the tightest turn at the flock's fastest speed (arc-length timing)
};

FlyableLimits flyable_limits(const Scene& scene, const FlockSpec& flock) {
    const birds::WingTypeSpec& wing = birds::wing_type_spec(flock.wing_type);
    FlyableLimits limits;
    limits.sin_climb = std::min(kSinMaxCurveClimb, portable_sin(static_cast<double>(wing.max_climb)));
    limits.sin_dive = std::min(kSinMaxCurveClimb, portable_sin(static_cast<double>(wing.max_dive)));
    const double bank = static_cast<double>(scene.flight.max_bank);
    if (flock.timing == birds::RouteTiming::ArcLength && bank > 0.0) {
        // r_min = v^2 / (g tan(max bank)) at the fastest bird, 1 % over for the rounding of
        // the birds' float speeds.
        const double fastest = static_cast<double>(flock.speed.value_or(wing.cruise_speed)) *
                               (1.0 + static_cast<double>(flock.speed_jitter));
        const double capacity = static_cast<double>(scene.flight.gravity) * portable_sin(bank) / portable_cos(bank);
        limits.min_radius = 1.01 * fastest * fastest / capacity;
    }
    return limits;
}

bool chord_ok(const Vec3& a, const Vec3& b, double min_spacing) {
    const double length = norm(sub(b, a));
    return length >= min_spacing && std::fabs(b[1] - a[1]) <= kSinMaxChordClimb * length;
}

// The direction change at b, between the chords a->b and b->c.
bool turn_ok(const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 in = sub(b, a);
    const Vec3 out = sub(c, b);
    return dot(in, out) >= kCosMaxTurn * norm(in) * norm(out);
}

// Climb, dive and radius of curvature of one segment within the limits, at the samples
// of the route check (birds/route_limits.hpp), so what passes here passes there.
bool segment_flyable(const std::array<Vec3, 4>& b, double min_radius, const FlyableLimits& limits) {
    constexpr int kSamples = static_cast<int>(birds::kRouteCheckSamples);
    for (int j = 0; j <= kSamples; ++j) {
        const double u = static_cast<double>(j) / kSamples;
        const Vec3 d1 = bezier_d1(b, u);
        const double speed = norm(d1);
        if (!(d1[1] <= limits.sin_climb * speed) || !(-d1[1] <= limits.sin_dive * speed)) return false;
        // kappa = |P' x P''| / |P'|^3 with P' = 3 d1 and P'' = 6 d2.
        const double curvature = 2.0 * norm(cross(d1, bezier_d2(b, u))) / (3.0 * speed * speed * speed);
        if (!(curvature * min_radius <= 1.0)) return false;
    }
    return true;
}

// Checks one segment of the curve: it never slows to below 5% of its mean |P'| (far
// from BirdWorld::add_route's cusp limit), no two consecutive control points are close,
// and climb angle and radius of curvature stay within the limits.
bool segment_ok(const std::array<Vec3, 4>& b, double min_spacing, double min_radius, const FlyableLimits& limits) {
    constexpr int kSamples = 32;
    for (std::size_t i = 0; i < 3; ++i) {
        if (!(norm(sub(b[i + 1], b[i])) >= 1e-3 * min_spacing)) return false;
    }
    if (!segment_flyable(b, min_radius, limits)) return false;
    double min_speed = std::numeric_limits<double>::infinity();
    double mean_speed = 0.0;
    for (int j = 0; j <= kSamples; ++j) {
        const double u = static_cast<double>(j) / kSamples;
        const Vec3 d1 = bezier_d1(b, u);
        const double speed = norm(d1);
        min_speed = std::min(min_speed, speed);
        mean_speed += speed / (kSamples + 1);
    }
    return min_speed >= 0.05 * mean_speed;
}

// A unit direction in the xz plane from a "diamond angle" in [0, 4): monotone in the
// true angle (0 = +x, 1 = +z, 2 = -x, 3 = -z) and made of arithmetic only, so it is the
// same bits everywhere, which std::sin and std::cos do not promise.
std::array<double, 2> diamond_direction(double a) {
    double x = 0.0;
    double z = 0.0;
    if (a < 1.0) {
        x = 1.0 - a;
        z = a;
    } else if (a < 2.0) {
        x = 1.0 - a;
        z = 2.0 - a;
    } else if (a < 3.0) {
        x = a - 3.0;
        z = 2.0 - a;
    } else {
        x = a - 3.0;
        z = a - 4.0;
    }
    const double length = std::sqrt(x * x + z * z);
    return {x / length, z / length};
}

// The leader route of a generated_route. Open routes: waypoints drawn uniformly inside
// center +- extent. Loops: waypoint k drawn in the k-th of `segments` sectors around
// the center (inside the ellipse the box encloses, at 50-100% of its radius), so the
// route goes round once and closes without doubling back. Each waypoint is kept only when it satisfies the limits above together with the
// waypoints before it (a segment is checked as soon as the four waypoints that shape it
// exist). A rejected draw is replaced by the next draw of the same stream, and a route
// that runs into a dead end is started again from the stream's current state, so the
// result depends on the seed alone.
Result<birds::RouteSpec> generate_route(const GeneratedRouteSpec& gen, const FlyableLimits& limits, const std::string& file,
                                        const std::string& path) {
    const std::size_t count = gen.loop ? gen.segments : gen.segments + 1;
    const std::size_t segments = gen.segments;
    const Vec3 center = to_vec3(gen.center);
    const Vec3 extent = to_vec3(gen.extent);
    // Loops share a perimeter of about 2 pi * 0.75 * mean radius among their segments.
    const double loop_chord = 2.0 * 3.14159265358979323846 * 0.75 * 0.5 * (extent[0] + extent[2]) / static_cast<double>(count);
    const double box_spacing = 0.3 * std::max({extent[0], extent[1], extent[2]});
    const double min_spacing = gen.loop ? std::min(box_spacing, 0.3 * loop_chord) : box_spacing;
    const double min_radius = std::max(0.5 * min_spacing, limits.min_radius);
    constexpr int kRouteAttempts = 256;
    constexpr int kPointAttempts = 1000;

    // Whether the segments that the newest waypoint (index k) completes are flyable.
    const auto new_segments_ok = [&](const std::vector<Vec3>& w) {
        const std::size_t k = w.size() - 1;
        std::size_t first = 0;
        std::size_t last = 0;  // one past
        if (!gen.loop) {
            // Segment j needs waypoints up to j + 2 (the last one uses a phantom).
            first = k >= 2 ? k - 2 : 0;
            last = k + 1 == count ? segments : (k >= 2 ? k - 1 : 0);
        } else if (k + 1 < count) {
            // Segment j needs j - 1 .. j + 2; segment 0 waits for the wrap-around.
            first = k >= 3 ? k - 2 : 0;
            last = k >= 3 ? k - 1 : 0;
        } else {
            first = k >= 2 ? k - 2 : 0;
            last = segments;
        }
        for (std::size_t j = first; j < last; ++j) {
            if (!segment_ok(segment_controls(w, j, gen.loop), min_spacing, min_radius, limits)) return false;
        }
        if (gen.loop && k + 1 == count && !segment_ok(segment_controls(w, 0, true), min_spacing, min_radius, limits)) return false;
        return true;
    };

    Random rng(gen.seed, Stream::Waypoints);
    const auto draw_waypoint = [&](std::size_t k, bool clockwise, double w_last_y) {
        Vec3 p{};
        if (!gen.loop) {
            for (std::size_t i = 0; i < 3; ++i) p[i] = center[i] + separate_product(extent[i], rng.symmetric());
            return p;
        }
        const double sector = static_cast<double>(k) + 0.15 + separate_product(0.7, rng.unit());
        const std::array<double, 2> dir = diamond_direction(4.0 * sector / static_cast<double>(count));
        const double radius = 0.5 + 0.5 * rng.unit();  // 0.5 * u is exact
        const double x = clockwise ? -dir[0] : dir[0];
        p[0] = center[0] + separate_product(separate_product(extent[0], radius), x);
        // Heights walk from the previous waypoint by at most 0.4 of a chord, so short
        // chords of many-segment loops are not mostly too steep to keep.
        const double step = std::min(extent[1], 0.4 * loop_chord);
        p[1] = k == 0 ? center[1] + separate_product(extent[1], rng.symmetric())
                      : std::clamp(w_last_y + separate_product(step, rng.symmetric()), center[1] - extent[1],
                                   center[1] + extent[1]);
        p[2] = center[2] + separate_product(separate_product(extent[2], radius), dir[1]);
        return p;
    };
    for (int attempt = 0; attempt < kRouteAttempts; ++attempt) {
        std::vector<Vec3> w;
        w.reserve(count);
        const bool clockwise = rng.unit() < 0.5;
        bool placed_all = true;
        for (std::size_t k = 0; k < count && placed_all; ++k) {
            bool placed = false;
            for (int tries = 0; tries < kPointAttempts && !placed; ++tries) {
                const Vec3 p = draw_waypoint(k, clockwise, k > 0 ? w[k - 1][1] : 0.0);
                bool ok = true;
                if (k >= 1) ok = ok && chord_ok(w[k - 1], p, min_spacing);
                // A turn below 180 degrees also keeps P_k apart from P_{k-2}, so the
                // Catmull-Rom tangent at P_{k-1} does not vanish.
                if (k >= 2) ok = ok && turn_ok(w[k - 2], w[k - 1], p);
                if (gen.loop && k + 1 == count) {
                    // Closing: the last chord returns to P_0, with the turns at P_last and P_0.
                    ok = ok && chord_ok(p, w[0], min_spacing) && turn_ok(w[k - 1], p, w[0]) && turn_ok(p, w[0], w[1]);
                }
                if (!ok) continue;
                w.push_back(p);
                if (new_segments_ok(w)) {
                    placed = true;
                } else {
                    w.pop_back();
                }
            }
            placed_all = placed;
        }
        if (!placed_all) continue;
        birds::RouteSpec route;
        route.loop = gen.loop;
        route.points.reserve(3 * segments + 1);
        for (std::size_t j = 0; j < segments; ++j) {
            const std::array<Vec3, 4> b = segment_controls(w, j, gen.loop);
            for (std::size_t i = 0; i < 3; ++i) route.points.push_back(to_float3(b[i]));
        }
        route.points.push_back(to_float3(gen.loop ? w[0] : w[count - 1]));
        return route;
    }
    return make_error(Error::Kind::InvalidInput,
                      file + ": " + path + ": expected an extent that leaves room for " + std::to_string(count) +
                          " waypoints at least " + scene_detail::format_number(min_spacing) +
                          " m apart on a smooth route with no turn tighter than " +
                          scene_detail::format_number(std::round(10.0 * min_radius) / 10.0) +
                          " m (the bird's at its speed), got none in " + std::to_string(kRouteAttempts) +
                          " attempts (make extent larger in more than one axis, use fewer segments, or fly slower)");
}

// A copy of `leader` whose junction points (3k) move by a random vector in
// [-jitter, jitter]^3, each together with its two handles so the route stays C1. The
// first and last points of a loop are one junction and move together.
birds::RouteSpec make_variant(const birds::RouteSpec& leader, double jitter, Random& rng) {
    birds::RouteSpec variant = leader;
    const std::size_t last = leader.points.size() - 1;
    const std::size_t junctions = last / 3 + 1;
    Vec3 first_move{};
    for (std::size_t k = 0; k < junctions; ++k) {
        Vec3 move{};
        if (leader.loop && k == junctions - 1) {
            move = first_move;
        } else {
            for (std::size_t i = 0; i < 3; ++i) move[i] = separate_product(jitter, rng.symmetric());
        }
        if (k == 0) first_move = move;
        const std::size_t j = 3 * k;
        for (std::size_t index : {j - 1, j, j + 1}) {
            // j - 1 wraps around for k = 0; the bound check drops it with index > last.
            if (index > last) continue;
            variant.points[index] = to_float3(add(to_vec3(leader.points[index]), move));
        }
    }
    return variant;
}

Result<void> add_flock(const Scene& scene, const FlockSpec& flock, std::size_t flock_index, birds::BirdWorld& world) {
    const std::string flock_path = "$.flocks[" + std::to_string(flock_index) + "]";
    const FlyableLimits limits = flyable_limits(scene, flock);
    birds::RouteSpec leader;
    std::string route_path;
    if (flock.route) {
        leader = *flock.route;
        route_path = flock_path + ".route";
    } else if (flock.generated_route) {
        route_path = flock_path + ".generated_route";
        // Within the bird's limits where the box leaves room for such a route; else within
        // the generator's own (45 degrees, half the waypoint spacing), as before the bird's
        // limits were known: the scene still builds, and the route check says where.
        auto generated = generate_route(*flock.generated_route, limits, scene.path, route_path);
        if (!generated) generated = generate_route(*flock.generated_route, FlyableLimits{}, scene.path, route_path);
        KW_SCENE_ASSIGN(leader, std::move(generated));
    } else {
        return make_error(Error::Kind::InvalidInput,
                          scene.path + ": " + flock_path + ": expected exactly one of \"route\" and \"generated_route\", got neither");
    }
    leader.timing = flock.timing;
    // A user's model hovers only if it is mapped onto a hovering type, which none is yet.
    const birds::WingTypeSpec& bird_type = birds::wing_type_spec(flock.wing_type);
    const bool can_hover = !flock.model && bird_type.can_hover;
    const std::string type_name = flock.model ? flock.model->name : std::string(bird_type.name);
    for (std::size_t k = 0; k < leader.modes.size(); ++k) {
        if (leader.modes[k] == birds::SegmentMode::Hover && !can_hover) {
            return make_error(Error::Kind::InvalidInput, scene.path + ": " + route_path + ".modes[" + std::to_string(k) +
                                                             "]: \"hover\" needs a bird that can hover (\"hummingbird\"); a " +
                                                             type_name + " cannot");
        }
    }

    const std::uint32_t variants = std::max(flock.formation.route_variants, 1u);
    const std::string what = scene.path + ": " + route_path;
    const auto first_route = static_cast<std::uint32_t>(world.routes.size());
    Random variant_rng(flock.seed, Stream::Variants);
    // A variant is redrawn (from the same stream, so the result depends on the seed alone)
    // until its segments are as flyable as the limits ask; a leader that is not (an
    // explicit route the author drew too tight) cannot give such variants, and after
    // kVariantAttempts the first draw stays: the route check then says where.
    constexpr int kVariantAttempts = 64;
    const auto flyable = [&](const birds::RouteSpec& r) {
        for (std::size_t k = 0; 3 * k + 3 < r.points.size(); ++k) {
            const std::array<Vec3, 4> b = {to_vec3(r.points[3 * k]), to_vec3(r.points[3 * k + 1]),
                                           to_vec3(r.points[3 * k + 2]), to_vec3(r.points[3 * k + 3])};
            if (!segment_flyable(b, limits.min_radius, limits)) return false;
        }
        return true;
    };
    const bool leader_flyable = flyable(leader);
    for (std::uint32_t v = 0; v < variants; ++v) {
        birds::RouteSpec route = leader;
        if (v > 0) {
            route = make_variant(leader, static_cast<double>(flock.formation.jitter), variant_rng);
            for (int attempt = 1; leader_flyable && attempt < kVariantAttempts && !flyable(route); ++attempt) {
                route = make_variant(leader, static_cast<double>(flock.formation.jitter), variant_rng);
            }
        }
        auto added = world.add_route(route, what);
        if (!added.ok()) {
            Error error = added.error();
            if (v > 0) {
                error.message += " (in route variant " + std::to_string(v) + " of " + std::to_string(variants) +
                                 ", made by moving the junction points by up to " + flock_path + ".formation.jitter = " +
                                 scene_detail::format_number(static_cast<double>(flock.formation.jitter)) + " m)";
            }
            return error;
        }
    }

    // A user's bird takes the figures derived from its wing (docs/bird-models.md) and the
    // type after the built-in ones and the models before it.
    const birds::WingTypeSpec& wing = birds::wing_type_spec(flock.wing_type);
    std::uint32_t type = static_cast<std::uint32_t>(flock.wing_type);
    float cruise_speed = wing.cruise_speed, flap_frequency = wing.flap_frequency, wing_amplitude = wing.amplitude;
    gpu::vec4 flight = birds::flight_params(wing);
    gpu::vec4 shape = birds::shape_params(wing);
    if (flock.model) {
        auto known = std::find(world.models.begin(), world.models.end(), flock.model);
        if (known == world.models.end()) known = world.models.insert(world.models.end(), flock.model);
        type = static_cast<std::uint32_t>(birds::kWingTypeCount + static_cast<std::size_t>(known - world.models.begin()));
        cruise_speed = flock.model->flight.cruise_speed;
        flap_frequency = flock.model->flight.flap_frequency;
        wing_amplitude = flock.model->flight.amplitude;
        flight = birds::model_flight_params(*flock.model);
        shape = {flock.model->measure.body_length, flock.model->measure.wingspan, 0.0f, 0.0f};
    }
    const double speed = static_cast<double>(flock.speed.value_or(cruise_speed));
    const double frequency = static_cast<double>(flock.frequency.value_or(flap_frequency));
    const double amplitude = static_cast<double>(flock.amplitude.value_or(wing_amplitude));
    const std::array<double, 3> spread = to_vec3(flock.formation.spread);
    const auto trail = static_cast<double>(flock.formation.trail);
    const bool takes_off = !leader.modes.empty() && leader.modes.front() == birds::SegmentMode::TakeOff;
    const auto phase_jitter = static_cast<double>(flock.phase_jitter);

    Random offset_rng(flock.seed, Stream::Offset);
    Random time_rng(flock.seed, Stream::TimeOffset);
    Random speed_rng(flock.seed, Stream::Speed);
    Random frequency_rng(flock.seed, Stream::Frequency);
    Random amplitude_rng(flock.seed, Stream::Amplitude);
    Random phase_rng(flock.seed, Stream::Phase);
    const auto jittered = [](double base, float jitter, Random& rng) {
        return static_cast<float>(base * (1.0 + separate_product(static_cast<double>(jitter), rng.symmetric())));
    };

    // A flocking flock's offsets keep its collision distance: a draw nearer an earlier one
    // is drawn again, at most 16 times (a formation too small for its birds keeps the
    // last). Route flocks draw as they always have.
    const double apart = flock.flocking ? static_cast<double>(flock.flocking->collision_distance) : 0.0;
    Spacing spacing(apart);
    for (std::uint32_t b = 0; b < flock.count; ++b) {
        gpu::BirdParams p{};
        for (int attempt = 0;; ++attempt) {
            double u[3] = {offset_rng.symmetric(), offset_rng.symmetric(), offset_rng.symmetric()};
            // Uniform in the ellipsoid: the box's draws again until one falls in the unit
            // ball (on average 1.9 draws of three; the stream is the offsets' own).
            while (flock.formation.shape == FormationSpec::Shape::Ellipsoid && u[0] * u[0] + u[1] * u[1] + u[2] * u[2] > 1.0) {
                for (double& c : u) c = offset_rng.symmetric();
            }
            p.offset.x = static_cast<float>(spread[0] * u[0]);
            p.offset.y = static_cast<float>(spread[1] * u[1]);
            p.offset.z = static_cast<float>(spread[2] * u[2]);
            if (apart <= 0.0) break;
            const Vec3 at{p.offset.x, p.offset.y, p.offset.z};
            if (attempt == 15 || spacing.clear(at)) {
                spacing.add(at);
                break;
            }
        }
        // On a route that takes off, a bird further back leaves its perch later (a negative
        // time offset: docs/flight-modes.md F.2); elsewhere it is further along the route.
        p.offset.w = static_cast<float>(trail * time_rng.unit());
        if (takes_off) p.offset.w = -p.offset.w;
        p.motion.x = jittered(speed, flock.speed_jitter, speed_rng);
        p.motion.y = jittered(frequency, flock.frequency_jitter, frequency_rng);
        p.motion.z = jittered(amplitude, flock.amplitude_jitter, amplitude_rng);
        // A draw just below 1 can round up to 1.0f, which is phase 0 of the next cycle.
        float phase = static_cast<float>(phase_jitter * phase_rng.unit());
        if (phase >= 1.0f) phase = 0.0f;
        p.motion.w = phase;
        p.ids.x = first_route + b % variants;
        p.ids.y = type;
        if (flock.flocking) {
            p.ids.z = world.driven++;
            p.ids.w = KW_BIRD_DRIVEN;
        }
        p.flight = flight;
        p.shape = shape;
        world.birds.push_back(p);
    }
    return {};
}

}  // namespace

Result<birds::BirdWorld> build_bird_world(const Scene& scene) {
    birds::BirdWorld world;
    world.fps = scene.fps;
    world.frames = scene.frame_count();
    world.settings = scene.flight;
    std::size_t total = 0;
    for (const FlockSpec& flock : scene.flocks) total += flock.count;
    world.birds.reserve(total);
    for (std::size_t i = 0; i < scene.flocks.size(); ++i) KW_TRY(add_flock(scene, scene.flocks[i], i, world));
    return world;
}

}  // namespace kodawari
