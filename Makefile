# pectus: the two commands of the README, and a few more for developers.
#   make demo   install dependencies, build, run the main job on bundled data, print where results are
#   make test   install dependencies, build everything once with ASan + UBSan (UBSan's per-access checks
#               in the bottom layer and the fuzzers only: cmake/PectusWarnings.cmake; the benchmarks
#               compiled at -O0 without instrumentation and linked, not run), run every test under them,
#               and every fuzzer's smoke run
BUILD      ?= build
SANBUILD   ?= build-sanitize
JOBS       ?= $(shell nproc)
SHARED     ?= $(abspath ../shared)
FUZZ_SECONDS ?= 10
CMAKE_ARGS ?=

.PHONY: demo test shared bootstrap build unit-test sanitize sanitize-all fuzz-smoke fuzz-smoke-all bench format format-check clean

# The sanitizers' settings for every sanitized program (tests, the programs they start, fuzzers): leaks
# are errors; only third-party leaks are suppressed, each with its reason (cmake/sanitizers/lsan.supp);
# traces symbolized by llvm-14's symbolizer (Debian's llvm-14 does not put it on PATH).
# OpenMP threads sleep while they wait (OMP_WAIT_POLICY=passive): ctest runs two tests at once on CI's two
# cores, and an OpenMP thread that spins for its partner (libomp, the sanitizer build's runtime, spins
# 200 ms and yields in a loop: mostly system time) takes the core the other test needs.
# `pectus surrogate evaluate` of SurrogateCommand.Evaluate* under the sanitizers, beside one busy core:
# 231 s wall (170 s of it system time) spinning, 41 s passive; alone 34 s and 38 s (2026-11-29).
TEST_ENV = OMP_WAIT_POLICY=passive
SANITIZER_ENV = $(TEST_ENV) ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1 \
  LSAN_OPTIONS=suppressions=$(CURDIR)/cmake/sanitizers/lsan.supp:print_suppressions=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-14/bin/llvm-symbolizer

demo: shared build
	scripts/demo $(BUILD) $(SHARED)

# One build serves the whole suite: every test runs under ASan + UBSan, which a Release run could only
# repeat without the checks, and the two builds together would not fit CI's 40 minutes on 2 cores. The
# Release (GCC -O3) suite is `make build unit-test`; `make demo` builds Release.
test: shared
	$(MAKE) --no-print-directory format-check
	$(MAKE) --no-print-directory fuzz-smoke-all
	@echo "make test: all suites passed"

# The real datasets the demo and the tests read. One message saying what is missing and where it comes from.
shared:
	@if [ ! -f "$(SHARED)/datasets/patients/nuss_ct_parameters.csv" ] || \
	    [ ! -f "$(SHARED)/datasets/stanford_bunny/bun.conf" ]; then \
	  echo "make: the shared data folder is missing: $(SHARED) must hold datasets/stanford_bunny/ (the ten" >&2; \
	  echo "  Stanford bunny sweeps and bun.conf, from the Stanford 3D Scanning Repository) and" >&2; \
	  echo "  datasets/patients/nuss_ct_parameters.csv (the CT table of 62 Nuss patients, Rechowicz 2012," >&2; \
	  echo "  Appendix A). It is handed out with the repository as the folder shared/, to be put beside it" >&2; \
	  echo "  (../shared), or named with: make $(MAKECMDGOALS) SHARED=/path/to/shared" >&2; \
	  exit 2; \
	fi

bootstrap:
	@scripts/bootstrap

build: bootstrap
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release -DPECTUS_SHARED_DIR=$(SHARED) $(CMAKE_ARGS)
	cmake --build $(BUILD) -j$(JOBS)

unit-test:
	$(TEST_ENV) ctest --test-dir $(BUILD) --output-on-failure -j$(JOBS)

# Sanitizer builds: clang, AddressSanitizer (with LeakSanitizer) and UBSan, -O2 (keeps the numeric tests
# fast) with line tables (all a trace needs), together with one libFuzzer target per reader.
#   sanitize-all  everything (the benchmarks built at -O0 uninstrumented, not run), the whole unit suite (RBF, ICP, merge,
#                 model, FEM, HDF5, the plugin through its C interface, the command line) and all 13
#                 fuzzers; OpenMP from libomp: `make test`;
#   sanitize      the bottom layer alone (types, every parser), its tests and its parsers' fuzzers: a few
#                 minutes, for working on the readers.
SANITIZE_FLAGS = -O2 -gline-tables-only -DNDEBUG
SANITIZE_CONFIGURE = CC=clang CXX=clang++ cmake -S . -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  "-DCMAKE_C_FLAGS_RELWITHDEBINFO=$(SANITIZE_FLAGS)" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$(SANITIZE_FLAGS)" \
	  -DPECTUS_FUZZ=ON -DPECTUS_SANITIZE=address,undefined \
	  -DPECTUS_SHARED_DIR=$(SHARED)
sanitize: bootstrap shared
	$(SANITIZE_CONFIGURE) -B $(SANBUILD) -DPECTUS_CORE_ONLY=ON $(CMAKE_ARGS)
	$(SANITIZER_ENV) cmake --build $(SANBUILD) -j$(JOBS)
	$(SANITIZER_ENV) ctest --test-dir $(SANBUILD) --output-on-failure -j$(JOBS)

# CTest starts the longest tests first when it knows their times: on a fresh build it has none, so it
# takes them from tests/ctest_costs.txt (those over 2 s under the sanitizers, from a `make test`; a build
# that has run its tests keeps its own), and the short ones fill the cores while the long ones end.
sanitize-all: bootstrap shared
	$(SANITIZE_CONFIGURE) -B $(SANBUILD)-all $(CMAKE_ARGS)
	$(SANITIZER_ENV) cmake --build $(SANBUILD)-all -j$(JOBS)
	@mkdir -p $(SANBUILD)-all/Testing/Temporary
	@[ -f $(SANBUILD)-all/Testing/Temporary/CTestCostData.txt ] || \
	  cp tests/ctest_costs.txt $(SANBUILD)-all/Testing/Temporary/CTestCostData.txt
	$(SANITIZER_ENV) ctest --test-dir $(SANBUILD)-all --output-on-failure -j$(JOBS)

fuzz-smoke: sanitize
	$(SANITIZER_ENV) scripts/fuzz-smoke $(SANBUILD) $(FUZZ_SECONDS)

fuzz-smoke-all: sanitize-all
	$(SANITIZER_ENV) scripts/fuzz-smoke $(SANBUILD)-all $(FUZZ_SECONDS)

bench: build
	cmake --build $(BUILD) --target pectus_benchmarks -j$(JOBS)

SOURCES = find apps datasets planner_plugin registration shape tests -name '*.h' -o -name '*.cc'
format:
	$(SOURCES) | xargs clang-format -i

# The tree as `make format` leaves it (clang-format 14, .clang-format): names every file it would change
# and fails, so that formatting does not drift (`make test` runs it first; a few seconds).
format-check: bootstrap
	@$(SOURCES) | xargs clang-format --dry-run -Werror
	@echo "format-check: every source as make format leaves it"

clean:
	rm -rf $(BUILD) $(SANBUILD) $(SANBUILD)-all
