# pectus: the two commands of the README, and a few more for developers.
#   make demo   install dependencies, build, run the main job on bundled data, print where results are
#   make test   install dependencies, build, run every test (unit, sanitizer build, fuzz smoke)
BUILD      ?= build
SANBUILD   ?= build-sanitize
JOBS       ?= $(shell nproc)
SHARED     ?= $(abspath ../shared)
FUZZ_SECONDS ?= 10
CMAKE_ARGS ?=

.PHONY: demo test bootstrap build unit-test sanitize fuzz-smoke bench format clean

demo: build
	scripts/demo $(BUILD) $(SHARED)

test: build
	$(MAKE) --no-print-directory unit-test sanitize fuzz-smoke
	@echo "make test: all suites passed"

bootstrap:
	@scripts/bootstrap

build: bootstrap
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release -DPECTUS_SHARED_DIR=$(SHARED) $(CMAKE_ARGS)
	cmake --build $(BUILD) -j$(JOBS)

unit-test:
	ctest --test-dir $(BUILD) --output-on-failure -j$(JOBS)

# The bottom layer (types, every parser, its tests) under AddressSanitizer and UBSan, built with clang,
# together with one libFuzzer target per parser.
sanitize: bootstrap
	CC=clang CXX=clang++ cmake -S . -B $(SANBUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DPECTUS_CORE_ONLY=ON -DPECTUS_FUZZ=ON -DPECTUS_SANITIZE=address,undefined \
	  -DPECTUS_SHARED_DIR=$(SHARED)
	cmake --build $(SANBUILD) -j$(JOBS)
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --test-dir $(SANBUILD) --output-on-failure -j$(JOBS)

fuzz-smoke: sanitize
	scripts/fuzz-smoke $(SANBUILD) $(FUZZ_SECONDS)

bench: build
	cmake --build $(BUILD) --target pectus_benchmarks -j$(JOBS)

format:
	find apps datasets planner_plugin registration shape tests -name '*.h' -o -name '*.cc' | xargs clang-format -i

clean:
	rm -rf $(BUILD) $(SANBUILD)
