// Frames stored by high-speed camera software, read directly (no export to TIFF, which for Phantom
// applies gain/gamma and for 8-bit exports drops bits): Phantom .cine and Photron .mraw (described
// by its .cih text or .cihx XML file). Frames are read one at a time, so memory does not depend on
// the length of the recording. Errors name the file and what is not supported (compressed or
// colour-filter-array data, unknown bit depths) and what to do.
#ifndef IMPACTDIC_IO_CAMERA_FILE_H_
#define IMPACTDIC_IO_CAMERA_FILE_H_

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace impactdic {

// What a camera file says of its recording.
struct CameraFileInfo {
  std::string path;    // The file the frames are read from (a .cine, or the .mraw).
  std::string format;  // "Phantom cine" or "Photron mraw".
  int width_px = 0;
  int height_px = 0;
  // Significant bits per pixel of the recorded data: 8, 10, 12 or 16 (the camera's bit depth,
  // not the container's: 12-bit packed data read into 16-bit pixels is 12).
  int data_bits = 0;
  long long frame_count = 0;
  // The camera's number of frame 0 of the file: negative for frames recorded before the
  // trigger (frame number 0 is the trigger frame).
  long long first_frame_number = 0;
  double fps = 0;  // The recording's frame rate [1/s].
  // Time of each frame relative to the trigger [s] (frame_count entries): the file's own time
  // stamps where it stores them, else (first_frame_number + index) / fps.
  std::vector<double> time_s;
};

// One open camera file.
class CameraFileReader {
 public:
  virtual ~CameraFileReader() = default;
  virtual const CameraFileInfo& info() const = 0;
  // Frame `index` of the file (0 .. frame_count - 1; the camera's frame number
  // first_frame_number + index), single channel, rows top-down: CV_8U for 8-bit data, CV_16U
  // (the recorded values, not rescaled) for 10, 12 and 16-bit data. Error naming the file and the
  // frame when the index is out of range or the file ends inside the frame.
  virtual cv::Mat ReadFrame(long long index) = 0;
};

// A Phantom .cine file (Vision Research, "The Cine File Format"): 8 and 16-bit, 10 and 12-bit
// packed, bottom-up rows, negative first frame numbers, time stamps from its tagged blocks.
// Refused with a clear error: compressed images, colour (CFA) data, unknown versions.
std::unique_ptr<CameraFileReader> OpenCineFile(const std::string& path);

// A Photron .mraw recording, given as the .mraw or its .cih / .cihx description (the other is
// found beside it by name): 8, 10, 12 and 16-bit raw frames as the .cih describes them.
std::unique_ptr<CameraFileReader> OpenMrawFile(const std::string& path);

// The files OpenMrawFile reads for `path`: {the description (.cih or .cihx), the .mraw}, the one
// `path` does not name found beside it by name (a .cihx before a .cih; the extension in lower or
// upper case). Error kFileNotFound naming `path` when it or its companion does not exist.
std::vector<std::string> MrawFileParts(const std::string& path);

// True when `path` names a camera file by its extension (.cine, .mraw, .cih, .cihx; any case).
bool IsCameraFile(const std::string& path);

// OpenCineFile or OpenMrawFile by the extension; error for any other file.
std::unique_ptr<CameraFileReader> OpenCameraFile(const std::string& path);

// Every file OpenCameraFile(path) reads: a .cine alone; a Photron recording's description and its
// .mraw (MrawFileParts: Error when one of them is missing). Error for any other extension, as
// OpenCameraFile. What must be unchanged for a recording to read the same (campaign resume).
std::vector<std::string> CameraFileParts(const std::string& path);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_CAMERA_FILE_H_
