// Counts the heap allocations of the whole process (any library, a dlopen'ed plugin included), so a test
// can assert that a real-time call allocates nothing. The counter replaces malloc, calloc, realloc and the
// aligned allocators with glibc's own behind a count; it is linked only where no sanitizer replaces them
// (PECTUS_COUNT_ALLOCATIONS is then defined).
#pragma once

#include <cstddef>

namespace pectus::testing_support {

/// Heap allocations made by this process so far (every thread).
std::size_t AllocationCount();

}  // namespace pectus::testing_support
