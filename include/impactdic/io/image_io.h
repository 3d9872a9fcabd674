// Reading camera frames: single images (8/16-bit greyscale TIFF/PNG/...), sorted sequences from a
// folder or a glob, and video files through OpenCV. Errors name the file and what was expected.
#ifndef IMPACTDIC_IO_IMAGE_IO_H_
#define IMPACTDIC_IO_IMAGE_IO_H_

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace impactdic {

// Error kFileNotFound naming the file unless `path` is an existing regular file (a cheap check
// before a long job; ReadGreyImage does it too).
void CheckImageFileExists(const std::string& path);

// Reads one image as single-channel 8- or 16-bit (colour images are converted to grey).
// Error kFileNotFound when missing, kFileFormat when OpenCV cannot decode it (corrupt/truncated).
cv::Mat ReadGreyImage(const std::string& path);

// Writes an 8/16-bit image atomically (format from the extension).
void WriteImage(const std::string& path, const cv::Mat& image);

// True when `path` is a whole PNG file: the signature at the start and the IEND chunk at the end.
// How the output of a helper program (gnuplot) that may stop writing on a full disk is checked.
bool IsCompletePng(const std::string& path);

// Expands a frames source into a sorted list of image files: a folder (all image files in it), a
// glob pattern ("frames/img_*.tif") or a single file. Error if nothing matches. Names are
// sorted naturally: runs of digits by value, so unpadded "f_9.png" comes before "f_10.png".
std::vector<std::string> ListFrames(const std::string& source);

// For a numbered image series (names that differ only in their last run of digits): Error
// naming the file after a gap ("frame_0024.png to frame_0026.png: 1 frame(s) missing") unless
// the numbers advance by a constant step. Names that are not one numbered series are not
// checked.
void CheckFrameNumbering(const std::vector<std::string>& files);

// True if `path` names a video container OpenCV should read (.mp4, .avi, .mov, .mkv).
bool IsVideoFile(const std::string& path);

// Reads all frames of a video as greyscale (up to max_frames if > 0).
std::vector<cv::Mat> ReadVideoFrames(const std::string& path, int max_frames = 0);

// Checks that all images have the same size and depth; Error naming the first file that differs.
void CheckSameSize(const std::vector<cv::Mat>& images, const std::vector<std::string>& names);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_IMAGE_IO_H_
