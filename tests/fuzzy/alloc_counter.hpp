#pragma once
// Counts heap allocations made through the global operator new of the test
// binary (replaced in alloc_counter.cpp), to prove evaluate() allocates nothing.
#include <cstddef>

namespace inspect::fuzzy::testing {

/// Number of global operator new calls since the program started.
std::size_t allocationCount();

}  // namespace inspect::fuzzy::testing
