#include <filesystem>

#include "impactdic/pipeline/output_writer.h"
#include "writers.h"

namespace impactdic {

std::string OutputContext::Path(const std::string& name) const {
  return (std::filesystem::path(folder) / name).string();
}

// The registry of the built-in output formats: one line each, in the order they are written.
OutputWriters BuiltInOutputWriters() {
  return {
      outputs::MakeResultsFileWriter(),
      outputs::MakeFiguresWriter(),
      outputs::MakeSummaryJsonWriter(),
      outputs::MakeSummaryCsvWriter(),
  };
}

}  // namespace impactdic
