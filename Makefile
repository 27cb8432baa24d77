# Thin wrapper over CMake + Ninja. Both main targets install the Debian
# packages first (quietly, and only what is missing): `make demo` only the
# ones the demo builds and runs, and builds only the host and the plugins it
# loads; `make test` the rest, reconfigures (finding what was just
# installed: tests, Python, learning, viewer, benchmarks) and builds
# everything.
BUILD_DIR ?= build
CMAKE_FLAGS ?=
CTEST_FLAGS ?=
# e.g. BENCH_FLAGS='--scene boxes --seconds 5'
BENCH_FLAGS ?=
JOBS ?= $(shell nproc)

.PHONY: all deps deps-demo configure build test demo bench sanitize sanitize-core package clean

all: build

deps:
	@scripts/install-deps

deps-demo:
	@scripts/install-deps --demo

$(BUILD_DIR)/build.ninja:
	cmake -S . -B $(BUILD_DIR) -G Ninja $(CMAKE_FLAGS)

configure: deps $(BUILD_DIR)/build.ninja

# Always reconfigures (a few seconds): a build folder that `make demo`
# configured before the test packages were installed finds them now, and
# MANIBENCH_REQUIRE_TESTS makes a missing GoogleTest an error, not a silent
# build without tests.
build: deps
	cmake -S . -B $(BUILD_DIR) -G Ninja -DMANIBENCH_REQUIRE_TESTS=ON $(CMAKE_FLAGS)
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) $(CTEST_FLAGS)

# The fast first run: the demo's packages, the host and the task plugins.
demo: deps-demo $(BUILD_DIR)/build.ninja
	cmake --build $(BUILD_DIR) -j $(JOBS) --target manibench_demo
	$(BUILD_DIR)/bin/manibench demo --out $(BUILD_DIR)/demo-results

# Simbody vs MuJoCo env steps per second (docs/performance.md).
bench: configure
	cmake --build $(BUILD_DIR) -j $(JOBS) --target manibench_physics_bench
	$(BUILD_DIR)/bin/manibench_physics_bench $(BENCH_FLAGS)

# The whole suite under AddressSanitizer and UndefinedBehaviorSanitizer, in
# its own build folder (docs/robustness.md: what it found, how long it
# takes). Leak checking is off: Mesa's EGL keeps allocations for the
# process's life. handle_segv=0: a policy that segfaults must die by the
# signal, as without the sanitizer (the evaluation kit's crash tests), not
# exit 1 through ASan's handler. allocator_may_return_null=1: a malloc past
# the sandboxed policy's memory limit (RLIMIT_AS) returns NULL as it does
# without ASan, so that a Python policy gets its MemoryError (ASan would
# report "out of memory" and abort); a C++ `new` past it still aborts under
# ASan (sandbox_test expects that there).
SANITIZE_DIR ?= build-sanitize
SANITIZE_FLAGS = -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
# -O1, as ASan's documentation advises, not the Release -O2: instrumented
# translation units compile about 30 % faster (three of the slowest, 96 s
# at -O2, 66 s at -O1), and the build is most of CI's sanitizer time;
# Simbody, libtorch and Mesa are Debian's uninstrumented -O2 either way.
SANITIZE_OPT = -O1
# The sanitized suite is the unit tests (label `unit`): every
# library, plugin and program the project ships runs in them, instrumented.
# The long scenario tests (label `scenario`: whole expert episodes, the
# contact pile under CPodes, demonstrations and videos over many episodes,
# the installed product and the .deb, the viewer's window) are not built
# there; `make test` builds and runs them all. Nor is the learning module
# (learning/: libtorch is Debian's uninstrumented library; its 22 units and
# 46 tests were a quarter of the sanitized build and a fifth of its suite),
# nor the physics benchmark (bench/: its one test is a scenario test).
# CI's two builds and suites have to fit its 90 minutes on its slow days:
# docs/robustness.md ("Sanitizers") has the figures. `make sanitize
# SANITIZE_SCOPE= SANITIZE_TESTS=` builds and runs everything.
SANITIZE_SCOPE ?= -DCMAKE_DISABLE_FIND_PACKAGE_Torch=ON -DCMAKE_DISABLE_FIND_PACKAGE_mujoco=ON \
  -DMANIBENCH_SCENARIO_TESTS=OFF
SANITIZE_TESTS ?= -L unit
# What the sanitized build builds (empty: everything in its scope).
SANITIZE_BUILD ?=
# A test that hangs is stopped and named after 10 minutes instead of
# CTest's default 25 (tests that need longer set their own TIMEOUT).
SANITIZE_TIMEOUT = 600
sanitize: deps
	cmake -S . -B $(SANITIZE_DIR) -G Ninja $(CMAKE_FLAGS) \
	  -DCMAKE_C_FLAGS="$(SANITIZE_FLAGS)" -DCMAKE_CXX_FLAGS="$(SANITIZE_FLAGS)" \
	  -DCMAKE_C_FLAGS_RELEASE="$(SANITIZE_OPT)" -DCMAKE_CXX_FLAGS_RELEASE="$(SANITIZE_OPT)" \
	  -DCMAKE_EXE_LINKER_FLAGS="$(SANITIZE_FLAGS)" -DCMAKE_SHARED_LINKER_FLAGS="$(SANITIZE_FLAGS)" \
	  -DCMAKE_MODULE_LINKER_FLAGS="$(SANITIZE_FLAGS)" $(SANITIZE_SCOPE)
	cmake --build $(SANITIZE_DIR) -j $(JOBS) $(SANITIZE_BUILD)
	cd $(SANITIZE_DIR) && ASAN_OPTIONS=detect_leaks=0:abort_on_error=1:handle_segv=0:allocator_may_return_null=1 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS) --timeout $(SANITIZE_TIMEOUT) \
	  $(SANITIZE_TESTS) $(CTEST_FLAGS)

# CI's sanitized pass: the unit tests that run only the libraries they
# link (label `unit_core`: the scene and its contact, URDF and mesh loading, the
# kit and the families' models, the workers and their wire format,
# configuration, rendering, observations), built and run instrumented.
# CI cannot fit two whole builds and suites in its time on its slow days
# (docs/robustness.md, "Sanitizers"); `make sanitize` runs every unit test.
sanitize-core:
	$(MAKE) sanitize SANITIZE_BUILD="--target manibench_core_tests" SANITIZE_TESTS="-L unit_core"

# The Debian package: build/manibench_<version>_amd64.deb (README.md,
# "Installing"); `dpkg-deb -I` shows its dependencies.
package: build
	cd $(BUILD_DIR) && cpack -G DEB

clean:
	rm -rf $(BUILD_DIR) $(SANITIZE_DIR)
