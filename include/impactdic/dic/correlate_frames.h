// The one correlation driver: `correlate`, `run`'s correlate stage and the library's
// CorrelateSequence all correlate a sequence through it. It reads the frames from a FrameSource
// (io/frame_source.h; preprocessed when it is a pipeline FrameStream), decoding frame k + 1 while
// frame k is correlated (TBB), shows the progress bar, and hands each frame's result to the
// caller as it is produced:
//
//   FrameStream frames("rec.cine", preprocess, /*calibration=*/nullptr);
//   DicResult r = CorrelateFrames(frames, options);               // r.frames: every frame
//   DicResult s = CorrelateFrames(frames, options, [&](FrameResult&& f) { Append(f); });
#ifndef IMPACTDIC_DIC_CORRELATE_FRAMES_H_
#define IMPACTDIC_DIC_CORRELATE_FRAMES_H_

#include <functional>

#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/frame_source.h"

namespace impactdic {

// Receives the result of each deformed frame, in order, as soon as it is correlated.
using FrameResultSink = std::function<void(FrameResult&&)>;

// Correlates frames 1.. of `frames` against frame 0 as the first reference (DicOptions::mode:
// a sequence, or independent pairs). Frame 0 is read first (an Error reading it names it); then
// the reference's precomputation runs while frame 1 is read, and every later frame is read while
// the one before it is correlated, so besides what the correlator keeps (its reference and, with
// `auto`, the last frame) at most two frames are held, whatever the length of the sequence. An
// error reading frame k + 1 is reported after frame k's correlation, unless that failed (its
// error is then the one reported).
// Each FrameResult goes to `sink` when one is given (DicResult::frames then stays empty), else
// into DicResult::frames. The result also carries every frame's number (FrameNumber, the first
// reference included), the time stamps when the source has them (DicResult::time_s), and the
// source's warnings (logged as found). Error unless the source has at least two frames.
DicResult CorrelateFrames(FrameSource& frames, const DicOptions& options,
                          const FrameResultSink& sink = {});

}  // namespace impactdic

#endif  // IMPACTDIC_DIC_CORRELATE_FRAMES_H_
