# The two commands of the README:
#   make run   installs what is missing, builds (Release) and bakes the default scene
#   make test  installs what is missing, builds and runs every test through ctest
PRESET ?= release
BUILD  := build/$(PRESET)
SCENE  ?= scenes/flock.json
JOBS   ?= $(shell nproc 2>/dev/null || echo 2)

.PHONY: run test build setup configure clean bench

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

bench: build
	@$(BUILD)/host/kodawari bench birds

clean:
	@rm -rf build
