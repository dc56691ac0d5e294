#pragma once
// Counts heap allocations made through operator new (every form) and malloc-family calls
// made by our code paths, so tests can prove a code path allocates nothing. Link
// alloc_counter.cpp into the test executable: it replaces the global operator new/delete.

#include <cstddef>

namespace staa::test {

// Allocations counted so far on the calling thread.
std::size_t allocationCount();

// Counts allocations between construction and count().
class AllocationScope {
 public:
  AllocationScope() : start_(allocationCount()) {}
  std::size_t count() const { return allocationCount() - start_; }

 private:
  std::size_t start_;
};

}  // namespace staa::test
