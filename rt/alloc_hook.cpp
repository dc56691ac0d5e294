// Replacement global operator new/delete (every form: plain, array, nothrow, aligned, sized)
// that count every allocation, per thread and for threads marked real-time
// (rt/alloc_count.hpp). Linked into staad and the tests that count allocations (target
// staa_rt_alloc_hook, an object library so that the linker cannot leave it out). Memory comes from malloc/aligned_alloc and goes back to free,
// which keeps it correct under AddressSanitizer (it sees matching malloc/free pairs).

#include "rt/alloc_count.hpp"

#include <cstddef>
#include <cstdlib>
#include <new>

namespace {

void count() { staa::rt::noteAllocation(); }

// operator new's contract: retry through the new-handler until it succeeds or there is none.
void* allocate(std::size_t size) {
  if (size == 0) size = 1;  // a unique non-null pointer even for 0 bytes
  for (;;) {
    if (void* p = std::malloc(size)) return p;
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

void* allocateAligned(std::size_t size, std::align_val_t align) {
  const auto a = static_cast<std::size_t>(align);
  // aligned_alloc wants a size that is a multiple of the alignment (ASan enforces it).
  if (size == 0) size = 1;
  if (size > static_cast<std::size_t>(-1) - a) throw std::bad_alloc();
  const std::size_t rounded = (size + a - 1) / a * a;
  for (;;) {
    if (void* p = std::aligned_alloc(a, rounded)) return p;
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

// Tells alloc_count that the counting operator new is in this program.
struct InstallNote {
  InstallNote() { staa::rt::noteHookInstalled(); }
};
const InstallNote g_install_note;

}  // namespace

void* operator new(std::size_t size) {
  count();
  return allocate(size);
}
void* operator new[](std::size_t size) {
  count();
  return allocate(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  count();
  try {
    return allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  count();
  try {
    return allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t align) {
  count();
  return allocateAligned(size, align);
}
void* operator new[](std::size_t size, std::align_val_t align) {
  count();
  return allocateAligned(size, align);
}
void* operator new(std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  count();
  try {
    return allocateAligned(size, align);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, std::align_val_t align, const std::nothrow_t&) noexcept {
  count();
  try {
    return allocateAligned(size, align);
  } catch (...) {
    return nullptr;
  }
}

void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
