/* The C API from C (issue 11, section 3), compiled as C99 with -Wall -Wextra -Wpedantic
 * -Werror: the ahoge scene's chain (scenes/ahoge.json, built here from arrays) stepped
 * under an orbiting camera and checked against values computed here (the view weights of
 * SPEC A.3, the segment lengths, the tip reading sideways from every side as the README
 * says), a flock checked against its route and speed, and every entry point given bad
 * input: the status, the message's content, and the state unchanged after the rejection.
 *
 * Exit status 0 when every check passed; each failure prints its file, line and why. */
#include <kodawari/kodawari.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int g_failures = 0;
static int g_checks = 0;

#define CHECK(cond, ...)                                                  \
    do {                                                                  \
        ++g_checks;                                                       \
        if (!(cond)) {                                                    \
            ++g_failures;                                                 \
            fprintf(stderr, "%s:%d: check failed: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                 \
            fprintf(stderr, "\n");                                        \
        }                                                                 \
    } while (0)

#define PI_F 3.14159265358979f

/* A call's outcome: `status` must be `expected`, and this thread's message must contain
 * every one of the NULL-terminated `needles` (and be "" on success). */
static void expect_(const char* file, int line, kodawari_status status, kodawari_status expected, const char* const* needles) {
    const char* message = kodawari_last_error();
    ++g_checks;
    if (status != expected) {
        ++g_failures;
        fprintf(stderr, "%s:%d: expected %s, got %s: \"%s\"\n", file, line, kodawari_status_name(expected),
                kodawari_status_name(status), message);
        return;
    }
    if (expected == KODAWARI_OK && message[0] != '\0') {
        ++g_failures;
        fprintf(stderr, "%s:%d: a call that succeeded left the message \"%s\"\n", file, line, message);
    }
    for (; needles != NULL && *needles != NULL; ++needles) {
        ++g_checks;
        if (strstr(message, *needles) == NULL) {
            ++g_failures;
            fprintf(stderr, "%s:%d: the message \"%s\" does not say \"%s\"\n", file, line, message, *needles);
        }
    }
}
#define EXPECT_OK(call) expect_(__FILE__, __LINE__, (call), KODAWARI_OK, NULL)
/* EXPECT_FAIL(call, status, "needle", ...): the message names the argument and the problem. */
#define EXPECT_FAIL(call, status, ...)                                     \
    do {                                                                   \
        const char* const needles_[] = {__VA_ARGS__, NULL};                \
        expect_(__FILE__, __LINE__, (call), (status), needles_);           \
    } while (0)

/* Vulkan validation (with synchronization validation) when ctest asks for it, as the other
 * GPU tests: KODAWARI_VALIDATION=1. The library reads no environment variable. */
static uint32_t validation_requested(void) {
    const char* value = getenv("KODAWARI_VALIDATION");
    return value != NULL && value[0] != '\0' && strcmp(value, "0") != 0 ? 1u : 0u;
}

/* ---- The ahoge scene's chain (scenes/ahoge.json), from arrays ---------------------------- */

enum { kJoints = 12, kViews = 5 };
static const float kLength = 0.14f;

/* A strand on a circular arc (the scene files' "arc": scene/chain_loader.cpp): joint i on
 * the circle, segment i along the tangent at its middle, (i + 1/2) steps of curl /
 * (joints - 1) from `direction` about `axis`. */
static void arc(float* positions, const float direction[3], const float axis[3], float curl_deg) {
    const float step = curl_deg * PI_F / 180.0f / (float)(kJoints - 1);
    const float segment = kLength / (float)(kJoints - 1);
    int i, k;
    positions[0] = positions[1] = positions[2] = 0.0f;
    for (i = 0; i + 1 < kJoints; ++i) {
        /* Rodrigues: rotate `direction` by the angle about the unit `axis`. */
        const float a = ((float)i + 0.5f) * step, c = cosf(a), s = sinf(a);
        const float d = axis[0] * direction[0] + axis[1] * direction[1] + axis[2] * direction[2];
        const float cross[3] = {axis[1] * direction[2] - axis[2] * direction[1], axis[2] * direction[0] - axis[0] * direction[2],
                                axis[0] * direction[1] - axis[1] * direction[0]};
        for (k = 0; k < 3; ++k) {
            const float r = direction[k] * c + cross[k] * s + axis[k] * d * (1.0f - c);
            positions[3 * (i + 1) + k] = positions[3 * i + k] + segment * r;
        }
    }
}

typedef struct ahoge {
    float base[kJoints * 3];
    float shapes[kViews][kJoints * 3];
    kodawari_view_example views[kViews];
    kodawari_chain_template_desc templ;
    kodawari_chain_desc chain;
    kodawari_collider_desc head_sphere;
    kodawari_chain_world_desc desc;
} ahoge;

static void make_ahoge(ahoge* a, kodawari_backend backend) {
    static const float up[3] = {0, 1, 0};
    static const float directions[kViews][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}};
    static const float bends[kViews][3] = {{0, 0, -1}, {0, 0, 1}, {-1, 0, 0}, {1, 0, 0}, {0, 0, -1}};
    static const float influences[kViews] = {4, 4, 4, 4, 8};
    int k;
    memset(a, 0, sizeof *a);
    arc(a->base, up, bends[0], 150.0f);
    for (k = 0; k < kViews; ++k) {
        arc(a->shapes[k], up, bends[k], 150.0f);
        memcpy(a->views[k].direction, directions[k], sizeof directions[k]);
        a->views[k].influence = influences[k];
        a->views[k].shape.positions = a->shapes[k];
        a->views[k].shape.orientations = NULL; /* the scene files' default */
    }
    a->templ.joint_count = kJoints;
    a->templ.base.positions = a->base;
    a->templ.views = a->views;
    a->templ.view_count = kViews;
    a->templ.thickness = 0.004f;
    a->templ.mass = 0.001f;
    kodawari_solver_params_default(&a->templ.solver);
    a->templ.solver.stiffness = 0.6f;
    a->templ.solver.damping = 3.0f;
    a->templ.solver.iterations = 4;
    /* On its rest shape and still at frame 0, which the checks below read (the default,
     * settle_start = 1, starts it settled under gravity: the C++ tests measure that). */
    a->templ.solver.settle_start = 0;
    a->chain.template_index = 0;
    a->chain.character = 0;
    a->chain.collider_begin = 0;
    a->chain.collider_count = 1;
    /* The scene's head sphere, on the reference joint (the head). */
    a->head_sphere.character = 0;
    a->head_sphere.local.a[1] = a->head_sphere.local.b[1] = 0.1f;
    a->head_sphere.local.radius = 0.11f;
    a->desc.templates = &a->templ;
    a->desc.template_count = 1;
    a->desc.chains = &a->chain;
    a->desc.chain_count = 1;
    a->desc.character_count = 1;
    a->desc.collider_count = 1;
    a->desc.colliders = &a->head_sphere;
    a->desc.backend.backend = backend;
    a->desc.backend.validation = validation_requested();
    a->desc.backend.threads = 3;
}

/* The scene's head (body 0.9 + neck 0.45 + head 0.12 m) standing still, the strand's root
 * 0.21 m above it, and the camera orbiting the head's target once in 12 s, 0.2 m above it
 * at 1.2 m: frame f at angle 2 pi f / 720. */
static const float kHead[3] = {0.0f, 1.47f, 0.0f};
static const float kRoot[3] = {0.0f, 1.68f, 0.0f};

typedef struct frame_data {
    kodawari_transform head;
    kodawari_transform root;
    kodawari_chain_frame frame;
} frame_data;

static void make_frame(frame_data* f, int index) {
    const float angle = 2.0f * PI_F * (float)index / 720.0f;
    memset(f, 0, sizeof *f);
    memcpy(f->head.position, kHead, sizeof kHead);
    f->head.rotation[3] = 1.0f;
    memcpy(f->root.position, kRoot, sizeof kRoot);
    f->root.rotation[3] = 1.0f;
    f->frame.dt = 1.0f / 60.0f;
    f->frame.camera.position[0] = 1.2f * sinf(angle);
    f->frame.camera.position[1] = 1.62f + 0.2f;
    f->frame.camera.position[2] = 1.2f * cosf(angle);
    f->frame.camera.forward[0] = -sinf(angle);
    f->frame.camera.forward[1] = -0.2f / 1.2f;
    f->frame.camera.forward[2] = -cosf(angle);
    f->frame.references = &f->head;
    f->frame.reference_count = 1;
    f->frame.roots = &f->root;
    f->frame.root_count = 1;
}

typedef struct chain_state {
    float positions[kJoints * 3];
    float orientations[kJoints * 4];
    float rest[kJoints * 3];
    float view[3];
    float weights[KODAWARI_WEIGHTS_PER_CHAIN];
} chain_state;

static kodawari_status read_state(kodawari_chain_world* world, chain_state* s) {
    kodawari_chain_output out;
    memset(&out, 0, sizeof out);
    out.positions = s->positions;
    out.positions_capacity = kJoints * 3;
    out.orientations = s->orientations;
    out.orientations_capacity = kJoints * 4;
    out.rest_positions = s->rest;
    out.rest_positions_capacity = kJoints * 3;
    out.view_directions = s->view;
    out.view_directions_capacity = 3;
    out.weights = s->weights;
    out.weights_capacity = KODAWARI_WEIGHTS_PER_CHAIN;
    return kodawari_chain_world_read(world, &out);
}

static float distance3(const float* a, const float* b) {
    const float d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* Quaternion (x, y, z, w) times vector. */
static void rotate(const float* q, const float* v, float* out) {
    const float t[3] = {2.0f * (q[1] * v[2] - q[2] * v[1]), 2.0f * (q[2] * v[0] - q[0] * v[2]), 2.0f * (q[0] * v[1] - q[1] * v[0])};
    out[0] = v[0] + q[3] * t[0] + (q[1] * t[2] - q[2] * t[1]);
    out[1] = v[1] + q[3] * t[1] + (q[2] * t[0] - q[0] * t[2]);
    out[2] = v[2] + q[3] * t[2] + (q[0] * t[1] - q[1] * t[0]);
}

static kodawari_chain_world* create_ahoge(kodawari_backend backend) {
    ahoge a;
    frame_data f;
    kodawari_chain_world* world = NULL;
    make_ahoge(&a, backend);
    make_frame(&f, 0);
    EXPECT_OK(kodawari_chain_world_create(&a.desc, &f.frame, &world));
    return world;
}

/* The ahoge under the orbiting camera: expected weights at frame 0, kept segment lengths,
 * and the tip to the camera's right at every frame of a full turn. */
static void test_ahoge(kodawari_backend backend, const char* name) {
    kodawari_chain_world* world = create_ahoge(backend);
    kodawari_chain_world_info info;
    chain_state s;
    frame_data f;
    int frame, i, k;
    float worst_stretch = 0.0f, least_right = 1e9f;
    if (world == NULL) return;
    EXPECT_OK(kodawari_chain_world_get_info(world, &info));
    CHECK(info.chain_count == 1 && info.joint_count == kJoints && info.character_count == 1 && info.collider_count == 1,
          "%u chains, %u joints", info.chain_count, info.joint_count);
    CHECK(info.backend == backend, "%d", (int)info.backend);
    CHECK(info.validation_messages == 0, "%u", info.validation_messages);
    printf("test_capi: %s on %s\n", name, info.device);

    /* Frame 0: at rest on the blended rest shape, joint 0 on the root. */
    EXPECT_OK(read_state(world, &s));
    CHECK(distance3(s.positions, kRoot) == 0.0f, "joint 0 at (%g, %g, %g)", s.positions[0], s.positions[1], s.positions[2]);
    for (i = 0; i < kJoints; ++i) {
        CHECK(distance3(s.positions + 3 * i, s.rest + 3 * i) < 1e-6f, "joint %d is %g m off its rest", i,
              distance3(s.positions + 3 * i, s.rest + 3 * i));
    }
    {
        /* SPEC A.3 by hand: d from the head to the camera at (0, 1.82, 1.2); s_k = (d_k . d + 1) / 2,
         * w_k = s_k^p_k, normalized when they sum past 1, w_0 = 1 - sum. */
        const double d[3] = {0.0, 0.35 / sqrt(0.35 * 0.35 + 1.44), 1.2 / sqrt(0.35 * 0.35 + 1.44)};
        static const double dk[kViews][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}};
        static const double p[kViews] = {4, 4, 4, 4, 8};
        double w[kViews + 1], sum = 0.0;
        for (k = 0; k < kViews; ++k) {
            w[k + 1] = pow((dk[k][0] * d[0] + dk[k][1] * d[1] + dk[k][2] * d[2] + 1.0) / 2.0, p[k]);
            sum += w[k + 1];
        }
        if (sum >= 1.0) {
            for (k = 1; k <= kViews; ++k) w[k] /= sum;
            sum = 1.0;
        }
        w[0] = 1.0 - sum;
        for (k = 0; k <= kViews; ++k) CHECK(fabs(s.weights[k] - w[k]) < 1e-5, "w_%d = %g, expected %g", k, s.weights[k], w[k]);
        for (k = kViews + 1; k < KODAWARI_WEIGHTS_PER_CHAIN; ++k) CHECK(s.weights[k] == 0.0f, "w_%d = %g", k, s.weights[k]);
        for (k = 0; k < 3; ++k) CHECK(fabs(s.view[k] - d[k]) < 1e-6, "d[%d] = %g, expected %g", k, s.view[k], d[k]);
        CHECK(w[1] > 0.5, "the front example leads seen from the front (w_1 = %g)", w[1]);
    }

    /* A full turn of the camera, 720 frames. */
    for (frame = 1; frame <= 720; ++frame) {
        float right[3], tip[3], length;
        make_frame(&f, frame);
        EXPECT_OK(kodawari_chain_world_step(world, &f.frame));
        EXPECT_OK(read_state(world, &s));
        CHECK(distance3(s.positions, kRoot) < 1e-6f, "frame %d: joint 0 left the root", frame);
        for (i = 0; i + 1 < kJoints; ++i) {
            const float l = distance3(s.positions + 3 * i, s.positions + 3 * i + 3);
            const float stretch = fabsf(l - kLength / (float)(kJoints - 1)) / (kLength / (float)(kJoints - 1));
            if (!(stretch <= worst_stretch)) worst_stretch = stretch;
        }
        for (i = 0; i < kJoints; ++i) {
            const float* q = s.orientations + 4 * i;
            length = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            CHECK(fabsf(length - 1.0f) < 1e-5f, "frame %d joint %d: orientation of length %g", frame, i, length);
        }
        /* The camera's right (forward x up, horizontal), and how far the tip lies along it. */
        length = sqrtf(f.frame.camera.forward[0] * f.frame.camera.forward[0] + f.frame.camera.forward[2] * f.frame.camera.forward[2]);
        right[0] = -f.frame.camera.forward[2] / length;
        right[1] = 0.0f;
        right[2] = f.frame.camera.forward[0] / length;
        for (k = 0; k < 3; ++k) tip[k] = s.positions[3 * (kJoints - 1) + k] - s.positions[k];
        length = (tip[0] * right[0] + tip[2] * right[2]) / kLength;
        if (length < least_right) least_right = length;
    }
    /* 0.5% of a segment: the rods' inextensibility bound; 0.25 of the strand's length to
     * the camera's right: the README's "reads sideways from every angle". */
    CHECK(worst_stretch < 0.005f, "%s: a segment stretched by %g", name, worst_stretch);
    CHECK(least_right > 0.25f, "%s: the tip came within %g strand lengths of the camera's right", name, least_right);
    printf("test_capi: %s: max stretch %.3g of a segment, tip at least %.2f strand lengths to the camera's right\n", name,
           (double)worst_stretch, (double)least_right);
    EXPECT_OK(kodawari_chain_world_get_info(world, &info));
    CHECK(info.validation_messages == 0, "%u validation messages", info.validation_messages);
    kodawari_chain_world_destroy(world);
}

/* Orientations come out as (x, y, z, w): without view examples, at rest, each joint's
 * local +Y runs along its segment (the default orientations, here placed by a root turned
 * half a turn about +Y), so the quaternion turns +Y onto the segment's direction. */
static void test_orientations(void) {
    ahoge a;
    frame_data f;
    kodawari_chain_world* world = NULL;
    chain_state s;
    int i, k;
    make_ahoge(&a, KODAWARI_BACKEND_CPU_REFERENCE);
    a.templ.view_count = 0;
    make_frame(&f, 0);
    f.root.rotation[1] = 1.0f;
    f.root.rotation[3] = 0.0f;
    EXPECT_OK(kodawari_chain_world_create(&a.desc, &f.frame, &world));
    if (world == NULL) return;
    EXPECT_OK(read_state(world, &s));
    for (i = 0; i < kJoints; ++i) {
        const int seg = i < kJoints - 1 ? i : kJoints - 2;
        const float y[3] = {0.0f, 1.0f, 0.0f};
        const float l = distance3(s.positions + 3 * seg + 3, s.positions + 3 * seg);
        float axis[3];
        rotate(s.orientations + 4 * i, y, axis);
        for (k = 0; k < 3; ++k) {
            const float expected = (s.positions[3 * seg + 3 + k] - s.positions[3 * seg + k]) / l;
            CHECK(fabsf(axis[k] - expected) < 1e-5f, "joint %d: its +Y is %g along axis %d, its segment %g", i, axis[k], k, expected);
        }
    }
    /* The strand curls towards +X in the root's frame, so towards -X in the world. */
    CHECK(s.positions[3 * (kJoints - 1)] < -0.05f, "the tip at x = %g", s.positions[3 * (kJoints - 1)]);
    kodawari_chain_world_destroy(world);
}

/* cpu-reference and cpu: the same bits, frame after frame; reset gives create's bits. */
static void test_backends_agree(void) {
    kodawari_chain_world* a = create_ahoge(KODAWARI_BACKEND_CPU_REFERENCE);
    kodawari_chain_world* b = create_ahoge(KODAWARI_BACKEND_CPU);
    chain_state sa, sb, first;
    frame_data f;
    int frame;
    if (a == NULL || b == NULL) return;
    EXPECT_OK(read_state(a, &first));
    for (frame = 1; frame <= 90; ++frame) {
        make_frame(&f, frame * 7);
        EXPECT_OK(kodawari_chain_world_step(a, &f.frame));
        EXPECT_OK(kodawari_chain_world_step(b, &f.frame));
    }
    EXPECT_OK(read_state(a, &sa));
    EXPECT_OK(read_state(b, &sb));
    CHECK(memcmp(&sa, &sb, sizeof sa) == 0, "cpu differs from cpu-reference");
    CHECK(memcmp(&sa, &first, sizeof sa) != 0, "90 frames changed nothing");
    make_frame(&f, 0);
    EXPECT_OK(kodawari_chain_world_reset(a, &f.frame));
    EXPECT_OK(read_state(a, &sa));
    CHECK(memcmp(&sa, &first, sizeof sa) == 0, "reset did not give create's state");
    kodawari_chain_world_destroy(a);
    kodawari_chain_world_destroy(b);
}

/* A collider attached to the reference joint rides on it: with the head turned half a turn
 * about +Y (a rotation whose arithmetic is exact: (x, y, z) -> (-x, y, -z)), a sphere
 * attached next to joint 6 gives the bits of the same sphere given in world space every
 * frame, and it pushes the strand out. */
static void test_attached_colliders(void) {
    ahoge a;
    frame_data f;
    kodawari_chain_world *attached = NULL, *given = NULL, *free_strand = NULL;
    chain_state s, sg, sf;
    kodawari_capsule world_sphere;
    float local[3];
    const float radius = 0.02f;
    int frame, i, k;

    /* Where joint 6 rests with the head turned and no collider. */
    make_ahoge(&a, KODAWARI_BACKEND_CPU_REFERENCE);
    a.chain.collider_count = 0;
    a.desc.collider_count = 0;
    a.desc.colliders = NULL;
    make_frame(&f, 0);
    f.head.rotation[1] = 1.0f;
    f.head.rotation[3] = 0.0f;
    memcpy(f.root.rotation, f.head.rotation, sizeof f.root.rotation);
    EXPECT_OK(kodawari_chain_world_create(&a.desc, &f.frame, &free_strand));
    if (free_strand == NULL) return;
    EXPECT_OK(read_state(free_strand, &s));
    /* The sphere's centre 1 cm above joint 6, in the head's frame. */
    local[0] = -(s.positions[18] - kHead[0]);
    local[1] = s.positions[19] + 0.01f - kHead[1];
    local[2] = -(s.positions[20] - kHead[2]);
    memcpy(a.head_sphere.local.a, local, sizeof local);
    memcpy(a.head_sphere.local.b, local, sizeof local);
    a.head_sphere.local.radius = radius;
    a.chain.collider_count = 1;
    a.desc.collider_count = 1;
    a.desc.colliders = &a.head_sphere;
    EXPECT_OK(kodawari_chain_world_create(&a.desc, &f.frame, &attached));
    a.desc.colliders = NULL;
    for (k = 0; k < 3; ++k) world_sphere.a[k] = world_sphere.b[k] = kHead[k] + (k == 1 ? local[k] : -local[k]);
    world_sphere.radius = radius;
    f.frame.colliders = &world_sphere;
    f.frame.collider_count = 1;
    EXPECT_OK(kodawari_chain_world_create(&a.desc, &f.frame, &given));
    if (attached == NULL || given == NULL) return;
    for (frame = 1; frame <= 60; ++frame) {
        make_frame(&f, frame * 3);
        f.head.rotation[1] = 1.0f;
        f.head.rotation[3] = 0.0f;
        memcpy(f.root.rotation, f.head.rotation, sizeof f.root.rotation);
        EXPECT_OK(kodawari_chain_world_step(attached, &f.frame));
        EXPECT_OK(kodawari_chain_world_step(free_strand, &f.frame));
        f.frame.colliders = &world_sphere;
        f.frame.collider_count = 1;
        EXPECT_OK(kodawari_chain_world_step(given, &f.frame));
    }
    EXPECT_OK(read_state(attached, &s));
    EXPECT_OK(read_state(given, &sg));
    EXPECT_OK(read_state(free_strand, &sf));
    CHECK(memcmp(&s, &sg, sizeof s) == 0, "an attached collider differs from the same collider in world space");
    CHECK(memcmp(s.positions, sf.positions, sizeof s.positions) != 0, "the collider changed nothing");
    for (i = 1; i < kJoints; ++i) {
        const float d = distance3(s.positions + 3 * i, world_sphere.a);
        CHECK(d > 0.9f * radius, "joint %d is %g m inside the sphere of radius %g", i, radius - d, radius);
    }
    kodawari_chain_world_destroy(attached);
    kodawari_chain_world_destroy(given);
    kodawari_chain_world_destroy(free_strand);
}

/* ---- Bad input ------------------------------------------------------------------------- */

static void test_version_and_status(void) {
    char text[64];
    sprintf(text, "%d.%d.%d", kodawari_version_major(), kodawari_version_minor(), kodawari_version_patch());
    CHECK(strcmp(text, kodawari_version()) == 0, "%s vs %s", text, kodawari_version());
    CHECK(strcmp(kodawari_status_name(KODAWARI_BUFFER_TOO_SMALL), "KODAWARI_BUFFER_TOO_SMALL") == 0, "name");
    CHECK(strcmp(kodawari_status_name((kodawari_status)99), "unknown kodawari_status") == 0, "unknown");
    CHECK(strcmp(kodawari_chain_world_last_error(NULL), "") == 0 && strcmp(kodawari_bird_world_last_error(NULL), "") == 0,
          "NULL handles have no message");
    EXPECT_FAIL(kodawari_solver_params_default(NULL), KODAWARI_INVALID_ARGUMENT, "kodawari_solver_params_default", "out: is NULL");
    {
        kodawari_solver_params p;
        EXPECT_OK(kodawari_solver_params_default(&p));
        CHECK(p.settle_start == 1 && p.teleport_distance == 1.0f, "defaults settle_start %u, teleport_distance %g",
              p.settle_start, (double)p.teleport_distance);
        CHECK(p.normal_drag == 0.0f && p.tangent_drag == 0.0f, "defaults normal_drag %g, tangent_drag %g",
              (double)p.normal_drag, (double)p.tangent_drag);
    }
    EXPECT_FAIL(kodawari_wind_default(NULL), KODAWARI_INVALID_ARGUMENT, "kodawari_wind_default", "out: is NULL");
    {
        kodawari_wind w;
        EXPECT_OK(kodawari_wind_default(&w));
        CHECK(w.velocity[0] == 0.0f && w.velocity[1] == 0.0f && w.velocity[2] == 0.0f && w.gust == 0.0f &&
                  w.gust_period == 3.0f && w.gust_size == 6.0f && w.seed == 0,
              "default wind: calm, gusts of 3 s and 6 m");
    }
    EXPECT_FAIL(kodawari_flight_settings_default(NULL), KODAWARI_INVALID_ARGUMENT, "out: is NULL");
}

static void test_camera_from_view_matrix(void) {
    /* A camera at (1, 2, 3) looking down world -Z: view = translate(-eye). */
    float view[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, -2, -3, 1};
    kodawari_camera camera, untouched;
    memset(&untouched, 0x5a, sizeof untouched);
    camera = untouched;
    EXPECT_OK(kodawari_camera_from_view_matrix(view, 0, &camera));
    CHECK(camera.position[0] == 1.0f && camera.position[1] == 2.0f && camera.position[2] == 3.0f, "eye (%g, %g, %g)",
          camera.position[0], camera.position[1], camera.position[2]);
    CHECK(camera.forward[0] == 0.0f && camera.forward[1] == 0.0f && camera.forward[2] == -1.0f, "forward");
    CHECK(camera.orthographic == 0, "perspective");
    camera = untouched;
    EXPECT_FAIL(kodawari_camera_from_view_matrix(NULL, 0, &camera), KODAWARI_INVALID_ARGUMENT, "view: is NULL");
    EXPECT_FAIL(kodawari_camera_from_view_matrix(view, 0, NULL), KODAWARI_INVALID_ARGUMENT, "out: is NULL");
    EXPECT_FAIL(kodawari_camera_from_view_matrix(view, 2, &camera), KODAWARI_INVALID_ARGUMENT, "orthographic: 2; expected 0 or 1");
    view[5] = (float)NAN;
    EXPECT_FAIL(kodawari_camera_from_view_matrix(view, 0, &camera), KODAWARI_INVALID_ARGUMENT, "view[5]: nan");
    view[5] = 2.0f;
    EXPECT_FAIL(kodawari_camera_from_view_matrix(view, 0, &camera), KODAWARI_INVALID_ARGUMENT, "not orthonormal");
    view[5] = 1.0f;
    view[3] = 0.5f;
    EXPECT_FAIL(kodawari_camera_from_view_matrix(view, 0, &camera), KODAWARI_INVALID_ARGUMENT, "last row", "not a projection");
    CHECK(memcmp(&camera, &untouched, sizeof camera) == 0, "a rejected call wrote its output");
}

/* create: every kind of bad description is rejected with the argument's path, and *out is NULL. */
static void test_chain_create_rejects(void) {
    ahoge a;
    frame_data f;
    kodawari_chain_world* world = (kodawari_chain_world*)&a; /* not NULL: create must set it */
    kodawari_chain_frame initial;
    float saved;

#define REJECT(status, ...)                                                                      \
    do {                                                                                         \
        world = (kodawari_chain_world*)&a;                                                       \
        EXPECT_FAIL(kodawari_chain_world_create(&a.desc, &initial, &world), status, __VA_ARGS__); \
        CHECK(world == NULL, "a failed create left *out set");                                   \
        make_ahoge(&a, KODAWARI_BACKEND_CPU_REFERENCE);                                          \
        make_frame(&f, 0);                                                                       \
        initial = f.frame;                                                                       \
    } while (0)

    make_ahoge(&a, KODAWARI_BACKEND_CPU_REFERENCE);
    make_frame(&f, 0);
    initial = f.frame;
    EXPECT_FAIL(kodawari_chain_world_create(&a.desc, &initial, NULL), KODAWARI_INVALID_ARGUMENT, "kodawari_chain_world_create: out: is NULL");
    EXPECT_FAIL(kodawari_chain_world_create(NULL, &initial, &world), KODAWARI_INVALID_ARGUMENT, "desc: is NULL");
    CHECK(world == NULL, "*out set to NULL");
    EXPECT_FAIL(kodawari_chain_world_create(&a.desc, NULL, &world), KODAWARI_INVALID_ARGUMENT, "initial: is NULL");

    a.desc.template_count = 0;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->template_count: 0");
    a.desc.templates = NULL;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates: is NULL, but desc->template_count is 1");
    a.desc.chain_count = 0;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->chain_count: 0");
    a.desc.character_count = 0;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->character_count: 0");
    a.templ.joint_count = 1;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].joint_count: 1; expected 2 to 32");
    a.templ.joint_count = 33;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].joint_count: 33");
    a.templ.base.positions = NULL;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].base.positions: is NULL");
    a.base[7] = (float)NAN;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].base.positions[2]", "finite");
    a.base[7] = (float)INFINITY;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].base.positions[2]", "inf");
    a.base[0] = 0.5f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].base.positions[0]", "expected (0, 0, 0)");
    /* Joint 3 on joint 2: a zero-length segment. */
    memcpy(a.base + 9, a.base + 6, 3 * sizeof(float));
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].base.positions[3]: 0 m from joint 2",
           "segments must be at least 1e-06 m long");
    memcpy(a.shapes[2] + 15, a.shapes[2] + 12, 3 * sizeof(float));
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].views[2].shape.positions[5]: 0 m from joint 4");
    {
        float orientations[kJoints * 4];
        int i;
        for (i = 0; i < kJoints; ++i) {
            orientations[4 * i] = orientations[4 * i + 1] = orientations[4 * i + 2] = 0.0f;
            orientations[4 * i + 3] = 1.0f;
        }
        orientations[4 * 6 + 3] = 0.5f;
        a.templ.base.orientations = orientations;
        REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].base.orientations[6]", "expected a unit quaternion");
    }
    a.templ.view_count = 8;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].view_count: 8; expected 0 to 7");
    a.templ.views = NULL;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].views: is NULL, but desc->templates[0].view_count is 5");
    a.views[2].direction[0] = 0.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].views[2].direction: (0, 0, 0) is a zero vector");
    a.views[1].direction[2] = (float)NAN;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].views[1].direction");
    a.views[4].influence = 0.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].views[4].influence: 0; expected a number in (0, 1000]");
    a.views[4].influence = (float)NAN;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].views[4].influence: nan");
    a.templ.thickness = 0.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].thickness: 0; expected a number in [1e-05, 1]");
    a.templ.mass = (float)INFINITY;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].mass: inf");
    a.templ.solver.iterations = 0;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.iterations: 0; expected 1 to 64");
    a.templ.solver.max_substep = 1.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.max_substep: 1; expected a number in [1e-04, 0.05]");
    a.templ.solver.max_substep = 1e-9f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.max_substep: 1e-09");
    a.templ.solver.stiffness = 2.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.stiffness: 2; expected a number in [0, 1]");
    a.templ.solver.rest_stiffness = -0.5f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.rest_stiffness: -0.5");
    a.templ.solver.damping = -1.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.damping: -1");
    a.templ.solver.gravity[1] = (float)NAN;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.gravity");
    a.templ.solver.wind[0] = 5000.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.wind", "within 1000");
    a.templ.solver.momentum_suppression = 1.5f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.momentum_suppression: 1.5");
    a.templ.solver.settle_start = 2;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.settle_start: 2; expected 0 or 1");
    a.templ.solver.teleport_distance = 0.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.teleport_distance: 0");
    a.templ.solver.normal_drag = -1.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.normal_drag: -1; expected a number in [0, 1000]");
    a.templ.solver.tangent_drag = (float)NAN;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->templates[0].solver.tangent_drag: nan");
    a.chain.template_index = 1;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->chains[0].template_index: 1; expected an index below desc->template_count (1)");
    a.chain.character = 3;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->chains[0].character: 3");
    a.chain.collider_begin = 1;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->chains[0].collider_begin", "do not fit in desc->collider_count (1)");
    a.chain.collider_count = 17;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->chains[0].collider_count: 17; expected at most 16");
    a.head_sphere.character = 1;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->colliders[0].character: 1");
    a.head_sphere.local.radius = -0.1f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->colliders[0].local.radius: -0.1");
    a.desc.backend.backend = (kodawari_backend)7;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->backend.backend: 7");
    a.desc.backend.validation = 2;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->backend.validation: 2; expected 0 or 1");
    a.desc.backend.threads = 5000;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->backend.threads: 5000");
    a.desc.backend.backend = KODAWARI_BACKEND_CPU;
    a.desc.backend.isa = "avx9";
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->backend.isa", "avx9", "scalar");
    a.desc.backend.isa = "scalar";
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->backend.isa: \"scalar\" with a backend other than KODAWARI_BACKEND_CPU");
    a.desc.backend.workgroup_size = 128;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->backend.workgroup_size: 128 with a backend other than KODAWARI_BACKEND_VULKAN");
    a.desc.backend.backend = KODAWARI_BACKEND_VULKAN;
    a.desc.backend.workgroup_size = 48;
    REJECT(KODAWARI_INVALID_ARGUMENT, "desc->backend.workgroup_size: 48; expected 0 (64) or a power of two from 32 to 1024");
    initial.reference_count = 2;
    REJECT(KODAWARI_INVALID_ARGUMENT, "initial->reference_count: 2; expected 1 (one per character)");
    f.root.rotation[3] = 0.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "initial->roots[0].rotation: (0, 0, 0, 0) has length 0", "unit quaternion");
    initial.camera.forward[0] = initial.camera.forward[1] = initial.camera.forward[2] = 0.0f;
    REJECT(KODAWARI_INVALID_ARGUMENT, "initial->camera.forward: (0, 0, 0) is a zero vector");
    initial.camera.orthographic = 3;
    REJECT(KODAWARI_INVALID_ARGUMENT, "initial->camera.orthographic: 3");
    initial.collider_count = 1;
    REJECT(KODAWARI_INVALID_ARGUMENT, "initial->colliders: is NULL, but initial->collider_count is 1");
    /* Without attachments, frames must give the colliders. */
    a.desc.colliders = NULL;
    REJECT(KODAWARI_INVALID_ARGUMENT, "initial->colliders: is NULL, but the world's 1 colliders have no attachments");
    /* dt is not used by create: any value. */
    saved = initial.dt;
    initial.dt = (float)NAN;
    EXPECT_OK(kodawari_chain_world_create(&a.desc, &initial, &world));
    kodawari_chain_world_destroy(world);
    initial.dt = saved;
