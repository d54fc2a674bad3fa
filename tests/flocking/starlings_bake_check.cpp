// Issue 32's measures of a murmuration, taken on the baked glTF a user gets from
// `kodawari run scenes/starlings.json --compact` (tests/flocking/starlings_bake_test.sh):
//
//   starlings_bake_check SCENE.json BAKE.glb
//
// It reads the file with its own reader (nlohmann::json and the bytes, nothing of the
// exporter's), samples every bird's `<bird>/Body` translation channel at every frame as a
// player does (LINEAR keys, glTF 2.0 Appendix C), and checks what starling flocks show
// (Ballerini et al. 2008, PNAS 105:1232; Cavagna et al. 2010, PNAS 107:11865):
//   - no two starlings closer than 0.1 m (half a body length) at any frame;
//   - while cruising (settled, 6 s on, and away from the falcon's pass): the median
//     nearest-neighbour distance between 0.5 and 2 m, polarization (the length of the mean
//     unit velocity) at least 0.9, and neighbours to the sides more than ahead or behind
//     (the mean cos^2 of the angle between a bird's flight and the direction to its
//     nearest neighbour at most 0.3; 1/3 is no structure), every frame;
//   - the falcon (a bird of another flock, the starlings' predator) first comes within its
//     reach of a starling no earlier than 20 s, splits the flock (the largest group at 3 m
//     single linkage, every half second, below 70% of it) and the flock rejoins (99% in one
//     group again) within 10 s of the split.
// The compaction moves a key by at most 1 mm (its default bound, docs/compact.md), which
// these bounds (0.1 m and up) absorb. Exit 0 when every check holds, 1 when one fails, 2
// when the files are not what it reads; it prints a line every second of the flight.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

namespace {

using json = nlohmann::json;

struct Vec3 {
    float x = 0, y = 0, z = 0;
};
Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

[[noreturn]] void bad(const std::string& what) { throw std::runtime_error(what); }

// The file, mapped: its JSON chunk parsed and its BIN chunk's bytes.
struct Glb {
    const std::uint8_t* bytes = nullptr;
    std::size_t size = 0;
    json doc;
    const std::uint8_t* bin = nullptr;
    std::size_t bin_size = 0;
    explicit Glb(const std::string& path) {
        const int fd = ::open(path.c_str(), O_RDONLY);
        if (fd < 0) bad(path + ": cannot open");
        struct stat st {};
        ::fstat(fd, &st);
        size = static_cast<std::size_t>(st.st_size);
        void* m = size ? ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0) : MAP_FAILED;
        ::close(fd);
        if (m == MAP_FAILED) bad(path + ": cannot map");
        bytes = static_cast<const std::uint8_t*>(m);
        const auto u32 = [&](std::size_t at) {
            std::uint32_t v;
            std::memcpy(&v, bytes + at, 4);
            return v;
        };
        if (size < 20 || u32(0) != 0x46546C67u) bad(path + ": not a .glb (magic)");
        const std::size_t json_size = u32(12);
        if (u32(16) != 0x4E4F534Au || 20 + json_size > size) bad(path + ": the first chunk is not JSON");
        doc = json::parse(bytes + 20, bytes + 20 + json_size);
        const std::size_t at = 20 + json_size;
        if (at + 8 > size || u32(at + 4) != 0x004E4942u) bad(path + ": no BIN chunk");
        bin = bytes + at + 8;
        bin_size = u32(at);
        if (at + 8 + bin_size > size) bad(path + ": the BIN chunk runs past the end");
    }
    ~Glb() { ::munmap(const_cast<std::uint8_t*>(bytes), size); }
    Glb(const Glb&) = delete;
    Glb& operator=(const Glb&) = delete;

    // Accessor `a`'s floats (componentType 5126, `width` of them an element).
    std::vector<float> floats(std::size_t a, std::size_t width) const {
        const json& acc = doc.at("accessors").at(a);
        if (acc.at("componentType").get<int>() != 5126) bad("accessor " + std::to_string(a) + ": expected floats (5126)");
        const json& view = doc.at("bufferViews").at(acc.at("bufferView").get<std::size_t>());
        const std::size_t count = acc.at("count"), stride = view.value("byteStride", width * 4);
        const std::size_t start = view.value("byteOffset", std::size_t{0}) + acc.value("byteOffset", std::size_t{0});
        if (count == 0 || start + (count - 1) * stride + width * 4 > bin_size) bad("accessor " + std::to_string(a) + ": outside the BIN chunk");
        std::vector<float> out(count * width);
        for (std::size_t i = 0; i < count; ++i) std::memcpy(&out[i * width], bin + start + i * stride, width * 4);
        return out;
    }
};

