// Reading camera frames: single images (8/16-bit greyscale TIFF/PNG/...), sorted sequences from a
// folder or a glob, and video files through OpenCV. Errors name the file and what was expected.
#ifndef IMPACTDIC_IO_IMAGE_IO_H_
#define IMPACTDIC_IO_IMAGE_IO_H_

#include <cstddef>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace impactdic {

// The largest image read: 32768 px a side and 2^28 pixels (16384 x 16384; a 1920x1440 frame has
// 2.8 million). Checked in the file header (PNG, TIFF, BMP, JPEG) before anything is decoded,
// so a header claiming 100000 x 100000 px is refused with its size instead of allocating 10 GB.
inline constexpr long long kMaxImageSidePx = 32768;
inline constexpr long long kMaxImagePixels = 1LL << 28;

// Error naming the file unless `path` is an existing regular file of at most kMaxImageFileBytes
// (io/input_file.h; a cheap check before a long job, ReadGreyImage does it too).
void CheckImageFileExists(const std::string& path);

// Reads one image as single-channel 8- or 16-bit (colour images are converted to grey,
// 0.299 R + 0.587 G + 0.114 B; the channel count of the file as decoded, 1, 3 or 4, goes to
// `file_channels` if given). A palette (indexed colour) TIFF whose palette is grey (red = green =
// blue in every entry) reads as its palette's grey values and counts as one channel; any other
// palette is converted to grey like a colour image, with one warning per process.
// Error kFileNotFound when missing (or a dangling symbolic link); kFileFormat for a folder,
// device or FIFO, an empty file, a header beyond the size limits above, a truncated or corrupt
// PNG (chunks, header and the image data's rows checked before decoding, so libpng prints
// nothing), a JPEG that ends before its end-of-image marker FF D9 (libjpeg would decode the rest
// flat grey; data after FF D9 are ignored), or anything else OpenCV cannot decode (with the
// reason OpenCV printed, kept off the terminal).
cv::Mat ReadGreyImage(const std::string& path, int* file_channels = nullptr);

// The dynamic range of an image's data in bits: 8 for 8-bit images; for 16-bit images 12 when no
// value exceeds 4095 (12-bit data in a 16-bit container, as high-speed cameras write), else 16;
// 0 for other depths. Its saturation level is 2^bits - 1. What the correlator's contrast and
// saturation limits are relative to (judged on the first reference, so for the whole sequence).
int DataBits(const cv::Mat& image);

// The pixel type of a grey image in words: "8-bit", "16-bit", "32-bit float", else "depth code D".
std::string DepthName(const cv::Mat& image);

// Watches the colour layout of the images of one sequence, in order: the first image sets it,
// and Check() returns (and logs) a warning naming an image whose layout differs, e.g. an RGB
// frame in a greyscale sequence, which would otherwise be converted to grey silently. The first
// kListed differing images are named; "" when the layout matches.
class SequenceColourCheck {
 public:
  static constexpr int kListed = 3;
  std::string Check(const std::string& path, int file_channels);

 private:
  std::string first_path_;
  int first_channels_ = 0;
  int mismatches_ = 0;
};

// Writes an 8/16-bit image atomically (format from the extension); `params` are OpenCV's encoder
// parameters (e.g. {cv::IMWRITE_PNG_COMPRESSION, 9}).
void WriteImage(const std::string& path, const cv::Mat& image, const std::vector<int>& params = {});

// True when `path` is a whole PNG file: the signature at the start and the IEND chunk at the end.
// How the output of a helper program (gnuplot) that may stop writing on a full disk is checked.
bool IsCompletePng(const std::string& path);

// Expands a frames source into a sorted list of image files: a folder (all image files in it), a
// glob pattern ("frames/img_*.tif") or a single file. Error if nothing matches, and naming the
// entry when one that would be a frame (an image name in the folder, or a match of the glob) is
// not a regular file: a folder, a dangling symbolic link, a FIFO (never opened), a device. Names
// are sorted naturally: runs of digits by value, so unpadded "f_9.png" comes before "f_10.png".
std::vector<std::string> ListFrames(const std::string& source);

// The numbers in the names of a numbered image series (names that differ only in their last run
// of digits, at most 9 of them: "frame_0012.png" -> 12), one per file; empty when the names are
// not one such series.
std::vector<long long> FrameNumbers(const std::vector<std::string>& files);

// For a numbered image series (names that differ only in their last run of digits): Error
// naming the file after a gap ("frame_0024.png to frame_0026.png: 1 frame(s) missing") unless
// the numbers advance by a constant step. Names that are not one numbered series are not
// checked.
void CheckFrameNumbering(const std::vector<std::string>& files);

// The first name of `paths` that is the same file as an earlier one (same device and inode:
// another spelling of the path, a symbolic or a hard link): {the earlier index, its index};
// nullopt when all are distinct. Names that cannot be stat()ed are skipped (left to the image
// reader's message). The one same-file check of `run`'s frames and `correlate`'s images.
std::optional<std::pair<std::size_t, std::size_t>> FirstRepeatedFile(
    const std::vector<std::string>& paths);

// The frames of one sequence: ListFrames, then CheckFrameNumbering (a gap is an error), then an
// Error when two of its names are the same file (a symbolic or hard link: the repeated image
// would read as no motion). Used by `run` (inputs.frames) and `correlate --frames` alike.
std::vector<std::string> ListFrameSequence(const std::string& source);

// True if `path` names a video container OpenCV should read (.mp4, .avi, .mov, .mkv).
bool IsVideoFile(const std::string& path);

// Reads the frames of a video one at a time, as greyscale, so that a long recording need not be
// held in memory:
//
//   VideoReader video("clip.avi");          // Error naming the file if empty or unopenable
//   cv::Mat frame;
//   while (video.Read(&frame)) { ... }
//   std::string warning = video.Finish();   // "" unless the video was truncated (then logged)
class VideoReader {
 public:
  explicit VideoReader(const std::string& path);
  ~VideoReader();
  VideoReader(const VideoReader&) = delete;
  VideoReader& operator=(const VideoReader&) = delete;

  // The next frame as one-channel grey (colour frames converted) in a buffer of its own; false
  // after the last one.
  bool Read(cv::Mat* grey);
  // Frames read so far.
  long long frames_read() const { return frames_read_; }
  // The frame count the container declares (its header or index); <= 0 when it does not say.
  double declared_frames() const { return declared_; }
  // After reading: when fewer frames were read than the container declares (or than
  // `max_frames` if > 0, when it declares more), the video is truncated or damaged: the warning
  // naming both counts, also logged. "" otherwise.
  std::string Finish(int max_frames = 0) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  double declared_ = 0;
  long long frames_read_ = 0;
};

// Reads all frames of a video as greyscale (up to max_frames if > 0). When fewer frames decode
// than the container declares (CAP_PROP_FRAME_COUNT), the video is truncated or damaged: the
// frames read are kept (they are the start of the recording, correctly timed) and a warning with
// both counts is logged and stored in `warning` if given.
std::vector<cv::Mat> ReadVideoFrames(const std::string& path, int max_frames = 0,
                                     std::string* warning = nullptr);

// Checks that all images have the same size and depth; Error naming the first file that differs.
void CheckSameSize(const std::vector<cv::Mat>& images, const std::vector<std::string>& names);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_IMAGE_IO_H_
