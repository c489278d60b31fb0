# pectus_target_defaults(target [UNINSTRUMENTED]): warnings, sanitizers and the include root, set once
# for every target. UNINSTRUMENTED is for programs a sanitizer build only compiles and links, never runs
# (the benchmarks): there they are built at -O0 without the sanitizers' instrumentation, which takes a
# fifth of the time (registration_benchmark.cc: 30 s against 150 s), and linked with the sanitizers'
# runtime that the instrumented libraries they link need. Elsewhere the flag changes nothing.
function(pectus_target_defaults target)
  cmake_parse_arguments(PARSE_ARGV 1 arg "UNINSTRUMENTED;GLUE" "" "")
  if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow-uncaptured-local
                           -Wnon-virtual-dtor -Wno-deprecated-copy)
  elseif(CMAKE_CXX_COMPILER_ID MATCHES "GNU")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local
                           -Wnon-virtual-dtor -Wno-deprecated-copy)
    # GCC 12's -Wrestrict misfires inside libstdc++ on plain string assignments and concatenations
    # (GCC bug 105329, fixed in 13): silence it there only.
    if(CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
      target_compile_options(${target} PRIVATE -Wno-restrict)
    endif()
  endif()
  if(PECTUS_SANITIZE AND arg_UNINSTRUMENTED)
    target_compile_options(${target} PRIVATE -O0 -g0)
    target_link_options(${target} PRIVATE -fsanitize=${PECTUS_SANITIZE})
  elseif(PECTUS_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=${PECTUS_SANITIZE} -fno-omit-frame-pointer
                           -fno-sanitize-recover=all)
    if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
      # The sanitizers' instrumentation keeps clang from vectorizing the `#pragma omp simd` loops, and
      # clang says so as a warning (-Wpass-failed): the Release build vectorizes them; not a defect here.
      target_compile_options(${target} PRIVATE -Wno-pass-failed)
      # clang 14's OpenMP optimisation pass runs on every function of a -fopenmp unit, whether it has an
      # OpenMP region or not, and with the sanitizers' instrumentation it is up to a third of a unit's
      # compile (shape_model_test.cc: 92 s, 57 s without it). It only optimises the runtime's calls
      # (deduplicates them, targets GPUs); the code is the same without it.
      target_compile_options(${target} PRIVATE "SHELL:-mllvm -openmp-opt-disable")
      # UBSan's checks of every memory access (null, alignment, object-size, pointer-overflow) double the
      # compile of Eigen code (local_rbf.cc: 35 s, 17 s without them; bar_response_basis.cc: 23 s, 16 s)
      # and find little that AddressSanitizer does not: it stops at a null or out-of-bounds access, and
      # x86 loads unaligned data. They stay where the bytes come from outside: the bottom layer (types and
      # every reader) and the fuzzers. Everywhere else UBSan keeps the arithmetic checks (signed
      # overflow, shifts, float-to-int casts, division by zero), array bounds, enum, bool, vptr, return.
      if(PECTUS_SANITIZE MATCHES "undefined" AND
         NOT target MATCHES "^(pectus_core|pectus_io|pectus_csv|pectus_patient_table_io|fuzz_.*)$")
        target_compile_options(${target} PRIVATE -fno-sanitize=null,alignment,object-size,pointer-overflow)
      endif()
    endif()
    target_link_options(${target} PRIVATE -fsanitize=${PECTUS_SANITIZE})
    # The command line's glue (GLUE: options, messages, calls into the libraries) is mostly CLI11's
    # header-only parser, which every command unit compiles whole: under the sanitizers at -O2 a unit of
    # 100 lines takes 24-37 s, a CLI11 "hello" alone 33 s (15 s at -O0). Nothing runs long there, the
    # libraries do the work: it is compiled at -O0, still instrumented (2026-11-29: place 24 -> 13 s,
    # register 28 -> 16 s).
    if(arg_GLUE)
      target_compile_options(${target} PRIVATE -O0)
    endif()
    # lld links the sanitizer build's programs in a quarter of GNU ld's time (2026-11-29: pectus-full
    # 1.9-2.3 s -> 0.4-0.5 s, the model tests 1.4-1.6 s -> 0.4 s).
    if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
      target_link_options(${target} PRIVATE -fuse-ld=lld)
    endif()
    # The sanitizer build is CI's, compiled from nothing each time: a target of many units parses the
    # headers they all include once, as a precompiled header (a unit spends about 3 s parsing the standard
    # library, Eigen and GoogleTest before its own code: enum_names_test.cc, 11 lines, takes 3.0 s).
    # Nothing defines a macro before these headers; the units still include what they use.
    get_target_property(sources ${target} SOURCES)
    list(FILTER sources INCLUDE REGEX "\\.cc$")
    list(LENGTH sources units)
    if(units GREATER_EQUAL 6)
      target_precompile_headers(${target} PRIVATE <algorithm> <cstdint> <filesystem> <functional> <map>
                                <memory> <optional> <string> <vector> <Eigen/Dense>)
      if(target MATCHES "_tests$")
        target_precompile_headers(${target} PRIVATE <gtest/gtest.h>)
      endif()
    endif()
    # It also compiles a target's units eight at a time, as one (a unity build): the headers they share,
    # beyond the precompiled ones (PCL, CGAL, CLI11, the project's own), are parsed and instantiated once
    # per eight units (2026-11-29: tests/shape 501 -> 407 CPU s, planner_plugin 407 -> 347). Names local
    # to a file must then be unique within its target (a shared helper is a header's, not a copy's). The
    # Release build keeps one unit per file, and so checks that each includes what it uses.
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8)
  endif()
endfunction()
