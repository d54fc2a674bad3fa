// kodawari: the command line of the crowd simulator.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "kodawari/atomic_file.hpp"
#include "kodawari/version.hpp"
#include "commands.hpp"

namespace {

constexpr const char* kUsage = R"(usage: kodawari <command> [options]

commands:
  run [SCENE] [--backend auto|vulkan|cpu|cpu-reference] [--frames N] [--out FILE.glb] [--no-export]
              [--compact[=METRES[,RADIANS]]] [--trace FILE.jsonl] [--device NAME|INDEX] [--threads N]
              [--isa NAME] [--validation] [--shard I/N | --mpi]
      simulate a scene (default )" "scenes/flock.json" R"() and bake it to glTF (default out/<scene>.glb);
      --compact drops the animation keys that linear interpolation reproduces within METRES (default
      0.001) for translations and RADIANS (default METRES, i.e. 0.001) for rotations and, relative, for
      scales, writes rotations as 16-bit integers (8-bit where RADIANS absorbs their rounding, up
      to 0.0158 rad), and prints the keys kept, the size ratio and the largest error
      (docs/compact.md);
      --shard I/N simulates only shard I of N (birds and characters [I*n/N, (I+1)*n/N)) and writes
      a part file (default out/<scene>.shard-I-of-N.kwpart) for merge, every key kept (give
      --compact to merge); under mpirun, --mpi runs one shard per rank and rank 0 writes
  merge PARTS... [--out FILE.glb] [--scene SCENE.json] [--compact[=METRES[,RADIANS]]]
      join the part files of every shard of one bake into the files one run writes, byte for byte
      (--scene: the scene file, when it moved since; its bytes must be unchanged; --compact as run's)
  validate [SCENE] [--backend vulkan|cpu] [--frames N]
      run a backend and the CPU reference side by side; exit 1 above tolerance
  bench birds [--count N] [--frames F] [--json FILE] [--readback] [--backends LIST] [--repetitions R]
  bench chains [--chains N] [--joints M] [--iterations K] [--steps S] [--json FILE] [--backends LIST] [--repetitions R]
  bench crowd [SCENE] [--count N] [--frames F] [--json FILE] [--backends LIST] [--repetitions R]
      time every backend on the same birds (or chains: joint-steps per second; or a crowd of N skinned
      characters, default 1000 of scenes/crowd-gltf.json: frames per second), R >= 3 interleaved
      repetitions after warm-up (default 3), and print medians, min, max, the ratios to cpu-reference
      and cpu, the cpu backend's SIMD instruction set and threads (--threads N, --isa NAME)
  rig CHARACTER [--chains PATTERNS|--roots NAMES] [--animation CLIP] [--name NAME] [--out SCENE.json]
      find the chains (VRM spring bones, name patterns or named roots) and colliders of a rigged
      .gltf/.glb/.vrm character and write a scene that simulates it (default ./<character>.json)
  sketch SCENE --chain CHARACTER/CHAIN --stroke STROKE.json [--frame N] [--camera EX,EY,EZ,TX,TY,TZ]
         [--size WxH] [--influence P] [--out SCENE2.json]
  sketch SCENE --chain CHARACTER/CHAIN --undo [--out SCENE2.json]
      the chain takes the shape of a stroke drawn in pixels over the view (default: the scene's camera
      at frame 0, 1280x720) as a new view example for that view direction (docs/sketch.md); --undo
      removes the last one a sketch added
  render [SCENE] --out DIR [--frames A:B[:STEP]|N] [--size WxH] [--contact-sheet FILE.png [--columns N]]
         [--animation FILE.png [--animation-size WxH]] [--backend ...] [--device NAME|INDEX] [--validation]
      simulate a scene as run does and draw frames A, A+STEP, ... below B (B exclusive; default the whole
      scene) offscreen at WxH (default 1280x720) to DIR/<scene>_<frame, 5 digits>.png (DIR is created);
      --contact-sheet also writes the frames shrunk into one grid (default min(frames, 4) columns);
      --animation also writes them as one looping animated PNG at the scene's fps / STEP (default the
      frames' size)
  view [SCENE] [--size WxH] [--backend ...] [--device NAME|INDEX] [--validation]
       [--frames N] [--keys K1,K2,...] [--screenshot FILE.png]
      an interactive window (GLFW + Vulkan): orbit / pan / zoom with the mouse, Space play/pause,
      Left/Right step, [ ] -+1 s, Home restart, 1/2/3 backend, S sketch mode, U undo, W save,
      P screenshot, Q quit (docs/viewer.md); --frames quits after N drawn frames, --keys applies
      one key per frame first (names: space right left home [ ] 1 2 3 s w u + - p q escape, and
      drag:X1:Y1:X2:Y2, a stroke in image pixels in sketch mode, orbit:DX:DY, a left drag, resize:W:H), --screenshot writes the last frame
  info
      version, Vulkan devices and which one is chosen, CPU threads and SIMD instruction sets
  schema
      print the JSON Schema of the scene format (docs/scene.schema.json, draft 2020-12), for editors
      and validators; a scene names it with "$schema"

environment: KODAWARI_DEVICE (device choice), KODAWARI_ISA (the cpu backend's SIMD instruction set:
avx512, avx2, sse4 or scalar; default the widest, as --isa), KODAWARI_VALIDATION=1 (Khronos validation
+ synchronization validation), KODAWARI_FORCE_STAGING=1 (staging copies even on unified memory)
)";

}  // namespace

int main(int argc, char** argv) {
    using namespace kodawari::cli;
    // Ctrl-C, a scheduler's SIGTERM, a closed terminal: no temporary output stays behind.
    kodawari::remove_temporary_files_on_signals();
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
        std::fputs(kUsage, args.empty() ? stderr : stdout);
        return args.empty() ? kExitBadInput : kExitOk;
    }
    if (args[0] == "--version") {
        std::printf("kodawari %s\n", std::string(kodawari::version()).c_str());
        return kExitOk;
    }
    const std::string command = args[0];
    args.erase(args.begin());
    // `kodawari COMMAND --help`: the same usage.
    if (std::find(args.begin(), args.end(), "--help") != args.end()) {
        std::fputs(kUsage, stdout);
        return kExitOk;
    }
    try {
        if (command == "run") return cmd_run(args);
        if (command == "merge") return cmd_merge(args);
        if (command == "validate") return cmd_validate(args);
        if (command == "info") return cmd_info(args);
        if (command == "bench") return cmd_bench(args);
        if (command == "rig") return cmd_rig(args);
        if (command == "sketch") return cmd_sketch(args);
        if (command == "render") return cmd_render(args);
        if (command == "view") return cmd_view(args);
        if (command == "schema") return cmd_schema(args);
        throw UsageError{"unknown command \"" + command + "\""};
    } catch (const UsageError& e) {
        std::fprintf(stderr, "kodawari: %s\n\n%s", e.message.c_str(), kUsage);
        return kExitBadInput;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "kodawari: internal error: %s\n", e.what());
        return kExitFailure;
    }
}
