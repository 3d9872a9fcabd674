#include <filesystem>
#include <string>

#include "impactdic/pipeline/output_writer.h"
#include "writers.h"

namespace impactdic {

std::string OutputContext::Path(const std::string& name) const {
  return (std::filesystem::path(folder) / name).string();
}

// The built-in output formats, in the order of output_writers.def (the order they are written).
// A new format adds one line there.
OutputWriters BuiltInOutputWriters() {
  return {
#define IMPACTDIC_OUTPUT_WRITER(factory, file) outputs::factory(),
#include "output_writers.def"
#undef IMPACTDIC_OUTPUT_WRITER
  };
}

}  // namespace impactdic
