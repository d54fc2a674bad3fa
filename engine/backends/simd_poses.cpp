// TEMPORARY stub
#include "backends/pose_backends.hpp"
namespace kodawari {
std::unique_ptr<PoseBackend> new_simd_pose_backend(simd::Isa, unsigned) { return new_reference_pose_backend(); }
}
