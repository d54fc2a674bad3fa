#version 450
// The fireflies' kernel (examples/own_domain/main.cpp): each firefly circles its own
// centre and bobs up and down, one invocation per firefly. Compiled by the example's
// CMakeLists.txt, not by Kodawari's: a domain brings its own kernels.
layout(local_size_x = 64) in;

// centre x, centre z, radius, angular speed (rad/s)
layout(std430, binding = 0) readonly buffer Params { vec4 params[]; };
layout(std430, binding = 1) buffer Angles { float angles[]; };
layout(std430, binding = 2) writeonly buffer Positions { vec4 positions[]; };

layout(push_constant) uniform Push {
    uint count;
    float dt;  // 0 at frame 0: where they start
} push;

const float kPi = 3.14159265358979;

void main() {
    const uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) return;  // the last workgroup's spare invocations
    const vec4 p = params[i];
    float a = angles[i] + p.w * push.dt;
    // Kept in [-pi, pi): where Vulkan bounds sin's and cos's error (2^-11 absolute).
    if (a >= kPi) a -= 2.0 * kPi;
    angles[i] = a;
    // Two bobs per turn, 0.15 m either way of 1.5 m.
    positions[i] = vec4(p.x + p.z * cos(a), 1.5 + 0.3 * sin(a) * cos(a), p.y + p.z * sin(a), 1.0);
}