#undef REJECT
}

/* step, reset, read, chain_joints, get_info: bad input rejected, the state unchanged (the
 * world steps on to the same bits as a twin that never saw the bad calls). */
static void test_chain_calls_reject(void) {
    kodawari_chain_world* world = create_ahoge(KODAWARI_BACKEND_CPU);
    kodawari_chain_world* twin = create_ahoge(KODAWARI_BACKEND_CPU);
    chain_state before, after, twin_state;
    frame_data f, bad;
    kodawari_chain_output out;
    kodawari_capsule collider;
    float small[kJoints * 3];
    uint32_t begin = 99, count = 99;
    int i;
    if (world == NULL || twin == NULL) return;
    for (i = 1; i <= 20; ++i) {
        make_frame(&f, i * 11);
        EXPECT_OK(kodawari_chain_world_step(world, &f.frame));
        EXPECT_OK(kodawari_chain_world_step(twin, &f.frame));
    }
    EXPECT_OK(read_state(world, &before));
    make_frame(&f, 300);

    /* A NULL handle reports on the thread only. */
    EXPECT_FAIL(kodawari_chain_world_step(NULL, &f.frame), KODAWARI_INVALID_ARGUMENT, "kodawari_chain_world_step: world: is NULL");
    EXPECT_FAIL(kodawari_chain_world_step(world, NULL), KODAWARI_INVALID_ARGUMENT, "kodawari_chain_world_step: frame: is NULL");
    CHECK(strstr(kodawari_chain_world_last_error(world), "frame: is NULL") != NULL, "the handle keeps the message: \"%s\"",
          kodawari_chain_world_last_error(world));

#define REJECT_STEP(...)                                                                   \
    do {                                                                                   \
        EXPECT_FAIL(kodawari_chain_world_step(world, &bad.frame), KODAWARI_INVALID_ARGUMENT, __VA_ARGS__); \
        make_frame(&bad, 300);                                                             \
    } while (0)
    make_frame(&bad, 300);
    bad.frame.dt = 0.0f;
    REJECT_STEP("frame->dt: 0; expected a number in [1e-05, 1]");
    bad.frame.dt = (float)NAN;
    REJECT_STEP("frame->dt: nan");
    bad.frame.dt = 2.0f;
    REJECT_STEP("frame->dt: 2");
    bad.frame.reference_count = 0;
    REJECT_STEP("frame->reference_count: 0; expected 1 (one per character)");
    bad.frame.references = NULL;
    REJECT_STEP("frame->references: is NULL, but frame->reference_count is 1");
    bad.frame.root_count = 2;
    REJECT_STEP("frame->root_count: 2; expected 1 (one per chain)");
    bad.root.position[1] = (float)INFINITY;
    REJECT_STEP("frame->roots[0].position: (0, inf, 0)", "within 1e+06 m");
    bad.head.rotation[0] = 1.0f;
    REJECT_STEP("frame->references[0].rotation", "has length 1.41421");
    bad.frame.camera.position[2] = (float)NAN;
    REJECT_STEP("frame->camera.position");
    bad.frame.camera.forward[0] = bad.frame.camera.forward[1] = bad.frame.camera.forward[2] = 0.0f;
    REJECT_STEP("frame->camera.forward", "zero vector");
    collider.a[0] = collider.a[1] = collider.a[2] = 0.0f;
    collider.b[0] = collider.b[1] = collider.b[2] = 0.0f;
    collider.radius = -1.0f;
    bad.frame.colliders = &collider;
    bad.frame.collider_count = 1;
    REJECT_STEP("frame->colliders[0].radius: -1");
    bad.frame.colliders = &collider;
    bad.frame.collider_count = 2;
    REJECT_STEP("frame->collider_count: 2; expected 1 (the world's colliders)");
    bad.frame.collider_count = 1;
    REJECT_STEP("frame->colliders: is NULL, but frame->collider_count is 1");
#undef REJECT_STEP

    EXPECT_FAIL(kodawari_chain_world_reset(NULL, &f.frame), KODAWARI_INVALID_ARGUMENT, "kodawari_chain_world_reset: world: is NULL");
    EXPECT_FAIL(kodawari_chain_world_reset(world, NULL), KODAWARI_INVALID_ARGUMENT, "frame: is NULL");
    make_frame(&bad, 0);
    bad.frame.root_count = 0;
    EXPECT_FAIL(kodawari_chain_world_reset(world, &bad.frame), KODAWARI_INVALID_ARGUMENT, "frame->root_count: 0");

    /* read: too small a buffer names the array, says how many floats it needs, writes nothing. */
    EXPECT_FAIL(kodawari_chain_world_read(NULL, &out), KODAWARI_INVALID_ARGUMENT, "world: is NULL");
    EXPECT_FAIL(kodawari_chain_world_read(world, NULL), KODAWARI_INVALID_ARGUMENT, "kodawari_chain_world_read: out: is NULL");
    memset(&out, 0, sizeof out);
    memset(small, 0x7f, sizeof small);
    out.positions = small;
    out.positions_capacity = kJoints * 3 - 1;
    EXPECT_FAIL(kodawari_chain_world_read(world, &out), KODAWARI_BUFFER_TOO_SMALL,
                "out->positions: holds 35 floats, needs 36 (12 joints x 3)");
    for (i = 0; i < kJoints * 3; ++i) CHECK(small[i] == small[0] && small[0] != 0.0f, "a rejected read wrote [%d]", i);
    out.positions_capacity = kJoints * 3;
    out.orientations = after.orientations;
    out.orientations_capacity = 47;
    EXPECT_FAIL(kodawari_chain_world_read(world, &out), KODAWARI_BUFFER_TOO_SMALL, "out->orientations: holds 47 floats, needs 48");
    out.orientations = NULL;
    out.weights = after.weights;
    out.weights_capacity = 7;
    EXPECT_FAIL(kodawari_chain_world_read(world, &out), KODAWARI_BUFFER_TOO_SMALL, "out->weights: holds 7 floats, needs 8");
    CHECK(strstr(kodawari_chain_world_last_error(world), "out->weights") != NULL, "handle message \"%s\"",
          kodawari_chain_world_last_error(world));
    /* NULL arrays are not read: a read of positions alone. */
    out.weights = NULL;
    EXPECT_OK(kodawari_chain_world_read(world, &out));
    CHECK(strcmp(kodawari_chain_world_last_error(world), "") == 0, "a call that succeeded clears the handle's message");
    CHECK(memcmp(small, before.positions, sizeof small) == 0, "read of positions alone");

    EXPECT_FAIL(kodawari_chain_world_chain_joints(NULL, 0, &begin, &count), KODAWARI_INVALID_ARGUMENT, "world: is NULL");
    EXPECT_FAIL(kodawari_chain_world_chain_joints(world, 1, &begin, &count), KODAWARI_INVALID_ARGUMENT,
                "chain: 1; expected an index below the world's chain count (1)");
    CHECK(begin == 99 && count == 99, "a rejected call wrote its outputs");
    EXPECT_OK(kodawari_chain_world_chain_joints(world, 0, &begin, &count));
    CHECK(begin == 0 && count == kJoints, "chain 0: %u joints from %u", count, begin);
    EXPECT_OK(kodawari_chain_world_chain_joints(world, 0, NULL, NULL));
    EXPECT_FAIL(kodawari_chain_world_get_info(NULL, NULL), KODAWARI_INVALID_ARGUMENT, "world: is NULL");
    EXPECT_FAIL(kodawari_chain_world_get_info(world, NULL), KODAWARI_INVALID_ARGUMENT, "out: is NULL");
    {
        /* set_wind: a field out of range names the member and leaves the world's air as it was. */
        kodawari_wind wind;
        EXPECT_OK(kodawari_wind_default(&wind));
        EXPECT_FAIL(kodawari_chain_world_set_wind(NULL, &wind), KODAWARI_INVALID_ARGUMENT,
                    "kodawari_chain_world_set_wind: world: is NULL");
        wind.gust = 5.0f;
        EXPECT_FAIL(kodawari_chain_world_set_wind(world, &wind), KODAWARI_INVALID_ARGUMENT, "wind.gust: 5; expected a number in [0, 4]");
        wind.gust = 0.5f;
        wind.velocity[2] = (float)INFINITY;
        EXPECT_FAIL(kodawari_chain_world_set_wind(world, &wind), KODAWARI_INVALID_ARGUMENT, "wind.velocity");
        wind.velocity[2] = 0.0f;
        wind.gust_period = 0.0f;
        EXPECT_FAIL(kodawari_chain_world_set_wind(world, &wind), KODAWARI_INVALID_ARGUMENT, "wind.gust_period: 0");
        wind.gust_period = 3.0f;
        wind.gust_size = 1e5f;
        EXPECT_FAIL(kodawari_chain_world_set_wind(world, &wind), KODAWARI_INVALID_ARGUMENT, "wind.gust_size: 1e+05; expected a number in [0.05, 10000]");
        EXPECT_OK(kodawari_chain_world_set_wind(world, NULL)); /* calm, as it was */
    }

    /* Nothing of that changed the world: the same state, and the next step gives the twin's bits. */
    EXPECT_OK(read_state(world, &after));
    CHECK(memcmp(&before, &after, sizeof before) == 0, "rejected calls changed the state");
    EXPECT_OK(kodawari_chain_world_step(world, &f.frame));
    EXPECT_OK(kodawari_chain_world_step(twin, &f.frame));
    EXPECT_OK(read_state(world, &after));
    EXPECT_OK(read_state(twin, &twin_state));
    CHECK(memcmp(&after, &twin_state, sizeof after) == 0, "after rejected calls the world steps differently from its twin");
    {
        /* And a wind blows: the world in a 10 m/s wind steps elsewhere than its twin in calm air. */
        kodawari_wind wind;
        EXPECT_OK(kodawari_wind_default(&wind));
        wind.velocity[0] = 10.0f;
        wind.gust = 0.5f;
        EXPECT_OK(kodawari_chain_world_set_wind(world, &wind));
        for (i = 0; i < 10; ++i) {
            make_frame(&f, 320 + i);
            EXPECT_OK(kodawari_chain_world_step(world, &f.frame));
            EXPECT_OK(kodawari_chain_world_step(twin, &f.frame));
        }
        EXPECT_OK(read_state(world, &after));
        EXPECT_OK(read_state(twin, &twin_state));
        CHECK(memcmp(&after, &twin_state, sizeof after) != 0, "a 10 m/s wind left the chain as in calm air");
    }
    kodawari_chain_world_destroy(world);
    kodawari_chain_world_destroy(twin);
    kodawari_chain_world_destroy(NULL);
}

