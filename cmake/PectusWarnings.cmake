# pectus_target_defaults(target [UNINSTRUMENTED]): warnings, sanitizers and the include root, set once
# for every target. UNINSTRUMENTED is for programs a sanitizer build only compiles and links, never runs
# (the benchmarks): there they are built at -O0 without the sanitizers' instrumentation, which takes a
# fifth of the time (registration_benchmark.cc: 30 s against 150 s), and linked with the sanitizers'
# runtime that the instrumented libraries they link need. Elsewhere the flag changes nothing.
function(pectus_target_defaults target)
  cmake_parse_arguments(PARSE_ARGV 1 arg "UNINSTRUMENTED" "" "")
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
    endif()
    target_link_options(${target} PRIVATE -fsanitize=${PECTUS_SANITIZE})
  endif()
endfunction()
