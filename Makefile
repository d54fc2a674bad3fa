# The two commands of the README:
#   make run   installs what is missing, builds (Release) and bakes the default scene
#   make test  installs what is missing, builds and runs every test through ctest
# and for development (docs/development.md):
#   make asan  the `asan` preset (clang, ASan + UBSan, leaks on) over the test suite
#   make fuzz  each libFuzzer target for FUZZ_TIME seconds (FUZZ_JOBS processes each),
#              or for FUZZ_RUNS executions from seed FUZZ_SEED (reproducible: CI's lane)
PRESET ?= release
BUILD  := build/$(PRESET)
SCENE  ?= scenes/flock.json
JOBS   ?= $(shell nproc 2>/dev/null || echo 2)

FUZZ_TIME ?= 60
FUZZ_JOBS ?= 1
FUZZ_RUNS ?= 0
FUZZ_SEED ?= 1
FUZZ_TARGETS := fuzz_scene fuzz_gltf fuzz_stroke fuzz_scene_edit fuzz_capi

# The asan lane: the test suite with the sanitizers on, and the Vulkan driver and layer
# kept loaded (tests/tools/asan_keep_loaded.c, preloaded) so that a leak in their objects
# is attributed rather than reported as "<unknown module>" once the loader unloads them.
# Left out: `package` (it builds the library again, with the consumers' compiler flags),
# `export_identity` (its hashes are gcc's release bytes) and the soak (the release lane
# runs it; ten minutes under ASan for steps the shorter tests already cover), and the
# crowd of 200 VRM avatars on every backend (the release lane runs it; 90 s a backend under
# ASan for the code ColliderKindsGroupsAndCentersMatchTheReference and the Avatars tests
# run there on a few characters), and the README tour (`readme_tour`: the release lane runs
# it; its commands' code is what cli, cli_exit_codes and the render tests run under ASan),
# and the GPU machine's run at small sizes (`gpu_run_quick`: it bundles and times the
# release binary; scripts/gpu_run.sh runs no code of its own under the sanitizers), and
# the settle measurement (`Settle.`: whole scenes for their figures; SettleBackends runs
# its code under ASan), and the cpu backend's middle instruction sets (`/cpu_avx2`,
# `/cpu_sse4`: the same Highway code as the widest and the scalar one, which run under
# ASan and bracket the lane counts and tails; 78 tests, 340 s of the lane's 2 060 s), and
# the murmuration's 12 000 birds on every backend (a big flock: the flock scene's tests
# run the same bird code under ASan), and the sharded crowd of 8 192 chains on the
# backends other than cpu-reference (the sharding is the facade's, which that one runs
# under ASan; the release lane runs every backend): 310 s more. And the viewer under Xvfb
# (`viewer_xvfb`: 300 s alone under ASan on this machine, past its own step limits when the
# lane runs two tests at once; the render and sketch tests run its drawing code under ASan)
# and the schema's check of every scene file (`schema`: 205 s, Node's validator driving the
# loader over the examples, which fuzz_scene runs under ASan from the same corpus). And
# (measured under ASan on this machine, 2 860 s of the lane's CPU time in all): the command
# tour `cli` (233 s: the commands' code runs under ASan in cli_exit_codes, faults,
# interrupt and the render tests), the sharded bake's byte check
# `Shards.MergedProceduralCrowdPartsAreTheSingleBakesBytes` (141 s: ShardedSimulation runs
# the sharding and merging under ASan), and the two comparisons whose other side is Node
# (`meshopt_readers`, 76 s, and `three_vrm_comparison`, 77 s: the compact encoder and the
# spring mapping run under ASan in the CompactExport and spring_conformance tests).
# And, to bring CI toward 25 minutes (stop 48's CI: 49 min, this lane 1 105 s of tests):
# the tests that run none of our compiled code (label `source`: the character generators,
# glTF-Validator on their output, the layering and link checks; 95 s), and five command
# tours whose code the unit tests and the remaining scripts run under ASan (316 s):
# `scaleout` (MPI launches of the command: ShardedSimulation and the shard merge run
# here), `cli_route_check` and `cli_motion` (the route and clip code: RouteLimits, Motion
# unit tests), `cli_completion` (a bash script's completions of the command's
# options) and `novulkan` (the loader pointed at no driver: cli_exit_codes and faults run
# the error paths). `faults`, `interrupt` and `cli_exit_codes` stay: error paths are
# where leaks hide. And the vulkan and scalar runs of the two big crowd tests
# (`CharacterBackends.CrowdLoadsAndSteps`, `WindBackends.GustyCrowdMatchesTheReference`:
# 73, 49, 63 and 29 s under ASan, stop 49): their cpu-reference and widest-cpu runs stay,
# and the vulkan backends' host code runs under ASan in the embedding, record-mode and
# render tests. And Blender importing our bakes (`.BlenderImports`: Blender's code, not
# ours; the exports themselves are written under ASan in the tests beside them).
# And a "...TheReference" test's cpu-reference case, which compares the reference
# with itself: every other case of the same test runs the reference as its baseline, so
# the reference's code stays under ASan (17 cases, 100 s of the lane's CPU at stop 51), and
# CrowdLoadsAndSteps on cpu-reference (39 s; the reference's crowd runs in
# WindBackends.GustyCrowdMatchesTheReference/cpu_avx512 and the sharded crowd). And the
# levels of detail's image check (`LodPixels`: two runs of 600 characters over 480 frames)
# but on the widest cpu: the posed and hand-over code runs under ASan on every backend in
# LevelOfDetail's tests. CTest's regular expressions take at most 10 groups: more, and -E silently excludes nothing.
# The preloaded library loads the driver and layer only into processes with the
# sanitizers' runtime: it used to load them into every bash, python and node process of
# the scripts (0.13 s a bash, seconds a python; BadBirdsAreRefused 33 s -> 2.6 s).
ASAN_ENV := ASAN_OPTIONS=detect_leaks=1 LD_PRELOAD=$(CURDIR)/build/asan/tests/libkodawari_asan_keep_loaded.so

