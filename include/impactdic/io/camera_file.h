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
  // Camera frames from one saved frame to the next (>= 1): 1 when every recorded frame was saved,
  // n when the camera software kept every n-th one (Photron's "Save Step"; a Phantom cine has no
  // such setting and is always 1). Frame `index` of the file is camera frame FrameNumber(index).
  long long frame_step = 1;
  // The frame rate of the file's frames [1/s], in kCameraFpsRange (core/range.h): the camera's
  // recording rate divided by frame_step, so that consecutive frames of the file are 1 / fps
  // apart (the rate the kinematics' time steps use). The camera recorded at fps * frame_step.
  double fps = 0;
  // Time of each frame relative to the trigger [s] (frame_count entries): the file's own time
  // stamps where it stores them, else FrameNumber(index) / (fps * frame_step).
  std::vector<double> time_s;

  // The camera's frame number of frame `index` of the file.
  long long FrameNumber(long long index) const { return first_frame_number + frame_step * index; }
};

// One open camera file.
class CameraFileReader {
 public:
  virtual ~CameraFileReader() = default;
  virtual const CameraFileInfo& info() const = 0;
  // Frame `index` of the file (0 .. frame_count - 1; the camera's frame number
  // info().FrameNumber(index)), single channel, rows top-down: CV_8U for 8-bit data, CV_16U
  // (the recorded values, not rescaled) for 10, 12 and 16-bit data. Error naming the file and the
  // frame when the index is out of range or the file ends inside the frame.
  virtual cv::Mat ReadFrame(long long index) = 0;
};

// A Phantom .cine file (Vision Research, "The Cine File Format"): 8 and 16-bit, 10 and 12-bit
// packed, bottom-up rows, negative first frame numbers, time stamps from its tagged blocks.
// 10-bit packed pixels are returned as stored (data_bits 10): Phantom's 10-bit codes are a
// monotone, non-linear (companded) function of the 12-bit sensor values, the same for every
// frame, so displacements are unaffected but the values are not proportional to the light (the
// maker's table LinLUT expands them to 12 bits; it is not applied here).
// Refused with a clear error: compressed images, colour (CFA) data, unknown versions, a FrameRate
// outside kCameraFpsRange or contradicting the time stamps, image dimensions the file cannot hold.
std::unique_ptr<CameraFileReader> OpenCineFile(const std::string& path);

// A Photron .mraw recording, given as the .mraw or its .cih / .cihx description (the other is
// found beside it by name): 8, 10, 12 and 16-bit raw frames as the .cih describes them. A "Save
// Step" n (.cihx: frameInfo/skipFrame) numbers the frames Start Frame + n * index, at
// Record Rate(fps) / n; both rates must lie in kCameraFpsRange.
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
