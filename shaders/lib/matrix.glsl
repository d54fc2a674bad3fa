// Matrix helpers. Every matrix the kernels and layers share with C++ is stored as four
// vec4 columns (shared/glsl_types.h allows only vec4 members, so that std430 and the C++
// ABI cannot disagree): PoseMatrixGpu, the placements, the inverse bind matrices and
// RenderPush.view_proj. This is the one place that turns them into a mat4.
#ifndef KODAWARI_SHADERS_LIB_MATRIX_GLSL
#define KODAWARI_SHADERS_LIB_MATRIX_GLSL

mat4 mat4_columns(vec4 c[4]) { return mat4(c[0], c[1], c[2], c[3]); }

#endif
