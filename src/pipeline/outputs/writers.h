// The factories of the built-in output writers (pipeline/output_writer.h), declared from the list
// output_writers.def; BuiltInOutputWriters() (output_writers.cc) tables them in that order.
#ifndef IMPACTDIC_SRC_PIPELINE_OUTPUTS_WRITERS_H_
#define IMPACTDIC_SRC_PIPELINE_OUTPUTS_WRITERS_H_

#include <memory>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/run_data.h"

namespace impactdic::outputs {

// The views of results.xdmf (xdmf_writer.cc) in the results.h5 being written: /xdmf
// (io/results_layout.h, kXdmfGroup), from the /dic, /kinematics and /strain datasets it holds.
// Writes nothing without /dic/x_px, /dic/y_px of shape [N] and /time/t_ms.
void WriteXdmfViews(H5Writer& out);

#define IMPACTDIC_OUTPUT_WRITER(factory, file) std::shared_ptr<const OutputWriter> factory();
#include "output_writers.def"
#undef IMPACTDIC_OUTPUT_WRITER

// The analysed frames' timeline (/time) and the groups of the analysis stages that ran
// (results_file_writer.cc): /sensor, /kinematics (with
// the attribute mm_per_px), /momentum, /model, /strain; each replaces its group. The one writer
// of results.h5 and of `impactdic analyze SCENE` (pipeline/scene_analysis.h).
void WriteAnalysisResults(H5Writer& out, const SceneRunData& d);

}  // namespace impactdic::outputs

#endif  // IMPACTDIC_SRC_PIPELINE_OUTPUTS_WRITERS_H_
