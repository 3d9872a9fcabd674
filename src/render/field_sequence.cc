#include "impactdic/render/field_sequence.h"

#include <cmath>
#include <utility>

#include "impactdic/core/error.h"

namespace impactdic {
void CheckFieldFrame(const cv::Mat& m, const cv::Mat& first, std::size_t i,
                     const std::string& type_name) {
  const std::string field = type_name + ".frames[" + std::to_string(i) + "]";
  CheckValue(!m.empty() && m.dims == 2, field, "an empty image", "a 2-D grey image");
  CheckValue(m.type() == CV_8UC1 || m.type() == CV_16UC1 || m.type() == CV_32FC1, field,
             "OpenCV type " + std::to_string(m.type()), "CV_8UC1, CV_16UC1 or CV_32FC1");
  CheckValue(m.size() == first.size() && m.type() == first.type(), field,
             std::to_string(m.cols) + "x" + std::to_string(m.rows), "the size and type of frame 0");
}

cv::Mat FieldSequence::Frame(std::size_t i) const {
  if (!frames.empty() || !load_frame) return frames.at(i);
  cv::Mat m = load_frame(i);
  CheckFieldFrame(m, m, i, "FieldSequence");
  return m;
}

void FieldSequence::CheckCommon(const std::string& type_name, bool require_images) const {
  const std::size_t n = num_subsets, f = num_frames();
  if (require_images)
    CheckValue(has_images(), type_name + ".frames", "no frames", "at least one frame");
  CheckValue(f > 0, type_name + ".time_ms", "no frames", "at least one frame");
  if (frames.empty() && has_images()) CheckFieldFrame(Frame(0), Frame(0), 0, type_name);
  for (std::size_t i = 0; i < frames.size(); ++i)
    CheckFieldFrame(frames[i], frames[0], i, type_name);
  CheckValue(time_ms.size() == f, type_name + ".time_ms",
             std::to_string(time_ms.size()) + " values", std::to_string(f) + " (one per frame)");
  CheckValue(x_px.size() == y_px.size() && (x_px.size() == n || x_px.size() == f * n),
             type_name + ".x_px/y_px",
             std::to_string(x_px.size()) + "/" + std::to_string(y_px.size()) + " values",
             std::to_string(n) + " (fixed) or " + std::to_string(f * n) + " (per frame)");
}

void FieldSequence::KeepRows(const std::vector<std::size_t>& rows,
                             const std::vector<std::vector<double>*>& per_frame) {
  const std::size_t n = num_subsets;
  auto keep = [&](std::vector<double>& per_row, std::size_t width) {
    std::vector<double> kept;
    for (std::size_t row : rows)
      kept.insert(kept.end(), per_row.begin() + row * width, per_row.begin() + (row + 1) * width);
    per_row = std::move(kept);
  };
  keep(time_ms, 1);
  for (std::vector<double>* field : per_frame) keep(*field, n);
  if (x_px.size() != n) {
    keep(x_px, n);
    keep(y_px, n);
  }
}

std::size_t FrameNearestTime(const FieldSequence& sequence, double t_ms) {
  std::size_t best = 0;
  double best_d = HUGE_VAL;
  for (std::size_t i = 0; i < sequence.time_ms.size(); ++i) {
    const double d = std::abs(sequence.time_ms[i] - t_ms);
    if (std::isfinite(d) && d < best_d) {
      best_d = d;
      best = i;
    }
  }
  return best;
}

}  // namespace impactdic