/* vulkan: runs the ahoge where a device exists, else says why (KODAWARI_UNAVAILABLE). */
static void test_vulkan(void) {
    ahoge a;
    frame_data f;
    kodawari_chain_world* world = NULL;
    kodawari_status status;
    make_ahoge(&a, KODAWARI_BACKEND_VULKAN);
    make_frame(&f, 0);
    status = kodawari_chain_world_create(&a.desc, &f.frame, &world);
    if (status == KODAWARI_UNAVAILABLE) {
        printf("test_capi: vulkan skipped: no Vulkan device here (%s)\n", kodawari_last_error());
        CHECK(strlen(kodawari_last_error()) > 0, "UNAVAILABLE says why");
        return;
    }
    EXPECT_OK(status);
    kodawari_chain_world_destroy(world);
    test_ahoge(KODAWARI_BACKEND_VULKAN, "vulkan");
}

/* ---- Birds ------------------------------------------------------------------------------ */

enum { kWaypoints = 6, kRoutePoints = 3 * kWaypoints + 1, kPigeons = 37, kGulls = 5 };

/* A closed route through 6 waypoints on a circle of 20 m at 10 m height (Catmull-Rom
 * handles, as kodawari.h describes). */
static void loop_route(float* points) {
    float w[kWaypoints][3];
    int k, c;
    for (k = 0; k < kWaypoints; ++k) {
        const float a = 2.0f * PI_F * (float)k / (float)kWaypoints;
        w[k][0] = 20.0f * cosf(a);
        w[k][1] = 10.0f;
        w[k][2] = 20.0f * sinf(a);
    }
    for (k = 0; k < kWaypoints; ++k) {
        const float* p0 = w[k];
        const float* p1 = w[(k + 1) % kWaypoints];
        const float* before = w[(k + kWaypoints - 1) % kWaypoints];
        const float* after = w[(k + 2) % kWaypoints];
        for (c = 0; c < 3; ++c) {
            points[9 * k + c] = p0[c];
            points[9 * k + 3 + c] = p0[c] + (p1[c] - before[c]) / 6.0f;
            points[9 * k + 6 + c] = p1[c] - (after[c] - p0[c]) / 6.0f;
        }
    }
    for (c = 0; c < 3; ++c) points[3 * (kRoutePoints - 1) + c] = points[c]; /* the loop closes on its first point */
}