// One bird's Body position at every frame: its translation channel sampled at f / fps.
std::vector<Vec3> sample_translation(const Glb& glb, const json& sampler, std::size_t frames, double fps) {
    if (sampler.value("interpolation", std::string("LINEAR")) != "LINEAR") bad("a Body translation sampler is not LINEAR");
    const std::vector<float> t = glb.floats(sampler.at("input"), 1), v = glb.floats(sampler.at("output"), 3);
    if (v.size() != t.size() * 3) bad("a Body translation sampler's input and output differ in count");
    const auto time = [&t](std::size_t i) { return static_cast<double>(t[i]); };
    std::vector<Vec3> out(frames);
    std::size_t k = 0;
    for (std::size_t f = 0; f < frames; ++f) {
        const double at = static_cast<double>(f) / fps;
        while (k + 1 < t.size() && time(k + 1) <= at) ++k;
        const auto key = [&](std::size_t i) { return Vec3{v[3 * i], v[3 * i + 1], v[3 * i + 2]}; };
        if (k + 1 >= t.size() || at <= time(k)) {
            out[f] = key(k);
            continue;
        }
        const float s = static_cast<float>((at - time(k)) / (time(k + 1) - time(k)));
        const Vec3 a = key(k), b = key(k + 1);
        out[f] = {a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), a.z + s * (b.z - a.z)};
    }
    return out;
}

// A uniform grid over one frame's points (cells of `h` m in a hash table), for the nearest
// neighbour and the pairs within a distance.
class Grid {
public:
    Grid(const Vec3* p, std::size_t n, float h) : p_(p), n_(n), h_(h) {
        std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
        for (std::size_t i = 0; i < n; ++i) keyed[i] = {key(cell(p[i])), static_cast<std::uint32_t>(i)};
        std::sort(keyed.begin(), keyed.end());
        order_.resize(n);
        for (std::size_t i = 0; i < n; ++i) order_[i] = keyed[i].second;
        std::size_t cap = 1;
        while (cap < 2 * n + 2) cap <<= 1;
        table_.assign(cap, Slot{});
        for (std::size_t i = 0; i < n;) {
            std::size_t j = i;
            while (j < n && keyed[j].first == keyed[i].first) ++j;
            std::size_t s = slot(keyed[i].first);
            while (table_[s].used) s = (s + 1) & (table_.size() - 1);
            table_[s] = {keyed[i].first, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j), true};
            i = j;
        }
    }
    // The nearest other point to point i, and its distance: rings of cells outward until
    // the best found is nearer than any point of the next ring can be.
    std::pair<std::uint32_t, float> nearest(std::size_t i) const {
        const std::array<int, 3> c = cell(p_[i]);
        float best2 = std::numeric_limits<float>::infinity();
        std::uint32_t best = UINT32_MAX;
        for (int r = 0; r <= 6; ++r) {
            for (int dx = -r; dx <= r; ++dx)
                for (int dy = -r; dy <= r; ++dy)
                    for (int dz = -r; dz <= r; ++dz) {
                        if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
                        visit({c[0] + dx, c[1] + dy, c[2] + dz}, [&](std::uint32_t j) {
                            if (j == i) return;
                            const Vec3 d = p_[j] - p_[i];
                            const float d2 = dot(d, d);
                            if (d2 < best2 || (d2 == best2 && j < best)) best2 = d2, best = j;
                        });
                    }
            if (r >= 1 && best2 <= (static_cast<float>(r) * h_) * (static_cast<float>(r) * h_)) return {best, std::sqrt(best2)};
        }
        for (std::uint32_t j = 0; j < n_; ++j) {  // an outlier far from the rest
            if (j == i) continue;
            const Vec3 d = p_[j] - p_[i];
            const float d2 = dot(d, d);
            if (d2 < best2) best2 = d2, best = j;
        }
        return {best, std::sqrt(best2)};
    }
    // Every pair (i, j), i < j, nearer than the grid's cell size.
    template <class F>
    void pairs_within(F&& each) const {
        const float h2 = h_ * h_;
        for (std::uint32_t i = 0; i < n_; ++i) {
            const std::array<int, 3> c = cell(p_[i]);
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz)
                        visit({c[0] + dx, c[1] + dy, c[2] + dz}, [&](std::uint32_t j) {
                            if (j <= i) return;
                            const Vec3 d = p_[j] - p_[i];
                            if (dot(d, d) < h2) each(i, j);
                        });
        }
    }

