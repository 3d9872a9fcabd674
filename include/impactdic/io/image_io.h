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

// Expands a frames source into a sorted list of image files: a folder (all image files in it), a
// glob pattern ("frames/img_*.tif") or a single file. Error if nothing matches.
std::vector<std::string> ListFrames(const std::string& source);

// True if `path` names a video container OpenCV should read (.mp4, .avi, .mov, .mkv).
bool IsVideoFile(const std::string& path);

// Reads all frames of a video as greyscale (up to max_frames if > 0).
std::vector<cv::Mat> ReadVideoFrames(const std::string& path, int max_frames = 0);

// Checks that all images have the same size and depth; Error naming the first file that differs.
void CheckSameSize(const std::vector<cv::Mat>& images, const std::vector<std::string>& names);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_IMAGE_IO_H_
