#version 450
// The raw weights u_1 .. u_J of the keyed examples (docs/keyed-examples.md K.2, K.3) of
// every chain that has some: one invocation per such chain measures its key sources
// against last frame's, smooths the motion keys, and writes u_j for rods_step.comp to
// combine with the view weights (K.4). Mirrors engine/rods/keyed.cpp keyed_weights()
// expression for expression (but for acos, see K.3 below); GLSL's exp and atan are not
// correctly rounded, so the weights agree with the CPU's closely, not bit for bit.
// shared/rod_keys.h has the layout.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require

#include "shared/rod_keys.h"
#include "shared/rods.h"
#include "lib/quat.glsl"
#include "lib/rod_lod.glsl"

layout(local_size_x = KW_ROD_KEYS_WORKGROUP_SIZE) in;

layout(std430, binding = KW_ROD_KEYS_BINDING_TEMPLATES) readonly buffer Templates { RodKeyTemplateGpu templates[]; };
layout(std430, binding = KW_ROD_KEYS_BINDING_CHAINS) readonly buffer Chains { RodKeyChainGpu chains[]; };
layout(std430, binding = KW_ROD_KEYS_BINDING_KEYS) readonly buffer Keys { RodTransformGpu keys[]; };
layout(std430, binding = KW_ROD_KEYS_BINDING_STATE) buffer States { RodKeyStateGpu states[]; };
layout(std430, binding = KW_ROD_KEYS_BINDING_WEIGHTS) writeonly buffer Weights { vec4 weights[]; };
layout(std430, binding = KW_ROD_KEYS_BINDING_REFERENCE) readonly buffer Reference { RodTransformGpu reference[]; };
layout(std430, binding = KW_ROD_KEYS_BINDING_CHAIN_STATE) readonly buffer ChainStates { RodChainStateGpu chain_states[]; };

layout(push_constant) uniform Push { RodKeyPush push; };

const vec4 IDENTITY = vec4(0.0, 0.0, 0.0, 1.0);


// keyed.cpp angular_velocity(): the turn from `last` to `now` over dt (K.2), world.
vec3 angular_velocity(vec4 last, vec4 now, float dt) {
    const vec4 dq = positive_w(qmul(now, qconj(last)));
    const vec3 axis = dq.xyz;
    const float sn = length(axis);
    if (!(sn > 0.0)) return vec3(0.0);
    return axis * (2.0 * atan(sn, dq.w) / (sn * dt));
}

// keyed.cpp gaussian(): K.2 and K.3's exp(-(d / sigma)^2 / 2), d^2 given.
float gaussian(float distance2, float sigma) { return exp(-0.5 * distance2 / (sigma * sigma)); }

