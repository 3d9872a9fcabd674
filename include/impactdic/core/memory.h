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

namespace impactdic {

// Asks the kernel to back the whole 2 MiB pages inside [data, data + bytes) with transparent huge
// pages (Linux madvise(MADV_HUGEPAGE); effective where /sys/kernel/mm/transparent_hugepage/enabled
// is "madvise" or "always"). Call it before the buffer is first written; pages already touched
// keep their size. Buffers under 4 MiB, other systems and a refusal: nothing happens. The data
// and its values are not affected.
void AdviseHugePages(void* data, std::size_t bytes);

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_MEMORY_H_
