# pectus_target_defaults(target): warnings, sanitizers and the include root, set once for every target.
function(pectus_target_defaults target)
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
  if(PECTUS_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=${PECTUS_SANITIZE} -fno-omit-frame-pointer
                           -fno-sanitize-recover=all)
    if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
      # The sanitizers' instrumentation keeps clang from vectorizing the `#pragma omp simd` loops, and
      # clang says so as a warning (-Wpass-failed): the Release build vectorizes them; not a defect here.
      target_compile_options(${target} PRIVATE -Wno-pass-failed)
    endif()
    target_link_options(${target} PRIVATE -fsanitize=${PECTUS_SANITIZE})
  endif()
endfunction()
