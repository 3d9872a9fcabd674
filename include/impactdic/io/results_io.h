// Checked reading of a results group, for the modules that own one (sensor/sensor_results.h,
// kinematics/kinematics_results.h, momentum/momentum_results.h, model/model_results.h): a
// missing group, dataset or attribute, or a dataset of another shape, is one Error kFileFormat
// naming the file and the path.
//
//   RequireGroup(in, "/sensor", file, "the accelerometer results (impactdic run or analyze)");
//   std::size_t k = kAnyLength;
//   std::vector<double> t = ReadSeries(in, "/sensor/t_s", file, &k);  // k = its length
//   std::vector<double> a = ReadSeries(in, "/sensor/accel_g", file, &k);  // must match
#ifndef IMPACTDIC_IO_RESULTS_IO_H_
#define IMPACTDIC_IO_RESULTS_IO_H_

#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/io/hdf5_store.h"

namespace impactdic {

inline constexpr std::size_t kAnyLength = std::numeric_limits<std::size_t>::max();

// Error kFileFormat naming `file` and `group` ("missing", expected `what`) unless it exists.
void RequireGroup(const H5Reader& in, const std::string& group, const std::string& file,
                  const std::string& what);

// A 1-D dataset. *length: kAnyLength on entry = any length, then set to the length read;
// otherwise the length required (an Error naming the dataset, its length and the expected one).
std::vector<double> ReadSeries(const H5Reader& in, const std::string& path, const std::string& file,
                               std::size_t* length);

// A dataset of exactly the dimensions `dims`.
std::vector<double> ReadField(const H5Reader& in, const std::string& path, const std::string& file,
                              const Dims& dims);

// The number attribute `name` of `object`, NaN when absent (a file of an earlier version).
double ReadNumberAttributeOr(const H5Reader& in, const std::string& object, const std::string& name,
                             double absent);
// The string attribute `name` of `object`, `absent` when it is not there.
std::string ReadStringAttributeOr(const H5Reader& in, const std::string& object,
                                  const std::string& name, const std::string& absent);

// One dataset of a results group bound to its field, so that one list of bindings is both the
// writer's and the reader's (Vector: const std::vector<double> to write, std::vector<double> to
// read):
//   for (const auto& d : Datasets(result)) out.Write(d.path, *d.values, d.units, d.description);
template <typename Vector>
struct DatasetBinding {
  const char* path;         // Its path in the file, a name of io/results_layout.h.
  const char* units;        // "m"
  const char* description;  // The dataset's description attribute.
  Vector* values;
};

// Writes / reads number attributes of `object` given as (name, value) pairs; the reader sets
// each value from the file, NaN where the attribute is absent.
void WriteNumberAttributes(H5Writer& out, const std::string& object,
                           const std::vector<std::pair<const char*, double>>& attributes);
void ReadNumberAttributes(const H5Reader& in, const std::string& object,
                          const std::vector<std::pair<const char*, double*>>& attributes);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_RESULTS_IO_H_
