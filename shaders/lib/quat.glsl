// Quaternion helpers of the kernels and the layers, (x, y, z, w) as glTF and glm store
// them. One definition each, because the kernels are compared bit for bit with the CPU
// code they mirror (the parity tests, and the exports of tests/export_identity.sh on the
// vulkan backend): every function keeps the operation order of the C++ named beside it,
// and changing that order changes results. For the same reason there are two products
// (qmul, qmul_flight) and two rotations of a vector (qrot, rotate): each mirrors a
// different CPU reference, and the roundings of the two orders differ.
#ifndef KODAWARI_SHADERS_LIB_QUAT_GLSL
#define KODAWARI_SHADERS_LIB_QUAT_GLSL

// glm's quat * quat (the rods, SPEC A, and the rigged characters' nodes).
vec4 qmul(vec4 p, vec4 q) {
    return vec4(p.w * q.x + p.x * q.w + p.y * q.z - p.z * q.y, p.w * q.y + p.y * q.w + p.z * q.x - p.x * q.z,
                p.w * q.z + p.z * q.w + p.x * q.y - p.y * q.x, p.w * q.w - p.x * q.x - p.y * q.y - p.z * q.z);
}

// engine/birds/flight.cpp quat_mul(): the same product summed in another order, that of
// the bird engine's scalar reference (SPEC B.2 arm and body rotations).
vec4 qmul_flight(vec4 a, vec4 b) {
    return vec4(a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z);
}

vec4 qconj(vec4 q) { return vec4(-q.xyz, q.w); }
// The same rotation with w >= 0, the short way (rods' positive_w in solver_internal.hpp).
vec4 positive_w(vec4 q) { return q.w < 0.0 ? -q : q; }

// glm's quat * vec3.
vec3 qrot(vec4 q, vec3 v) {
    const vec3 uv = cross(q.xyz, v);
    const vec3 uuv = cross(q.xyz, uv);
    return v + ((uv * q.w) + uuv) * 2.0;
}

// The rotation of v by unit q as v + 2 q.xyz x (q.xyz x v + w v): the rigged characters'
// collider ends (rod_inputs.comp) and the bird layer's parts (birds.vert) have always
// used this form; qrot's order would round differently.
vec3 rotate(vec4 q, vec3 v) { return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v); }

// glm::normalize of a quaternion: the identity for a zero one.
vec4 qnormalize(vec4 q) {
    const float len = length(q);
    if (len <= 0.0) return vec4(0.0, 0.0, 0.0, 1.0);
    return q * (1.0 / len);
}

// glm::mat3_cast (columns).
mat3 mat3_cast(vec4 q) {
    const float xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    const float xz = q.x * q.z, xy = q.x * q.y, yz = q.y * q.z;
    const float wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    return mat3(vec3(1.0 - 2.0 * (yy + zz), 2.0 * (xy + wz), 2.0 * (xz - wy)),
                vec3(2.0 * (xy - wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz + wx)),
                vec3(2.0 * (xz + wy), 2.0 * (yz - wx), 1.0 - 2.0 * (xx + yy)));
}

// engine/rods/shape.cpp shortest_arc(): the rotation taking unit `from` to unit `to`
// through their half vector; opposite vectors turn half a turn about an axis normal to
// `from` (SPEC A.2's bone directions, and rigged_world()'s joints).
vec4 shortest_arc(vec3 from, vec3 to) {
    const vec3 h = from + to;
    const float h_len = length(h);
    if (h_len < 1e-6) {
        const vec3 a = abs(from);
        const vec3 other = (a.x <= a.y && a.x <= a.z) ? vec3(1, 0, 0) : (a.y <= a.z) ? vec3(0, 1, 0) : vec3(0, 0, 1);
        return vec4(normalize(cross(from, other)), 0.0);
    }
    const vec3 hn = h / h_len;
    return qnormalize(vec4(cross(from, hn), dot(from, hn)));
}

#endif
