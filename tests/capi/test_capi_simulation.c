/* The C API's scene simulations (kodawari_simulation_*, issue 33) from C99: scenes/flock.json
 * and scenes/ahoge.json opened from their files, stepped, read and baked, with figures
 * checked (the bird count, the rig's rigid parts, flight speeds, the chain's root joint on
 * its root, cpu-reference and cpu giving the same bits, one long step giving the bits of
 * many short ones, a bake leaving the stepped state alone) and every entry point given bad
 * input: the status, the message naming the argument or the file, nothing changed; and
 * kodawari_rig_scene on scenes/characters/chibi.glb.
 *
 *   test_capi_simulation SOURCE_DIR TEMP_DIR
 *
 * Exit status 0 when every check passed; each failure prints its file, line and why. */
#include <kodawari/kodawari.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int g_failures = 0;
static int g_checks = 0;

#define CHECK(cond, ...)                                                                     \
    do {                                                                                     \
        ++g_checks;                                                                          \
        if (!(cond)) {                                                                       \
            ++g_failures;                                                                    \
            fprintf(stderr, "%s:%d: check failed: %s: ", __FILE__, __LINE__, #cond);        \
            fprintf(stderr, __VA_ARGS__);                                                    \
            fprintf(stderr, "\n");                                                           \
        }                                                                                    \
    } while (0)

/* As test_capi.c: the status must be `expected`, and the message (the thread's, and the
 * handle's when given) must contain every one of the NULL-terminated `needles`. */
static void expect_(const char* file, int line, kodawari_status status, kodawari_status expected,
                    const kodawari_simulation* sim, const char* const* needles) {
    const char* message = kodawari_last_error();
    ++g_checks;
    if (status != expected) {
        ++g_failures;
        fprintf(stderr, "%s:%d: expected %s, got %s: \"%s\"\n", file, line, kodawari_status_name(expected),
                kodawari_status_name(status), message);
        return;
    }
    if (sim != NULL && strcmp(kodawari_simulation_last_error(sim), message) != 0) {
        ++g_failures;
        fprintf(stderr, "%s:%d: the handle's message \"%s\" is not the thread's \"%s\"\n", file, line,
                kodawari_simulation_last_error(sim), message);
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
#define EXPECT_OK(call) expect_(__FILE__, __LINE__, (call), KODAWARI_OK, NULL, NULL)
#define EXPECT_FAIL(call, status, sim, ...)                                \
    do {                                                                   \
        const char* const needles_[] = {__VA_ARGS__, NULL};                \
        expect_(__FILE__, __LINE__, (call), (status), (sim), needles_);    \
    } while (0)

enum { kBirds = 270, kFrames = 30, kFloatsPerBird = KODAWARI_BIRD_PARTS * KODAWARI_TRANSFORM_FLOATS };

static char g_flock[4096];
static char g_ahoge[4096];
static char g_temp[4096];
static char g_not_scene[4096]; /* JSON, but not a scene */

static kodawari_simulation* open_scene(const char* path, kodawari_backend backend, uint32_t frames) {
    kodawari_backend_options options;
    kodawari_simulation* sim = NULL;
    memset(&options, 0, sizeof options);
    options.backend = backend;
    EXPECT_OK(kodawari_simulation_open(path, &options, frames, &sim));
    return sim;
}

static float distance3(const float* a, const float* b) {
    const float d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* Bird poses of the last frame, local and world. */
static void read_poses(kodawari_simulation* sim, float* local, float* world) {
    kodawari_bird_output out;
    out.local_transforms = local;
    out.local_transforms_capacity = local ? (size_t)kBirds * kFloatsPerBird : 0;
    out.world_transforms = world;
    out.world_transforms_capacity = world ? (size_t)kBirds * kFloatsPerBird : 0;
    EXPECT_OK(kodawari_simulation_bird_poses(sim, &out));
}

static void test_flock(void) {
    static float local[kBirds * kFloatsPerBird], world[kBirds * kFloatsPerBird], first[kBirds * kFloatsPerBird];
    kodawari_simulation_info info;
    kodawari_simulation* sim = open_scene(g_flock, KODAWARI_BACKEND_CPU_REFERENCE, kFrames);
    size_t b;
    int k;
    float fastest = 0.0f;
    if (sim == NULL) return;
    EXPECT_OK(kodawari_simulation_get_info(sim, &info));
    CHECK(info.bird_count == kBirds, "%u birds; scenes/flock.json has 120 + 90 + 60", info.bird_count);
    CHECK(info.chain_count == 0 && info.joint_count == 0 && info.character_count == 0, "%u chains", info.chain_count);
    CHECK(info.frame_count == kFrames && info.next_frame == 0, "%u frames, next %u", info.frame_count, info.next_frame);
    CHECK(info.fps == 60.0f, "%g fps", (double)info.fps);
    CHECK(info.backend == KODAWARI_BACKEND_CPU_REFERENCE, "backend %d", (int)info.backend);
    CHECK(strcmp(info.name, "flock") == 0, "name \"%s\"", info.name);

    EXPECT_OK(kodawari_simulation_step(sim, 10));
    read_poses(sim, NULL, first);
    EXPECT_OK(kodawari_simulation_step(sim, kFrames - 10));
    read_poses(sim, local, world);
    EXPECT_OK(kodawari_simulation_get_info(sim, &info));
    CHECK(info.next_frame == kFrames, "next frame %u", info.next_frame);
    for (b = 0; b < kBirds; ++b) {
        const float* l = local + b * kFloatsPerBird;
        const float* w = world + b * kFloatsPerBird;
        /* Body is in world space in both; each child part sits at its rig offset from its
         * parent (a rigid rig: the offset's length, to float rounding of a rotation). */
        CHECK(memcmp(l, w, 7 * sizeof(float)) == 0, "bird %u: Body local != world", (unsigned)b);
        for (k = 1; k < KODAWARI_BIRD_PARTS; ++k) {
            const int parent = (k == KODAWARI_PART_LEFT_ARM2) ? KODAWARI_PART_LEFT_ARM1
                               : (k == KODAWARI_PART_RIGHT_ARM2) ? KODAWARI_PART_RIGHT_ARM1 : KODAWARI_PART_BODY;
            const float* o = l + k * KODAWARI_TRANSFORM_FLOATS;
            const float length = sqrtf(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
            const float d = distance3(w + k * KODAWARI_TRANSFORM_FLOATS, w + parent * KODAWARI_TRANSFORM_FLOATS);
            CHECK(fabsf(d - length) <= 1e-5f * (1.0f + length), "bird %u part %d: %g m from its parent, offset %g m",
                  (unsigned)b, k, (double)d, (double)length);
        }
        {
            /* Frames 9 to 29: 20 frames at 60 fps. Every bird flies (faster than 1 m/s) and
             * none faster than 40 m/s (the wing types cruise at 8 to 20 m/s, jittered by
             * at most 8 %; the scene's formations do not add speed). */
            const float speed = distance3(w, first + b * kFloatsPerBird) / (20.0f / 60.0f);
            CHECK(speed > 1.0f && speed < 40.0f, "bird %u flew at %g m/s", (unsigned)b, (double)speed);
            if (speed > fastest) fastest = speed;
        }
    }
    {
        /* The tail spreads as the glTF export's Tail scale takes them: finite, and a
         * fan of at most a tail's width again (wingbeat.cpp's looks spread 0 to 0.9). */
        static float spreads[kBirds];
        EXPECT_OK(kodawari_simulation_bird_tail_spreads(sim, spreads, kBirds));
        for (b = 0; b < kBirds; ++b) {
            CHECK(spreads[b] >= 0.0f && spreads[b] <= 1.0f, "bird %u: tail spread %g", (unsigned)b, (double)spreads[b]);
        }
    }
    printf("flock: %u birds, %u frames on %s, fastest %.2f m/s\n", info.bird_count, info.frame_count, info.device,
           (double)fastest);

    /* Past the end, and zero frames: rejected, nothing changed. */
    EXPECT_FAIL(kodawari_simulation_step(sim, 1), KODAWARI_INVALID_ARGUMENT, sim, "kodawari_simulation_step", "frames",
                "stepped all its 30 frames: expected no further step");
    EXPECT_FAIL(kodawari_simulation_step(sim, 0), KODAWARI_INVALID_ARGUMENT, sim, "frames: 0");
    /* A scene of birds has no chains to read (nothing written), and no chain 0. */
    {
        float positions[3] = {7.0f, 7.0f, 7.0f};
        kodawari_chain_output out;
        memset(&out, 0, sizeof out);
        out.positions = positions;
        out.positions_capacity = 3;
        EXPECT_OK(kodawari_simulation_read_chains(sim, &out));
        CHECK(positions[0] == 7.0f, "read_chains wrote into a scene without chains");
        EXPECT_FAIL(kodawari_simulation_chain_joints(sim, 0, NULL, NULL), KODAWARI_INVALID_ARGUMENT, sim, "chain: 0",
                    "chain count (0)");
    }
    kodawari_simulation_destroy(sim);
}

/* The largest difference of two pose arrays: positions (floats 0-2 of each part) and
 * rotations (floats 3-6) apart. */
static void pose_difference(const float* a, const float* b, float* position, float* rotation) {
    size_t i;
    *position = 0.0f;
    *rotation = 0.0f;
    for (i = 0; i < (size_t)kBirds * kFloatsPerBird; ++i) {
        const float d = fabsf(a[i] - b[i]);
        float* max = (i % KODAWARI_TRANSFORM_FLOATS) < 3 ? position : rotation;
        if (d > *max) *max = d;
    }
}

/* cpu-reference and cpu agree as the bird backends' parity test says (tests/backends:
 * everything the decisions rest on bit for bit; the poses, which take the cpu backend's own
 * vectorized sines of the wingbeat phase, within BirdTolerances: rotations within 1e-4 rad,
 * which moves a unit quaternion's components by at most 5e-5, and positions within 1e-5 of
 * the route, 2e-3 m on these ~200 m routes). One step of 30 frames gives the bits of 30
 * steps of one. */
static void test_backends_agree(void) {
    static float reference[kBirds * kFloatsPerBird], cpu[kBirds * kFloatsPerBird], single[kBirds * kFloatsPerBird];
    kodawari_simulation* a = open_scene(g_flock, KODAWARI_BACKEND_CPU_REFERENCE, kFrames);
    kodawari_simulation* b = open_scene(g_flock, KODAWARI_BACKEND_CPU, kFrames);
    kodawari_simulation* c = open_scene(g_flock, KODAWARI_BACKEND_CPU, kFrames);
    float position = 0.0f, rotation = 0.0f;
    int f;
    if (a == NULL || b == NULL || c == NULL) return;
    EXPECT_OK(kodawari_simulation_step(a, kFrames));
    EXPECT_OK(kodawari_simulation_step(b, kFrames));
    for (f = 0; f < kFrames; ++f) EXPECT_OK(kodawari_simulation_step(c, 1));
    read_poses(a, reference, NULL);
    read_poses(b, cpu, NULL);
    read_poses(c, single, NULL);
    pose_difference(reference, cpu, &position, &rotation);
    printf("birds: cpu against cpu-reference, positions within %g m, rotations within %g\n", (double)position,
           (double)rotation);
    CHECK(position <= 2e-3f && rotation <= 5e-5f, "cpu's poses are %g m and %g off cpu-reference's", (double)position,
          (double)rotation);
    CHECK(memcmp(cpu, single, sizeof cpu) == 0, "30 steps of 1 frame differ from 1 step of 30");
    kodawari_simulation_destroy(a);
    kodawari_simulation_destroy(b);
    kodawari_simulation_destroy(c);
}

/* The chains of cpu and cpu-reference are the same bits (the rod backends' rule). */
static void test_chain_backends_agree(void) {
    enum { kAhogeFloats = 12 * 3 };
    float reference[kAhogeFloats], cpu[kAhogeFloats];
    kodawari_chain_output out;
    kodawari_simulation* a = open_scene(g_ahoge, KODAWARI_BACKEND_CPU_REFERENCE, 40);
    kodawari_simulation* b = open_scene(g_ahoge, KODAWARI_BACKEND_CPU, 40);
    if (a == NULL || b == NULL) return;
    EXPECT_OK(kodawari_simulation_step(a, 40));
    EXPECT_OK(kodawari_simulation_step(b, 40));
    memset(&out, 0, sizeof out);
    out.positions = reference;
    out.positions_capacity = kAhogeFloats;
    EXPECT_OK(kodawari_simulation_read_chains(a, &out));
    out.positions = cpu;
    EXPECT_OK(kodawari_simulation_read_chains(b, &out));
    CHECK(memcmp(reference, cpu, sizeof cpu) == 0, "the ahoge's joints differ between cpu and cpu-reference");
    kodawari_simulation_destroy(a);
    kodawari_simulation_destroy(b);
}

static void test_chains(void) {
    enum { kAhogeJoints = 12 };
    float positions[kAhogeJoints * 3], rest[kAhogeJoints * 3], orientations[kAhogeJoints * 4];
    kodawari_chain_output out;
    kodawari_simulation_info info;
    uint32_t begin = 99, count = 0;
    uint8_t levels[2] = {9, 9}, kept[2] = {9, 9};
    int j;
    kodawari_simulation* sim = open_scene(g_ahoge, KODAWARI_BACKEND_CPU, 20);
    if (sim == NULL) return;
    EXPECT_OK(kodawari_simulation_get_info(sim, &info));
    CHECK(info.chain_count == 1 && info.joint_count == kAhogeJoints && info.character_count == 1 && info.bird_count == 0,
          "%u chains, %u joints, %u characters, %u birds", info.chain_count, info.joint_count, info.character_count,
          info.bird_count);
    EXPECT_OK(kodawari_simulation_chain_joints(sim, 0, &begin, &count));
    CHECK(begin == 0 && count == kAhogeJoints, "chain 0: joints [%u, +%u)", begin, count);
    memset(&out, 0, sizeof out);
    out.positions = positions;
    out.positions_capacity = sizeof positions / sizeof(float);
    EXPECT_FAIL(kodawari_simulation_read_chains(sim, &out), KODAWARI_INVALID_ARGUMENT, sim, "no frame simulated yet");
    EXPECT_FAIL(kodawari_simulation_chain_levels(sim, levels, kept, 2), KODAWARI_INVALID_ARGUMENT, sim,
                "no frame simulated yet", "kodawari_simulation_step");
    EXPECT_OK(kodawari_simulation_step(sim, 20));
    /* The levels of detail: the ahoge's scene has none, so its one chain is full and steps. */
    EXPECT_OK(kodawari_simulation_chain_levels(sim, levels, kept, 2));
    CHECK(levels[0] == KODAWARI_LEVEL_FULL && kept[0] == 0 && levels[1] == 9 && kept[1] == 9,
          "levels %u %u, kept %u %u", levels[0], levels[1], kept[0], kept[1]);
    EXPECT_OK(kodawari_simulation_chain_levels(sim, levels, NULL, 1));
    EXPECT_FAIL(kodawari_simulation_chain_levels(sim, levels, kept, 0), KODAWARI_BUFFER_TOO_SMALL, sim, "levels: holds 0",
                "needs 1");
    EXPECT_FAIL(kodawari_simulation_chain_levels(sim, NULL, kept, 2), KODAWARI_INVALID_ARGUMENT, sim, "levels", "NULL");
    /* No budget on a scene without levels of detail: inactive, the rest zero. */
    {
        kodawari_lod_budget budget;
        memset(&budget, 0xff, sizeof budget);
        EXPECT_OK(kodawari_simulation_lod_budget(sim, &budget));
        CHECK(budget.active == 0 && budget.measured == 0 && budget.budget_ms == 0.0f && budget.full_distance == 0.0f,
              "lod_budget without a budget: active %u, %g ms", budget.active, (double)budget.budget_ms);
        EXPECT_FAIL(kodawari_simulation_lod_budget(sim, NULL), KODAWARI_INVALID_ARGUMENT, sim, "out", "NULL");
    }
    out.rest_positions = rest;
    out.rest_positions_capacity = sizeof rest / sizeof(float);
    out.orientations = orientations;
    out.orientations_capacity = 4 * kAhogeJoints - 1;
    EXPECT_FAIL(kodawari_simulation_read_chains(sim, &out), KODAWARI_BUFFER_TOO_SMALL, sim, "out->orientations",
                "holds 47 floats, needs 48", "12 joints x 4");
    out.orientations_capacity = 4 * kAhogeJoints;
    EXPECT_OK(kodawari_simulation_read_chains(sim, &out));
    /* Joint 0 follows the chain root exactly (SPEC A.4), where the rest shape is placed. */
    CHECK(distance3(positions, rest) == 0.0f, "root joint %g m off its rest place", (double)distance3(positions, rest));
    /* Segments keep their length: the ahoge is 0.14 m in 11 segments; the distance
     * constraints after 4 iterations per 1/120 s substep hold each within 2 % of it (it
     * swings gently: the scene's motion is a head turn). */
    for (j = 1; j < kAhogeJoints; ++j) {
        const float segment = distance3(positions + 3 * j, positions + 3 * (j - 1));
        CHECK(fabsf(segment - 0.14f / 11.0f) < 0.02f * 0.14f / 11.0f, "segment %d: %g m", j, (double)segment);
    }
    for (j = 0; j < kAhogeJoints; ++j) {
        const float* q = orientations + 4 * j;
        const float n = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        CHECK(fabsf(n - 1.0f) < 1e-4f, "joint %d's orientation has length %g", j, (double)n);
    }
    EXPECT_FAIL(kodawari_simulation_chain_joints(sim, 1, &begin, &count), KODAWARI_INVALID_ARGUMENT, sim, "chain: 1",
                "chain count (1)");
    kodawari_simulation_destroy(sim);
}

static int starts_with_gltf_magic(const char* path, long* size) {
    char magic[4] = {0, 0, 0, 0};
    FILE* file = fopen(path, "rb");
    size_t n;
    if (file == NULL) return 0;
    n = fread(magic, 1, 4, file);
    fseek(file, 0, SEEK_END);
    *size = ftell(file);
    fclose(file);
    return n == 4 && memcmp(magic, "glTF", 4) == 0;
}

static void test_bake(void) {
    char path[4200], missing[4200], written[8192];
    long size = 0;
    kodawari_simulation_info info;
    kodawari_simulation* sim = open_scene(g_flock, KODAWARI_BACKEND_CPU, 12);
    if (sim == NULL) return;
    snprintf(path, sizeof path, "%s/flock.glb", g_temp);
    snprintf(missing, sizeof missing, "%s/no-such-folder/flock.glb", g_temp);
    remove(path);
    EXPECT_OK(kodawari_simulation_step(sim, 5));
    EXPECT_OK(kodawari_simulation_bake(sim, path, 0, written, sizeof written));
    CHECK(strcmp(written, path) == 0, "written \"%s\"", written);
    CHECK(starts_with_gltf_magic(path, &size), "%s is not a glTF binary file", path);
    printf("bake: %s, %ld bytes\n", path, size);
    /* The bake ran a simulation of its own: this one is still after frame 4. */
    EXPECT_OK(kodawari_simulation_get_info(sim, &info));
    CHECK(info.next_frame == 5, "next frame %u after a bake", info.next_frame);
    {
        long compact_size = 0;
        EXPECT_OK(kodawari_simulation_bake(sim, path, 1, NULL, 0));
        CHECK(starts_with_gltf_magic(path, &compact_size) && compact_size < size, "compacted: %ld bytes, full %ld",
              compact_size, size);
    }
    EXPECT_FAIL(kodawari_simulation_bake(sim, missing, 0, NULL, 0), KODAWARI_INVALID_ARGUMENT, sim,
                "kodawari_simulation_bake", missing);
    EXPECT_FAIL(kodawari_simulation_bake(sim, path, 2, NULL, 0), KODAWARI_INVALID_ARGUMENT, sim, "compact: 2");
    EXPECT_FAIL(kodawari_simulation_bake(sim, "", 0, NULL, 0), KODAWARI_INVALID_ARGUMENT, sim, "path");
    /* A bake is binary glTF: a .gltf name is refused, as by `kodawari run --out`. */
    EXPECT_FAIL(kodawari_simulation_bake(sim, "out-capi.gltf", 0, NULL, 0), KODAWARI_INVALID_ARGUMENT, sim, "name it .glb");
    EXPECT_FAIL(kodawari_simulation_bake(sim, NULL, 0, NULL, 0), KODAWARI_INVALID_ARGUMENT, sim, "path");
    kodawari_simulation_destroy(sim);
}

static void test_rejects(void) {
    static float small[kBirds * kFloatsPerBird];
    char missing[4200];
    kodawari_simulation* sim = (kodawari_simulation*)&g_checks; /* must be set to NULL */
    kodawari_backend_options options;
    kodawari_bird_output out;
    kodawari_simulation_info info;
    snprintf(missing, sizeof missing, "%s/no-such-scene.json", g_temp);
    EXPECT_FAIL(kodawari_simulation_open(missing, NULL, 0, &sim), KODAWARI_INVALID_ARGUMENT, NULL,
                "kodawari_simulation_open", missing);
    CHECK(sim == NULL, "a failed open left *out set");
    EXPECT_FAIL(kodawari_simulation_open(NULL, NULL, 0, &sim), KODAWARI_INVALID_ARGUMENT, NULL, "path");
    EXPECT_FAIL(kodawari_simulation_open(g_flock, NULL, 0, NULL), KODAWARI_INVALID_ARGUMENT, NULL, "out");
    memset(&options, 0, sizeof options);
    options.backend = (kodawari_backend)7;
    EXPECT_FAIL(kodawari_simulation_open(g_flock, &options, 0, &sim), KODAWARI_INVALID_ARGUMENT, NULL,
                "backend.backend: 7");
    options.backend = KODAWARI_BACKEND_CPU;
    options.threads = 5000;
    EXPECT_FAIL(kodawari_simulation_open(g_flock, &options, 0, &sim), KODAWARI_INVALID_ARGUMENT, NULL,
                "backend.threads: 5000");
    options.threads = 0;
    EXPECT_FAIL(kodawari_simulation_open(g_flock, &options, 10000001u, &sim), KODAWARI_INVALID_ARGUMENT, NULL,
                "frames: 10000001; expected 0 (the scene's) or 1 to 10000000");
    /* A file that is not a scene: the loader's message, naming the file. */
    EXPECT_FAIL(kodawari_simulation_open(g_not_scene, NULL, 0, &sim), KODAWARI_INVALID_ARGUMENT, NULL, g_not_scene);
    CHECK(sim == NULL, "a failed open left *out set");

    EXPECT_FAIL(kodawari_simulation_step(NULL, 1), KODAWARI_INVALID_ARGUMENT, NULL, "sim");
    EXPECT_FAIL(kodawari_simulation_get_info(NULL, &info), KODAWARI_INVALID_ARGUMENT, NULL, "sim");
    CHECK(strcmp(kodawari_simulation_last_error(NULL), "") == 0, "NULL's message");
    kodawari_simulation_destroy(NULL);

    sim = open_scene(g_flock, KODAWARI_BACKEND_CPU_REFERENCE, 3);
    if (sim == NULL) return;
    memset(&out, 0, sizeof out);
    out.world_transforms = small;
    out.world_transforms_capacity = kFloatsPerBird;
    EXPECT_FAIL(kodawari_simulation_bird_poses(sim, &out), KODAWARI_INVALID_ARGUMENT, sim, "no frame simulated yet");
    EXPECT_FAIL(kodawari_simulation_step(sim, 4), KODAWARI_INVALID_ARGUMENT, sim, "frames: 4", "expected 1 to 3");
    EXPECT_OK(kodawari_simulation_step(sim, 1));
    EXPECT_FAIL(kodawari_simulation_bird_poses(sim, &out), KODAWARI_BUFFER_TOO_SMALL, sim, "out->world_transforms",
                "holds 49 floats, needs 13230", "270 birds x 7 parts x 7");
    EXPECT_FAIL(kodawari_simulation_bird_poses(sim, NULL), KODAWARI_INVALID_ARGUMENT, sim, "out");
    EXPECT_FAIL(kodawari_simulation_bird_tail_spreads(sim, small, kBirds - 1), KODAWARI_BUFFER_TOO_SMALL, sim,
                "out: holds 269 floats, needs 270");
    EXPECT_FAIL(kodawari_simulation_bird_tail_spreads(sim, NULL, 0), KODAWARI_INVALID_ARGUMENT, sim, "out", "NULL");
    EXPECT_FAIL(kodawari_simulation_get_info(sim, NULL), KODAWARI_INVALID_ARGUMENT, sim, "out");
    /* Flock agents: each member out of range named; a scene without flocking flocks takes
       good ones (and does nothing with them); NULL with 0 removes them. */
    {
        kodawari_flock_agent agents[2];
        EXPECT_FAIL(kodawari_flock_agent_default(NULL), KODAWARI_INVALID_ARGUMENT, NULL, "out");
        EXPECT_OK(kodawari_flock_agent_default(&agents[0]));
        CHECK(agents[0].kind == KODAWARI_FLOCK_PREDATOR && agents[0].radius == 15.0f && agents[0].weight == 40.0f &&
                  agents[0].margin == 2.0f,
              "flock agent defaults: kind %u, radius %g, weight %g, margin %g", agents[0].kind, (double)agents[0].radius,
              (double)agents[0].weight, (double)agents[0].margin);
        agents[1] = agents[0];
        agents[1].kind = KODAWARI_FLOCK_OBSTACLE;
        agents[1].margin = 0.0f;
        EXPECT_FAIL(kodawari_simulation_set_flock_agents(sim, agents, 2), KODAWARI_INVALID_ARGUMENT, sim, "agents[1].margin");
        agents[1].margin = 1.0f;
        agents[1].kind = 9;
        EXPECT_FAIL(kodawari_simulation_set_flock_agents(sim, agents, 2), KODAWARI_INVALID_ARGUMENT, sim, "agents[1].kind");
        agents[1].kind = KODAWARI_FLOCK_ATTRACTOR;
        agents[1].position[1] = 1e30f;
        EXPECT_FAIL(kodawari_simulation_set_flock_agents(sim, agents, 2), KODAWARI_INVALID_ARGUMENT, sim, "agents[1].position");
        agents[1].position[1] = 40.0f;
        CHECK(agents[0].normal[0] == 0.0f && agents[0].normal[1] == 1.0f && agents[0].normal[2] == 0.0f &&
                  agents[0].end[0] == 0.0f && agents[0].end[1] == 0.0f && agents[0].end[2] == 0.0f,
              "flock agent defaults: normal (%g, %g, %g), end (%g, %g, %g)", (double)agents[0].normal[0],
              (double)agents[0].normal[1], (double)agents[0].normal[2], (double)agents[0].end[0], (double)agents[0].end[1],
              (double)agents[0].end[2]);
        /* A capsule and a plane: a capsule's end and a plane's normal are checked. */
        agents[1].kind = KODAWARI_FLOCK_CAPSULE;
        agents[1].end[2] = -1e30f;
        EXPECT_FAIL(kodawari_simulation_set_flock_agents(sim, agents, 2), KODAWARI_INVALID_ARGUMENT, sim, "agents[1].end");
        agents[1].end[2] = 10.0f;
        EXPECT_OK(kodawari_simulation_set_flock_agents(sim, agents, 2));
        agents[1].kind = KODAWARI_FLOCK_PLANE;
        agents[1].normal[1] = 0.0f;
        EXPECT_FAIL(kodawari_simulation_set_flock_agents(sim, agents, 2), KODAWARI_INVALID_ARGUMENT, sim, "agents[1].normal");
        agents[1].normal[1] = -3.0f;
        EXPECT_FAIL(kodawari_simulation_set_flock_agents(sim, NULL, 2), KODAWARI_INVALID_ARGUMENT, sim, "agents");
        EXPECT_FAIL(kodawari_simulation_set_flock_agents(NULL, agents, 2), KODAWARI_INVALID_ARGUMENT, NULL, "sim");
        EXPECT_OK(kodawari_simulation_set_flock_agents(sim, agents, 2));
        EXPECT_OK(kodawari_simulation_set_flock_agents(sim, NULL, 0));
        /* Agents on the device: their encoding (FlockAgentGpu's 12 floats), and the count
           bounded (this scene has no flocking flock: 0 and 64 do nothing). */
        float encoded[12];
        agents[0].position[0] = 3.0f;
        agents[0].velocity[2] = -5.0f;
        EXPECT_OK(kodawari_encode_flock_agent(&agents[0], encoded));
        CHECK(encoded[0] == 3.0f && encoded[3] == 15.0f && encoded[4] == 0.0f && encoded[5] == 40.0f && encoded[6] == 0.0f &&
                  encoded[10] == -5.0f,
              "encoded predator: position (%g, ...), radius %g, kind %g, weight %g, margin %g, velocity z %g",
              (double)encoded[0], (double)encoded[3], (double)encoded[4], (double)encoded[5], (double)encoded[6],
              (double)encoded[10]);
        agents[0].radius = -1.0f;
        EXPECT_FAIL(kodawari_encode_flock_agent(&agents[0], encoded), KODAWARI_INVALID_ARGUMENT, NULL, "agent.radius");
        EXPECT_FAIL(kodawari_encode_flock_agent(NULL, encoded), KODAWARI_INVALID_ARGUMENT, NULL, "agent");
        EXPECT_FAIL(kodawari_simulation_set_flock_device_agents(sim, 65), KODAWARI_INVALID_ARGUMENT, sim, "count: 65");
        EXPECT_OK(kodawari_simulation_set_flock_device_agents(sim, 0));
        kodawari_buffer_range agent_range;
        EXPECT_FAIL(kodawari_simulation_buffer(sim, KODAWARI_BUFFER_FLOCK_AGENTS, &agent_range), KODAWARI_INVALID_ARGUMENT, sim,
                    "flocking.agents");
    }
    /* Nothing changed: the rejected step of 4 left frame 1 next. */
    EXPECT_OK(kodawari_simulation_get_info(sim, &info));
    CHECK(info.next_frame == 1, "next frame %u", info.next_frame);
    kodawari_simulation_destroy(sim);
}

/* kodawari_rig_scene: scenes/characters/chibi.glb's 7 chains (the README's `kodawari rig`
 * listing), a scene that opens with them, and bad arguments named. */
static void test_rig(const char* source) {
    char character[4200], scene[4200], missing[4200], chains[4096];
    kodawari_simulation* sim = NULL;
    kodawari_simulation_info info;
    snprintf(character, sizeof character, "%s/scenes/characters/chibi.glb", source);
    snprintf(scene, sizeof scene, "%s/chibi.json", g_temp);
    snprintf(missing, sizeof missing, "%s/no-such-character.glb", g_temp);
    EXPECT_OK(kodawari_rig_scene(character, scene, NULL, 2.0f, chains, sizeof chains));
    CHECK(strstr(chains, "tail_0\ttail_0\t8") != NULL && strstr(chains, "ahoge_0\tahoge_0\t5") != NULL,
          "chains \"%s\"", chains);
    EXPECT_OK(kodawari_simulation_open(scene, NULL, 0, &sim));
    if (sim != NULL) {
        EXPECT_OK(kodawari_simulation_get_info(sim, &info));
        CHECK(info.chain_count == 7 && info.joint_count == 40 && info.frame_count == 120,
              "%u chains, %u joints, %u frames", info.chain_count, info.joint_count, info.frame_count);
        kodawari_simulation_destroy(sim);
    }
    EXPECT_FAIL(kodawari_rig_scene(missing, scene, NULL, 2.0f, NULL, 0), KODAWARI_INVALID_ARGUMENT, NULL, missing);
    EXPECT_FAIL(kodawari_rig_scene(character, scene, NULL, 0.0f, NULL, 0), KODAWARI_INVALID_ARGUMENT, NULL, "duration: 0");
    EXPECT_FAIL(kodawari_rig_scene(character, scene, "dance", 2.0f, NULL, 0), KODAWARI_INVALID_ARGUMENT, NULL, "dance");
    EXPECT_FAIL(kodawari_rig_scene(character, NULL, NULL, 2.0f, NULL, 0), KODAWARI_INVALID_ARGUMENT, NULL, "scene_path");
}

int main(int argc, char** argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: test_capi_simulation SOURCE_DIR TEMP_DIR\n");
        return 2;
    }
    snprintf(g_flock, sizeof g_flock, "%s/scenes/flock.json", argv[1]);
    snprintf(g_ahoge, sizeof g_ahoge, "%s/scenes/ahoge.json", argv[1]);
    snprintf(g_temp, sizeof g_temp, "%s", argv[2]);
    snprintf(g_not_scene, sizeof g_not_scene, "%s/docs/scene.schema.json", argv[1]);
    test_flock();
    test_backends_agree();
    test_chain_backends_agree();
    test_chains();
    test_bake();
    test_rejects();
    test_rig(argv[1]);
    printf("%d checks, %d failures\n", g_checks, g_failures);
    return g_failures == 0 ? 0 : 1;
}
