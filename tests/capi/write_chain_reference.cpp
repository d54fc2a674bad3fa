// The C++ path's run of a scene's chains, written as JSON for tests/capi/test_capi.py
// (which has no C++ of its own): the chain templates as the scene file gives them (shapes,
// views, physics), the chains, and per frame the kinematic input (camera, reference joints,
// roots, world-space colliders) with what the cpu-reference RodBackend computed from it
// (joint positions and orientations). Floats are written with 9 significant digits, which
// read back as the same float32 bits, so the Python side can ask for equality.
//
// Usage: kodawari_capi_reference SCENE.json FRAMES OUT.json
#include <cstdio>
#include <cstdlib>
#include <string>

#include "kodawari/backends/rod_backend.hpp"
#include "kodawari/scene/scene.hpp"

using namespace kodawari;

namespace {

int fail(const std::string& what) {
    std::fprintf(stderr, "kodawari_capi_reference: %s\n", what.c_str());
    return 1;
}

class Writer {
public:
    explicit Writer(std::FILE* file) : file_(file) {}
    void raw(const char* text) { std::fputs(text, file_); }
    void number(float v) { std::fprintf(file_, "%.9g", static_cast<double>(v)); }
    void floats(const float* v, std::size_t n) {
        raw("[");
        for (std::size_t i = 0; i < n; ++i) {
            if (i) raw(",");
            number(v[i]);
        }
        raw("]");
    }
    void vec3(glm::vec3 v) { floats(&v.x, 3); }
    void quat(glm::quat q) {
        const float xyzw[4] = {q.x, q.y, q.z, q.w};
        floats(xyzw, 4);
    }
    template <typename T, typename Fn>
    void list(const T& items, Fn&& each) {
        raw("[");
        bool first = true;
        for (const auto& item : items) {
            if (!first) raw(",");
            first = false;
            each(item);
        }
        raw("]");
    }
    void shape(const rods::ChainShape& s) {
        raw("{\"positions\":");
        list(s.positions, [&](glm::vec3 p) { vec3(p); });
        raw(",\"orientations\":");
        list(s.orientations, [&](glm::quat q) { quat(q); });
        raw("}");
    }
    void transform(const rods::Transform& t) {
        const float v[7] = {t.position.x, t.position.y, t.position.z, t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w};
        floats(v, 7);
    }

private:
    std::FILE* file_;
};

}  // namespace

int main(int argc, char** argv) {
    if (argc != 4) return fail("usage: kodawari_capi_reference SCENE.json FRAMES OUT.json");
    const auto frames = static_cast<std::uint32_t>(std::strtoul(argv[2], nullptr, 10));
    auto scene = load_scene(argv[1]);
    if (!scene) return fail(scene.error().message);
    auto built = build_rod_scene(scene.value());
    if (!built) return fail(built.error().message);
    const RodScene& rods = built.value();
    auto made = make_cpu_rod_backend(BackendKind::CpuReference, {});
    if (!made) return fail(made.error().message);
    RodBackend& backend = *made.value();

    std::FILE* file = std::fopen(argv[3], "w");
    if (file == nullptr) return fail(std::string("cannot write ") + argv[3]);
    Writer w(file);
    w.raw("{\"scene\":\"");
    w.raw(scene.value().name.c_str());
    w.raw("\",\"templates\":[");
    bool first = true;
    for (const CharacterSpec& ch : scene.value().characters) {
        for (const ChainSpec& c : ch.chains) {
            if (!first) w.raw(",");
            first = false;
            w.raw("{\"name\":\"");
            w.raw((ch.name + "/" + c.name).c_str());
            w.raw("\",\"base\":");
            w.shape(c.base);
            w.raw(",\"views\":");
            w.list(c.views, [&](const ViewSpec& v) {
                w.raw("{\"direction\":");
                w.vec3(v.view.direction);
                w.raw(",\"influence\":");
                w.number(v.view.influence);
                w.raw(",\"shape\":");
                w.shape(v.shape);
                w.raw("}");
            });
            const rods::SolverParams& p = c.params;
            w.raw(",\"thickness\":");
            w.number(c.thickness);
            w.raw(",\"mass\":");
            w.number(c.mass);
            w.raw(",\"solver\":{\"max_substep\":");
            w.number(p.max_substep);
            std::fprintf(file, ",\"iterations\":%u,\"stiffness\":", p.iterations);
            w.number(p.stiffness);
            w.raw(",\"rest_stiffness\":");
            w.number(p.rest_stiffness);
            w.raw(",\"damping\":");
            w.number(p.damping);
            w.raw(",\"gravity\":");
            w.vec3(p.gravity);
            w.raw(",\"wind\":");
            w.vec3(p.wind);
            w.raw(",\"momentum_suppression\":");
            w.number(p.momentum_suppression);
            std::fprintf(file, ",\"settle_start\":%u,\"teleport_distance\":", p.settle_start ? 1u : 0u);
            w.number(p.teleport_distance);
            w.raw(",\"normal_drag\":");
            w.number(p.normal_drag);
            w.raw(",\"tangent_drag\":");
            w.number(p.tangent_drag);
            w.raw("}}");
        }
    }
    w.raw("],\"chains\":");
    w.list(rods.world.chains, [&](const rods::ChainInstance& c) {
        std::fprintf(file, "{\"template\":%u,\"character\":%u,\"collider_begin\":%u,\"collider_count\":%u}", c.template_index,
                     c.character, c.collider_begin, c.collider_count);
    });
    std::fprintf(file, ",\"character_count\":%u,\"collider_count\":%u,\"joint_count\":%u,\"frames\":[\n",
                 rods.world.character_count, rods.world.collider_count, rods.world.joint_count);
    rods::RodFrame frame;
    ChainSnapshot snapshot;
    for (std::uint32_t f = 0; f <= frames; ++f) {
        rods.frame(f, frame);
        const auto ok = f == 0 ? backend.load(rods.world, frame) : backend.step(frame);
        if (!ok) return fail(ok.error().message);
        if (auto read = backend.read(snapshot); !read) return fail(read.error().message);
        w.raw(f ? ",\n{\"dt\":" : "{\"dt\":");
        w.number(frame.dt);
        std::fprintf(file, ",\"camera\":{\"orthographic\":%d,\"position\":",
                     frame.camera.projection == rods::Camera::Projection::Orthographic ? 1 : 0);
        w.vec3(frame.camera.position);
        w.raw(",\"forward\":");
        w.vec3(frame.camera.forward);
        w.raw("},\"references\":");
        w.list(frame.reference, [&](const rods::Transform& t) { w.transform(t); });
        w.raw(",\"roots\":");
        w.list(frame.roots, [&](const rods::Transform& t) { w.transform(t); });
        w.raw(",\"colliders\":");
        w.list(frame.colliders, [&](const rods::Collider& c) {
            const float v[7] = {c.a.x, c.a.y, c.a.z, c.b.x, c.b.y, c.b.z, c.radius};
            w.floats(v, 7);
        });
        w.raw(",\"positions\":");
        w.list(snapshot.positions, [&](glm::vec3 p) { w.vec3(p); });
        w.raw(",\"orientations\":");
        w.list(snapshot.orientations, [&](glm::quat q) { w.quat(q); });
        w.raw("}");
    }
    w.raw("]}\n");
    if (std::fclose(file) != 0) return fail(std::string("cannot write ") + argv[3]);
    return 0;
}
