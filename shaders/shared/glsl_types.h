// Lets one struct definition compile as GLSL (std430) and as C++.
// In C++ the GLSL vector types become 16-byte aligned PODs with the same layout as
// std430 vec4/uvec4; the structs that use them must only contain vec4, uvec4 and
// arrays of those, so no std430 rule can disagree with the C++ ABI.
// GLSL includes this directory's headers as "shared/NAME.h"; C++ as
// <kodawari/shared/NAME.h>, through the link engine/include/kodawari/shared, so the
// engine's public headers name no path into the shader tree and the one definition
// travels with them.
#ifndef KODAWARI_SHADERS_SHARED_GLSL_TYPES_H
#define KODAWARI_SHADERS_SHARED_GLSL_TYPES_H

#ifdef __cplusplus
#include <cstdint>
namespace kodawari::gpu {
struct alignas(16) vec4 {
    float x, y, z, w;
};
struct alignas(16) uvec4 {
    std::uint32_t x, y, z, w;
};
using uint = std::uint32_t;
static_assert(sizeof(vec4) == 16 && alignof(vec4) == 16);
static_assert(sizeof(uvec4) == 16 && alignof(uvec4) == 16);
}  // namespace kodawari::gpu
#define KW_NAMESPACE_BEGIN namespace kodawari::gpu {
#define KW_NAMESPACE_END }
#else
#define KW_NAMESPACE_BEGIN
#define KW_NAMESPACE_END
#endif

#endif