private:
    struct Slot {
        std::uint64_t key = 0;
        std::uint32_t begin = 0, end = 0;
        bool used = false;
    };
    std::array<int, 3> cell(Vec3 q) const {
        return {static_cast<int>(std::floor(q.x / h_)), static_cast<int>(std::floor(q.y / h_)), static_cast<int>(std::floor(q.z / h_))};
    }
    static std::uint64_t key(std::array<int, 3> c) {
        const auto u = [](int v) { return static_cast<std::uint64_t>(static_cast<std::uint32_t>(v + (1 << 20)) & 0x1FFFFFu); };
        return (u(c[0]) << 42) | (u(c[1]) << 21) | u(c[2]);
    }
    std::size_t slot(std::uint64_t k) const { return static_cast<std::size_t>((k * 0x9E3779B97F4A7C15ull) >> 20) & (table_.size() - 1); }
    template <class F>
    void visit(std::array<int, 3> c, F&& each) const {
        const std::uint64_t k = key(c);
        for (std::size_t s = slot(k); table_[s].used; s = (s + 1) & (table_.size() - 1)) {
            if (table_[s].key != k) continue;
            for (std::uint32_t o = table_[s].begin; o < table_[s].end; ++o) each(order_[o]);
            return;
        }
    }
    const Vec3* p_;
    std::size_t n_;
    float h_;
    std::vector<std::uint32_t> order_;
    std::vector<Slot> table_;
};

