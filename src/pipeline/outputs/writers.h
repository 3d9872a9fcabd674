// The factories of the built-in output writers (pipeline/output_writer.h), one file each;
// BuiltInOutputWriters() (output_writers.cc) lists them.
#ifndef IMPACTDIC_SRC_PIPELINE_OUTPUTS_WRITERS_H_
#define IMPACTDIC_SRC_PIPELINE_OUTPUTS_WRITERS_H_

#include <memory>

#include "impactdic/pipeline/output_writer.h"

namespace impactdic::outputs {

std::shared_ptr<const OutputWriter> MakeResultsFileWriter();  // results.h5
std::shared_ptr<const OutputWriter> MakeFiguresWriter();      // figures, snapshot, animation
std::shared_ptr<const OutputWriter> MakeSummaryJsonWriter();  // summary.json
std::shared_ptr<const OutputWriter> MakeSummaryCsvWriter();   // summary.csv

}  // namespace impactdic::outputs

#endif  // IMPACTDIC_SRC_PIPELINE_OUTPUTS_WRITERS_H_
