/* Kodawari's CPU path from C (kodawari.h, libkodawari.so), no scene file: three strands on a
 * character that walks to the side for a second. main.cpp does the same in C++. */
#include <stdio.h>

#include <kodawari/kodawari.h>

int main(void) {
    float strand[8 * 3] = {0}, tips[3 * 8 * 3];
    kodawari_chain_template_desc templ = {0};
    kodawari_chain_desc chains[3] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};
    kodawari_chain_world_desc desc = {0};
    kodawari_transform head = {{0.0f, 1.5f, 0.0f}, {0, 0, 0, 1}}, roots[3];
    kodawari_chain_frame frame = {0};
    kodawari_chain_output out = {0};
    kodawari_chain_world* world = NULL;
    int i, f, c;
    for (i = 0; i < 8; ++i) strand[3 * i] = 0.012f * i, strand[3 * i + 1] = 0.016f * i; /* leaning to +X */
    templ.joint_count = 8;
    templ.base.positions = strand; /* orientations NULL: each joint's +Y along its segment */
    templ.thickness = 0.004f;
    templ.mass = 0.001f;
    kodawari_solver_params_default(&templ.solver);
    desc.templates = &templ, desc.template_count = 1, desc.chains = chains, desc.chain_count = 3;
    desc.character_count = 1;
    desc.backend.backend = KODAWARI_BACKEND_CPU;
    frame.dt = 1.0f / 60.0f; /* the camera in front, the head at 1.5 m, the roots on it */
    frame.camera.position[1] = 1.6f, frame.camera.position[2] = 2.0f, frame.camera.forward[2] = -1.0f;
    frame.references = &head, frame.reference_count = 1, frame.roots = roots, frame.root_count = 3;
    for (f = 0; f <= 60; ++f) { /* frame 0 puts the strands at rest; then 1 s at 60 fps */
        for (c = 0; c < 3; ++c) roots[c] = (kodawari_transform){{0.5f * f / 60.0f + 0.05f * c, 1.6f, 0.0f}, {0, 0, 0, 1}};
        if (f == 0 ? kodawari_chain_world_create(&desc, &frame, &world) : kodawari_chain_world_step(world, &frame))
            return fprintf(stderr, "%s\n", kodawari_last_error()), 1; /* KODAWARI_OK is 0; the message says why */
    }
    out.positions = tips, out.positions_capacity = sizeof tips / sizeof tips[0];
    if (kodawari_chain_world_read(world, &out) != KODAWARI_OK) return fprintf(stderr, "%s\n", kodawari_last_error()), 1;
    for (c = 0; c < 3; ++c) {
        const float* tip = tips + 3 * (8 * c + 7); /* chain c's joints start at 8 c */
        printf("strand %d tip: %.6f %.6f %.6f\n", c, tip[0], tip[1], tip[2]);
    }
    kodawari_chain_world_destroy(world);
    return 0;
}
