#include "impactdic/core/memory.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace impactdic {

void AdviseHugePages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  if (data == nullptr || bytes < 2 * kHugePage) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t first = (begin + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t last = (begin + bytes) & ~(kHugePage - 1);
  if (last <= first) return;
  // A hint: a kernel without transparent huge pages refuses it, which changes nothing.
  // NOLINTNEXTLINE(performance-no-int-to-ptr): the page-aligned range of the caller's buffer
  (void)madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

void FaultInParallel(void* data, std::size_t bytes) {
  constexpr std::size_t kPage = 4096;
  if (data == nullptr || bytes == 0) return;
  auto* const bytes_of = static_cast<volatile unsigned char*>(data);
  const std::size_t pages = (bytes + kPage - 1) / kPage;
  // Blocks of 64 pages: one task per 256 KiB, so that the pool's threads share a few MB.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pages, 64),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t p = range.begin(); p != range.end(); ++p)
                        bytes_of[p * kPage] = 0;
                    });
}

}  // namespace impactdic