typedef struct flock {
    float points[kRoutePoints * 3];
    float line[4 * 3];
    kodawari_route_desc routes[2];
    kodawari_flock_desc flocks[2];
    float offsets[kPigeons * 4];
    kodawari_bird_world_desc desc;
} flock;

static void make_flock(flock* f, kodawari_backend backend) {
    int b;
    static const float line[4 * 3] = {0, 5, 0, 10, 5, 0, 20, 5, 0, 30, 5, 0};
    memset(f, 0, sizeof *f);
    loop_route(f->points);
    memcpy(f->line, line, sizeof line);
    f->routes[0].points = f->points;
    f->routes[0].point_count = kRoutePoints;
    f->routes[0].loop = 1;
    f->routes[1].points = f->line;
    f->routes[1].point_count = 4;
    kodawari_flock_desc_default(KODAWARI_WING_PIGEON, kPigeons, &f->flocks[0]);
    kodawari_flock_desc_default(KODAWARI_WING_GULL, kGulls, &f->flocks[1]);
    f->flocks[1].route = 1;
    for (b = 0; b < kPigeons; ++b) {
        f->offsets[4 * b] = 0.1f * (float)(b % 5);
        f->offsets[4 * b + 1] = 0.05f * (float)(b % 3);
        f->offsets[4 * b + 2] = 0.0f;
        f->offsets[4 * b + 3] = 0.02f * (float)b;
    }
    f->flocks[0].offsets = f->offsets;
    f->desc.routes = f->routes;
    f->desc.route_count = 2;
    f->desc.flocks = f->flocks;
    f->desc.flock_count = 2;
    f->desc.fps = 60.0f;
    kodawari_flight_settings_default(&f->desc.flight);
    f->desc.backend.backend = backend;
}

