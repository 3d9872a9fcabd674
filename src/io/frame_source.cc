#include "impactdic/io/frame_source.h"

#include <fmt/format.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <limits>
#include <memory>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/io/camera_file.h"
#include "impactdic/io/image_io.h"

namespace impactdic {

double FrameSource::TimeS(int /*index*/) const { return std::numeric_limits<double>::quiet_NaN(); }

void FrameSource::MeasureFirstFrame() {
  if (first_bits_ >= 0) return;
  const cv::Mat first = Read(0);
  first_size_ = first.size();
  first_bits_ = DataBits(first);
}

cv::Size FrameSource::frame_size() {
  MeasureFirstFrame();
  return first_size_;
}

int FrameSource::data_bits() {
  MeasureFirstFrame();
  return first_bits_;
}

namespace {

class ImageFileSource : public FrameSource {
 public:
  ImageFileSource(std::vector<std::string> files, std::string description)
      : files_(std::move(files)), description_(std::move(description)) {
    CheckValue(!files_.empty(), "frames", "no image", "at least one image");
    // A missing file is reported before any work; a corrupt one when it is decoded.
    for (const std::string& f : files_) CheckImageFileExists(f);
    numbers_ = FrameNumbers(files_);
  }
  ~ImageFileSource() override {
    if (ahead_) ahead_->group.wait();  // Its result or error is dropped.
  }
  ImageFileSource(const ImageFileSource&) = delete;
  ImageFileSource& operator=(const ImageFileSource&) = delete;
  int frame_count() const override { return static_cast<int>(files_.size()); }
  // The file is decoded in a task of the TBB arena (so within the run's thread limit); only the
  // decoding runs there, the checks of the sequence stay in Read, in file order.
  void ReadAhead(int index) override {
    if (ahead_ || index < 0 || index >= frame_count()) return;
    ahead_ = std::make_unique<Ahead>();
    Ahead* a = ahead_.get();
    a->index = index;
    a->group.run([a, path = files_[static_cast<std::size_t>(index)]] {
      try {
        a->image = ReadGreyImage(path, &a->channels);
      } catch (...) {
        a->error = std::current_exception();
      }
    });
  }
  cv::Mat Read(int index) override {
    const std::string& path = files_.at(static_cast<std::size_t>(index));
    int channels = 1;
    cv::Mat image;
    if (ahead_ && ahead_->index == index) {
      const std::unique_ptr<Ahead> a = std::move(ahead_);
      a->group.wait();
      if (a->error) std::rethrow_exception(a->error);
      image = std::move(a->image);
      channels = a->channels;
    } else {
      image = ReadGreyImage(path, &channels);
    }
    if (index > colour_checked_) {  // Each file's warning once, in the order of the files.
      const std::string warning = colour_.Check(path, channels);
      if (!warning.empty()) AddWarning(warning);
      colour_checked_ = index;
    }
    return image;
  }
  std::string Name(int index) const override { return files_.at(static_cast<std::size_t>(index)); }
  long long FrameNumber(int index) const override {
    return numbers_.empty() ? index : numbers_.at(static_cast<std::size_t>(index));
  }
  std::string description() const override {
    return description_.empty() ? files_.front() : description_;
  }

 private:
  std::vector<std::string> files_;
  std::string description_;
  std::vector<long long> numbers_;  // Empty: not one numbered series.
  SequenceColourCheck colour_;
  int colour_checked_ = -1;  // Highest index whose colour was checked.
  // A frame being decoded ahead (ReadAhead).
  struct Ahead {
    int index = -1;
    cv::Mat image;
    int channels = 1;
    std::exception_ptr error;
    tbb::task_group group;
  };
  std::unique_ptr<Ahead> ahead_;
};

class VideoSource : public FrameSource {
 public:
  explicit VideoSource(std::string path) : path_(std::move(path)) {
    // The container's frame count is not to be trusted (a truncated recording): count the frames
    // that decode, one at a time.
    VideoReader video(path_);
    cv::Mat frame;
    while (video.Read(&frame)) {
    }
    frames_ = static_cast<int>(video.frames_read());
    const std::string truncated = video.Finish();
    if (!truncated.empty()) AddWarning(truncated);
  }
  int frame_count() const override { return frames_; }
  cv::Mat Read(int index) override {
    if (!video_ || index < next_) {  // Going back: decode from the start again.
      video_ = std::make_unique<VideoReader>(path_);
      next_ = 0;
    }
    cv::Mat frame;
    while (next_ <= index) {
      if (!video_->Read(&frame)) {
        throw Error(ErrorKind::kFileFormat, "video frame", std::to_string(index),
                    fmt::format("a frame that decodes ({} decoded when the run started)", frames_))
            .WithFile(path_);
      }
      ++next_;
    }
    return frame;
  }
  std::string Name(int index) const override { return fmt::format("{} frame {}", path_, index); }
  long long FrameNumber(int index) const override { return index; }
  std::string description() const override { return path_; }

