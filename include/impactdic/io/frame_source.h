// Where the frames of a sequence come from, behind one interface: image files (a list, a folder,
// a glob, a numbered sequence), a video, a high-speed camera's own file (Phantom .cine, Photron
// .mraw) or frames in memory (the library, synth, tests). A source reads raw grey frames, one at a
// time, so memory does not depend on the length of the recording; preprocessing and the analysed
// range sit on top of it (pipeline/frame_stream.h), the correlation driver below that
// (dic CorrelateFrames).
//
//   std::unique_ptr<FrameSource> source = OpenFrameSource("rec.cine");
//   for (int i = 0; i < source->frame_count(); ++i) {
//     cv::Mat frame = source->Read(i);                 // CV_8U or CV_16U, one channel
//     LogInfo("{} at {} s", source->Name(i), source->TimeS(i));   // "rec.cine frame -12"
//   }
//
// Reading in increasing order is efficient for every source (a video decodes each frame once);
// any index may be read (a video then decodes again from its start).
#ifndef IMPACTDIC_IO_FRAME_SOURCE_H_
#define IMPACTDIC_IO_FRAME_SOURCE_H_

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace impactdic {

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  // Frames in the source (>= 1 for a source that opened).
  virtual int frame_count() const = 0;
  // Frame `index` (0 .. frame_count() - 1) as decoded: one channel, CV_8U or CV_16U (float for
  // frames given in memory), rows top-down, in a buffer of its own. Error naming the frame
  // (Name) when it cannot be read.
  virtual cv::Mat Read(int index) = 0;
  // A hint that frame `index` will be read soon: a source that can decode it on another thread
  // (image files) starts doing so, and the Read(index) that follows takes the result (or its
  // error). At most one frame ahead; the default does nothing.
  virtual void ReadAhead(int /*index*/) {}
  // The frame's name in messages: "frame_0012.png", "clip.mp4 frame 12", "rec.cine frame -12".
  virtual std::string Name(int index) const = 0;
  // The frame's number in the source's own numbering: the number in the file name for a
  // numbered image sequence (frame_0012.png -> 12; else the 0-based index), the 0-based index
  // of a video's or in-memory frame, the camera's frame number of a camera file (negative
  // before the trigger). Increasing with the index.
  virtual long long FrameNumber(int index) const = 0;
  // The frame's time stamp [s] where the source stores one (camera files: relative to the
  // trigger), NaN otherwise.
  virtual double TimeS(int index) const;
  // The recording's frame rate [1/s] where the source states it (camera files), else 0.
  virtual double fps() const { return 0; }
  // The size and the data bits (8, 10, 12 or 16: io DataBits for image files and video; the
  // camera's for a camera file) of the frames; image files and video read frame 0 for them once.
  virtual cv::Size frame_size();
  virtual int data_bits();
  // Whether data_bits() is the bit depth the recording states (a camera file: 10-bit data is
  // then known as such), not measured from frame 0's pixels.
  virtual bool StatesDataBits() const { return false; }
  // What reading found (a colour image in a grey sequence, a truncated video), each once, in
  // the order found.
  virtual const std::vector<std::string>& warnings() const { return warnings_; }
  // What the frames are ("frames/*.png", "clip.mp4", "rec.cine"), for messages.
  virtual std::string description() const = 0;

 protected:
  void AddWarning(const std::string& warning) { warnings_.push_back(warning); }

 private:
  void MeasureFirstFrame();  // Reads frame 0 once for frame_size() and data_bits().

  std::vector<std::string> warnings_;
  cv::Size first_size_;
  int first_bits_ = -1;  // -1: frame 0 not measured yet.
};

// Image files in the order given (each must exist: Error naming the first missing file before
// any is decoded). Numbers from the names when they are one numbered series (io FrameNumbers).
// An image whose colour layout differs from the first one's is converted to grey with a warning
// (io SequenceColourCheck), in file order.
std::unique_ptr<FrameSource> MakeImageFileSource(const std::vector<std::string>& files,
                                                 const std::string& description = "");

// A video (io VideoReader): its decodable frames are counted once here (a truncated video ends
// at its last decodable frame, with the warning naming both counts).
std::unique_ptr<FrameSource> MakeVideoSource(const std::string& path);

// A camera file (io OpenCameraFile: .cine, .mraw, .cih, .cihx): the camera's frame numbers,
// time stamps, frame rate and data bits.
std::unique_ptr<FrameSource> MakeCameraFileSource(const std::string& path);

// Frames in memory, numbered 0.. ("frame 3" in messages); no time stamps unless `time_s` (one
// per frame) is given, and `fps` if known.
std::unique_ptr<FrameSource> MakeMemoryFrameSource(std::vector<cv::Mat> frames,
                                                   std::vector<double> time_s = {}, double fps = 0);

// The source a frames setting names: a camera file (IsCameraFile), a video (IsVideoFile), else
// an image sequence (io ListFrameSequence: folder, glob or file; a gap in its numbering is an
// Error).
std::unique_ptr<FrameSource> OpenFrameSource(const std::string& frames);

// Every file OpenFrameSource(frames) reads, in a fixed order: a camera file's parts
// (CameraFileParts: a .cine, or a Photron description and its .mraw), the video, or the
// sequence's images (ListFrameSequence). Error as those when the files cannot be listed (a missing
// Photron companion, no image matching, a gap in the numbering).
std::vector<std::string> FrameSourceFiles(const std::string& frames);

// The index of the frame numbered `number` (FrameNumber) in `source`. Error naming `where`, the
// number and the source's span ("frames -12..87 of rec.cine") when no frame has that number.
int FrameIndexOf(const FrameSource& source, long long number, const std::string& where);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_FRAME_SOURCE_H_