static void test_birds(void) {
    enum { kFrames = 61, kBirds = kPigeons + kGulls, kFloats = kFrames * kBirds * KODAWARI_BIRD_PARTS * KODAWARI_TRANSFORM_FLOATS };
    static float local[kFloats], global[kFloats], again[kFloats];
    static const int parents[KODAWARI_BIRD_PARTS] = {-1, 0, 0, 0, 3, 0, 5};
    flock f;
    kodawari_bird_world* world = NULL;
    kodawari_bird_world_info info;
    kodawari_bird_output out;
    int frame, b, k;
    float worst_speed = 0.0f, worst_compose = 0.0f;
    make_flock(&f, KODAWARI_BACKEND_CPU);
    EXPECT_OK(kodawari_bird_world_create(&f.desc, &world));
    if (world == NULL) return;
    EXPECT_OK(kodawari_bird_world_get_info(world, &info));
    CHECK(info.bird_count == kBirds && info.route_count == 2 && info.next_frame == 0 && info.fps == 60.0f, "info");
    memset(&out, 0, sizeof out);
    out.local_transforms = local;
    out.local_transforms_capacity = kFloats;
    out.world_transforms = global;
    out.world_transforms_capacity = kFloats;
    EXPECT_OK(kodawari_bird_world_simulate(world, kFrames, &out));
    EXPECT_OK(kodawari_bird_world_get_info(world, &info));
    CHECK(info.next_frame == kFrames, "next frame %u", info.next_frame);
    for (frame = 0; frame < kFrames; ++frame) {
        for (b = 0; b < kBirds; ++b) {
            const float* l = local + (size_t)(frame * kBirds + b) * 49;
            const float* g = global + (size_t)(frame * kBirds + b) * 49;
            /* The route: pigeons within 20 m (+ offsets) of the loop's centre at 10 m height,
             * gulls on the straight line at 5 m. */
            if (b < kPigeons) {
                const float r = sqrtf(g[0] * g[0] + g[2] * g[2]);
                CHECK(fabsf(r - 20.0f) < 2.0f && fabsf(g[1] - 10.0f) < 1.0f, "pigeon %d frame %d at (%g, %g, %g)", b, frame, g[0], g[1], g[2]);
            } else {
                /* y within the wingbeat's bob, 0.05 body lengths x amplitude (flight-modes.md F.4). */
                CHECK(fabsf(g[1] - 5.0f) < 0.03f && fabsf(g[2]) < 1e-3f, "gull %d frame %d at (%g, %g, %g)", b, frame, g[0], g[1], g[2]);
            }
            /* World = the locals composed down the rig. */
            for (k = 1; k < KODAWARI_BIRD_PARTS; ++k) {
                const float* parent = g + 7 * parents[k];
                float p[3], e;
                rotate(parent + 3, l + 7 * k, p);
                e = fabsf(parent[0] + p[0] - g[7 * k]) + fabsf(parent[1] + p[1] - g[7 * k + 1]) + fabsf(parent[2] + p[2] - g[7 * k + 2]);
                if (e > worst_compose) worst_compose = e;
            }
            /* Speed along the route: one frame moves speed / fps (arc-length timing), measured
             * across (both routes are level; y carries the bob). */
            if (frame > 0) {
                const float* previous = global + (size_t)((frame - 1) * kBirds + b) * 49;
                const float speed = sqrtf((g[0] - previous[0]) * (g[0] - previous[0]) + (g[2] - previous[2]) * (g[2] - previous[2])) * 60.0f;
                const float expected = f.flocks[b < kPigeons ? 0 : 1].speed;
                const float e = fabsf(speed - expected) / expected;
                if (e > worst_speed) worst_speed = e;
            }
        }
    }
    CHECK(worst_compose < 1e-4f, "world transforms differ from the composed locals by %g m", worst_compose);
    /* The loop's curvature shortens the chord of a frame against its arc by < 0.1%. */
    CHECK(worst_speed < 0.01f, "a bird's speed was off by %g of the flock's", worst_speed);
    printf("test_capi: %d birds x %d frames: speed within %.2g, world = composed locals within %.2g m\n", kBirds, kFrames,
           (double)worst_speed, (double)worst_compose);

    /* Rewind: the same bits again. */
    EXPECT_OK(kodawari_bird_world_rewind(world));
    out.local_transforms = NULL;
    out.world_transforms = again;
    EXPECT_OK(kodawari_bird_world_simulate(world, kFrames, &out));
    CHECK(memcmp(again, global, sizeof again) == 0, "rewind gave other bits");
    kodawari_bird_world_destroy(world);
}

