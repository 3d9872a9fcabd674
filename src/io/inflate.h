// Inflation of raw deflate data (RFC 1951) into a buffer of known size: the image data of the PNG
// frames (png_grey.cc), whose decoding was zlib's inflate for the most part (nearly all literals
// in a speckle frame). This decoder reads 56 bits at a time, decodes a code of up to 11 bits
// (litlen) or 8 bits (distance) in one table look-up (longer ones in two) and up to three
// literals per refill: 8.3 ms against zlib's 14.8 ms for the 2.2 MB of image data of the
// 1920 x 1440 benchmark frame (docs/dic_speed.md "Latest"; tests/io/inflate_test.cc checks it
// against zlib on every kind of block).
//
//   std::vector<unsigned char> out(expected_size);
//   if (!InflateRaw(data, size, out.data(), out.size())) /* damaged, or not that size */;
#ifndef IMPACTDIC_IO_INFLATE_H_
#define IMPACTDIC_IO_INFLATE_H_

#include <cstddef>

namespace impactdic {

// Inflates the raw deflate stream in [in, in + in_size) into [out, out + out_size). True when the
// stream is valid, ends (its final block) within the input, and fills the output exactly; bytes
// after its end do not change the result (the decoder may read up to 8 of them, inside the input).
// False for anything else (an invalid block type, code or distance, a stream longer or shorter than
// out_size, input ending early); the output is then undefined. Never reads or writes outside the
// two ranges.
bool InflateRaw(const unsigned char* in, std::size_t in_size, unsigned char* out,
                std::size_t out_size);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_INFLATE_H_
