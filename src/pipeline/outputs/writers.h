// The factories of the built-in output writers (pipeline/output_writer.h), declared from the list
// output_writers.def; BuiltInOutputWriters() (output_writers.cc) tables them in that order.
#ifndef IMPACTDIC_SRC_PIPELINE_OUTPUTS_WRITERS_H_
#define IMPACTDIC_SRC_PIPELINE_OUTPUTS_WRITERS_H_

#include <memory>
#include <vector>

#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/run_data.h"

namespace impactdic::outputs {

#define IMPACTDIC_OUTPUT_WRITER(factory, file) std::shared_ptr<const OutputWriter> factory();
#include "output_writers.def"
#undef IMPACTDIC_OUTPUT_WRITER

// The time of each analysed frame since the impact [ms] (/time/t_ms; results_file_writer.cc):
// without a sensor record from the first analysed frame, by the camera's time stamps or k / fps.
std::vector<double> AnalysedFrameTimesMs(const SceneRunData& d);

}  // namespace impactdic::outputs

#endif  // IMPACTDIC_SRC_PIPELINE_OUTPUTS_WRITERS_H_
