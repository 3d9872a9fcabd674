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

// kCheckedByCaller: the chunks' CRC-32s were verified already (PngStructureProblem in image_io's
// checks), so the decoder does not compute them again.
enum class PngChunkCrcs { kCheck, kCheckedByCaller };
bool DecodeGreyPng(const std::string& bytes, cv::Mat* image,
                   PngChunkCrcs crcs = PngChunkCrcs::kCheck);

// For any PNG (every colour type and bit depth, interlaced or not) whose chunks are whole: its
// header and image data as libpng reads them, so that a damaged file is reported in one message
// of ours instead of a "libpng error: ..." line that libpng (through OpenCV, which keeps libpng's
// default handler) prints to stderr: an invalid IHDR, a corrupt zlib stream, less data than the
// rows of its header need, a row filter type other than 0-4 ("bad adaptive filter value"). Data
// after the last row is not looked at (libpng only warns about it). "" when sound or not a PNG;
// else what is wrong, e.g. "a corrupt PNG: row 40 has filter type 7; the PNG filter types are
// 0-4". Costs one inflate of the image data (no pixels are kept).
std::string PngImageDataProblem(const std::string& bytes);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_PNG_GREY_H_
