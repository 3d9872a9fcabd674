// A decoder for the PNGs DIC frames come in: greyscale (colour type 0), 8 or 16 bit, not
// interlaced, no transparency chunk. It needs only zlib, so reading such frames does not load
// OpenCV's image codecs (io/opencv_codecs.h). The pixels are exactly those cv::imdecode gives
// with IMREAD_ANYDEPTH | IMREAD_ANYCOLOR (16-bit samples in host byte order; gamma and sBIT are
// not applied, as OpenCV does not apply them).
//
//   cv::Mat image;
//   if (!DecodeGreyPng(bytes, &image)) image = opencv_codecs::Decode(bytes, flags);
//
// Returns false, leaving *image alone, for anything else: another colour type or bit depth,
// interlacing, a tRNS or PLTE chunk, an unknown critical chunk, and any damage (bad CRC, bad
// zlib stream, wrong amount of data, bad filter type), so that the caller's general decoder
// handles the file and reports its problems as before.
#ifndef IMPACTDIC_IO_PNG_GREY_H_
#define IMPACTDIC_IO_PNG_GREY_H_

#include <opencv2/core.hpp>
#include <string>

namespace impactdic {

bool DecodeGreyPng(const std::string& bytes, cv::Mat* image);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_PNG_GREY_H_