/* A take-off and a landing through the C API: a gull sits on the perch at the route's
 * start, and 0.3 s (crouch) + 2 x 5 s (take-off and landing at 12 m/s over 30 m each)
 * later sits on the one at its end (docs/flight-modes.md F.2). */
static void test_birds_perch(void) {
    enum { kFrames = 700 };
    static const float points[7 * 3] = {0, 5, 0, 10, 5, 0, 20, 5, 0, 30, 5, 0, 40, 5, 0, 50, 5, 0, 60, 5, 0};
    static const int32_t modes[2] = {KODAWARI_SEGMENT_TAKEOFF, KODAWARI_SEGMENT_LANDING};
    static float global[kFrames * KODAWARI_BIRD_PARTS * KODAWARI_TRANSFORM_FLOATS];
    kodawari_route_desc route;
    kodawari_flock_desc flock_desc;
    kodawari_bird_world_desc desc;
    kodawari_bird_world* world = NULL;
    kodawari_bird_output out;
    const float* first;
    const float* last;
    memset(&route, 0, sizeof route);
    route.points = points;
    route.point_count = 7;
    route.modes = modes;
    kodawari_flock_desc_default(KODAWARI_WING_GULL, 1, &flock_desc);
    flock_desc.speed = 12.0f;
    memset(&desc, 0, sizeof desc);
    desc.routes = &route;
    desc.route_count = 1;
    desc.flocks = &flock_desc;
    desc.flock_count = 1;
    desc.fps = 60.0f;
    kodawari_flight_settings_default(&desc.flight);
    desc.backend.backend = KODAWARI_BACKEND_CPU;
    EXPECT_OK(kodawari_bird_world_create(&desc, &world));
    if (world == NULL) return;
    memset(&out, 0, sizeof out);
    out.world_transforms = global;
    out.world_transforms_capacity = sizeof global / sizeof global[0];
    EXPECT_OK(kodawari_bird_world_simulate(world, kFrames, &out));
    first = global;
    last = global + (size_t)(kFrames - 1) * KODAWARI_BIRD_PARTS * KODAWARI_TRANSFORM_FLOATS;
    CHECK(distance3(first, points) < 1e-4f, "frame 0 at (%g, %g, %g), not on the first perch", first[0], first[1], first[2]);
    CHECK(distance3(last, points + 18) < 1e-3f, "the last frame at (%g, %g, %g), not on the last perch", last[0], last[1], last[2]);
    kodawari_bird_world_destroy(world);
}