void main() {
    const uint i = gl_GlobalInvocationID.x;
    if (i >= push.counts.x) return;
    const uvec4 ids = chains[i].ids;
    const RodKeyTemplateGpu t = templates[ids.x];
    RodKeyStateGpu state = states[i];
    const uint sources = t.counts.x;
    const uint examples = t.counts.y;
    // The posed and hidden levels' rate (rods_step.comp decides the same from the same
    // values): a chain that keeps its state is measured at its next step, over the frames
    // it kept (rods::measure_keys' frames).
    uint frames = 1u;
    if (push.counts.y != 0u && (push.counts.z & KW_RODS_RATE_ON) != 0u && ids.w != KW_ROD_KEYS_EVERY_FRAME) {
        const uint packed = uint(chain_states[ids.y].view.w);  // level + KW_RODS_IDLE_UNIT x idle
        const uint previous = packed % KW_RODS_IDLE_UNIT;
        const vec3 offset = reference[ids.w].position.xyz - push.camera_position.xyz;
        const float depth = dot(offset, push.camera_forward.xyz);
        const float right = dot(offset, push.camera_right.xyz);
        const float up = dot(offset, push.camera_up.xyz);
        const uint level = rod_level(depth, right, up, push.camera_right.w, push.camera_up.w, push.frame.y, push.frame.z,
                                     push.frame.w, push.camera_position.w, push.camera_forward.w, previous);
        const bool far_off = level == KW_RODS_LEVEL_HIDDEN &&
                             rod_far_off_view(depth, right, up, push.camera_right.w, push.camera_up.w, push.frame.y);
        if (rod_rests(level, previous, depth, push.camera_position.w, far_off, rod_rate_turn(push.counts.z, ids.w))) return;
        frames = packed / KW_RODS_IDLE_UNIT + 1u;
    }
    const float dt = frames == 1u ? push.frame.x : push.frame.x * float(frames);

    // Every index into these arrays is a constant of an unrolled loop (a source picked by
    // an example is selected, not indexed), so they stay in registers: lavapipe keeps an
    // array indexed by a variable in scratch memory, accessed lane by lane.
    vec4 rotation[KW_ROD_KEYS_MAX_SOURCES];
    vec3 velocity[KW_ROD_KEYS_MAX_SOURCES], acceleration[KW_ROD_KEYS_MAX_SOURCES], spin[KW_ROD_KEYS_MAX_SOURCES];
    // K.2: the measures of every motion source; then the last poses move on.
    [[unroll]] for (uint s = 0; s < KW_ROD_KEYS_MAX_SOURCES; ++s) {
        velocity[s] = vec3(0.0);
        acceleration[s] = vec3(0.0);
        spin[s] = vec3(0.0);
        rotation[s] = IDENTITY;
        if (s < sources) {
            const RodTransformGpu key = keys[ids.z + s];
            rotation[s] = key.rotation;
            if ((t.counts.z & (1u << s)) != 0u) {
                const vec3 jump = key.position.xyz - state.position[s].xyz;
                const float reach = uintBitsToFloat(t.counts.w);  // the teleport distance
                spin[s] = angular_velocity(state.rotation[s], key.rotation, dt);
                state.rotation[s] = key.rotation;
                if (dot(jump, jump) > reach * reach) {  // a teleport (keyed.cpp): motion as it was
                    velocity[s] = state.velocity[s].xyz;
                    state.position[s].xyz = key.position.xyz;
                } else {
                    velocity[s] = jump / dt;
                    acceleration[s] = state.position[s].w != 0.0 ? (velocity[s] - state.velocity[s].xyz) / dt : vec3(0.0);
                    state.position[s] = vec4(key.position.xyz, 1.0);
                    state.velocity[s] = vec4(velocity[s], 0.0);
                }
            }
        }
    }

    float u[KW_ROD_KEYS_MAX_EXAMPLES];
    [[unroll]] for (uint j = 0; j < KW_ROD_KEYS_MAX_EXAMPLES; ++j) {
        u[j] = 0.0;  // entries past J are 0, as KeyedWeights' (K.4 sums them all)
        if (j < examples) {
            const uvec4 e = t.examples[j];
            float distance2 = 0.0;
            if (e.x == KW_ROD_KEYS_KIND_MOTION) {
                vec3 raw = vec3(0.0);
                vec4 joint = IDENTITY;
                [[unroll]] for (uint s = 0; s < KW_ROD_KEYS_MAX_SOURCES; ++s) {
                    if (s == e.y) {
                        raw = e.z == KW_ROD_KEYS_MEASURE_SPEED          ? velocity[s]
                              : e.z == KW_ROD_KEYS_MEASURE_ACCELERATION ? acceleration[s]
                                                                       : spin[s];
                        joint = rotation[s];
                    }
                }
                const vec3 read = e.w == KW_ROD_KEYS_FRAME_JOINT ? qrot(qconj(joint), raw) : vec3(length(raw), 0.0, 0.0);
                // alpha_j for this frame's dt, from the host (RodKeyTemplateGpu); over several
                // frames 1 - (1 - alpha)^frames (the CPU's exp of their length, to rounding).
                float alpha = t.smoothing[j].z;
                if (frames > 1u) {
                    const float one = 1.0 - alpha;
                    float kept = one;
                    for (uint k = 1u; k < frames; ++k) kept *= one;
                    alpha = 1.0 - kept;
                }
                vec3 m = state.smoothed[j].xyz;
                m += alpha * (read - m);
                state.smoothed[j] = vec4(m, 0.0);
                const vec3 key = e.w == KW_ROD_KEYS_FRAME_JOINT ? m : vec3(min(m.x, t.smoothing[j].y), 0.0, 0.0);
                const vec3 d = key - t.keys[j].xyz;
                distance2 = dot(d, d);
            } else {
                // K.3: the angle of q_s kappa_{j,s}^T for every keyed source.
                [[unroll]] for (uint s = 0; s < KW_ROD_KEYS_MAX_SOURCES; ++s) {
                    if (s < sources && (e.y & (1u << s)) != 0u) {
                        const float c = min(1.0, abs(dot(rotation[s], t.rotations[j * KW_ROD_KEYS_MAX_SOURCES + s])));
                        // keyed.cpp's 2 acos(c), as the same angle's atan: lavapipe's acos is a
                        // low-order approximation (~1e-4 rad off, which moves u_j by ~1e-4 at
                        // sigma 0.2 rad), its atan good to ~1e-6. 1 - c is exact for c >= 0.5,
                        // so the sine costs ~2 ulp.
                        const float theta = 2.0 * atan(sqrt((1.0 - c) * (1.0 + c)), c);
                        distance2 += theta * theta;
                    }
                }
            }
            u[j] = gaussian(distance2, t.keys[j].w);
        }
    }
    states[i] = state;
    weights[ids.y] = vec4(u[0], u[1], u[2], u[3]);
}
