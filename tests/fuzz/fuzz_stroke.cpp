// Fuzz target: the stroke reader (docs/sketch.md) and the sketch that fits a chain to a
// stroke it accepted (SPEC A.6). The input is a stroke file; the camera, chain and
// reference are fixed (a 640 x 480 perspective view of a 5-joint chain at the origin).
//
// Invariants: any input reads or is rejected with a message naming the file; a stroke
// that reads sketches (or is refused with a message, e.g. zero length) to a shape with
// finite joints, whose segment lengths are the chain's within 1e-3 relative (the fit
// places each joint at distance l_i from the previous one in double precision, SPEC A.6;
// the float shape rounds that to ~1e-7).
#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "kodawari/rods/sketch.hpp"
#include "kodawari/scene/scene_edit.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace kodawari;
    const std::string path = "fuzz-stroke.json";
    auto stroke = parse_stroke(std::string(reinterpret_cast<const char*>(data), size), path);
    if (!stroke) {
        if (stroke.error().message.find(path) == std::string::npos) {
            fuzz::finding("the error does not name the file: " + stroke.error().message);
        }
        return 0;
    }
    rods::SketchInput input;
    input.camera.width = 640;
    input.camera.height = 480;
    input.camera.position = {0.0, 0.3, 2.0};
    input.camera.target = {0.0, 0.3, 0.0};
    input.lengths = {0.05f, 0.05f, 0.04f, 0.03f};
    input.stroke = std::move(stroke).value();
    auto sketch = rods::sketch_view_example(input);
    if (!sketch) return 0;
    const auto& joints = sketch.value().world_positions;
    if (joints.size() != input.lengths.size() + 1) fuzz::finding("the sketch has the wrong joint count");
    for (std::size_t k = 0; k < joints.size(); ++k) {
        fuzz::require_finite(static_cast<float>(joints[k].x + joints[k].y + joints[k].z), "a sketched joint");
        if (k == 0) continue;
        const double l = std::sqrt((joints[k].x - joints[k - 1].x) * (joints[k].x - joints[k - 1].x) +
                                   (joints[k].y - joints[k - 1].y) * (joints[k].y - joints[k - 1].y) +
                                   (joints[k].z - joints[k - 1].z) * (joints[k].z - joints[k - 1].z));
        const double want = input.lengths[k - 1];
        if (std::abs(l - want) > 1e-3 * want) {
            fuzz::finding("a sketched segment is " + std::to_string(l) + " m, not " + std::to_string(want));
        }
    }
    return 0;
}
