# Thin wrapper around CMake. Every target installs what it needs first (idempotent).
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= 2
DEMO_DIR ?= out/demo

# Recursive (=) so that the ccache check runs when configure does, after `deps` may have installed it.
CCACHE = $(shell command -v ccache 2>/dev/null)
CMAKE_FLAGS = -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(if $(CCACHE),-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)

.PHONY: all deps configure build test demo bench soak test-data asan-test tsan-test fuzz format format-check clean

all: build

deps:
	bash scripts/install-deps.sh

configure: deps
	cmake -S . -B $(BUILD_DIR) $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)

test-data: deps
	bash scripts/fetch-test-data.sh

test: build test-data
	cd $(BUILD_DIR) && ctest --output-on-failure -j$(JOBS)

demo: build test-data
	bash scripts/demo.sh $(BUILD_DIR) $(DEMO_DIR)

bench: build test-data
	bash scripts/bench.sh $(BUILD_DIR)

# A simulated dive against a real server for SOAK_MINUTES (20): camera-rate frames, a planner's
# queries, subscribers that come and go, bad frames; prints RSS and query latency (bench/soak.py).
# Outside CI.
SOAK_MINUTES ?= 20
soak: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target cenote cenote-server cenote_python_stubs
	/usr/bin/python3 bench/soak.py $(BUILD_DIR) --minutes $(SOAK_MINUTES)

# AddressSanitizer + UndefinedBehaviorSanitizer build of the whole suite.
asan-test: deps test-data
	cmake --preset asan
	cmake --build --preset asan -j$(JOBS)
	ctest --preset asan -j$(JOBS)

# ThreadSanitizer build of the concurrency tests only (readers during ingest and during a pose
# correction: each block old or new, never a mix; the server's corrections with ingest, block reads
# and distance queries going on), in build-tsan; not part of `make test`.
# tests/tsan.supp: reports inside uninstrumented Debian libraries only, each with its reason.
TSAN_DIR ?= build-tsan
tsan-test: deps
	cmake -S . -B $(TSAN_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCENOTE_TSAN=ON -DCENOTE_BUILD_BENCH=OFF \
	  $(if $(CCACHE),-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
	cmake --build $(TSAN_DIR) -j$(JOBS) --target mapping_concurrency_test server_concurrency_test
	TSAN_OPTIONS="suppressions=$(CURDIR)/tests/tsan.supp halt_on_error=1 second_deadlock_stack=1" \
	  $(TSAN_DIR)/tests/mapping_concurrency_test
	TSAN_OPTIONS="suppressions=$(CURDIR)/tests/tsan.supp halt_on_error=1 second_deadlock_stack=1" \
	  $(TSAN_DIR)/tests/server/server_concurrency_test

# libFuzzer on every harness of tests/fuzz/ (a clang build of its own in build-fuzz): FUZZ_RUNS inputs
# each from the committed seed corpus; new inputs go to build-fuzz/corpus/, crashes to
# build-fuzz/crashes/ (copy one into tests/fuzz/corpus/<harness>/ and ctest replays it from then on).
FUZZ_DIR ?= build-fuzz
FUZZ_RUNS ?= 200000
FUZZ_HARNESSES = image_decode ply_reader map_file frame_decoder config_yaml recording
fuzz:
	bash scripts/install-deps.sh --fuzz
	cmake -S . -B $(FUZZ_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
	  -DCENOTE_FUZZ=ON -DCENOTE_BUILD_BENCH=OFF $(if $(CCACHE),-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
	cmake --build $(FUZZ_DIR) -j$(JOBS) --target fuzzers
	mkdir -p $(FUZZ_DIR)/crashes
	set -e; for h in $(FUZZ_HARNESSES); do \
	  mkdir -p $(FUZZ_DIR)/corpus/$$h; \
	  TEST_TMPDIR=$(FUZZ_DIR) $(FUZZ_DIR)/tests/fuzz/$${h}_fuzzer -runs=$(FUZZ_RUNS) -seed=1 -max_len=65536 -timeout=20 \
	    -rss_limit_mb=2048 -artifact_prefix=$(FUZZ_DIR)/crashes/$$h- $(FUZZ_DIR)/corpus/$$h tests/fuzz/corpus/$$h; \
	done

# Layout of every tracked C++ file by .clang-format (clang-format 14): format in place, or only name the files that differ.
format:
	bash scripts/check-format.sh --fix

format-check:
	bash scripts/check-format.sh

clean:
	rm -rf $(BUILD_DIR) build-asan $(TSAN_DIR)
