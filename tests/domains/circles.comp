#version 450
// The test domain's kernel (tests/domains/test_domain_contract.cpp): particles on
// circles, one invocation per particle. Compiled by the tests' CMake, not the engine's:
// a domain brings its own kernels.
layout(local_size_x = 64) in;

// center x, center z, radius, angular speed (rad/s)
layout(std430, binding = 0) readonly buffer Params { vec4 params[]; };
layout(std430, binding = 1) buffer Angles { float angles[]; };
layout(std430, binding = 2) writeonly buffer Positions { vec4 positions[]; };

layout(push_constant) uniform Push {
    uint count;
    float dt;   // 0 at frame 0: the start, nothing advanced
} push;

const float kPi = 3.14159265358979;

void main() {
    const uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) return;
    const vec4 p = params[i];
    float a = angles[i] + p.w * push.dt;
    // Kept in [-pi, pi): where Vulkan bounds sin and cos's error (2^-11 absolute).
    if (a >= kPi) a -= 2.0 * kPi;
    angles[i] = a;
    positions[i] = vec4(p.x + p.z * cos(a), 1.0, p.y + p.z * sin(a), 1.0);
}
