# Thin wrapper over CMake. `make demo` and `make test` are the README's quick start.
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps configure build demo test bench clean test-sanitize fuzz

all: build

deps:
	@scripts/install-deps

configure: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

# Renders the default scene with the reference and every registered technique; the report (open
# out/report/index.html), its images, compare.json and compare.md go to out/report/, the cached reference to out/cache/.
demo: build
	$(BUILD)/bin/penumbra compare --out out

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# The library and the tests built with AddressSanitizer + UndefinedBehaviorSanitizer (-O1, assertions
# on, no benchmarks) in their own build folder, then the whole suite; any finding fails the run.
SANITIZE_BUILD ?= build-asan
SANITIZE_ENV = ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:check_initialization_order=1 \
               UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
               LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0
test-sanitize: deps
	@cmake -S . -B $(SANITIZE_BUILD) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" \
	  -DPENUMBRA_SANITIZE=ON -DPENUMBRA_BUILD_BENCH=OFF -DPENUMBRA_BUILD_PYTHON=OFF $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(SANITIZE_BUILD) -j $(JOBS)
	cd $(SANITIZE_BUILD) && $(SANITIZE_ENV) ctest --output-on-failure -j $(JOBS)

# libFuzzer targets (tests/fuzz/*_fuzz.cpp, clang from Debian) for FUZZ_SECONDS each. They start from
# the committed seeds (tests/fuzz/corpus/<target>/) and keep what they find in $(FUZZ_BUILD)/corpus;
# a crash is written to $(FUZZ_BUILD)/crashes/ and stops the run: copy it into the committed corpus,
# where the test suite replays it (tests/io/fuzz_corpus_test.cpp), and fix it.
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS = $(patsubst tests/fuzz/%_fuzz.cpp,fuzz_%,$(wildcard tests/fuzz/*_fuzz.cpp))
fuzz: deps
	@cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
	  -DPENUMBRA_FUZZ=ON -DPENUMBRA_BUILD_TESTS=OFF -DPENUMBRA_BUILD_BENCH=OFF -DPENUMBRA_BUILD_PYTHON=OFF $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(FUZZ_BUILD) --target $(FUZZ_TARGETS) -j $(JOBS)
	@mkdir -p $(FUZZ_BUILD)/crashes
	@for name in $(FUZZ_TARGETS); do \
	  bin=$(FUZZ_BUILD)/bin/$$name; target=$${name#fuzz_}; \
	  dict=tests/fuzz/$$target.dict; \
	  mkdir -p $(FUZZ_BUILD)/corpus/$$target; \
	  echo "fuzz: $$target for $(FUZZ_SECONDS) s"; \
	  $(SANITIZE_ENV) $$bin -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=4096 -max_len=8192 -print_final_stats=1 \
	    -artifact_prefix=$(FUZZ_BUILD)/crashes/$$target- $$( [ -f $$dict ] && echo -dict=$$dict ) \
	    $(FUZZ_BUILD)/corpus/$$target tests/fuzz/corpus/$$target || exit 1; \
	done

# Micro-benchmarks (Google Benchmark), then per-technique pass times on `crowded` at 1024x1024 with
# ratios to `hard` measured in the same run (every shadow map defaults to 1024x1024).
bench: build
	$(BUILD)/bin/penumbra_bench --benchmark_counters_tabular=true
	$(BUILD)/bin/penumbra bench --scene crowded --width 1024 --height 1024 --spp 16 --repeat 5

clean:
	rm -rf $(BUILD) $(SANITIZE_BUILD) $(FUZZ_BUILD) out
