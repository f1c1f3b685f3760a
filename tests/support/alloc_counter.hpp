#pragma once
// Counts heap allocations made through the global operator new of the test
// program (replaced in alloc_counter.cpp, a source of the programs that use
// it), to prove a hot path allocates nothing.
#include <cstddef>

namespace inspect::test {

/// Number of global operator new calls since the program started.
std::size_t allocationCount();

}  // namespace inspect::test
