# Thin wrapper over CMake. `make demo` and `make test` are the README's quick start.
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps configure build demo test bench clean

all: build

deps:
	@scripts/install-deps

configure: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

# Renders the default scene with the reference and the foundation's techniques; images and the table go to out/.
demo: build
	$(BUILD)/bin/penumbra compare --out out

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# Micro-benchmarks (Google Benchmark), then per-technique pass times on `crowded` at 1024x1024 with
# ratios to `hard` measured in the same run (every shadow map defaults to 1024x1024).
bench: build
	$(BUILD)/bin/penumbra_bench --benchmark_counters_tabular=true
	$(BUILD)/bin/penumbra bench --scene crowded --width 1024 --height 1024 --spp 16 --repeat 5

clean:
	rm -rf $(BUILD) out