std::size_t largest_group(const Vec3* p, std::size_t n, float link) {
    std::vector<std::uint32_t> parent(n);
    std::iota(parent.begin(), parent.end(), 0u);
    const auto root = [&](std::uint32_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    Grid(p, n, link).pairs_within([&](std::uint32_t i, std::uint32_t j) {
        const std::uint32_t a = root(i), b = root(j);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    });
    std::vector<std::uint32_t> sizes(n, 0);
    std::size_t largest = 0;
    for (std::uint32_t i = 0; i < n; ++i) largest = std::max<std::size_t>(largest, ++sizes[root(i)]);
    return largest;
}

struct FrameMeasures {
    float min_nn = 0, median_nn = 0, polarization = 0, cos2 = 0, falcon_nearest = 0;
};

int run(const std::string& scene_path, const std::string& glb_path) {
    std::ifstream scene_file(scene_path);
    if (!scene_file) bad(scene_path + ": cannot open");
    const json scene = json::parse(scene_file);
    const double fps = scene.at("fps").get<double>();
    const std::size_t frames = static_cast<std::size_t>(std::llround(scene.at("duration").get<double>() * fps));
    // The starlings: the flock with `flocking`; the falcon: its predator that is a flock.
    std::size_t first = 0, count = 0, falcon = SIZE_MAX, index = 0;
    std::string falcon_flock;
    float reach = 0;
    for (const json& flock : scene.at("flocks")) {
        if (flock.contains("flocking")) {
            first = index, count = flock.at("count");
            for (const json& pred : flock["flocking"].value("predators", json::array()))
                if (pred.contains("flock")) falcon_flock = pred["flock"], reach = pred.value("radius", 15.0f);
        }
        index += flock.at("count").get<std::size_t>();
    }
    index = 0;
    for (const json& flock : scene.at("flocks")) {
        if (flock.at("name") == falcon_flock) falcon = index;
        index += flock.at("count").get<std::size_t>();
    }
    if (count == 0 || falcon == SIZE_MAX) bad(scene_path + ": expected a flocking flock whose predator is another flock's bird");

    const Glb glb(glb_path);
    // Each bird's Body node, by its root's name `<wing type>_<bird index>`; every node
    // above a Body must be without a transform, so that its translation is the world's.
    const json& nodes = glb.doc.at("nodes");
    std::vector<long> parent(nodes.size(), -1);
    for (std::size_t n = 0; n < nodes.size(); ++n)
        for (const json& c : nodes[n].value("children", json::array())) parent.at(c.get<std::size_t>()) = static_cast<long>(n);
    std::map<std::size_t, std::size_t> body_of;  // bird index -> node
    for (std::size_t n = 0; n < nodes.size(); ++n) {
        const std::string name = nodes[n].value("name", "");
        const std::size_t slash = name.find("/Body");
        if (slash == std::string::npos || slash + 5 != name.size()) continue;
        const std::size_t under = name.rfind('_', slash);
        if (under == std::string::npos) bad(glb_path + ": node " + std::to_string(n) + " \"" + name + "\": expected <wing type>_<bird>/Body");
        body_of[std::stoul(name.substr(under + 1, slash - under - 1))] = n;
        for (long a = parent[n]; a >= 0; a = parent[static_cast<std::size_t>(a)])
            for (const char* key : {"translation", "rotation", "scale", "matrix"})
                if (nodes[static_cast<std::size_t>(a)].contains(key))
                    bad(glb_path + ": node " + std::to_string(a) + " above a Body has a " + key + "; expected none");
    }
    std::map<std::size_t, const json*> sampler_of;  // Body node -> its translation sampler
    for (const json& anim : glb.doc.at("animations"))
        for (const json& ch : anim.at("channels"))
            if (ch.at("target").value("path", "") == "translation")
                sampler_of[ch.at("target").at("node").get<std::size_t>()] = &anim.at("samplers").at(ch.at("sampler").get<std::size_t>());
    const auto track = [&](std::size_t bird) {
        const auto b = body_of.find(bird);
        if (b == body_of.end()) bad(glb_path + ": no node for bird " + std::to_string(bird) + "'s Body");
        const auto s = sampler_of.find(b->second);
        if (s == sampler_of.end()) bad(glb_path + ": bird " + std::to_string(bird) + "'s Body has no translation channel");
        return sample_translation(glb, *s->second, frames, fps);
    };
    std::vector<Vec3> pos(frames * count);  // [frame][starling]
    for (std::size_t b = 0; b < count; ++b) {
        const std::vector<Vec3> t = track(first + b);
        for (std::size_t f = 0; f < frames; ++f) pos[f * count + b] = t[f];
    }
    const std::vector<Vec3> hawk = track(falcon);
    std::printf("%s: %zu starlings and the falcon, %zu frames at %.0f fps, read from %s (%.1f MiB)\n", scene_path.c_str(), count, frames,
                fps, glb_path.c_str(), static_cast<double>(glb.size) / 1048576.0);

    // Every frame's measures, the frames shared between threads.
    std::vector<FrameMeasures> m(frames);
    const auto measure = [&](std::size_t f) {
        const Vec3* p = &pos[f * count];
        const Grid grid(p, count, 1.0f);
        std::vector<float> nn(count);
        double cos2 = 0, vx = 0, vy = 0, vz = 0;
        float falcon_nearest = std::numeric_limits<float>::infinity();
        const std::size_t f0 = f == 0 ? 0 : f - 1, f1 = std::min(f + 1, frames - 1);
        for (std::size_t i = 0; i < count; ++i) {
            const auto [j, d] = grid.nearest(i);
            nn[i] = d;
            Vec3 v = pos[f1 * count + i] - pos[f0 * count + i];
            const float speed = std::sqrt(dot(v, v));
            v = {v.x / speed, v.y / speed, v.z / speed};
            vx += static_cast<double>(v.x), vy += static_cast<double>(v.y), vz += static_cast<double>(v.z);
            const Vec3 to = p[j] - p[i];
            const float c = dot(v, to) / d;
            cos2 += static_cast<double>(c * c);
            const Vec3 h = hawk[f] - p[i];
            falcon_nearest = std::min(falcon_nearest, std::sqrt(dot(h, h)));
        }
        std::vector<float> sorted = nn;
        std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(count / 2), sorted.end());
        m[f] = {*std::min_element(nn.begin(), nn.end()), sorted[count / 2],
                static_cast<float>(std::sqrt(vx * vx + vy * vy + vz * vz) / static_cast<double>(count)),
                static_cast<float>(cos2 / static_cast<double>(count)), falcon_nearest};
    };
    {
        const unsigned threads = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
        std::vector<std::thread> pool;
        for (unsigned t = 0; t < threads; ++t)
            pool.emplace_back([&, t] {
                for (std::size_t f = t; f < frames; f += threads) measure(f);
            });
        for (std::thread& t : pool) t.join();
    }
    // The largest group at 3 m every half second.
    const std::size_t every = static_cast<std::size_t>(std::llround(fps / 2));
    std::vector<std::size_t> group(frames, 0);
    for (std::size_t f = 0; f < frames; f += every) group[f] = largest_group(&pos[f * count], count, 3.0f);

    // The falcon's pass, the split and the rejoining.
    std::size_t pass = SIZE_MAX, split = SIZE_MAX, rejoined = SIZE_MAX;
    for (std::size_t f = 0; f < frames; ++f)
        if (pass == SIZE_MAX && m[f].falcon_nearest <= reach) pass = f;
    for (std::size_t f = 0; f < frames; f += every) {
        if (split == SIZE_MAX && group[f] * 10 < count * 7) split = f;
        if (split != SIZE_MAX && rejoined == SIZE_MAX && group[f] * 100 >= count * 99) rejoined = f;
    }
    const auto seconds = [&](std::size_t f) { return f == SIZE_MAX ? -1.0 : static_cast<double>(f) / fps; };
    // Cruising: from 6 s (settled from the formation it starts in), outside the falcon's
    // pass (from its first reach to the rejoining, or to the end without one).
    const std::size_t settled = static_cast<std::size_t>(std::llround(6 * fps));
    const auto cruising = [&](std::size_t f) { return f >= settled && (pass == SIZE_MAX || f < pass || (rejoined != SIZE_MAX && f > rejoined)); };

    std::printf("   t (s)  nearest (m)  median nn (m)  polarization  cos^2   falcon's nearest (m)  largest group at 3 m\n");
    for (std::size_t f = 0; f < frames; f += static_cast<std::size_t>(std::llround(fps))) {
        std::printf("  %5.1f  %10.3f  %13.2f  %12.3f  %6.3f  %20.1f  %zu%s\n", seconds(f), static_cast<double>(m[f].min_nn),
                    static_cast<double>(m[f].median_nn), static_cast<double>(m[f].polarization), static_cast<double>(m[f].cos2),
                    static_cast<double>(m[f].falcon_nearest), group[f], cruising(f) ? "" : "   (not cruising)");
    }
    float nearest = std::numeric_limits<float>::infinity(), lo_median = nearest, lo_pol = nearest;
    float hi_median = 0, hi_cos2 = 0;
    std::size_t nearest_at = 0, cruise_frames = 0;
    for (std::size_t f = 0; f < frames; ++f) {
        if (m[f].min_nn < nearest) nearest = m[f].min_nn, nearest_at = f;
        if (!cruising(f)) continue;
        ++cruise_frames;
        lo_median = std::min(lo_median, m[f].median_nn), hi_median = std::max(hi_median, m[f].median_nn);
        lo_pol = std::min(lo_pol, m[f].polarization), hi_cos2 = std::max(hi_cos2, m[f].cos2);
    }
    std::size_t fewest = count;
    for (std::size_t f = 0; f < frames; f += every) fewest = std::min(fewest, group[f]);
    int failed = 0;
    const auto check = [&](bool ok, const char* what) {
        std::printf("%s %s\n", ok ? "[ ok   ]" : "[ FAIL ]", what);
        failed += ok ? 0 : 1;
    };
    char line[256];
    std::snprintf(line, sizeof line, "nearest two starlings %.3f m apart (at %.2f s), at least 0.1 m at every frame", static_cast<double>(nearest),
                  seconds(nearest_at));
    check(nearest >= 0.1f, line);
    std::snprintf(line, sizeof line, "cruising (%zu frames): median nearest neighbour %.2f to %.2f m, within 0.5 to 2 m", cruise_frames,
                  static_cast<double>(lo_median), static_cast<double>(hi_median));
    check(cruise_frames > 0 && lo_median >= 0.5f && hi_median <= 2.0f, line);
    std::snprintf(line, sizeof line, "cruising: polarization at least %.3f, at least 0.9", static_cast<double>(lo_pol));
    check(cruise_frames > 0 && lo_pol >= 0.9f, line);
    std::snprintf(line, sizeof line, "cruising: mean cos^2 to the nearest neighbour at most %.3f, at most 0.3", static_cast<double>(hi_cos2));
    check(cruise_frames > 0 && hi_cos2 <= 0.3f, line);
    std::snprintf(line, sizeof line, "the falcon first within %.0f m of a starling at %.2f s, no earlier than 20 s", static_cast<double>(reach),
                  seconds(pass));
    check(pass != SIZE_MAX && seconds(pass) >= 20.0, line);
    std::snprintf(line, sizeof line, "split at %.1f s (largest group at 3 m %zu of %zu at the fewest, below 70%%)", seconds(split), fewest, count);
    check(split != SIZE_MAX && split >= pass, line);
    std::snprintf(line, sizeof line, "rejoined (99%% in one group) at %.1f s, %.1f s after the split, within 10 s", seconds(rejoined),
                  seconds(rejoined) - seconds(split));
    check(split != SIZE_MAX && rejoined != SIZE_MAX && seconds(rejoined) - seconds(split) <= 10.0, line);
    return failed ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: starlings_bake_check SCENE.json BAKE.glb\n");
        return 2;
    }
    try {
        return run(argv[1], argv[2]);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "starlings_bake_check: %s\n", e.what());
        return 2;
    }
}