static void test_birds_reject(void) {
    flock f;
    kodawari_bird_world* world = NULL;
    kodawari_bird_world* twin = NULL;
    kodawari_bird_world_info info;
    kodawari_bird_output out;
    kodawari_flock_desc flock_desc;
    float buffer[(kPigeons + kGulls) * 49 * 2], twin_buffer[(kPigeons + kGulls) * 49 * 2];
    float phases[kPigeons];
    static const int32_t bad_modes[1] = {2}, landing_first[1] = {KODAWARI_SEGMENT_LANDING}, hover[1] = {KODAWARI_SEGMENT_HOVER};

#define REJECT(...)                                                                             \
    do {                                                                                        \
        world = (kodawari_bird_world*)&f;                                                       \
        EXPECT_FAIL(kodawari_bird_world_create(&f.desc, &world), KODAWARI_INVALID_ARGUMENT, __VA_ARGS__); \
        CHECK(world == NULL, "a failed create left *out set");                                  \
        make_flock(&f, KODAWARI_BACKEND_CPU_REFERENCE);                                         \
    } while (0)
    make_flock(&f, KODAWARI_BACKEND_CPU_REFERENCE);
    EXPECT_FAIL(kodawari_bird_world_create(NULL, &world), KODAWARI_INVALID_ARGUMENT, "kodawari_bird_world_create: desc: is NULL");
    EXPECT_FAIL(kodawari_bird_world_create(&f.desc, NULL), KODAWARI_INVALID_ARGUMENT, "out: is NULL");
    f.desc.route_count = 0;
    REJECT("desc->route_count: 0");
    f.desc.flocks = NULL;
    REJECT("desc->flocks: is NULL, but desc->flock_count is 2");
    f.desc.fps = 0.0f;
    REJECT("desc->fps: 0; expected a number in [0.01, 1000]");
    f.routes[1].point_count = 5;
    REJECT("desc->routes[1].point_count: 5; expected 3n + 1");
    f.routes[0].points = NULL;
    REJECT("desc->routes[0].points: is NULL");
    f.line[7] = (float)NAN;
    REJECT("desc->routes[1].points[2]", "finite");
    memcpy(f.line + 6, f.line + 3, 3 * sizeof(float));
    REJECT("desc->routes[1].points[2]: coincides with points[1]");
    f.points[3 * (kRoutePoints - 1)] += 1.0f;
    REJECT("desc->routes[0].loop", "must end where it starts");
    f.routes[0].loop = 2;
    REJECT("desc->routes[0].loop: 2; expected 0 or 1");
    f.routes[1].parametric = 1;
    f.routes[1].segment_duration = 0.0f;
    REJECT("desc->routes[1].segment_duration: 0");
    f.flocks[1].route = 2;
    REJECT("desc->flocks[1].route: 2; expected an index below desc->route_count (2)");
    f.routes[1].modes = bad_modes;
    REJECT("desc->routes[1].modes[0]: 2; expected a kodawari_segment_mode");
    f.routes[1].modes = landing_first;
    REJECT("desc->routes[1].modes[0]: a route cannot start with \"landing\"");
    f.routes[1].modes = hover;
    REJECT("desc->flocks[1].wing_type: gull cannot hover, but its route's segment 0 is KODAWARI_SEGMENT_HOVER");
    f.flocks[0].wing_type = (kodawari_wing_type)5;
    REJECT("desc->flocks[0].wing_type: 5");
    f.flocks[1].count = 0;
    REJECT("desc->flocks[1].count: 0");
    f.flocks[0].speed = 0.0f;
    REJECT("desc->flocks[0].speed: 0");
    f.flocks[1].frequency = (float)INFINITY;
    REJECT("desc->flocks[1].frequency: inf");
    f.flocks[0].amplitude = 4.0f;
    REJECT("desc->flocks[0].amplitude: 4; expected a number in (0, 3]");
    f.offsets[4 * 20 + 1] = (float)NAN;
    REJECT("desc->flocks[0].offsets[20] (x, y, z)");
    f.offsets[4 * 3 + 3] = -1.0f;
    REJECT("desc->flocks[0].offsets[3] (w, the time offset in s): -1");
    memset(phases, 0, sizeof phases);
    phases[36] = 1.0f;
    f.flocks[0].phases = phases;
    REJECT("desc->flocks[0].phases[36]: 1; expected a number in [0, 1)");
    f.desc.flight.ascend_exit = 0.5f;
    REJECT("desc->flight.ascend_exit", "expected below ascend_enter");
    f.desc.flight.descend_exit = 0.1f;
    REJECT("desc->flight.descend_exit", "at or below ascend_exit");
    f.desc.flight.blend_rates[2] = 0.0f;
    REJECT("desc->flight.blend_rates[2]: 0");
    f.desc.flight.max_bank = 2.0f;
    REJECT("desc->flight.max_bank: 2");
    f.desc.flight.seed_mode_rule = 9;
    REJECT("desc->flight.seed_mode_rule: 9");
    f.desc.flight.bank_time_constant = 11.0f;
    REJECT("desc->flight.bank_time_constant: 11");
    f.desc.backend.backend = (kodawari_backend)(-1);
    REJECT("desc->backend.backend: -1");
#undef REJECT
    EXPECT_FAIL(kodawari_flock_desc_default((kodawari_wing_type)9, 1, &flock_desc), KODAWARI_INVALID_ARGUMENT, "wing_type: 9");
    EXPECT_FAIL(kodawari_flock_desc_default((kodawari_wing_type)5, 1, &flock_desc), KODAWARI_INVALID_ARGUMENT, "_STARLING (4)");
    EXPECT_OK(kodawari_flock_desc_default(KODAWARI_WING_HUMMINGBIRD, 1, &flock_desc));
    EXPECT_OK(kodawari_flock_desc_default(KODAWARI_WING_STARLING, 1, &flock_desc));
    CHECK(fabsf(flock_desc.speed - 15.0f) < 1e-6f, "a starling's default speed is docs/wing-types.md's 15 m/s, got %g", flock_desc.speed);
    EXPECT_FAIL(kodawari_flock_desc_default(KODAWARI_WING_HAWK, 1, NULL), KODAWARI_INVALID_ARGUMENT, "out: is NULL");

    /* simulate, rewind, get_info on a world and its twin. */
    EXPECT_OK(kodawari_bird_world_create(&f.desc, &world));
    EXPECT_OK(kodawari_bird_world_create(&f.desc, &twin));
    if (world == NULL || twin == NULL) return;
    EXPECT_OK(kodawari_bird_world_simulate(world, 3, NULL));
    EXPECT_OK(kodawari_bird_world_simulate(twin, 3, NULL));
    memset(&out, 0, sizeof out);
    out.world_transforms = buffer;
    out.world_transforms_capacity = (kPigeons + kGulls) * 49 * 2 - 1;
    EXPECT_FAIL(kodawari_bird_world_simulate(world, 2, &out), KODAWARI_BUFFER_TOO_SMALL,
                "out->world_transforms: holds 4115 floats, needs 4116 (2 frames x 42 birds x 7 parts x 7)");
    EXPECT_FAIL(kodawari_bird_world_simulate(NULL, 1, &out), KODAWARI_INVALID_ARGUMENT, "world: is NULL");
    EXPECT_FAIL(kodawari_bird_world_simulate(world, 0, &out), KODAWARI_INVALID_ARGUMENT, "frames: 0; expected 1 to 100000");
    EXPECT_FAIL(kodawari_bird_world_simulate(world, 100001, NULL), KODAWARI_INVALID_ARGUMENT, "frames: 100001");
    CHECK(strstr(kodawari_bird_world_last_error(world), "frames: 100001") != NULL, "handle message \"%s\"",
          kodawari_bird_world_last_error(world));
    EXPECT_FAIL(kodawari_bird_world_rewind(NULL), KODAWARI_INVALID_ARGUMENT, "kodawari_bird_world_rewind: world: is NULL");
    EXPECT_FAIL(kodawari_bird_world_get_info(world, NULL), KODAWARI_INVALID_ARGUMENT, "out: is NULL");
    EXPECT_OK(kodawari_bird_world_get_info(world, &info));
    CHECK(info.next_frame == 3, "rejected calls moved the world to frame %u", info.next_frame);
    CHECK(strcmp(kodawari_bird_world_last_error(world), "") == 0, "a call that succeeded clears the handle's message");
    out.world_transforms_capacity = (kPigeons + kGulls) * 49 * 2;
    EXPECT_OK(kodawari_bird_world_simulate(world, 2, &out));
    out.world_transforms = twin_buffer;
    EXPECT_OK(kodawari_bird_world_simulate(twin, 2, &out));
    CHECK(memcmp(buffer, twin_buffer, sizeof buffer) == 0, "after rejected calls the world flies differently from its twin");
    kodawari_bird_world_destroy(world);
    kodawari_bird_world_destroy(twin);
    kodawari_bird_world_destroy(NULL);
}

int main(void) {
    printf("test_capi: Kodawari %s\n", kodawari_version());
    test_version_and_status();
    test_camera_from_view_matrix();
    test_ahoge(KODAWARI_BACKEND_CPU_REFERENCE, "cpu-reference");
    test_ahoge(KODAWARI_BACKEND_CPU, "cpu");
    test_orientations();
    test_backends_agree();
    test_attached_colliders();
    test_chain_create_rejects();
    test_chain_calls_reject();
    test_vulkan();
    test_birds();
    test_birds_perch();
    test_birds_reject();
    printf("test_capi: %d checks, %d failed\n", g_checks, g_failures);
    return g_failures == 0 ? 0 : 1;
}
