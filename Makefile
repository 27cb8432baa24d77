# Thin wrapper over CMake + Ninja. Both main targets install the Debian
# packages first (quietly, and only what is missing).
BUILD_DIR ?= build
CMAKE_FLAGS ?=
CTEST_FLAGS ?=
# e.g. BENCH_FLAGS='--scene boxes --seconds 5'
BENCH_FLAGS ?=
JOBS ?= $(shell nproc)

.PHONY: all deps configure build test demo bench clean

all: build

deps:
	@scripts/install-deps

$(BUILD_DIR)/build.ninja:
	cmake -S . -B $(BUILD_DIR) -G Ninja $(CMAKE_FLAGS)

configure: deps $(BUILD_DIR)/build.ninja

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) $(CTEST_FLAGS)

demo: build
	$(BUILD_DIR)/bin/manibench demo --out $(BUILD_DIR)/demo-results

# Simbody vs MuJoCo env steps per second (docs/performance.md).
bench: configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target manibench_physics_bench
	$(BUILD_DIR)/bin/manibench_physics_bench $(BENCH_FLAGS)

clean:
	rm -rf $(BUILD_DIR)