.PHONY: run test build setup configure clean bench asan fuzz

setup:
	@bash scripts/setup

configure: setup
	@cmake --preset $(PRESET) >/dev/null

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

run: build
	@$(BUILD)/host/kodawari run $(SCENE)

test: build
	@ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS) --timeout 900

asan: setup
	@cmake --preset asan >/dev/null
	@cmake --build build/asan -j $(JOBS)
	@$(ASAN_ENV) ctest --preset asan -j $(JOBS) --timeout 900 -LE '^source$$' -E '^(package|export_identity|viewer_soak|viewer_xvfb|schema|readme_tour|gpu_run_quick|starlings|cli|meshopt_readers|three_vrm_comparison|scaleout|cli_route_check|cli_motion|cli_completion|novulkan)$$|Shards\.MergedProceduralCrowdPartsAreTheSingleBakesBytes|^blender|/Soak\.|AvatarCrowdOf200|Flocking\.FliesLikeStarlings|Flocking\.VulkanGridOfMoreScanTilesThanLanes|^Settle\.|/cpu_(avx2|sse4)( |$$)|OnTheMurmuration|ShardedSimulation\.CharacterShardsAreTheWholeRunsChains/(vulkan|cpu_avx512|cpu_scalar)( |$$)|(CharacterBackends\.CrowdLoadsAndSteps|WindBackends\.GustyCrowdMatchesTheReference)/(vulkan|cpu_scalar)( |$$)|\.BlenderImports|TheReference[A-Za-z]*/cpu_reference |CharacterBackends\.CrowdLoadsAndSteps/cpu_reference |LodPixels\.[A-Za-z]*/cpu_reference |LodPixels\.[A-Za-z]*/cpu_scalar |LodPixels\.[A-Za-z]*/vulkan '

fuzz: setup
	@cmake --preset asan >/dev/null
	@cmake --build build/asan -j $(JOBS) --target $(FUZZ_TARGETS)
	@bash scripts/fuzz --time $(FUZZ_TIME) --jobs $(FUZZ_JOBS) --runs $(FUZZ_RUNS) --seed $(FUZZ_SEED)

bench: build
	@$(BUILD)/host/kodawari bench birds

clean:
	@rm -rf build
