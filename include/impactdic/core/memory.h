// Large buffers written once, right after they are allocated (a frame's B-spline coefficients,
// the reference's gradient images): their first touch costs a page fault per 4 KiB page (zeroing,
// accounting), a visible share of a one-shot correlation.
//
//   cv::Mat coefficients(rows, cols, CV_32F);
//   AdviseHugePages(coefficients.data, coefficients.total() * coefficients.elemSize());
//   Fill(coefficients);  // now one fault per 2 MiB where the kernel grants huge pages
#ifndef IMPACTDIC_CORE_MEMORY_H_
#define IMPACTDIC_CORE_MEMORY_H_

#include <cstddef>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace impactdic {

// Asks the kernel to back the whole 2 MiB pages inside [data, data + bytes) with transparent huge
// pages (Linux madvise(MADV_HUGEPAGE); effective where /sys/kernel/mm/transparent_hugepage/enabled
// is "madvise" or "always"). Call it before the buffer is first written; pages already touched
// keep their size. Buffers under 4 MiB, other systems and a refusal: nothing happens. The data
// and its values are not affected.
void AdviseHugePages(void* data, std::size_t bytes);

// Writes one byte of every 4 KiB page of [data, data + bytes) on the thread pool, so that the
// page faults (and the kernel's zeroing) of a new buffer's first touch run in parallel rather than
// in the serial loop that then constructs its elements (types a parallel loop cannot construct:
// FilledInParallel is for trivially copyable ones). Only for memory not yet holding objects: the
// bytes written become zero.
void FaultInParallel(void* data, std::size_t bytes);

// The allocator of FilledInParallel: resize() leaves the new elements of a trivially copyable
// type as the memory has them, for the caller's parallel loop to assign every one; any other
// construction (copies, values given) is std::allocator's.
template <typename T>
struct AssignedLaterAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = AssignedLaterAllocator<U>;
  };
  AssignedLaterAllocator() = default;
  template <typename U>
  explicit AssignedLaterAllocator(const AssignedLaterAllocator<U>& /*other*/) {}
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0 && std::is_trivially_copyable_v<U>) {
      // Left for the caller's loop: the page is first touched there, on its thread.
    } else {
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
  }
};

// A large array that a parallel loop fills right after resize(), every element assigned: the
// pages are first touched (a page fault each, zeroed by the kernel) by the loop's threads, not by
// a serial zero-fill before it (a subset's inverse Hessian, reference data and attempt: several
// MB each for a dense grid, a visible share of a one-shot correlation).
//
//   FilledInParallel<double> hinv;
//   hinv.resize(n * 36);
//   tbb::parallel_for(0, n, [&](int i) { std::fill_n(&hinv[i * 36], 36, 0.0); ... });
template <typename T>
using FilledInParallel = std::vector<T, AssignedLaterAllocator<T>>;

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_MEMORY_H_
