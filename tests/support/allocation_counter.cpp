// The replaced global allocation functions behind allocation_count(). Link this file into a
// test program (tests/CMakeLists.txt) to count its allocations; a program can have only one.
//
// Every replaceable allocation function is replaced — new and new[], each plain, aligned
// (std::align_val_t), nothrow and aligned nothrow — and so is every deallocation function, so
// whichever form the library or the standard library calls (std::stable_partition's temporary
// buffer takes the nothrow new), the memory comes from this file's malloc or aligned_alloc and
// goes back through its free: no allocation is missed, none counted twice (each form allocates
// itself instead of calling another), and none is freed by another allocator's delete (which
// AddressSanitizer reports as alloc-dealloc-mismatch).
//
// Under clang's ThreadSanitizer the runtime must own operator new (it links its own definitions
// statically, and two definitions do not link), so there the count comes from the sanitizer's
// malloc hook instead, which its allocator runs for every new and malloc alike. (GCC's runtime
// is a shared library whose definitions these replace, as without a sanitizer.)
#include "tests/support/allocation_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define LIMBER_COUNT_WITH_SANITIZER_HOOKS 1
#endif
#endif

namespace {

std::atomic<long> allocations{0};

}  // namespace

#if defined(LIMBER_COUNT_WITH_SANITIZER_HOOKS)
#include <sanitizer/allocator_interface.h>

namespace {

void count_allocation(const volatile void*, std::size_t) { ++allocations; }
void ignore_free(const volatile void*) {}
// The runtime takes a free hook with every malloc hook; nothing is counted on free.
[[maybe_unused]] const int hooks_installed = __sanitizer_install_malloc_and_free_hooks(count_allocation, ignore_free);

}  // namespace
#else
namespace {

// One counted allocation: malloc, or aligned_alloc for an alignment beyond the default (its size
// rounded up to a multiple of the alignment, as aligned_alloc requires). On failure, calls the
// new-handler and retries, as the standard's operator new does; null when there is none.
void* allocate(std::size_t size, std::size_t alignment) noexcept {
  ++allocations;
  if (size == 0) size = 1;
  for (;;) {
    void* p = alignment <= __STDCPP_DEFAULT_NEW_ALIGNMENT__ ? std::malloc(size)
                                                            : std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
    if (p) return p;
    const std::new_handler handler = std::get_new_handler();
    if (!handler) return nullptr;
    try {
      handler();
    } catch (...) {  // a handler that throws bad_alloc: the nothrow forms return null, the others rethrow below
      return nullptr;
    }
  }
}

void* allocate_or_throw(std::size_t size, std::size_t alignment) {
  if (void* p = allocate(size, alignment)) return p;
  throw std::bad_alloc();
}

std::size_t alignment_of(std::align_val_t alignment) { return static_cast<std::size_t>(alignment); }

}  // namespace

// GCC 12 warns that the std::free below may meet memory from another allocator: it cannot see
// that these replacements are the program's only allocation functions.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) { return allocate_or_throw(size, 0); }
void* operator new[](std::size_t size) { return allocate_or_throw(size, 0); }
void* operator new(std::size_t size, std::align_val_t alignment) { return allocate_or_throw(size, alignment_of(alignment)); }
void* operator new[](std::size_t size, std::align_val_t alignment) { return allocate_or_throw(size, alignment_of(alignment)); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return allocate(size, 0); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return allocate(size, 0); }
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return allocate(size, alignment_of(alignment));
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return allocate(size, alignment_of(alignment));
}

// Whatever form allocated it, the memory came from malloc or aligned_alloc: free takes both.
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
#endif

long limber::testing::allocation_count() { return allocations.load(); }
