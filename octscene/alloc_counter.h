// Counts heap allocations (operator new calls) of the whole process while
// switched on. Defined in alloc_counter.cpp, which replaces the global
// operator new/delete and is linked into the octscene executable only (a
// library must not replace them for its users).
#pragma once
#include <cstdint>

namespace octbake::scene {

// Starts counting from zero.
void start_counting_allocations();
// Stops counting; returns the operator new calls since the start.
uint64_t stop_counting_allocations();

}  // namespace octbake::scene
