// The correlation driver: the first reference, then each frame through its steps (correlator_impl.h
// lists the files that hold them).
#include "impactdic/dic/correlator.h"

#include <cassert>
#include <memory>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "correlator_impl.h"
#include "impactdic/core/progress.h"
#include "impactdic/core/timer.h"
#include "impactdic/dic/reference_update.h"
#include "impactdic/io/image_io.h"

namespace impactdic {

using internal::Attempt;
using internal::Usable;

Correlator::Correlator(const DicOptions& options) : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->options = options;
  impl_->half = options.grid.subset_size / 2;
  impl_->size = options.grid.subset_size;
  impl_->shape = internal::MakeShape(options.icgn.shape, impl_->half);
  // Pairs: the reference never changes (UpdateOptions do not apply).
  impl_->policy = ReferenceUpdatePolicyFromString(
      options.mode == SequenceMode::kPairs ? "fixed" : options.update.policy, options.update);
}

Correlator::~Correlator() = default;

void Correlator::SetReference(const cv::Mat& image) {
  Impl& m = *impl_;
  m.SetUpGrid(image);
  StopPoint();  // Stop points (core/progress.h) between the phases.
  const int n = static_cast<int>(m.initial.size());
  m.last_index = 0;
  m.summary = DicSummary{};
  m.summary.subsets = n;
  m.summary.data_bits = m.options.data_bits > 0 ? m.options.data_bits : DataBits(image);
  m.iteration_sum = m.converged_sum = 0;
  FrameResult timing;
  WallTimer timer;
  cv::Mat image32 = image;
  if (image.depth() != CV_8U && image.depth() != CV_32F) image.convertTo(image32, CV_32F);
  m.BuildReference(0, image, nullptr, image32, &timing);
  StopPoint();
  m.summary.seconds_coefficients += timing.seconds_coefficients;
  m.summary.seconds_reference += timing.seconds_reference;
  m.summary.seconds_total += timer.ElapsedSeconds();
  // The reference frame is every usable subset's previous position (zero displacement); the
  // first Correlate() has no velocity yet: pos_last stays NaN so that it uses the seeds (pair
  // mode) rather than a zero-displacement prediction.
  m.last_frame.reset();
  for (int i = 0; i < n; ++i) {
    if (m.tracks[i].active && Usable(m.ref.subsets[i].status)) m.tracks[i].pos_prev = m.initial[i];
  }
}

FrameResult Correlator::Correlate(const cv::Mat& image) {
  Impl& m = *impl_;
  assert(!m.initial.empty() && "Correlator::SetReference() must come before Correlate()");
  m.CheckImage(image, "deformed image");
  WallTimer total;
  FrameResult out;
  out.frame = m.last_index + 1;
  if (m.options.mode == SequenceMode::kPairs) {
    // An independent image: nothing is predicted from the images before it (seeds and
    // propagation, as for the first frame after the reference).
    for (internal::SubsetTrack& t : m.tracks) {
      t.pos_last = cv::Point2d(kNaN, kNaN);
      t.params_valid = false;
    }
  }
  // First frame after the reference: positions at frame 0 are the prediction base only through
  // the seeds; afterwards constant-velocity prediction.
  WallTimer timer;
  std::unique_ptr<internal::Frame> frame = m.NewFrame();
  m.MakeFrame(image, out.frame, frame.get());
  out.seconds_coefficients += timer.ElapsedSeconds();
  StopPoint();
  internal::Attempts at = m.Solve(*frame, &out);
  StopPoint();
  m.RedoIfThePolicyAsks(*frame, &at, &out);
  out.reference_frame = m.ref.frame;

  // Results: tracked positions and accumulated displacements.
  std::vector<cv::Point2d> pos = m.StoreResults(at, &out);
  m.PostCheck(&at, &pos, &out);
  m.KeepGradients(&out);
  m.KeepPositions(pos, out.frame);
  m.last_index = out.frame;
  m.AdvanceReference(image, std::move(frame), at, &out);
  out.seconds_total = total.ElapsedSeconds();
  m.AddToSummary(out);
  return out;
}

int Correlator::subsets() const { return static_cast<int>(impl_->initial.size()); }
const std::vector<cv::Point2d>& Correlator::positions() const { return impl_->initial; }
int Correlator::rows() const { return impl_->ny; }
int Correlator::cols() const { return impl_->nx; }
const DicSummary& Correlator::summary() const { return impl_->summary; }
const DicOptions& Correlator::options() const { return impl_->options; }

}  // namespace impactdic
