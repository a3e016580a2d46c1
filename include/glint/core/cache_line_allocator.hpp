// glint/core/cache_line_allocator.hpp: an allocator for arrays a query reads at random
// (triangle records, tree nodes): aligned to cache lines, and to huge pages when large.
#pragma once

#include <cstddef>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace glint {

namespace detail {

/// Allocator aligned to a cache line (64 bytes), so that a store's blocks of records start
/// on a line boundary and a SIMD load never straddles two lines more than it must. Arrays of
/// 2 MiB and more are aligned to 2 MiB and, on Linux, marked for transparent huge pages
/// (madvise), as Embree does for its BVHs: a query on a scene of millions of triangles
/// touches a few dozen lines spread over ~100 MB, and with 4 KiB pages each is a TLB miss.
template <class T>
struct CacheLineAllocator {
    using value_type = T;
    static constexpr std::size_t huge_page = std::size_t(1) << 21;
    static constexpr std::align_val_t alignment_for(std::size_t bytes) {
        return std::align_val_t{bytes >= huge_page ? huge_page : 64};
    }
    CacheLineAllocator() = default;
    template <class U>
    CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}
    T* allocate(std::size_t n) {
        const std::size_t bytes = n * sizeof(T);
        void* p = ::operator new(bytes, alignment_for(bytes));
#if defined(__linux__) && defined(MADV_HUGEPAGE)
        if (bytes >= huge_page) madvise(p, bytes & ~(huge_page - 1), MADV_HUGEPAGE);  // a hint; failure is harmless
#endif
        return static_cast<T*>(p);
    }
    void deallocate(T* p, std::size_t n) noexcept { ::operator delete(p, alignment_for(n * sizeof(T))); }
    template <class U>
    bool operator==(const CacheLineAllocator<U>&) const noexcept { return true; }
};

}  // namespace detail

}  // namespace glint