 private:
  std::string path_;
  int frames_ = 0;
  std::unique_ptr<VideoReader> video_;
  int next_ = 0;  // Index of the frame video_ decodes next.
};

class CameraFileSource : public FrameSource {
 public:
  explicit CameraFileSource(const std::string& path) : path_(path), file_(OpenCameraFile(path)) {
    const CameraFileInfo& info = file_->info();
    CheckValue(info.frame_count >= 1 && info.frame_count <= std::numeric_limits<int>::max(),
               "frame count", std::to_string(info.frame_count), "1 .. 2^31 - 1 frames");
  }
  int frame_count() const override { return static_cast<int>(file_->info().frame_count); }
  cv::Mat Read(int index) override { return file_->ReadFrame(index); }
  std::string Name(int index) const override {
    return fmt::format("{} frame {}", path_, FrameNumber(index));
  }
  long long FrameNumber(int index) const override { return file_->info().FrameNumber(index); }
  double TimeS(int index) const override {
    const std::vector<double>& t = file_->info().time_s;
    const auto k = static_cast<std::size_t>(index);
    return k < t.size() ? t[k] : FrameSource::TimeS(index);
  }
  double fps() const override { return file_->info().fps; }
  cv::Size frame_size() override { return {file_->info().width_px, file_->info().height_px}; }
  int data_bits() override { return file_->info().data_bits; }
  bool StatesDataBits() const override { return true; }
  std::string description() const override { return path_; }

 private:
  std::string path_;
  std::unique_ptr<CameraFileReader> file_;
};

class MemoryFrameSource : public FrameSource {
 public:
  MemoryFrameSource(std::vector<cv::Mat> frames, std::vector<double> time_s, double fps)
      : frames_(std::move(frames)), time_s_(std::move(time_s)), fps_(fps) {
    CheckValue(time_s_.empty() || time_s_.size() == frames_.size(), "time stamps",
               std::to_string(time_s_.size()), fmt::format("one per frame ({})", frames_.size()));
  }
  int frame_count() const override { return static_cast<int>(frames_.size()); }
  cv::Mat Read(int index) override { return frames_.at(static_cast<std::size_t>(index)); }
  std::string Name(int index) const override { return fmt::format("frame {}", index); }
  long long FrameNumber(int index) const override { return index; }
  double TimeS(int index) const override {
    return time_s_.empty() ? FrameSource::TimeS(index)
                           : time_s_.at(static_cast<std::size_t>(index));
  }
  double fps() const override { return fps_; }
  std::string description() const override { return "frames in memory"; }

 private:
  std::vector<cv::Mat> frames_;
  std::vector<double> time_s_;
  double fps_ = 0;
};

}  // namespace

std::unique_ptr<FrameSource> MakeImageFileSource(const std::vector<std::string>& files,
                                                 const std::string& description) {
  return std::make_unique<ImageFileSource>(files, description);
}

std::unique_ptr<FrameSource> MakeVideoSource(const std::string& path) {
  return std::make_unique<VideoSource>(path);
}

std::unique_ptr<FrameSource> MakeCameraFileSource(const std::string& path) {
  return std::make_unique<CameraFileSource>(path);
}

std::unique_ptr<FrameSource> MakeMemoryFrameSource(std::vector<cv::Mat> frames,
                                                   std::vector<double> time_s, double fps) {
  return std::make_unique<MemoryFrameSource>(std::move(frames), std::move(time_s), fps);
}

std::unique_ptr<FrameSource> OpenFrameSource(const std::string& frames) {
  if (IsCameraFile(frames)) return MakeCameraFileSource(frames);
  if (IsVideoFile(frames)) return MakeVideoSource(frames);
  // A gap in the numbering is an error.
  return MakeImageFileSource(ListFrameSequence(frames), frames);
}

std::vector<std::string> FrameSourceFiles(const std::string& frames) {
  if (IsCameraFile(frames)) return CameraFileParts(frames);
  if (IsVideoFile(frames)) return {frames};
  return ListFrameSequence(frames);
}

int FrameIndexOf(const FrameSource& source, long long number, const std::string& where) {
  int lo = 0, hi = source.frame_count();  // Numbers increase with the index: bisect.
  while (lo < hi) {
    const int mid = lo + (hi - lo) / 2;
    if (source.FrameNumber(mid) < number) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  if (lo < source.frame_count() && source.FrameNumber(lo) == number) return lo;
  const int last = source.frame_count() - 1;
  throw Error(ErrorKind::kInvalidValue, where, std::to_string(number),
              fmt::format("a frame number of {} (frames {}..{}{})", source.description(),
                          source.FrameNumber(0), source.FrameNumber(last),
                          last > 0 && source.FrameNumber(1) - source.FrameNumber(0) != 1
                              ? fmt::format(" in steps of {}",
                                            source.FrameNumber(1) - source.FrameNumber(0))
                              : ""));
}

}  // namespace impactdic
